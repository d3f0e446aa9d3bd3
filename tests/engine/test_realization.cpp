// The realization protocol on tiny hoppers (docs/model.md, realization protocol; issue 2's
// required behaviour tests). Each run takes about a second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "hopper/core/error.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper::engine;

namespace {

// A 12 cm wide hopper of 300 particles with the published material and tau_c = 8e-4 s.
SceneParams tiny(double D_cm, double theta_deg = 45.0) {
    SceneParams p;
    p.hopper.width = 12.0 * cm;
    p.particles.count = 300;
    p.hopper.outlet = D_cm * cm;
    p.hopper.theta = theta_deg * deg;
    p.material.collision_time = 8.0e-4;
    p.protocol.max_time = 30.0;
    // The published integrator setting, pinned: these tests are about the protocol and need
    // speed, not the accuracy of the default (verlet, delta = 75, corrected; README,
    // "Accuracy").
    p.integrator.scheme = Scheme::gear4;
    p.integrator.steps_per_collision = 50.0;
    return p;
}

// Invariants every finished realization must satisfy, whatever happened in it.
void expect_consistent(const RealizationResult& r) {
    ASSERT_EQ(r.survival_times.size(), r.censored.size());
    ASSERT_EQ(r.jam_onsets.size(), std::size_t(r.n_jams));
    ASSERT_EQ(r.shakes_per_jam.size(), std::size_t(r.n_jams));
    EXPECT_EQ(std::accumulate(r.shakes_per_jam.begin(), r.shakes_per_jam.end(), 0), r.n_shakes);
    // Only the last interval may be censored; one uncensored interval per jam.
    int uncensored = 0;
    for (std::size_t k = 0; k < r.censored.size(); ++k) {
        if (r.censored[k]) {
            EXPECT_EQ(k + 1, r.censored.size());
        }
        uncensored += !r.censored[k];
        EXPECT_GE(r.survival_times[k], 0.0);
    }
    EXPECT_EQ(uncensored, r.n_jams);
    EXPECT_TRUE(std::is_sorted(r.jam_onsets.begin(), r.jam_onsets.end()));
    EXPECT_TRUE(std::is_sorted(r.exit_times.begin(), r.exit_times.end()));
    EXPECT_EQ(int(r.exit_times.size()), r.discharged);
    EXPECT_EQ(r.curve_time.size(), r.curve_count.size());
    EXPECT_TRUE(std::is_sorted(r.curve_count.rbegin(), r.curve_count.rend()));
    if (r.empty_time) {
        // Survival intervals partition the flowing part of the discharge: their sum cannot
        // exceed the empty time (the rest is detection waiting, t_check per jam).
        const double sum = std::accumulate(r.survival_times.begin(), r.survival_times.end(), 0.0);
        EXPECT_LE(sum, *r.empty_time + 1e-12);
        EXPECT_EQ(r.discharged, r.particles);
    }
}

}  // namespace

// integrator.settle_steps_per_collision (issue 41): the settle steps at tau_c / 25, the
// discharge at tau_c / 50 (the steps of each phase counted against its simulated time), and
// the realization ends as the protocol says. Unset, the settle steps at dt.
TEST(Realization, TheSettleStepsAtItsOwnTimeStepAndTheDischargeAtDt) {
    SceneParams p = tiny(4.5, 60.0);
    p.integrator.settle_steps_per_collision = 25.0;
    const RealizationResult r = run_realization(p, 1);
    expect_consistent(r);
    ASSERT_EQ(r.status, Status::complete) << r.message;
    const double dt = 8.0e-4 / 50.0, settle_dt = 8.0e-4 / 25.0;
    EXPECT_DOUBLE_EQ(r.diagnostics.dt, dt);
    EXPECT_NEAR(double(r.diagnostics.settle_steps), r.diagnostics.settle_time / settle_dt, 1.0);
    ASSERT_TRUE(r.empty_time.has_value());
    const double discharge_steps = double(r.diagnostics.steps - r.diagnostics.settle_steps);
    EXPECT_GE(discharge_steps + 1.0, *r.empty_time / dt);  // and the shakes' steps, if any
    EXPECT_LT(discharge_steps, (*r.empty_time + 0.5) / dt);
    const RealizationResult plain = run_realization(tiny(4.5, 60.0), 1);
    EXPECT_NEAR(double(plain.diagnostics.settle_steps), plain.diagnostics.settle_time / dt, 1.0);
    std::printf(
        "[ measured ] settle: %lld steps (%.3f s) at tau_c/25, %lld (%.3f s) at "
        "tau_c/50\n",
        (long long)r.diagnostics.settle_steps, r.diagnostics.settle_time,
        (long long)plain.diagnostics.settle_steps, plain.diagnostics.settle_time);
}

