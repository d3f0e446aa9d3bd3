#pragma once
// `campaign simulate`: one realization of one scene of a sweep file, no MPI.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>

#include "cli/snapshot_writer.hpp"

namespace hopper::cli {

// Exit codes of the campaign executable.
enum ExitCode : int {
    exit_ok = 0,
    exit_error = 1,               // an unexpected failure (I/O, internal error)
    exit_usage = 2,               // bad command line or sweep file (core::ConfigError)
    exit_realization_failed = 3,  // the realization ended with status failed
};

struct SimulateOptions {
    std::filesystem::path sweep;
    double D_cm = 0.0;
    double theta_deg = 0.0;
    std::uint64_t seed = 0;
    bool json = false;
    std::optional<std::filesystem::path> snapshot_dir;
    double snapshot_interval = 0.05;  // s of simulated time
    SnapshotFormats snapshot_formats;  // default: both vtu and dump
    bool progress = false;
    double progress_interval = 0.5;  // s of simulated time
};

// Loads the sweep, runs the realization and prints the result to `out` (JSON or summary);
// progress lines go to `err`. Returns exit_ok, or exit_realization_failed when the realization
// failed. Throws core::ConfigError for a bad sweep file or scene, std::runtime_error (or a
// std::filesystem error) when snapshots cannot be written.
int run_simulate(const SimulateOptions& opt, std::ostream& out, std::ostream& err);

}  // namespace hopper::cli
