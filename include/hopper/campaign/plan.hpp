#pragma once
// From a sweep file's campaign to what the store records and checks: each point's physics as a
// canonical text, the plan (labels, physics, seeds), the resume check, and the order in which
// tasks are handed out.

#include <filesystem>
#include <string>
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

// The store's view of the campaign: every point with its label, physics text and seeds.
store::CampaignPlan make_plan(const config::CampaignSpec& spec);

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

// Relative cost of one realization, to hand out the longest first: particles x steps per
// simulated second x an estimate of the simulated time (settling plus the time to empty the
// hopper at the 2-D Beverloo rate, capped by max_time). Only the order matters.
double expected_cost(const engine::SceneParams& p);

}  // namespace hopper::campaign
