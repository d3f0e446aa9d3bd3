#include "cli/scene_run.hpp"

#include <variant>

#include "hopper/core/error.hpp"

namespace hopper::cli {

SceneRun base_scene_run(const config::SweepFile& sweep, const std::string& sweep_name, double D_cm,
                        double theta_deg, std::uint64_t seed) {
    return {config::scene_at(sweep, D_cm, theta_deg),
            RunRequest{sweep_name, D_cm, theta_deg, seed}};
}

SceneRun point_run(const config::SweepFile& sweep, const std::string& sweep_name, std::size_t point,
                   int realization) {
    const auto& points = sweep.campaign.points;
    if (!sweep.has_campaign)
        throw core::ConfigError(sweep_name +
                                ": has no [campaign] section, so no points: give the outlet, the "
                                "wall angle and the seed instead");
    if (point >= points.size())
        throw core::ConfigError(sweep_name + ": point " + std::to_string(point) +
                                " does not exist; its points are 0.." +
                                std::to_string(points.size() - 1));
    if (realization < 0)
        throw core::ConfigError("realization " + std::to_string(realization) +
                                " is negative; realizations are numbered from 0");
    const config::Point& p = points[point];
    // The outlet and the angle as the file wrote them (every point's parameters have both).
    const auto written = [&p](const char* name) {
        for (const auto& s : p.parameters)
            if (s.name == name && std::holds_alternative<double>(s.value))
                return std::get<double>(s.value);
        throw core::ConfigError(std::string("point '") + p.label + "' has no " + name);
    };
    const std::uint64_t seed = config::derive_seed(sweep.campaign.seed, p.settings, realization);
    return {p.scene, RunRequest{sweep_name, written("D_cm"), written("theta_deg"), seed}};
}

std::size_t point_index(const config::SweepFile& sweep, const std::string& label) {
    const auto& points = sweep.campaign.points;
    std::string labels;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (points[i].label == label) return i;
        labels += "\n  '" + points[i].label + "'";
    }
    throw core::ConfigError("no point '" + label + "' in " + sweep.path.string() +
                            (points.empty() ? std::string(" (it has no [campaign] points)")
                                            : "; its points are:" + labels));
}

double base_number(const config::SweepFile& sweep, const std::string& name) {
    for (const auto& s : sweep.base_parameters)
        if (s.name == name && std::holds_alternative<double>(s.value))
            return std::get<double>(s.value);
    throw core::ConfigError(sweep.path.string() + ": no number '" + name + "' in its scene");
}

engine::RealizationResult run_scene(const SceneRun& run, const engine::RunHooks& hooks) {
    return engine::run_realization(run.scene, run.request.seed, hooks);
}

}  // namespace hopper::cli
