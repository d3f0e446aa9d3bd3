#pragma once
// How `campaign simulate` reports one realization: a JSON object for machines and a readable
// summary for people.
//
// JSON (one object; keys in this order):
//   status message version sweep D_cm theta_deg seed particles wall_particles discharged
//   n_jams n_shakes n_jams_multi_shake survival_times censored jam_onsets shakes_per_jam
//   empty_time discharge_rate discharge_rate_kg_s steps wall_seconds ns_per_particle_step
//   diagnostics{every Diagnostics field} discharge_curve{time, in_hopper} exit_times
//   events[{kind, time, sim_time, in_hopper}]
//   fields{...} (only when the scene samples fields: a one-line summary,
//   analysis::add_fields_summary in hopper/analysis/json.hpp; the per-node maps are in a campaign
//   store, see the README)
// Built as an analysis::Json (nlohmann) with the analysis layer's number rule (integral values
// without a fraction, shortest round-trip otherwise); a non-finite number is written as null.
// Layout: an object outside any array has one member per line, except the fields summary, which
// sits on one line; an array sits on one line, except an array of objects, which puts each object
// (on one line) on its own line.
// Times in seconds of discharge time (shaking excluded) unless named sim_time. empty_time,
// discharge_rate and discharge_rate_kg_s are null when the engine has no value for them.
//
// Determinism: everything except the wall-clock fields depends only on (sweep, D, theta, seed).
// The wall-clock fields -- "wall_seconds", "ns_per_particle_step" (top level and in diagnostics)
// and the diagnostics' "seconds_*" -- each sit alone on their own line, so
//   grep -vE '"(wall_seconds|ns_per_particle_step|seconds_[a-z_]+)":'
// leaves text that is byte-identical between two runs of the same realization.

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>

#include "hopper/analysis/json.hpp"
#include "hopper/engine/result.hpp"

namespace hopper::cli {

// What was asked for, echoed in the output.
struct RunRequest {
    std::string sweep;  // the sweep file as given
    double D_cm = 0.0;
    double theta_deg = 0.0;
    std::uint64_t seed = 0;
};

// Keys whose values are wall-clock measurements (not reproducible run to run).
bool is_wall_clock_key(std::string_view key);

// The result object.
analysis::Json result_object(const RunRequest& req, const engine::RealizationResult& r);

// The whole JSON document in the layout above (no trailing newline).
std::string result_json(const RunRequest& req, const engine::RealizationResult& r);

// A readable multi-line summary.
void write_summary(std::ostream& os, const RunRequest& req, const engine::RealizationResult& r);

}  // namespace hopper::cli
