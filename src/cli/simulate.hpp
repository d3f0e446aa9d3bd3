#pragma once
// `campaign simulate`: one realization of one scene of a sweep file, no MPI.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "cli/exit_codes.hpp"  // run_simulate returns them
#include "cli/snapshot_writer.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::cli {

struct SimulateOptions {
    std::filesystem::path sweep;  // empty with `point`: the scene comes from the store
    // A stored realization to run again (--store, --point, --realization): its point's scene from
    // the sweep text the store recorded (checked against the point's stored scene text) and its
    // seed from the store's plan.
    std::optional<std::filesystem::path> store;
    std::optional<std::string> point;
    int realization = 0;
    double D_cm = 0.0;
    double theta_deg = 0.0;
    std::uint64_t seed = 0;
    bool json = false;
    std::optional<std::filesystem::path> snapshot_dir;
    double snapshot_interval = 0.05;   // s of simulated time
    SnapshotFormats snapshot_formats;  // default: both vtu and dump
    bool progress = false;
    double progress_interval = 0.5;  // s of simulated time
};

// The scene and seed of realization `realization` of the point labelled `label` in a store.
// Throws core::ConfigError naming what is missing (no such point: the labels there; index out of
// range; no recorded sweep file that gives the stored physics).
struct StoredTask {
    engine::SceneParams scene;
    std::uint64_t seed = 0;
    double D_cm = 0.0, theta_deg = 0.0;
    std::string sweep_path;                  // of the run whose sweep text gave the scene
    std::vector<std::string> code_versions;  // of the store's runs, oldest first, each once
};
StoredTask stored_task(const std::filesystem::path& store, const std::string& label,
                       int realization);

// Loads the sweep, runs the realization and prints the result to `out` (JSON or summary);
// progress lines go to `err`. Returns exit_ok, or exit_realization_failed when the realization
// failed. Throws core::ConfigError for a bad sweep file or scene, std::runtime_error (or a
// std::filesystem error) when snapshots cannot be written.
int run_simulate(const SimulateOptions& opt, std::ostream& out, std::ostream& err);

// `campaign simulate ARGS` (simulate_command.cpp): its options, checked, into SimulateOptions,
// then run_simulate on stdout and stderr.
void print_simulate_help(std::ostream& os);
int simulate_command(const std::vector<std::string>& args);

}  // namespace hopper::cli
