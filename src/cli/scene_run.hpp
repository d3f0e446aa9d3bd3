#pragma once
// One realization of a sweep file's scene as `campaign simulate` runs it, shared by the command
// (simulate.cpp) and the Python module (src/python/hopper_engine.cpp), so that both give the same
// scene, seed and JSON by construction (docs/usage.md, "The engine from Python").

#include <cstddef>
#include <cstdint>
#include <string>

#include "cli/result_output.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/result.hpp"

namespace hopper::cli {

// What to run (the scene, and the seed in `request`) and what the result's JSON echoes.
struct SceneRun {
    engine::SceneParams scene;
    RunRequest request;
};

// `campaign simulate SWEEP --D D_cm --theta theta_deg --seed seed`: the sweep's base scene with
// the outlet and the wall angle set (config::scene_at: their ranges, the outlet inside the
// hopper, the orders of magnitude of docs/model.md, "Checked before a run"). `sweep_name` is the
// JSON's "sweep" (the file as given). Throws core::ConfigError.
SceneRun base_scene_run(const config::SweepFile& sweep, const std::string& sweep_name, double D_cm,
                        double theta_deg, std::uint64_t seed);

// Realization `realization` of the campaign's point number `point` (0-based, in the order of
// `campaign run`'s points), as `campaign run` runs it: the point's scene and its task's seed
// (config::derive_seed of the campaign seed, the point's settings and the index, as
// config::TaskList gives it, whatever the number of realizations planned). D_cm and theta_deg
// are echoed as the file wrote them. Throws core::ConfigError without a [campaign], or for a
// point or an index out of range.
SceneRun point_run(const config::SweepFile& sweep, const std::string& sweep_name, std::size_t point,
                   int realization);

// The number of the point labelled `label` ("D_cm=2.7 theta_deg=45"). Throws core::ConfigError
// listing the labels when there is none.
std::size_t point_index(const config::SweepFile& sweep, const std::string& label);

// The value of parameter `name` ("D_cm", "material.mu") as the sweep's base scene has it
// (config::SweepFile::base_parameters), for a number; throws core::ConfigError otherwise.
double base_number(const config::SweepFile& sweep, const std::string& name);

// engine::run_realization of the run's scene and seed.
engine::RealizationResult run_scene(const SceneRun& run, const engine::RunHooks& hooks = {});

}  // namespace hopper::cli
