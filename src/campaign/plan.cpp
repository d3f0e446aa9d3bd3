#include "hopper/campaign/plan.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <string_view>
#include <variant>

#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/config/sanity.hpp"
#include "hopper/config/scene_schema.hpp"
#include "hopper/core/error.hpp"
#include "hopper/engine/scene.hpp"
#include "hopper/store/codec.hpp"

namespace hopper::campaign {

namespace {

// "name=value" texts of typed settings, by name.
std::map<std::string, std::string> by_name(const std::vector<core::Setting>& settings) {
    std::map<std::string, std::string> m;
    for (const auto& s : settings)
        m[s.name] = config::value_text(s);
    return m;
}

// The parameters in which two points of different physics differ, one "\n    name = value
// (store: value)" line each.
std::string physics_diff(const store::PointPlan& mine, const store::PointPlan& stored) {
    using Values = std::map<std::string, std::string>;
    // "\n    name = value (store: value)" for each name whose value differs, unless `same`.
    const auto compare = [](const Values& a, const Values& b, auto same) {
        std::string out;
        for (const auto& [k, v] : a) {
            const auto it = b.find(k);
            const std::string old = it == b.end() ? "absent" : it->second;
            if (old != v && !same(k, v, it == b.end()))
                out += "\n    " + k + " = " + v + " (store: " + old + ")";
        }
        for (const auto& [k, v] : b)
            if (!a.count(k)) out += "\n    " + k + " absent (store: " + v + ")";
        return out;
    };
    std::string diff;
    if (!mine.parameters.empty() && !stored.parameters.empty())
        // A parameter newer than the store is its physics at the default (issue 28).
        diff = compare(by_name(mine.parameters), by_name(stored.parameters),
                       [](const std::string& k, const std::string& v, bool absent) {
                           const auto def = absent ? config::default_parameter(k) : std::nullopt;
                           return def && config::value_text(*def) == v;
                       });
    if (!diff.empty()) return diff;
    // No sweep parameter differs: name the physics text's lines that do.
    const auto lines = [](const std::string& text) {
        Values m;
        std::size_t at = 0;
        while (at < text.size()) {
            const std::size_t end = std::min(text.find('\n', at), text.size());
            const std::string line = text.substr(at, end - at);
            const std::size_t eq = line.find('=');
            if (eq != std::string::npos) m[line.substr(0, eq)] = line.substr(eq + 1);
            at = end + 1;
        }
        return m;
    };
    const auto a = lines(mine.scene), b = lines(stored.scene);
    diff = compare(a, b, [](const std::string&, const std::string&, bool) { return false; });
    if (a.count("protocol.reinsertion") && !b.count("protocol.reinsertion"))
        diff +=
            "\n    (the store was written before the fix of the steady state's springs, "
            "CHANGELOG: there every re-insertion reset every tangential spring; finish it "
            "with the version that wrote it, which `campaign status` names, or start a new "
            "store)";
    return diff.empty() ? "\n    (the physics text differs in a value no sweep key sets)" : diff;
}

}  // namespace

std::string scene_text(const engine::SceneParams& p) {
    // Generated from the scene schema (config/scene_schema.hpp), byte for byte the text of the
    // hand-written list it replaced (tests/campaign/test_fingerprint_rows.cpp).
    return config::scene_fingerprint(p);
}

namespace {

// A number of a point's parameters (file units, as written), else `fallback`.
double written_number(const std::vector<core::Setting>& parameters, std::string_view name,
                      double fallback) {
    for (const auto& s : parameters)
        if (s.name == name)
            if (const double* v = std::get_if<double>(&s.value)) return *v;
    return fallback;
}

}  // namespace

std::map<std::string_view, int> allotments(const store::CampaignPlan& plan) {
    std::map<std::string_view, int> out;
    for (const auto& p : plan.points)
        out.emplace(p.label, p.realizations());
    return out;
}

int first_allotment(const config::CampaignSpec& spec, const config::Point& point) {
    if (!spec.target) return point.realizations;
    return std::clamp(point.first_round, std::min(1, point.realizations), point.realizations);
}

store::CampaignPlan make_plan(const config::CampaignSpec& spec) {
    store::CampaignPlan plan;
    plan.name = spec.name;
    plan.seed = spec.seed;
    for (const auto& pt : spec.points) {
        store::PointPlan p;
        p.label = pt.label;
        p.scene = scene_text(pt.scene);
        // As the sweep file wrote them (60, not the quotient 59.99999999999999): /points and
        // the tables read from it must find `theta_deg == 60`.
        p.D_cm = written_number(pt.parameters, "D_cm", pt.scene.hopper.outlet / core::cm);
        p.theta_deg = written_number(pt.parameters, "theta_deg", pt.scene.hopper.theta / core::deg);
        p.particles = pt.scene.particles.count;
        p.settings = pt.settings;
        p.parameters = pt.parameters;
        // With a target, the plan lists the first round's seeds and the limit; each later round
        // adds its own (store::AllotmentRecord), so the plan costs what is planned (issue 29).
        p.limit = pt.realizations;
        const int listed = first_allotment(spec, pt);
        p.seeds.reserve(static_cast<std::size_t>(listed));
        for (int r = 0; r < listed; ++r)
            p.seeds.push_back(config::derive_seed(spec.seed, pt.settings, r));
        plan.points.push_back(std::move(p));
    }
    return plan;
}

store::CampaignPlan plan_additions(const store::CampaignPlan& stored, store::CampaignPlan sweep) {
    std::map<std::string_view, const store::PointPlan*> by_label;
    for (const auto& s : stored.points)
        by_label.emplace(s.label, &s);
    std::vector<store::PointPlan> added;
    for (auto& p : sweep.points) {
        const auto it = by_label.find(p.label);
        if (it == by_label.end() || p.realizations() > it->second->realizations() ||
            p.max_realizations() > it->second->max_realizations())
            added.push_back(std::move(p));
    }
    sweep.points = std::move(added);
    return sweep;
}

void restore_settings(store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs) {
    const auto missing = [](const store::PointPlan& p) {
        return p.settings.empty() || p.parameters.empty();
    };
    if (std::none_of(plan.points.begin(), plan.points.end(), missing)) return;
    const auto recorded = recorded_points(plan, runs, missing);  // the legacy path
    for (std::size_t i = 0; i < plan.points.size(); ++i)
        if (recorded[i]) {
            plan.points[i].settings = recorded[i]->point.settings;
            plan.points[i].parameters = recorded[i]->point.parameters;
        }
}

store::CampaignPlan read_plan(const std::filesystem::path& store) {
    store::StoreStatus status = store::read_status(store);
    restore_settings(status.plan, status.runs);
    return std::move(status.plan);
}

std::vector<std::string> check_compatible(const store::CampaignPlan& stored,
                                          const store::CampaignPlan& sweep) {
    std::vector<std::string> notes;
    if (stored.points.empty()) return notes;
    const std::string advice =
        "\n  Results of different physics must not be mixed in one store: run this sweep with "
        "another --store path (adding points or realizations to a sweep is fine).";
    if (stored.seed != sweep.seed)
        throw core::ConfigError("the sweep file's campaign seed " + std::to_string(sweep.seed) +
                                " differs from the store's " + std::to_string(stored.seed) +
                                ": every realization would change." + advice);
    // Differences per point, grouped so that one changed base value reads as one line.
    std::map<std::string, std::vector<std::string>> by_diff;  // diff text -> points
    int changed = 0;
    int new_points = 0;
    long long more_realizations = 0;
    std::map<std::string_view, const store::PointPlan*> by_label;  // not find(): 10^5 points
    for (const auto& s : stored.points)
        by_label.emplace(s.label, &s);
    for (const auto& p : sweep.points) {
        const auto found = by_label.find(p.label);
        const store::PointPlan* s = found == by_label.end() ? nullptr : found->second;
        if (!s) {
            ++new_points;
            more_realizations += p.max_realizations();
            continue;
        }
        if (p.scene != s->scene) {
            ++changed;
            by_diff[physics_diff(p, *s)].push_back(p.label);
            continue;
        }
        const std::size_t n = std::min(p.seeds.size(), s->seeds.size());
        for (std::size_t r = 0; r < n; ++r)
            if (p.seeds[r] != s->seeds[r])
                throw core::ConfigError(
                    "point '" + p.label + "' realization " + std::to_string(r) + " has seed " +
                    std::to_string(p.seeds[r]) + " here but " + std::to_string(s->seeds[r]) +
                    " in the store (the seed derivation changed between versions?)" + advice);
        // Counted to the limits: a target campaign lists only the seeds of its rounds so far.
        if (p.max_realizations() > s->max_realizations())
            more_realizations += p.max_realizations() - s->max_realizations();
    }
    if (changed > 0) {
        std::string msg = "the sweep file's physics differs from the store's for " +
                          std::to_string(changed) + " point(s) already in the store:";
        int shown = 0;
        for (const auto& [diff, labels] : by_diff) {
            if (++shown > 5) {
                msg += "\n  ...";
                break;
            }
            msg += "\n  point '" + labels.front() + "'" +
                   (labels.size() > 1 ? " and " + std::to_string(labels.size() - 1) + " more"
                                      : std::string()) +
                   ":" + diff;
        }
        throw core::ConfigError(msg + advice);
    }
    if (new_points > 0 || more_realizations > 0)
        notes.push_back("the sweep extends the campaign: " + std::to_string(new_points) +
                        " new point(s), " + std::to_string(more_realizations) +
                        " new realization(s)");
    return notes;
}

// Calibration of the cost model (docs/performance.md, "The cost model", where each constant's
// measurement is listed).
namespace cost_model {
// Settling: simulated seconds per metre of settled packing, beyond protocol.settle_hold_s.
constexpr double settle_s_per_m = 2.0;
// 2-D Beverloo, W = C (phi / a) sqrt(g) (D - k d)^(3/2) f(theta) particles/s: D the outlet's
// free gap, d the number-mean diameter, a the mean disk area, phi the packing fraction.
constexpr double beverloo_C = 1.1;
constexpr double beverloo_k = 1.5;
constexpr double packing_fraction = 0.82;
// Steeper walls flow faster (theta to the horizontal): f = (sin theta / sin 45)^0.35 above 45
// degrees, 1 below (the flow then makes its own funnel in stagnant material).
constexpr double wall_angle_exponent = 0.35;
// Jams per second of flow: lambda = A exp(-B (D - k d) / d).
constexpr double jam_rate_A = 80.0;
constexpr double jam_rate_B = 2.4;
constexpr double shakes_per_jam = 1.15;
// Small systems run faster per particle-step (they stay in cache): the prior speed scales as
// (N / 8750)^0.1 from the full-size 35 ns.
constexpr double speed_exponent = 0.1;
constexpr double speed_particles = 8750;
}  // namespace cost_model

CostEstimate estimate_cost(const engine::SceneParams& p) {
    using namespace cost_model;
    const auto c = engine::derive_constants(p);
    const auto& s = p.particles;
    const double N = s.count;
    CostEstimate e;
    e.fill_height = config::settled_fill_height(p);
    e.settle_time = p.protocol.settle_hold + settle_s_per_m * e.fill_height;
    const double d = s.small_fraction * s.d_small + (1 - s.small_fraction) * s.d_large;
    const double area =
        std::numbers::pi / 4 *
        (s.small_fraction * s.d_small * s.d_small + (1 - s.small_fraction) * s.d_large * s.d_large);
    // The free width (D - k d), kept above a quarter disk so that a jamming outlet has a rate.
    const double free_width =
        std::max(engine::outlet_free_gap(p.hopper) - beverloo_k * d, 0.25 * d);
    const double theta = p.hopper.theta;
    const double f_theta =
        theta > std::numbers::pi / 4
            ? std::pow(std::sin(theta) / std::sin(std::numbers::pi / 4), wall_angle_exponent)
            : 1.0;
    e.flow_rate = beverloo_C * packing_fraction / area * std::sqrt(p.gravity) *
                  std::pow(free_width, 1.5) * f_theta;
    const double jam_rate = jam_rate_A * std::exp(-jam_rate_B * free_width / d);
    const auto& pr = p.protocol;
    // What is mobile on average: the published protocol empties the hopper at a steady rate
    // (N/2 on average over the emptying; a discharge cut by max_time keeps the rest); the
    // steady state puts every particle back (N throughout).
    double mobile = N;
    if (pr.mode == engine::ProtocolMode::steady_state) {
        // Until jams_per_realization jams (each after 1 / jam_rate of flow), or max_time.
        const double per_jam = 1 / jam_rate + c.t_check;
        const double until =
            pr.jams_per_realization > 0 ? pr.jams_per_realization * per_jam : pr.max_time;
        e.discharge_time = std::min(pr.max_time, until);
        e.jams = e.discharge_time / per_jam;
        e.jammed_time = e.jams * c.t_check;
    } else {
        const double flow_time = N / e.flow_rate;
        e.jams = flow_time * jam_rate;
        e.jammed_time = e.jams * c.t_check;
        const double to_empty = flow_time + e.jammed_time;
        e.discharge_time = std::min(pr.max_time, to_empty);
        const double share = e.discharge_time / to_empty;  // of the emptying that happens
        e.jams *= share;
        e.jammed_time *= share;
        mobile = N * (1 - share / 2);
    }
    e.shake_time = e.jams * shakes_per_jam * pr.shake_period;
    e.particle_steps = (N * e.settle_time + mobile * (e.discharge_time + e.shake_time)) / c.dt;
    e.seconds = e.particle_steps * prior_seconds_per_particle_step *
                std::pow(N / speed_particles, speed_exponent);
    return e;
}

double expected_cost(const engine::SceneParams& p) {
    return estimate_cost(p).particle_steps;
}

}  // namespace hopper::campaign