TEST(Realization, WideOutletEmptiesWithoutJamming) {
    const RealizationResult r = run_realization(tiny(4.5, 60.0), 1);
    expect_consistent(r);
    EXPECT_EQ(r.status, Status::complete) << r.message;
    EXPECT_EQ(r.n_jams, 0);
    ASSERT_EQ(r.survival_times.size(), 1u);
    EXPECT_TRUE(r.censored[0]);
    ASSERT_TRUE(r.empty_time.has_value());
    EXPECT_DOUBLE_EQ(r.survival_times[0], *r.empty_time);
    ASSERT_TRUE(r.discharge_rate.has_value());
    // 300 particles leave in about a second or two: the rate must be of that order.
    EXPECT_GT(*r.discharge_rate, 50.0);
    EXPECT_LT(*r.discharge_rate, 2000.0);
    EXPECT_GT(r.discharge_rate_mass, 0.0);
}

TEST(Realization, SmallOutletJamsAndShakingUnjamsIt) {
    // D = 2.0 cm is about 2.9 mean diameters: clogs are frequent.
    int jams = 0, cleared = 0;
    for (std::uint64_t seed : {1, 2}) {
        const RealizationResult r = run_realization(tiny(2.0), seed);
        expect_consistent(r);
        EXPECT_EQ(r.status, Status::complete) << r.message;
        jams += r.n_jams;
        cleared += r.n_jams;  // complete => every jam was cleared by shaking
        EXPECT_GE(r.n_shakes, r.n_jams);
        EXPECT_EQ(r.discharged, 300);
    }
    EXPECT_GE(jams, 2);
    EXPECT_EQ(cleared, jams);
}

TEST(Realization, WithoutFrictionTheSmallOutletDoesNotJam) {
    SceneParams p = tiny(2.0);
    p.material.system.mu = 0.0;
    p.material.wall.mu = 0.0;
    const RealizationResult r = run_realization(p, 1);
    expect_consistent(r);
    EXPECT_EQ(r.status, Status::complete) << r.message;
    EXPECT_EQ(r.n_jams, 0);
}

TEST(Realization, DeterministicForASeedAndDifferentForAnother) {
    const SceneParams p = tiny(2.0);
    const RealizationResult a = run_realization(p, 7), b = run_realization(p, 7);
    const RealizationResult c = run_realization(p, 8);
    EXPECT_EQ(a.survival_times, b.survival_times);
    EXPECT_EQ(a.jam_onsets, b.jam_onsets);
    EXPECT_EQ(a.exit_times, b.exit_times);
    EXPECT_EQ(a.curve_count, b.curve_count);
    EXPECT_EQ(a.diagnostics.steps, b.diagnostics.steps);
    EXPECT_EQ(a.empty_time, b.empty_time);
    EXPECT_NE(a.exit_times, c.exit_times);
}

TEST(Realization, NoShakesAllowedEndsArrestedAtTheFirstJam) {
    SceneParams p = tiny(1.6);
    p.protocol.max_shakes = 0;
    const RealizationResult r = run_realization(p, 1);
    expect_consistent(r);
    EXPECT_EQ(r.status, Status::arrested) << r.message;
    EXPECT_EQ(r.n_jams, 1);
    EXPECT_FALSE(r.empty_time.has_value());
    EXPECT_NE(r.message.find("not cleared"), std::string::npos) << r.message;
}

TEST(Realization, TimeLimitCensorsTheRunningInterval) {
    SceneParams p = tiny(4.5, 60.0);
    p.protocol.max_time = 0.3;
    const RealizationResult r = run_realization(p, 1);
    expect_consistent(r);
    EXPECT_EQ(r.status, Status::time_limit) << r.message;
    ASSERT_FALSE(r.censored.empty());
    EXPECT_TRUE(r.censored.back());
    EXPECT_NEAR(r.survival_times.back(), 0.3, 1e-3);
    EXPECT_FALSE(r.empty_time.has_value());
    EXPECT_LT(r.discharged, 300);
}

