// Loading a sweep file, the scene at a given outlet and angle, setting names and texts, and the
// deterministic task list with its seeds.
#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "config/key_table.hpp"
#include "config/parser.hpp"
#include "hopper/config/sanity.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/core/units.hpp"

namespace hopper::config {

using core::ConfigError;
using namespace detail;
namespace fs = std::filesystem;

namespace {

std::string display_name(const fs::path& p) {
    return p.string();
}

}  // namespace

SweepFile load_sweep(const fs::path& path) {
    const std::string file = display_name(path);
    std::error_code ec;
    const auto st = fs::status(path, ec);
    if (ec || !fs::exists(st)) {
        throw ConfigError(file + ": cannot read the sweep file: " +
                          (ec ? ec.message() : std::string("no such file")));
    }
    if (fs::is_directory(st))
        throw ConfigError(file + ": cannot read the sweep file: it is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw ConfigError(file + ": cannot read the sweep file: " + std::strerror(errno));
    }
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw ConfigError(file + ": cannot read the sweep file: read error");
    return parse_sweep(text, path);
}

SweepFile parse_sweep(std::string_view text, const fs::path& source_name) {
    return Parser(text, source_name).run();
}

SweepFile parse_sweep_tree(const nlohmann::json& tree, const fs::path& source_name) {
    const toml::table root = table_from_tree(tree, display_name(source_name));
    std::ostringstream text;  // the provenance: the TOML text of the same table
    text << root;
    const std::string t = text.str();
    return Parser(t, source_name).run(root);
}

engine::SceneParams scene_at(const SweepFile& sweep, double D_cm, double theta_deg) {
    const std::string file = display_name(sweep.path);
    const KeyDef& dD = *find_name("D_cm");
    const KeyDef& dT = *find_name("theta_deg");
    if (auto err = range_error(dD, D_cm)) throw ConfigError(file + ": " + *err);
    if (auto err = range_error(dT, theta_deg)) throw ConfigError(file + ": " + *err);
    engine::SceneParams p = sweep.base;
    dD.apply(p, D_cm);
    dT.apply(p, theta_deg);
    if (!(p.hopper.outlet < p.hopper.width))
        throw ConfigError(
            file + ": D_cm = " + message_number(D_cm) + " must be smaller than hopper.width_cm = " +
            approx_number(p.hopper.width / core::cm) + " (the outlet must fit inside the hopper)");
    try {
        engine::validate_scene(p);
    } catch (const ConfigError& e) {
        throw ConfigError(file + ": " + e.what());
    }
    // The orders of magnitude the sweep file's points get (a value in metres or radians).
    if (const std::string problem = scene_problem(p); !problem.empty())
        throw ConfigError(file + ": " + problem);
    return p;
}

std::string to_string(CampaignTarget::Quantity q) {
    return q == CampaignTarget::Quantity::tau ? "tau" : "mean_s";
}

std::string to_string(const core::Setting& setting) {
    return setting.name + "=" + value_text(setting.value);
}

std::string value_text(const core::Setting& setting) {
    return detail::value_text(setting.value);
}

std::vector<std::string> parameter_names() {
    std::vector<std::string> out;
    for (const auto& d : key_table())
        out.emplace_back(d.name);
    return out;
}

std::optional<core::Setting> default_parameter(std::string_view name) {
    static const engine::SceneParams defaults{};
    const KeyDef* d = find_name(name);
    if (!d) return std::nullopt;
    if (auto v = d->read(defaults)) return core::Setting{std::string(name), std::move(*v)};
    return std::nullopt;
}

std::uint64_t derive_seed(std::uint64_t campaign_seed, const std::vector<core::Setting>& settings,
                          int realization) {
    if (realization < 0)
        throw ConfigError("derive_seed: realization index " + std::to_string(realization) +
                          " is negative");
    // Canonical order, whatever order the caller holds them in, so that the seed is a function
    // of the point's parameter set alone.
    std::vector<const core::Setting*> sorted;
    for (const auto& s : settings)
        sorted.push_back(&s);
    std::sort(sorted.begin(), sorted.end(), [](const core::Setting* a, const core::Setting* b) {
        return canonical_less(a->name, b->name);
    });
    std::uint64_t seed = campaign_seed;
    for (const auto* s : sorted)
        seed = core::mix_seed(seed, std::string_view(to_string(*s)));
    return core::mix_seed(seed, static_cast<std::uint64_t>(realization));
}

TaskList::TaskList(const CampaignSpec& spec) : seed_(spec.seed) {
    long long total = 0;
    offset_.reserve(spec.points.size() + 1);
    settings_.reserve(spec.points.size());
    for (const auto& p : spec.points) {
        if (p.realizations < 0)
            throw ConfigError("point '" + p.label + "' has a negative number of realizations");
        offset_.push_back(total);
        settings_.push_back(p.settings);
        total += p.realizations;
    }
    if (total > INT_MAX) throw ConfigError("the campaign has too many tasks for one list");
    offset_.push_back(total);
}

int TaskList::realizations(int point) const {
    if (point < 0 || point >= points())
        throw std::out_of_range("point " + std::to_string(point) + " is not in the list");
    const auto p = static_cast<std::size_t>(point);
    return static_cast<int>(offset_[p + 1] - offset_[p]);
}

Task TaskList::at(int task_id) const {
    if (task_id < 0 || task_id >= size())
        throw std::out_of_range("task id " + std::to_string(task_id) + " is not in the list");
    // The last point whose first id is <= task_id (points of no realizations share an offset).
    const auto it = std::upper_bound(offset_.begin(), offset_.end() - 1, task_id);
    const int point = static_cast<int>(it - offset_.begin()) - 1;
    return at(point, task_id - static_cast<int>(offset_[static_cast<std::size_t>(point)]));
}

Task TaskList::at(int point, int realization) const {
    if (realization < 0 || realization >= realizations(point))
        throw std::out_of_range("realization " + std::to_string(realization) + " of point " +
                                std::to_string(point) + " is not in the list");
    const auto p = static_cast<std::size_t>(point);
    return Task{static_cast<int>(offset_[p]) + realization, point, realization,
                derive_seed(seed_, settings_[p], realization)};
}

std::vector<Task> expand_tasks(const CampaignSpec& spec) {
    const TaskList list(spec);
    std::vector<Task> tasks;
    tasks.reserve(static_cast<std::size_t>(list.size()));
    for (int p = 0; p < list.points(); ++p)
        for (int r = 0; r < list.realizations(p); ++r)
            tasks.push_back(list.at(p, r));
    return tasks;
}

}  // namespace hopper::config
