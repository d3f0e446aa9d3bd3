#include "hopper/campaign/stored_scenes.hpp"

#include <algorithm>
#include <exception>

#include "hopper/campaign/plan.hpp"
#include "hopper/config/scene_schema.hpp"
#include "hopper/core/error.hpp"

namespace hopper::campaign {

std::vector<std::optional<RecordedPoint>> recorded_points(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs,
    const std::function<bool(const store::PointPlan&)>& wanted) {
    std::vector<std::optional<RecordedPoint>> out(plan.points.size());
    std::vector<bool> open(plan.points.size());
    for (std::size_t i = 0; i < plan.points.size(); ++i)
        open[i] = !wanted || wanted(plan.points[i]);
    const auto any_open = [&] { return std::find(open.begin(), open.end(), true) != open.end(); };
    for (auto run = runs.rbegin(); run != runs.rend() && any_open(); ++run) {
        std::vector<config::Point> points;
        try {
            points = config::parse_sweep(run->info.sweep_text, "<recorded sweep>").campaign.points;
        } catch (const core::ConfigError&) {
            continue;  // written for another version of the keys: no help
        }
        for (std::size_t i = 0; i < plan.points.size(); ++i) {
            if (!open[i]) continue;
            const store::PointPlan& p = plan.points[i];
            for (auto& q : points)
                if (q.label == p.label && scene_text(q.scene) == p.scene) {
                    out[i] = RecordedPoint{std::move(q), run->info.sweep_path};
                    open[i] = false;
                    break;
                }
        }
    }
    return out;
}

std::optional<config::CampaignSpec> recorded_campaign(const std::vector<store::RunSummary>& runs) {
    if (runs.empty()) return std::nullopt;
    try {
        return config::parse_sweep(runs.back().info.sweep_text, runs.back().info.sweep_path)
            .campaign;
    } catch (const std::exception&) {
        return std::nullopt;  // a sweep text this version no longer reads
    }
}

std::optional<engine::SceneParams> typed_scene(const store::PointPlan& p) {
    if (p.parameters.empty()) return std::nullopt;
    try {
        engine::SceneParams s = config::scene_from_parameters(p.parameters);
        if (scene_text(s) == p.scene) return s;
    } catch (const core::ConfigError&) {
        // parameters of another version of the keys
    }
    return std::nullopt;
}

std::vector<std::optional<engine::SceneParams>> point_scenes(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs) {
    std::vector<std::optional<engine::SceneParams>> out;
    for (const auto& p : plan.points)
        out.push_back(typed_scene(p));
    if (std::all_of(out.begin(), out.end(), [](const auto& s) { return s.has_value(); }))
        return out;
    const auto legacy = recorded_points(plan, runs, [&](const store::PointPlan& p) {
        return !out[static_cast<std::size_t>(&p - plan.points.data())];
    });
    for (std::size_t i = 0; i < out.size(); ++i)
        if (!out[i] && legacy[i]) out[i] = legacy[i]->point.scene;
    return out;
}

}  // namespace hopper::campaign