TEST(Realization, OverlapGuardFailsWithTheCauseAndTheRemedy) {
    SceneParams p = tiny(4.5, 60.0);
    p.protocol.max_overlap = 1e-4;  // no real packing stays below this
    const RealizationResult r = run_realization(p, 1);
    EXPECT_EQ(r.status, Status::failed);
    EXPECT_NE(r.message.find("overlap"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("time step"), std::string::npos) << r.message;
    EXPECT_TRUE(r.survival_times.empty());  // nothing half-measured is reported as data
}

TEST(Realization, UnstableTimeStepFailsInsteadOfProducingGarbage) {
    // Velocity Verlet is unstable for omega dt > 2; for a disk on a wall omega = sqrt(k_n/m).
    // steps_per_collision = 1.5 gives dt = tau_c / 1.5, i.e. omega dt ~ 1.5 pi / sqrt(2) ~ 3.3.
    SceneParams p = tiny(4.5, 60.0);
    p.integrator.scheme = Scheme::verlet;
    p.integrator.steps_per_collision = 2.0;
    p.protocol.max_overlap = 0.25;
    const RealizationResult r = run_realization(p, 1);
    EXPECT_EQ(r.status, Status::failed) << "status " << to_string(r.status);
    EXPECT_NE(r.message.find("time step"), std::string::npos) << r.message;
}

TEST(Realization, SettledColumnCarriesItsWeightOnTheWalls) {
    // After settling, the closed hopper is at rest: the walls carry the whole weight.
    SceneParams p = tiny(2.7, 45.0);
    Realization run(p, 3);
    run.settle();
    ASSERT_FALSE(run.finished()) << run.result().message;
    System& s = run.system();
    double weight = 0.0;
    for (double m : s.m())
        weight += m * p.gravity;
    // Momentum balance: averaged over a window much longer than a contact period (tau_c =
    // 0.8 ms; the window is 0.05 s), the walls carry exactly the weight of a packing whose
    // centre of mass does not accelerate. The instantaneous force still rings at the ~1 % level
    // after the settle criterion (kinetic energy below 1e-4 m g d per particle); the average
    // must match to 1 %.
    Vec2 mean = Vec2::Zero();
    const int steps = 3125;  // 0.05 s at dt = 1.6e-5 s
    for (int k = 0; k < steps; ++k) {
        s.step();
        mean += s.wall_force() / steps;
    }
    EXPECT_NEAR(mean.y(), -weight, 0.01 * weight);
    EXPECT_NEAR(mean.x(), 0.0, 0.01 * weight);
}

// Issue 23: growing shakes. The k-th shake of a jam has the amplitude
// min(A g^(k-1), A_max) (docs/model.md, step 5), measured here on the walls themselves: every
// shake's largest vertical displacement of an edge disk, sampled 64 times per period.
TEST(Realization, ShakesOfOneJamGrowByTheFactorUpToTheCap) {
    SceneParams p = tiny(1.6);
    p.protocol.shake_amplitude = 0.02;  // too weak to clear a jam: the shakes must grow
    p.protocol.shake_growth = 2.0;
    p.protocol.shake_amplitude_max = 0.1;
    p.protocol.max_shakes = 6;
    p.protocol.max_time = 4.0;
    const double T = p.protocol.shake_period;
    struct Sample {
        Phase phase;
        double t, y;
    };
    std::vector<Sample> samples;
    RunHooks hooks;
    hooks.snapshot_interval = T / 64;
    hooks.on_snapshot = [&](const Snapshot& s) {
        if (s.phase != Phase::settle) samples.push_back({s.phase, s.sim_time, s.wall_y[0]});
    };
    const RealizationResult r = run_realization(p, 1, hooks);
    expect_consistent(r);
    ASSERT_GE(r.n_jams, 1) << r.message;
    ASSERT_FALSE(samples.empty());
    ASSERT_NE(samples.front().phase, Phase::shake);
    const double rest = samples.front().y;
    // One maximum per shake: a shake is a run of consecutive shake-phase samples.
    std::vector<double> peaks;
    bool in_shake = false;
    for (const Sample& s : samples) {
        if (s.phase == Phase::shake) {
            if (!in_shake) peaks.push_back(0.0);
            peaks.back() = std::max(peaks.back(), std::abs(s.y - rest));
        }
        in_shake = s.phase == Phase::shake;
    }
    // The amplitudes the jams' shake counts call for, in order.
    std::vector<double> expected;
    int most = 0;
    for (int n : r.shakes_per_jam) {
        most = std::max(most, n);
        for (int k = 1; k <= n; ++k)
            expected.push_back(std::min(0.02 * std::pow(2.0, k - 1), 0.1) * p.particles.d_large);
    }
    ASSERT_GE(most, 4) << "no jam needed four shakes: the cap was never reached";
    ASSERT_EQ(peaks.size(), expected.size());
    for (std::size_t k = 0; k < peaks.size(); ++k) {
        EXPECT_LE(peaks[k], expected[k] * (1 + 1e-9)) << "shake " << k;
        EXPECT_GE(peaks[k], expected[k] * 0.99) << "shake " << k;
    }
}

// At shake_growth = 1 (the default) the cap plays no part: every shake is the first one.
TEST(Realization, WithoutGrowthTheCapChangesNothing) {
    SceneParams a = tiny(1.8);
    a.protocol.max_time = 3.0;
    SceneParams b = a;
    b.protocol.shake_amplitude_max = 0.01;  // below the amplitude: ignored without growth
    const RealizationResult ra = run_realization(a, 3), rb = run_realization(b, 3);
    ASSERT_GE(ra.n_shakes, 1);
    EXPECT_EQ(ra.exit_times, rb.exit_times);
    EXPECT_EQ(ra.shakes_per_jam, rb.shakes_per_jam);
}
