// Stress suite, short version (issue 6, item 3; ctest label `stress`): extreme but legal
// parameters on a small hopper. Every case must either run to a sane result or fail cleanly
// with a message; never crash, hang or report a non-finite number. Set HOPPER_STRESS_LONG=1 for
// the long version (more seeds, more particles).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "hopper/core/error.hpp"
#include "hopper/engine/realization.hpp"

using namespace hopper::engine;

namespace {

bool long_version() {
    return std::getenv("HOPPER_STRESS_LONG") != nullptr;
}

SceneParams small_hopper() {
    SceneParams p;
    p.hopper.width = 10.0 * cm;
    p.hopper.outlet = 3.0 * cm;
    p.hopper.theta = 45.0 * deg;
    p.particles.count = long_version() ? 600 : 120;
    p.material.collision_time = 8.0e-4;
    // The published integrator setting, pinned: these tests are about the protocol and need
    // speed, not the accuracy of the default (verlet, delta = 200; README, "Accuracy").
    p.integrator.scheme = Scheme::gear4;
    p.integrator.steps_per_collision = 50.0;
    p.protocol.max_time = 3.0;  // bounded: a stuck case ends as time_limit
    p.protocol.settle_max_time = 5.0;
    p.protocol.max_shakes = 3;
    return p;
}

struct Case {
    std::string name;
    std::function<void(SceneParams&)> change;
};

void expect_finite(double v, const std::string& what) {
    EXPECT_TRUE(std::isfinite(v)) << what << " = " << v;
}

// Every number a result reports is finite; a failed run explains itself.
void expect_sane(const RealizationResult& r, const std::string& name) {
    SCOPED_TRACE(name + ": status " + to_string(r.status) + ", " + r.message);
    EXPECT_FALSE(r.message.empty());
    for (double t : r.survival_times)
        expect_finite(t, "survival time");
    for (double t : r.jam_onsets)
        expect_finite(t, "jam onset");
    for (double t : r.exit_times)
        expect_finite(t, "exit time");
    for (double t : r.curve_time)
        expect_finite(t, "curve time");
    if (r.empty_time) expect_finite(*r.empty_time, "empty time");
    if (r.discharge_rate) expect_finite(*r.discharge_rate, "discharge rate");
    expect_finite(r.discharge_rate_mass, "mass rate");
    expect_finite(r.diagnostics.max_overlap_ratio, "max overlap");
    expect_finite(r.diagnostics.settled_kinetic_energy, "settled kinetic energy");
    if (r.fields) {
        const auto& f = *r.fields;
        for (int k = 0; k < field_count; ++k)
            for (int c = 0; c < f.grid.size(); ++c) {
                expect_finite(f.mean[k][c], "field mean");
                expect_finite(f.m2[k][c], "field M2");
                EXPECT_GE(f.m2[k][c], 0.0);
            }
    }
    EXPECT_EQ(r.survival_times.size(), r.censored.size());
    EXPECT_LE(r.discharged, r.particles);
    if (r.status == Status::failed) {
        // A clean failure names a cause (what happened) and a remedy (what to change).
        const bool cause = r.message.find("overlap") != std::string::npos ||
                           r.message.find("non-finite") != std::string::npos ||
                           r.message.find("kinetic energy") != std::string::npos ||
                           r.message.find("did not come to rest") != std::string::npos;
        EXPECT_TRUE(cause) << r.message;
    } else {
        // A run that did not fail kept its overlaps within the guard.
        EXPECT_LE(r.diagnostics.max_overlap_ratio, 0.25 + 1e-12);
    }
}

class Stress : public ::testing::TestWithParam<Scheme> {};

TEST_P(Stress, ExtremeButLegalParametersEndSaneOrFailCleanly) {
    const std::vector<Case> cases = {
        {"e_n = 0.01", [](SceneParams& p) { p.material.system.e_n = p.material.wall.e_n = 0.01; }},
        {"e_n = 1", [](SceneParams& p) { p.material.system.e_n = p.material.wall.e_n = 1.0; }},
        {"mu = 0", [](SceneParams& p) { p.material.system.mu = p.material.wall.mu = 0.0; }},
        {"mu = 2", [](SceneParams& p) { p.material.system.mu = p.material.wall.mu = 2.0; }},
        {"k_t = 0", [](SceneParams& p) { p.material.kt_over_kn = 0.0; }},
        {"k_t = k_n", [](SceneParams& p) { p.material.kt_over_kn = 1.0; }},
        // k_n a hundred times stiffer at the same dt: tau_c / 10 with delta / 10.
        {"k_n x100 at the same dt",
         [](SceneParams& p) {
             p.material.collision_time = 8.0e-5;
             p.integrator.steps_per_collision = 5.0;
         }},
        {"theta = 0 (flat bottom, dead zone)", [](SceneParams& p) { p.hopper.theta = 0.0; }},
        {"theta = 90 (slot)", [](SceneParams& p) { p.hopper.theta = 90.0 * deg; }},
        {"D below one diameter", [](SceneParams& p) { p.hopper.outlet = 0.5 * cm; }},
        {"D nearly the hopper width", [](SceneParams& p) { p.hopper.outlet = 9.5 * cm; }},
        {"very few particles", [](SceneParams& p) { p.particles.count = 3; }},
        {"monodisperse", [](SceneParams& p) { p.particles.small_fraction = 1.0; }},
        {"fields on, Gaussian, every step",
         [](SceneParams& p) {
             p.fields.enabled = true;
             p.fields.kernel = FieldKernel::gaussian;
             p.fields.sample_interval = 0.0;
         }},
        {"delta = 2 (far too coarse)",
         [](SceneParams& p) { p.integrator.steps_per_collision = 2.0; }},
    };
    const int seeds = long_version() ? 3 : 1;
    for (const auto& c : cases) {
        for (int seed = 1; seed <= seeds; ++seed) {
            SceneParams p = small_hopper();
            p.integrator.scheme = GetParam();
            c.change(p);
            try {
                const RealizationResult r = run_realization(p, seed);
                std::printf("[ outcome  ] %-6s %-36s %-10s jams %-3d %s\n",
                            to_string(GetParam()).c_str(), c.name.c_str(),
                            to_string(r.status).c_str(), r.n_jams, r.message.substr(0, 90).c_str());
                expect_sane(r, c.name);
            } catch (const hopper::core::ConfigError& e) {
                std::printf("[ outcome  ] %-6s %-36s rejected   %s\n",
                            to_string(GetParam()).c_str(), c.name.c_str(),
                            std::string(e.what()).substr(0, 90).c_str());
                // Rejected up front with a message: also a clean outcome (e.g. a slot narrower
                // than a particle cannot be filled).
                EXPECT_NE(std::string(e.what()).size(), 0u) << c.name;
            }
        }
    }
}

// Many particles: the published scene (8750 disks, W = 43 cm) in the long version, 1500 disks in
// a 25 cm hopper in the short one; both must run without failing. A tall narrow column (8750
// disks in 25 cm, about 290 rows) loads the bottom contacts beyond the overlap guard with the
// published stiffness: it must end sane or fail cleanly, naming both remedies.
TEST_P(Stress, ManyParticlesRunAndStaySane) {
    SceneParams p = small_hopper();
    p.integrator.scheme = GetParam();
    p.hopper.width = long_version() ? 43.0 * cm : 25.0 * cm;
    p.particles.count = long_version() ? 8750 : 1500;
    p.protocol.max_time = long_version() ? 30.0 : 0.5;
    const RealizationResult r = run_realization(p, 1);
    std::printf("[ outcome  ] %-6s %-36s %-10s jams %-3d %s\n", to_string(GetParam()).c_str(),
                "many particles", to_string(r.status).c_str(), r.n_jams,
                r.message.substr(0, 90).c_str());
    expect_sane(r, "many particles");
    EXPECT_NE(r.status, Status::failed) << r.message;
    if (!long_version()) return;
    p.hopper.width = 25.0 * cm;
    const RealizationResult tall = run_realization(p, 1);
    std::printf("[ outcome  ] %-6s %-36s %-10s jams %-3d %s\n", to_string(GetParam()).c_str(),
                "tall narrow column (8750 in 25 cm)", to_string(tall.status).c_str(), tall.n_jams,
                tall.message.substr(0, 160).c_str());
    expect_sane(tall, "tall narrow column");
    if (tall.status == Status::failed) {
        EXPECT_NE(tall.message.find("steps_per_collision"), std::string::npos);
        EXPECT_NE(tall.message.find("collision_time_s"), std::string::npos);
    }
}

INSTANTIATE_TEST_SUITE_P(Schemes, Stress, ::testing::Values(Scheme::verlet, Scheme::gear4),
                         [](const auto& param_info) { return to_string(param_info.param); });

}  // namespace
