// Every scene parameter a sweep file can set reaches a point's physics text (issue 28): each row
// of the key table (src/config/key_table.cpp) is applied with a value other than its default, in
// a scene where the setting matters, and the text (campaign::scene_text, the fingerprint a store
// compares on resume) must change. A key added to the table and forgotten in the text fails here.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "config/key_table.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/core/error.hpp"

namespace hopper::campaign {
namespace {

using config::detail::KeyDef;
using config::detail::Kind;
using config::detail::Value;

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

TEST(FingerprintRows, EveryKeyTableRowReachesThePhysicsText) {
    std::vector<std::string> missing, untested;
    int tested = 0;
    for (const KeyDef& d : config::detail::key_table()) {
        const std::string name(d.name);
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

}  // namespace
}  // namespace hopper::campaign
