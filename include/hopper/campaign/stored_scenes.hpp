#pragma once
// The scene of a stored point (issue 28): rebuilt from the typed parameters its plan records
// (config::scene_from_parameters), and checked against its stored fingerprint. The one legacy
// path, for stores older than typed parameters: the points of the sweep texts the runs recorded,
// newest run first, matched by label and fingerprint. restore_settings (plan.hpp), `campaign
// status`'s estimate and `campaign simulate --point` all go through here. It is the one place that
// parses recorded sweep texts; the campaign's target, recorded nowhere else, is read here too
// (recorded_campaign).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hopper/config/sweep.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/store/records.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

// The legacy path. A point of a recorded sweep text, and the path that run recorded.
struct RecordedPoint {
    config::Point point;
    std::string sweep_path;
};
// For each point of `plan` that `wanted` selects (every point when empty): the point of the
// newest recorded sweep text (RunInfo::sweep_text) with the same label and scene text; nullopt
// where none does. Sweep texts this version cannot read are skipped; the texts are read only
// while a selected point is unexplained.
std::vector<std::optional<RecordedPoint>> recorded_points(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs,
    const std::function<bool(const store::PointPlan&)>& wanted = {});

// The campaign of the newest run's recorded sweep text (its target, rounds and points as that run
// planned them): what `campaign status` replays a target campaign's rounds with, as `campaign
// run` does. nullopt without runs or when this version cannot read that text (the plan's counts
// then stand).
std::optional<config::CampaignSpec> recorded_campaign(const std::vector<store::RunSummary>& runs);

// The point's scene from its typed parameters, when they give its stored text exactly; nullopt
// when it has none (a store older than them) or they do not (another version's keys).
std::optional<engine::SceneParams> typed_scene(const store::PointPlan& p);

// Every point's scene, in plan order: typed_scene, else the legacy path; nullopt where neither
// gives the stored text.
std::vector<std::optional<engine::SceneParams>> point_scenes(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs);

}  // namespace hopper::campaign
