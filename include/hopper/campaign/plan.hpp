#pragma once
// From a sweep file's campaign to what the store records and checks: each point's physics as a
// canonical text, the plan (labels, physics, seeds), the resume check, and the order in which
// tasks are handed out.

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "hopper/config/sweep.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/store/records.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

// Every parameter of the scene, one "name=value" line each in a fixed order, SI units in the
// names (hopper.width_m=0.43), numbers in their shortest round-trip form, optionals "unset".
// Two scenes give the same text exactly when they give the same physics.
std::string scene_text(const engine::SceneParams& p);

// The store's view of the campaign: every point with its label, physics text, limit and the
// seeds of its first allotment (first_allotment).
store::CampaignPlan make_plan(const config::CampaignSpec& spec);

// Each point's allotment (realizations planned so far), by label (views into `plan`): with a
// target the rounds so far, else the sweep's realizations.
std::map<std::string_view, int> allotments(const store::CampaignPlan& plan);

// The realizations a point is allotted before anything is stored: all of them, or with a target
// its first round (its `realizations`, at most max_realizations).
int first_allotment(const config::CampaignSpec& spec, const config::Point& point);

// What a resumed run records as its plan (issue 29): the points of `sweep` that `stored` lacks
// or that they extend (more seeds listed, a higher limit), whole; the points already stored as
// they are left out, so that a resume of 10^5 points does not write the plan again. The union of
// the plans (store::State) is the same.
store::CampaignPlan plan_additions(const store::CampaignPlan& stored, store::CampaignPlan sweep);

// Gives the points recorded before typed settings existed (empty `settings`/`parameters`) theirs,
// from the sweep texts the runs recorded (newest first; RunInfo::sweep_text): a point takes them
// from the first sweep whose campaign has a point of the same label and scene text. Sweep texts
// this version cannot read are skipped; a point no sweep text explains keeps empty vectors.
void restore_settings(store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs);

// The campaign plan of a store (the journal's, read without locks: store::read_status) with its
// typed settings, restored for points recorded before them.
store::CampaignPlan read_plan(const std::filesystem::path& store);

// Checks that `sweep` may run on a store holding `stored`: the same campaign seed, and for
// every point already in the store the same physics and seeds (scene texts compared as
// fingerprints). Throws core::ConfigError naming what differs (point, parameter under its
// sweep-file name, both values: from the typed parameters, so `stored` should have been through
// restore_settings). Returns notes on what the sweep adds.
std::vector<std::string> check_compatible(const store::CampaignPlan& stored,
                                          const store::CampaignPlan& sweep);

// The cost model (docs/performance.md, "The cost model"): what one realization of a scene is
// expected to compute, calibrated on measured realizations of this engine. Each term is an
// estimate of what the realization reports in its diagnostics.
struct CostEstimate {
    double fill_height = 0.0;     // m, the settled packing (config::settled_fill_height)
    double settle_time = 0.0;     // s simulated while the packing settles
    double flow_rate = 0.0;       // particles/s while it flows (2-D Beverloo with the wall angle)
    double jams = 0.0;            // expected jams over the discharge
    double jammed_time = 0.0;     // s of discharge time spent jammed (until each jam is seen)
    double shake_time = 0.0;      // s simulated while shaking
    double discharge_time = 0.0;  // s of discharge time: to empty (the steady state: to its
                                  // jams_per_realization-th jam), at most protocol.max_time
    double particle_steps = 0.0;  // the cost: mobile particles summed over the time steps
    double seconds = 0.0;         // particle_steps at the prior speed for N particles
};
CostEstimate estimate_cost(const engine::SceneParams& p);

// The engine's speed before anything of a campaign is measured: 35 ns per particle-step, one
// full-size realization on one core (docs/performance.md); estimate_cost scales it to smaller
// systems.
inline constexpr double prior_seconds_per_particle_step = 35e-9;
// A pessimistic speed, for limits that must not fire early (a worker's silence).
inline constexpr double slow_seconds_per_particle_step = 100e-9;

// The expected cost of one realization in particle-steps (estimate_cost): hands out the
// longest first, and scales by measured worker seconds into times.
double expected_cost(const engine::SceneParams& p);

}  // namespace hopper::campaign
