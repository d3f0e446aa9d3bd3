// Issue 13 inside small realizations: avalanche sizes, the arch at each jam, and the
// steady-state protocol. Each run takes about a second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "hopper/core/error.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/scene.hpp"

using namespace hopper::engine;

namespace {

// The 12 cm, 300-particle hopper of test_realization at an outlet that jams often.
SceneParams tiny(double D_cm) {
    SceneParams p;
    p.hopper.width = 12.0 * cm;
    p.particles.count = 300;
    p.hopper.outlet = D_cm * cm;
    p.hopper.theta = 45.0 * deg;
    p.material.collision_time = 8.0e-4;
    p.protocol.max_time = 30.0;
    p.integrator.scheme = Scheme::gear4;
    p.integrator.steps_per_collision = 50.0;
    return p;
}

TEST(Avalanches, SizesPartitionTheDischargeAndArchesSpanTheOutlet) {
    const SceneParams p = tiny(1.8);
    int jams = 0, arches = 0;
    for (std::uint64_t seed : {3u, 4u}) {
        const RealizationResult r = run_realization(p, seed);
        ASSERT_EQ(r.status, Status::complete) << r.message;
        ASSERT_EQ(r.avalanche_sizes.size(), r.survival_times.size());
        ASSERT_EQ(r.arches.size(), r.jam_onsets.size());
        // Every particle crosses the outlet plane in exactly one interval.
        EXPECT_EQ(std::accumulate(r.avalanche_sizes.begin(), r.avalanche_sizes.end(), 0),
                  r.particles);
        jams += r.n_jams;
        for (const Arch& a : r.arches) {
            if (!a.found()) continue;
            ++arches;
            ASSERT_EQ(a.x.size(), a.ids.size());
            // The arch rests on the walls across the outlet: its disks lie above the outlet
            // plane (below it the region is empty at a jam), its span at least the free gap
            // minus a small disk, and no disk far out on the funnel.
            for (std::size_t k = 0; k < a.ids.size(); ++k) {
                EXPECT_GT(a.y[k], -0.5 * p.particles.d_large);
                EXPECT_LT(std::abs(a.x[k]), p.hopper.outlet + 2 * p.particles.d_large);
            }
            EXPECT_GT(a.span, p.hopper.outlet - p.particles.d_small);
            EXPECT_GE(a.ids.size(), 2u);  // D = 1.8 cm is more than two large diameters
            EXPECT_GT(a.max_angle, 0.0);
            EXPECT_LT(a.max_angle, 2 * hopper::core::pi);
        }
    }
    ASSERT_GE(jams, 3) << "the outlet should jam";
    // Nearly every jam has an arch. Not all: the detector calls a jam when the region below
    // the outlet stays empty for t_check, and once here (21 arches in 22 jams) the disks above
    // the outlet were still moving at that moment (one 0.3 mm above the outlet plane touching
    // nothing): no chain of contacts spans the outlet, and the finder rightly says so.
    EXPECT_GE(arches, jams - jams / 5);
    EXPECT_LE(arches, jams);
}

TEST(SteadyState, ReinsertsWhatLeavesAndStopsAfterTheJamsAskedFor) {
    SceneParams p = tiny(1.8);
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.jams_per_realization = 4;
    // Re-inserted particles land on the packing: no particle ever rises more than the
    // insertion band (3.5 large diameters and a radius) above the packing's top at the
    // opening. (Measuring the top anew at each insertion followed the particles still falling
    // from earlier insertions upward, a runaway to metres within 20 s.)
    double top_at_open = -1.0, highest = -1.0;
    RunHooks hooks;
    hooks.snapshot_interval = 0.01;
    hooks.on_snapshot = [&](const Snapshot& s) {
        if (s.phase == Phase::settle) return;
        double top = -1.0;
        for (std::size_t i = 0; i < s.y.size(); ++i)
            top = std::max(top, s.y[i] + s.radius[i]);
        if (top_at_open < 0) top_at_open = top;
        highest = std::max(highest, top);
    };
    const RealizationResult r = run_realization(p, 5, hooks);
    EXPECT_LT(highest, top_at_open + 4.5 * p.particles.d_large);
    ASSERT_EQ(r.status, Status::complete) << r.message;
    EXPECT_EQ(r.n_jams, 4);
    EXPECT_EQ(r.survival_times.size(), 4u);  // the last interval ended with a jam: uncensored
    for (bool c : r.censored)
        EXPECT_FALSE(c);
    EXPECT_FALSE(r.empty_time);
    // The head stays constant: every sample of the discharge curve holds all particles but the
    // few that are falling below the outlet.
    for (int n : r.curve_count)
        EXPECT_GE(n, p.particles.count - 20);
    // Particles that crossed the outlet by the last jam: those removed (and re-inserted) plus
    // the few still falling below the outlet when it was detected.
    const int crossed = std::accumulate(r.avalanche_sizes.begin(), r.avalanche_sizes.end(), 0);
    EXPECT_GE(crossed, r.discharged);
    EXPECT_LE(crossed, r.discharged + 20);
    EXPECT_GT(r.discharged, 0);
}

// Issue 23: a small head, whose top lies in the funnel (20 cm hopper at 45 deg: the funnel
// reaches 8.8 cm up; 60 disks fill about 4 cm of it). Every re-inserted disk must land inside
// the container: none may ever be found outside the walls above the outlet plane (before the
// fix, x was drawn across the whole hopper width and disks fell down the funnel's outside).
TEST(SteadyState, ASmallHeadReinsertsInsideTheFunnel) {
    SceneParams p = tiny(2.4);
    p.hopper.width = 20.0 * cm;  // the funnel reaches 8.8 cm up
    p.particles.count = 60;
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.max_time = 2.0;
    int outside = 0, samples = 0;
    double top_at_open = -1.0;
    RunHooks hooks;
    hooks.snapshot_interval = 0.01;
    hooks.on_snapshot = [&](const Snapshot& s) {
        if (s.phase == Phase::settle) return;
        if (samples++ == 0)
            for (std::size_t i = 0; i < s.x.size(); ++i)
                top_at_open = std::max(top_at_open, s.y[i] + s.radius[i]);
        for (std::size_t i = 0; i < s.x.size(); ++i) {
            if (s.y[i] <= 0.0) continue;
            if (std::abs(s.x[i]) > inner_half_width(p.hopper, s.y[i]) + 1e-9) ++outside;
        }
    };
    const RealizationResult r = run_realization(p, 2, hooks);
    ASSERT_NE(r.status, Status::failed) << r.message;
    ASSERT_GT(r.discharged, 60) << "too few re-insertions to test anything";
    ASSERT_GT(samples, 10);
    EXPECT_LT(top_at_open, 0.06) << "the head is meant to lie well inside the funnel";
    EXPECT_EQ(outside, 0);
}

TEST(SteadyState, IsDeterministicAndDiffersFromThePublishedProtocolOnlyAfterTheFirstExit) {
    SceneParams p = tiny(1.8);
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.jams_per_realization = 2;
    const RealizationResult a = run_realization(p, 9), b = run_realization(p, 9);
    EXPECT_EQ(a.survival_times, b.survival_times);
    EXPECT_EQ(a.exit_times, b.exit_times);
    EXPECT_EQ(a.avalanche_sizes, b.avalanche_sizes);
    // The same fill and settling as the published protocol (the generator's first draws are
    // the fill's): the first exit happens at the same moment.
    const RealizationResult pub = run_realization(tiny(1.8), 9);
    ASSERT_FALSE(pub.exit_times.empty());
    EXPECT_EQ(a.exit_times.front(), pub.exit_times.front());
    EXPECT_EQ(a.diagnostics.settle_steps, pub.diagnostics.settle_steps);
}

TEST(SteadyState, ValidationNamesTheSetting) {
    SceneParams p = tiny(1.8);
    p.protocol.jams_per_realization = 3;  // with the published protocol
    try {
        validate_scene(p);
        FAIL() << "accepted jams_per_realization with the published protocol";
    } catch (const hopper::core::ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("protocol.mode = steady_state"), std::string::npos);
    }
}

}  // namespace

