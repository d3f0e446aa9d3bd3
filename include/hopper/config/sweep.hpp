#pragma once
// The sweep file (TOML) -> validated scene parameters and campaign spec, and the deterministic
// task list. The only code that includes the TOML parser (toml++). Every bad value is rejected
// with a core::ConfigError naming the file, the key, the value and the allowed range; unknown
// keys are errors.
//
// File layout (all sections optional; defaults are the published values of docs/model.md):
//   [hopper]     width_cm particles small_fraction d_small_cm d_large_cm thickness_cm
//                density_kg_m3 D_cm theta_deg
//   [material]   e_n mu kt_over_kn youngs_modulus_pa poisson_ratio collision_time_s
//   [walls]      e_n mu particle_diameter_cm spacing
//   [integrator] scheme ("gear4" | "verlet") steps_per_collision skin
//   [protocol]   see docs in README (jam detection, shaking, limits, sampling, guards)
//   [campaign]   name store seed realizations, and for a campaign that stops when good
//                enough: target target_rel_ci max_realizations round_realizations
//   [sweep]      D_cm = [..], theta_deg = [..], <section>.<key> = [..]  (Cartesian product)
//   [[points]]   D_cm, theta_deg, <section> = { key = value }, realizations (optional)

#include <cstdint>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hopper/core/setting.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::config {

struct Point {
    // The point's varied settings (what its label shows), canonical order: D_cm, theta_deg,
    // then by name; numbers as the file wrote them.
    std::vector<core::Setting> settings;
    // Every key of the sweep file's scene sections under its canonical name (parameter_names()
    // order) and in file units: as the file gave it, else the scene's default converted from SI
    // (the shortest decimal that converts back to the same bits). Unset optionals
    // (walls.edge_diameter_cm, material.collision_time_s, protocol.t_check_s, fields.end_s) are
    // left out.
    std::vector<core::Setting> parameters;
    engine::SceneParams scene;  // the base scene with the settings applied, validated
    int realizations = 0;       // planned (with a target: max_realizations)
    std::string label;          // e.g. "D_cm=2.7 theta_deg=45 material.mu=0.5"
    // With a campaign target: the realizations of the first round (the point's `realizations`
    // as written); 0 without a target.
    int first_round = 0;
};

// A campaign that stops when good enough (issue 13; campaign/adaptive.hpp): realizations run in
// rounds until the relative half-width of the 95 % interval of `quantity` is at most
// rel_half_width at every point, or a point has max_realizations.
struct CampaignTarget {
    enum class Quantity { tau, mean_s };
    Quantity quantity = Quantity::tau;
    double rel_half_width = 0.1;
    int max_realizations = 0;
    int round = 0;  // realizations added to a point that needs more, per round
};

std::string to_string(CampaignTarget::Quantity q);

struct CampaignSpec {
    std::string name;
    std::filesystem::path store;  // resolved relative to the sweep file's directory
    std::uint64_t seed = 0;
    int realizations = 1;  // default per point
    std::vector<Point> points;
    std::optional<CampaignTarget> target;
};

struct SweepFile {
    std::filesystem::path path;  // as given ("<string>" when parsed from text)
    std::string text;            // the file's full text (provenance)
    engine::SceneParams base;    // the scene sections, validated
    // Every key of the scene sections as Point::parameters has it (as the file gave it, else the
    // default in file units, converted back to the same bits): `hopper.D_cm` is "D_cm".
    std::vector<core::Setting> base_parameters;
    bool has_campaign = false;  // a [campaign] section was present
    CampaignSpec campaign;      // filled when has_campaign (points from [sweep]/[[points]])
};

// Parses and validates. Throws core::ConfigError (file, key, value, allowed range).
SweepFile load_sweep(const std::filesystem::path& path);
SweepFile parse_sweep(std::string_view text, const std::filesystem::path& source_name);
// The same from a tree of values instead of a text (the Python module's dict scene, docs/usage.md
// "The engine from Python"): objects are tables, a key with dots a dotted key ("material.mu"),
// and arrays, strings, integers (64-bit signed), floats and booleans what TOML has; null is
// refused. The table goes through the same checks as a file's, and the messages name
// `source_name` and the key (no line). `text` is the table written as TOML.
SweepFile parse_sweep_tree(const nlohmann::json& tree, const std::filesystem::path& source_name);

// The base scene with outlet D (cm) and wall angle theta (deg) set, validated.
engine::SceneParams scene_at(const SweepFile& sweep, double D_cm, double theta_deg);

// One realization to run.
struct Task {
    int task_id;  // index in the list
    int point_index;
    int realization;     // 0-based within the point
    std::uint64_t seed;  // derived from (campaign seed, point's settings, realization)
};

// Same list on every rank; a task's seed depends only on the campaign seed, its point's
// settings and its realization index, so adding points or realizations never changes it.
std::vector<Task> expand_tasks(const CampaignSpec& spec);

// The same list without building it (issue 29: a campaign with a target plans max_realizations
// per point, of which a round runs a few): the ids are expand_tasks's (the points' realizations
// in order), each task made when asked for. Memory: one offset and the settings per point.
class TaskList {
  public:
    TaskList() = default;
    explicit TaskList(const CampaignSpec& spec);
    int size() const { return offset_.empty() ? 0 : static_cast<int>(offset_.back()); }
    int points() const { return static_cast<int>(settings_.size()); }
    // Realizations of point `point` (its `realizations`, max_realizations with a target).
    int realizations(int point) const;
    // Throws std::out_of_range for an id not in the list.
    Task at(int task_id) const;
    // Throws std::out_of_range for a realization the point does not plan.
    Task at(int point, int realization) const;

  private:
    std::uint64_t seed_ = 0;
    std::vector<std::vector<core::Setting>> settings_;
    std::vector<long long> offset_;  // the first id of each point, then the total
};

// Seed of realization `realization` of a point with the given settings.
std::uint64_t derive_seed(std::uint64_t campaign_seed, const std::vector<core::Setting>& settings,
                          int realization);

// Canonical text of one setting, "name=value": numbers in their shortest round-trip form
// (std::to_chars), strings verbatim, e.g. "D_cm=2.7", "integrator.scheme=verlet". Labels and
// seeds are built from it.
std::string to_string(const core::Setting& setting);
// Its value alone, as labels write it ("2.7", "verlet").
std::string value_text(const core::Setting& setting);

// The canonical names of every scene parameter a [sweep] or [[points]] entry may set, in the
// order of campaigns/README.md: "D_cm", "theta_deg", then "<section>.<key>" ("hopper.width_cm",
// "material.mu", ...). For documentation checks and command-line help.
std::vector<std::string> parameter_names();

// The value scene parameter `name` has when no sweep file sets it (the default scene), as a
// point's `parameters` record it (file units); nullopt for an unset optional or an unknown name.
// A point stored before a setting existed has no entry for it, and ran with this value: the
// settings added since keep the earlier physics at their defaults (campaign/mixing.hpp).
std::optional<core::Setting> default_parameter(std::string_view name);

}  // namespace hopper::config
