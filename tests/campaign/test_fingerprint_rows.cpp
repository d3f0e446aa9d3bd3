// The physics fingerprint generated from the scene schema (issue 28).
// 1. Every row of the schema (src/config/key_table.cpp) reaches the text: each row is applied
//    with a value other than its default, in a scene where the setting matters, and the text
//    (campaign::scene_text, the fingerprint a store compares on resume) must change. A row added
//    with a fingerprint line that never enters fails here.
// 2. The generated text is byte for byte the text of the hand-written list it replaced (kept
//    below, frozen, as the oracle: stores written since the first round hold its texts), for
//    every single-row change, thousands of random combinations, and every point of the sweep
//    files in campaigns/ and tests/ (the golden files' included).
// 3. The stores of the tests' fixtures resume: their stored texts come out of the scenes rebuilt
//    from their typed parameters (or, older than those, from their recorded sweep texts).
#include <gtest/gtest.h>

#include <unistd.h>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "config/key_table.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/config/scene_schema.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {
namespace {

using config::detail::KeyDef;
using config::detail::Kind;
using config::detail::Value;

// ---------------------------------------------------------------------------------------------
// The oracle: campaign::scene_text as it was written by hand until issue 28 (commit 5cef94a),
// frozen. Never edit it: a new row's line is the schema's business, and a scene that uses none
// of the new rows must keep this text.
std::string number(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

class Lines {
  public:
    void add(const char* name, double v) { text_ += std::string(name) + "=" + number(v) + "\n"; }
    void add(const char* name, int v) {
        text_ += std::string(name) + "=" + std::to_string(v) + "\n";
    }
    void add(const char* name, const std::string& v) {
        text_ += std::string(name) + "=" + v + "\n";
    }
    void add(const char* name, const std::optional<double>& v) {
        if (v)
            add(name, *v);
        else
            add(name, std::string("unset"));
    }
    std::string take() { return std::move(text_); }

  private:
    std::string text_;
};

std::string frozen_scene_text(const engine::SceneParams& p) {
    // Keep in step with engine::SceneParams (every field that changes the physics). The text is
    // a fingerprint only: it is hashed and compared, never parsed back into values (the typed
    // `parameters` of the plan are for that).
    Lines l;
    l.add("hopper.width_m", p.hopper.width);
    l.add("hopper.outlet_m", p.hopper.outlet);
    l.add("hopper.theta_rad", p.hopper.theta);
    l.add("hopper.wall_diameter_m", p.hopper.wall_diameter);
    l.add("hopper.wall_spacing", p.hopper.wall_spacing);
    l.add("particles.count", p.particles.count);
    l.add("particles.small_fraction", p.particles.small_fraction);
    l.add("particles.d_small_m", p.particles.d_small);
    l.add("particles.d_large_m", p.particles.d_large);
    l.add("particles.thickness_m", p.particles.thickness);
    l.add("particles.density_kg_m3", p.particles.density);
    l.add("material.e_n", p.material.system.e_n);
    l.add("material.mu", p.material.system.mu);
    l.add("walls.e_n", p.material.wall.e_n);
    l.add("walls.mu", p.material.wall.mu);
    l.add("material.kt_over_kn", p.material.kt_over_kn);
    l.add("material.youngs_modulus_pa", p.material.youngs_modulus);
    l.add("material.poisson_ratio", p.material.poisson_ratio);
    l.add("material.collision_time_s", p.material.collision_time);
    l.add("integrator.scheme", engine::to_string(p.integrator.scheme));
    l.add("integrator.steps_per_collision", p.integrator.steps_per_collision);
    l.add("integrator.skin", p.integrator.skin);
    const auto& q = p.protocol;
    l.add("protocol.fill_gap", q.fill_gap);
    l.add("protocol.fill_speed_m_s", q.fill_speed);
    l.add("protocol.settle_ke", q.settle_ke);
    l.add("protocol.settle_hold_s", q.settle_hold);
    l.add("protocol.settle_max_time_s", q.settle_max_time);
    l.add("protocol.jam_region_height", q.jam_region_height);
    l.add("protocol.t_check_s", q.t_check);
    l.add("protocol.detector_interval_s", q.detector_interval);
    l.add("protocol.shake_amplitude", q.shake_amplitude);
    l.add("protocol.shake_period_s", q.shake_period);
    l.add("protocol.shake_direction_rad", q.shake_direction);
    l.add("protocol.max_shakes", q.max_shakes);
    l.add("protocol.max_time_s", q.max_time);
    l.add("protocol.exit_depth", q.exit_depth);
    l.add("protocol.empty_threshold", q.empty_threshold);
    l.add("protocol.sample_interval_s", q.sample_interval);
    l.add("protocol.max_overlap", q.max_overlap);
    l.add("gravity_m_s2", p.gravity);
    // Modelling choices added later (issue 11): listed only when they differ from the default,
    // so that a point's text (and its physics check) is unchanged for stores written before.
    const engine::SceneParams d;
    const auto& h = p.hopper;
    const auto& m = p.material;
    if (h.outlet_measure != d.hopper.outlet_measure)
        l.add("hopper.outlet_measure", engine::to_string(h.outlet_measure));
    if (h.edge_diameter) l.add("hopper.edge_diameter_m", *h.edge_diameter);
    if (h.edge_offset != d.hopper.edge_offset) l.add("hopper.edge_offset", h.edge_offset);
    if (m.gamma_t_over_gamma_n != d.material.gamma_t_over_gamma_n)
        l.add("material.gamma_t_over_gamma_n", m.gamma_t_over_gamma_n);
    if (m.slip_rule != d.material.slip_rule)
        l.add("material.slip_rule", engine::to_string(m.slip_rule));
    if (m.lever_arm != d.material.lever_arm)
        l.add("material.lever_arm", engine::to_string(m.lever_arm));
    // Issue 28: the normal law, listed only when it is not the linear one.
    if (m.normal_law != d.material.normal_law)
        l.add("material.normal_law", engine::to_string(m.normal_law));
    if (m.mu_r != d.material.mu_r) l.add("material.mu_r", m.mu_r);
    if (m.normal_damping != d.material.normal_damping)
        l.add("material.normal_damping", engine::to_string(m.normal_damping));
    if (q.fill_base != d.protocol.fill_base) l.add("protocol.fill_base", q.fill_base);
    // Issue 12: listed only when on (stores written before it have it off).
    if (p.integrator.contact_corrections)
        l.add("integrator.contact_corrections", std::string("true"));
    // Steady state (issue 13): listed only when not the published protocol.
    if (q.mode != d.protocol.mode) l.add("protocol.mode", engine::to_string(q.mode));
    if (q.jams_per_realization != d.protocol.jams_per_realization)
        l.add("protocol.jams_per_realization", q.jams_per_realization);
    // The unjamming protocol (issue 26): listed only when it is not the shake.
    if (q.unjam != d.protocol.unjam) l.add("protocol.unjam", engine::to_string(q.unjam));
    // Growing shakes (issue 23): listed only when the shakes grow.
    if (q.shake_growth != d.protocol.shake_growth) {
        l.add("protocol.shake_growth", q.shake_growth);
        l.add("protocol.shake_amplitude_max", q.shake_amplitude_max);
    }
    // Fields: listed only when on, so stores written before fields existed stay compatible.
    const auto& f = p.fields;
    if (f.enabled) {
        l.add("fields.window_s", f.window);
        l.add("fields.cell_dlarge", f.cell);
        l.add("fields.sample_interval_s", f.sample_interval);
        l.add("fields.start_s", f.start);
        l.add("fields.end_s", f.end);
        l.add("fields.kernel", engine::to_string(f.kernel));
        if (f.kernel == engine::FieldKernel::gaussian)
            l.add("fields.kernel_width_dlarge", f.kernel_width);
    }
    // The steady state keeps the springs at a re-insertion (round 3's fix): said in its text,
    // so that stores written before the fix are refused.
    if (q.mode != d.protocol.mode) l.add("protocol.reinsertion", std::string("keeps_springs"));
    // Polydispersity (issue 39): only off its default.
    if (p.particles.size_spread != d.particles.size_spread)
        l.add("particles.size_spread", p.particles.size_spread);
    // Plate friction (issue 39): only off its defaults.
    if (p.material.plate_friction != d.material.plate_friction)
        l.add("material.plate_friction", p.material.plate_friction);
    if (p.material.plate_speed != d.material.plate_speed)
        l.add("material.plate_speed_m_s", p.material.plate_speed);
    // The tangential law named (issue 42): only off its default, automatic.
    if (p.material.tangential_law != d.material.tangential_law)
        l.add("material.tangential_law", engine::to_string(p.material.tangential_law));
    // The rolling law (issue 39): only off its default, the constant torque.
    if (p.material.rolling_law != d.material.rolling_law)
        l.add("material.rolling_law", engine::to_string(p.material.rolling_law));
    // The jam detector's speed floor (issue 39): only off its default.
    if (q.jam_min_speed != d.protocol.jam_min_speed)
        l.add("protocol.jam_min_speed", q.jam_min_speed);
    // The lid (issue 40): only with a lid, and then with its depth.
    if (q.lid_gravity != d.protocol.lid_gravity) {
        l.add("protocol.lid_gravity", q.lid_gravity);
        l.add("protocol.lid_depth", q.lid_depth);
    }
    // The settle's own time step (issue 41): only off its default, 0 (the settle at dt).
    if (p.integrator.settle_steps_per_collision != d.integrator.settle_steps_per_collision)
        l.add("integrator.settle_steps_per_collision", p.integrator.settle_steps_per_collision);
    return l.take();
}

// A valid scene with D and theta given (their keys have no default of their own).
engine::SceneParams base_scene() {
    engine::SceneParams p;
    p.hopper.width = 0.43;
    p.hopper.outlet = 0.045;
    p.hopper.theta = 1.0;
    return p;
}

// Settings that only act together with another one: the context in which a row is changed.
// (At its default the other setting makes this one irrelevant, so the text rightly leaves it out.)
void context(const std::string& name, engine::SceneParams& p) {
    if (name == "protocol.shake_amplitude_max") p.protocol.shake_growth = 1.5;
    if (name == "protocol.jams_per_realization")
        p.protocol.mode = engine::ProtocolMode::steady_state;
    if (name.rfind("fields.", 0) == 0 && name != "fields.enabled") p.fields.enabled = true;
    if (name == "fields.kernel_width_dlarge") p.fields.kernel = engine::FieldKernel::gaussian;
    if (name == "material.rolling_law") p.material.mu_r = 0.05;
    if (name == "protocol.lid_gravity" || name == "protocol.lid_depth") {
        p.protocol.mode = engine::ProtocolMode::steady_state;
        if (name == "protocol.lid_depth") p.protocol.lid_gravity = 10.0;
    }
}

// Values to try for a row, other than the current one: within the row's range first.
std::vector<Value> candidates(const KeyDef& d, const engine::SceneParams& p) {
    std::vector<Value> out;
    const auto now = d.read(p);
    switch (d.kind) {
        case Kind::boolean:
            out.push_back(
                std::string(now && std::get<std::string>(*now) == "true" ? "false" : "true"));
            break;
        case Kind::choice: {
            std::stringstream ss{std::string(d.choices)};
            for (std::string c; std::getline(ss, c, ',');)
                if (!now || std::get<std::string>(*now) != c) out.push_back(c);
            break;
        }
        case Kind::integer:
        case Kind::real: {
            const double x = now ? std::get<double>(*now) : 0.0;
            const double span = std::isfinite(d.hi - d.lo) ? d.hi - d.lo : 1.0;
            for (double v : {x * 1.1, x * 0.9, x + 1.0, x - 1.0, x * 1.5, x * 0.5, x * 2.0,
                             d.lo + 0.5 * span, d.lo + 0.01 * span, d.hi, x + 0.01, 1.0, 0.5}) {
                if (d.kind == Kind::integer) v = std::round(v);
                const bool above = d.open_lo ? v > d.lo : v >= d.lo;
                const bool below = d.open_hi ? v < d.hi : v <= d.hi;
                if (above && below && (!now || v != x)) out.emplace_back(std::in_place_index<0>, v);
            }
            break;
        }
    }
    return out;
}

TEST(FingerprintRows, EverySchemaRowReachesThePhysicsText) {
    std::vector<std::string> missing, untested;
    int tested = 0;
    for (const KeyDef& d : config::scene_schema()) {
        const std::string name(d.name);
        // A row with one value that no file sets (protocol.reinsertion) cannot change; its line
        // is checked by the frozen texts below.
        if (!d.in_sweep_file && d.kind == Kind::choice &&
            std::string_view(d.choices).find(',') == std::string_view::npos)
            continue;
        engine::SceneParams base = base_scene();
        context(name, base);
        ASSERT_NO_THROW(engine::validate_scene(base)) << name;
        const std::string before = scene_text(base);
        bool applied = false;
        for (const Value& v : candidates(d, base)) {
            engine::SceneParams q = base;
            d.apply(q, v);
            try {
                engine::validate_scene(q);
            } catch (const core::ConfigError&) {
                continue;  // another value may be valid here
            }
            applied = true;
            if (scene_text(q) == before) missing.push_back(name);
            break;
        }
        if (applied)
            ++tested;
        else
            untested.push_back(name);
    }
    std::string m, u;
    for (const auto& s : missing)
        m += " " + s;
    for (const auto& s : untested)
        u += " " + s;
    EXPECT_TRUE(missing.empty()) << "settings that change the scene but not its physics text:" << m;
    EXPECT_TRUE(untested.empty()) << "rows no candidate value could change validly:" << u;
    // The table has every row the physics needs: far more than a handful.
    EXPECT_GT(tested, 50);
}

// Scenes of single-row changes (every candidate value of every row, with and without the
// context in which it matters) and of random combinations of them.
std::vector<engine::SceneParams> many_scenes() {
    std::vector<engine::SceneParams> out;
    const auto& rows = config::scene_schema();
    for (const KeyDef& d : rows) {
        for (bool with_context : {false, true}) {
            engine::SceneParams base = base_scene();
            if (with_context) context(std::string(d.name), base);
            out.push_back(base);
            for (const Value& v : candidates(d, base)) {
                engine::SceneParams q = base;
                d.apply(q, v);
                out.push_back(q);
            }
        }
    }
    std::mt19937_64 rng(28);
    for (int n = 0; n < 4000; ++n) {
        engine::SceneParams q = base_scene();
        const int changes = 1 + static_cast<int>(rng() % 12);
        for (int c = 0; c < changes; ++c) {
            const KeyDef& d = rows[rng() % rows.size()];
            if (rng() % 2) context(std::string(d.name), q);
            const auto values = candidates(d, q);
            if (!values.empty()) d.apply(q, values[rng() % values.size()]);
        }
        out.push_back(q);
    }
    return out;
}

TEST(FingerprintRows, GeneratedTextIsTheFrozenTextForManyScenes) {
    int compared = 0, differing = 0;
    std::string first;
    for (const auto& q : many_scenes()) {
        ++compared;
        const std::string generated = scene_text(q), frozen = frozen_scene_text(q);
        if (generated != frozen && differing++ == 0)
            first = "generated:\n" + generated + "frozen:\n" + frozen;
    }
    EXPECT_EQ(differing, 0) << "of " << compared << " scenes; the first:\n" << first;
    EXPECT_GT(compared, 4000);
}

// Every sweep file of the repository (campaigns/, tests/: the golden files, the fixtures):
// every point's generated text is the frozen one.
TEST(FingerprintRows, GeneratedTextIsTheFrozenTextForEverySweepFileOfTheRepository) {
    namespace fs = std::filesystem;
    const fs::path src = HOPPER_SOURCE_DIR;
    int files = 0, points = 0;
    for (const char* dir : {"campaigns", "tests"}) {
        for (const auto& e : fs::recursive_directory_iterator(src / dir)) {
            if (e.path().extension() != ".toml") continue;
            config::SweepFile sweep;
            try {
                sweep = config::load_sweep(e.path());
            } catch (const std::exception&) {
                continue;  // the tests' deliberately bad files
            }
            ++files;
            if (!sweep.has_campaign) {
                EXPECT_EQ(scene_text(sweep.base), frozen_scene_text(sweep.base)) << e.path();
                continue;
            }
            for (const auto& pt : sweep.campaign.points) {
                ++points;
                EXPECT_EQ(scene_text(pt.scene), frozen_scene_text(pt.scene))
                    << e.path() << " point " << pt.label;
                // The scene rebuilt from the point's typed parameters has the same text.
                EXPECT_EQ(scene_text(config::scene_from_parameters(pt.parameters)),
                          frozen_scene_text(pt.scene))
                    << e.path() << " point " << pt.label;
            }
        }
    }
    EXPECT_GT(files, 20);
    EXPECT_GT(points, 100);
}

// The store of tests/campaign/data (written by commit ff4dcd8, before typed parameters and
// before issue 13; campaign.old_store resumes it with mini_extended.toml): every stored point's
// text is what this build generates for the sweep that resumes it. Its recorded sweep text
// (mini.toml of that day) no longer explains it (the default of contact_corrections changed
// since), so the legacy path finds nothing, as before issue 28, and says so.
TEST(FingerprintRows, FixtureStoreTextsComeOutOfThisBuild) {
    namespace fs = std::filesystem;
    const fs::path src = HOPPER_SOURCE_DIR;
    const fs::path dir =
        fs::temp_directory_path() / ("hopper_fingerprint_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string cmd = "tar xzf '" +
                            (src / "tests/campaign/data/store_before_issue13.tar.gz").string() +
                            "' -C '" + dir.string() + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const store::StoreStatus st = store::read_status(dir / "old.h5");
    fs::remove_all(dir);
    ASSERT_FALSE(st.plan.points.empty());
    const auto resume = config::load_sweep(src / "tests/campaign/data/mini_extended.toml");
    int matched = 0;
    for (const auto& p : st.plan.points) {
        EXPECT_TRUE(p.parameters.empty()) << "the fixture predates typed parameters";
        for (const auto& q : resume.campaign.points)
            if (q.label == p.label) {
                ++matched;
                EXPECT_EQ(scene_text(q.scene), p.scene) << p.label;
                EXPECT_EQ(frozen_scene_text(q.scene), p.scene) << p.label;
                EXPECT_EQ(scene_text(config::scene_from_parameters(q.parameters)), p.scene);
            }
    }
    EXPECT_EQ(matched, static_cast<int>(st.plan.points.size()));
    const auto scenes = point_scenes(st.plan, st.runs);
    ASSERT_EQ(scenes.size(), st.plan.points.size());
    for (std::size_t i = 0; i < scenes.size(); ++i)
        EXPECT_FALSE(scenes[i].has_value()) << st.plan.points[i].label;
}

// A store's points with typed parameters (as every store since typed settings records them):
// the scene comes from them, without a sweep text; one without them takes the legacy path.
TEST(FingerprintRows, PointScenesFromTypedParametersThenTheLegacyPath) {
    const auto sweep = config::load_sweep(std::filesystem::path(HOPPER_SOURCE_DIR) /
                                          "tests/campaign/data/mini_physics.toml");
    store::CampaignPlan plan = make_plan(sweep.campaign);
    ASSERT_GE(plan.points.size(), 2u);
    store::RunSummary run;
    run.info.sweep_text = sweep.text;
    run.info.sweep_path = "mini_physics.toml";
    plan.points[1].parameters.clear();
    plan.points[1].settings.clear();
    const auto none = point_scenes(plan, {});
    EXPECT_TRUE(none[0].has_value());
    EXPECT_FALSE(none[1].has_value());
    const auto both = point_scenes(plan, {run});
    for (std::size_t i = 0; i < plan.points.size(); ++i) {
        ASSERT_TRUE(both[i].has_value()) << i;
        EXPECT_EQ(scene_text(*both[i]), plan.points[i].scene);
    }
    restore_settings(plan, {run});
    EXPECT_EQ(plan.points[1].parameters, sweep.campaign.points[1].parameters);
}

TEST(FingerprintRows, SchemaRowsDescribeThemselves) {
    // Every row: a sweep name, a unit in SI, a default that reads back; a fingerprint line unless
    // it shows through others (fields.enabled); distinct fingerprint names and positions.
    std::map<std::string, int> names;
    std::map<int, int> positions;
    for (const auto& r : config::scene_schema()) {
        EXPECT_FALSE(r.name.empty());
        EXPECT_FALSE(config::si_unit(r).empty()) << r.name;
        if (r.fingerprint.enters == config::Enters::never) {
            EXPECT_TRUE(r.fingerprint.name.empty()) << r.name;
            continue;
        }
        EXPECT_EQ(++names[std::string(r.fingerprint.name)], 1) << r.fingerprint.name;
        EXPECT_EQ(++positions[r.fingerprint.position], 1) << r.name;
        if (!r.fingerprint.only_with.empty()) {
            EXPECT_NE(config::find_row(r.fingerprint.only_with), nullptr) << r.name;
        }
    }
    EXPECT_EQ(config::find_row("gravity_m_s2")->in_sweep_file, false);
    EXPECT_EQ(config::detail::find_name("gravity_m_s2"), nullptr);  // not a sweep key
    EXPECT_EQ(config::find_row("protocol.reinsertion")->in_sweep_file, false);
    EXPECT_EQ(config::detail::find_name("protocol.reinsertion"), nullptr);  // not a sweep key
    EXPECT_EQ(config::detail::key_table().size() + 2, config::scene_schema().size());
}

TEST(FingerprintRows, SceneFromParametersRefusesWhatNoRowDescribes) {
    EXPECT_THROW(config::scene_from_parameters({{"material.nu", 0.5}}), core::ConfigError);
    EXPECT_THROW(config::scene_from_parameters({{"material.mu", std::string("high")}}),
                 core::ConfigError);
    EXPECT_THROW(config::scene_from_parameters({{"integrator.scheme", std::string("euler")}}),
                 core::ConfigError);
    EXPECT_THROW(config::scene_from_parameters({{"material.e_n", 2.0}}), core::ConfigError);
    EXPECT_THROW(config::scene_from_parameters({{"gravity_m_s2", 1.0}}), core::ConfigError);
    const auto p = config::scene_from_parameters({{"D_cm", 3.1}, {"material.mu", 0.25}});
    EXPECT_EQ(p.hopper.outlet, 3.1 * core::cm);
    EXPECT_EQ(p.material.system.mu, 0.25);
}

}  // namespace
}  // namespace hopper::campaign