// Issue 26: the unjamming protocols, on a flat-bottomed silo of monodisperse disks (theta = 0,
// 12 cm wide, 300 disks of d_large, mu = 0.5), outlet 2.4 d.
namespace {

SceneParams tiny_silo() {
    SceneParams p = tiny(1.9);
    p.hopper.theta = 0.0;
    p.particles.small_fraction = 0.0;
    p.material.system.mu = p.material.wall.mu = 0.5;
    return p;
}

TEST(Unjam, RemovingTheArchClearsEveryJamWithoutShaking) {
    SceneParams p = tiny_silo();
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.unjam = UnjamMode::remove_arch;
    p.protocol.jams_per_realization = 6;
    int shaking = 0;
    RunHooks hooks;
    hooks.snapshot_interval = 0.005;
    hooks.on_snapshot = [&](const Snapshot& s) { shaking += s.phase == Phase::shake; };
    const RealizationResult r = run_realization(p, 4, hooks);
    ASSERT_EQ(r.status, Status::complete) << r.message;
    ASSERT_EQ(r.n_jams, 6);
    EXPECT_EQ(shaking, 0);
    EXPECT_DOUBLE_EQ(r.diagnostics.shake_time, 0.0);
    // Each jam but the last (which ends the realization) needed at least one removal.
    ASSERT_EQ(r.shakes_per_jam.size(), 6u);
    for (std::size_t k = 0; k + 1 < r.shakes_per_jam.size(); ++k)
        EXPECT_GE(r.shakes_per_jam[k], 1) << "jam " << k;
    EXPECT_EQ(r.shakes_per_jam.back(), 0);
    // The arch's disks go back in at the top: the count stays (but for those falling below the
    // outlet), and they are not exits: the avalanche sizes still add up to the exits.
    for (int n : r.curve_count)
        EXPECT_GE(n, p.particles.count - 20);
    const int crossed = std::accumulate(r.avalanche_sizes.begin(), r.avalanche_sizes.end(), 0);
    EXPECT_GE(crossed, r.discharged);
    EXPECT_LE(crossed, r.discharged + 20);
    int arch_disks = 0;
    for (const Arch& a : r.arches)
        arch_disks += int(a.ids.size());
    EXPECT_GT(arch_disks, 0);
}

TEST(Unjam, RefillEndsTheRealizationAtItsFirstJam) {
    SceneParams p = tiny_silo();
    p.protocol.unjam = UnjamMode::refill;
    const RealizationResult r = run_realization(p, 4);
    ASSERT_EQ(r.status, Status::complete) << r.message;
    EXPECT_EQ(r.n_jams, 1);
    EXPECT_EQ(r.n_shakes, 0);
    ASSERT_EQ(r.survival_times.size(), 1u);
    EXPECT_FALSE(r.censored[0]);
    ASSERT_EQ(r.avalanche_sizes.size(), 1u);
    EXPECT_GT(r.avalanche_sizes[0], 0);
    EXPECT_NE(r.message.find("refill"), std::string::npos) << r.message;
    // The same fill and flow as the shaking protocol up to that jam.
    const RealizationResult shaken = run_realization(tiny_silo(), 4);
    ASSERT_GE(shaken.n_jams, 1);
    EXPECT_EQ(shaken.jam_onsets[0], r.jam_onsets[0]);
    EXPECT_EQ(shaken.avalanche_sizes[0], r.avalanche_sizes[0]);
}

}  // namespace
