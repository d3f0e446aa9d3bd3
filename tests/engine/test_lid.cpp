// The load band behind the steady state's lid (issue 40; docs/model.md, "The lid"): each mobile
// disk whose centre lies in [y_lo, y_hi] feels a further m a downward, with answers derived by
// hand.
//
// A disk falling from rest above the band falls at g until it enters the band, at g + a inside
// it and at g again below it. A disk at rest on a wall disk inside the band presses on it with
// m (g + a), outside it with m g. Every force path and arrangement of the step's passes gives
// the same bits with the band, and a band with a = 0 spends nothing (the golden files hold it).
#include <gtest/gtest.h>

#include <cmath>

#include "hopper/core/error.hpp"
#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

SystemConfig lid_config(Scheme scheme) {
    return system_config(scheme, 50.0, contact_params(0.5, 0.5), contact_params(0.5, 0.5),
                         Vec2(0.0, -g));
}

class LoadBand : public ::testing::TestWithParam<Scheme> {};

// The slope of v_y over a stretch of the fall that lies wholly above, inside or below the band.
TEST_P(LoadBand, AFallingDiskFallsFasterOnlyInsideTheBand) {
    const double a = 4.0 * g;
    System s(lid_config(GetParam()));
    s.set_load_band(-0.10, -0.05, a);
    const int id = add_disk(s, Vec2(0.0, 0.0), d_large);
    struct Sample {
        double t, v, y;
    };
    std::vector<Sample> trace;
    while (s.position(s.index_of(id)).y() > -0.3) {
        s.step();
        const int i = s.index_of(id);
        trace.push_back({s.time(), s.velocity(i).y(), s.position(i).y()});
    }
    // The mean acceleration between the first and the last sample with y in (lo, hi), a margin
    // of two steps' fall inside so that no step straddles an edge.
    const auto slope_in = [&](double lo, double hi) {
        const Sample *first = nullptr, *last = nullptr;
        for (const Sample& x : trace)
            if (x.y < hi && x.y > lo) {
                if (!first) first = &x;
                last = &x;
            }
        EXPECT_TRUE(first && last && last->t - first->t > 0.005) << lo << " " << hi;
        if (!first || !last || first == last) return 0.0;
        return -(last->v - first->v) / (last->t - first->t);
    };
    const double above = slope_in(-0.045, 0.0), inside = slope_in(-0.095, -0.055),
                 below = slope_in(-0.3, -0.105);
    std::printf(
        "measured: %.6f m/s^2 above the band, %.6f inside, %.6f below; hand-derived "
        "%.6f, %.6f, %.6f\n",
        above, inside, below, g, g + a, g);
    EXPECT_NEAR(above, g, 1e-9 * g);
    EXPECT_NEAR(inside, g + a, 1e-9 * g);
    EXPECT_NEAR(below, g, 1e-9 * g);
}

// A disk brought to rest on a wall disk (a damped fall of a few millimetres): the wall carries
// its weight, times 1 + a / g inside the band.
TEST_P(LoadBand, ADiskAtRestInTheBandPressesWithItsWeightTimesOnePlusAOverG) {
    for (const bool in_band : {false, true}) {
        const double a = 9.0 * g;
        System s(lid_config(GetParam()));
        s.add_wall(Vec2(0.0, 0.0), d_large);
        const int id = add_disk(s, Vec2(0.0, d_large + 0.001), d_large);
        if (in_band) s.set_load_band(0.5 * d_large, 2.0 * d_large, a);
        while (s.time() < 0.5)
            s.step();
        ASSERT_LT(s.velocity(s.index_of(id)).norm(), 1e-6) << "the disk must be at rest";
        const double want = m_large * (g + (in_band ? a : 0.0));
        std::printf("measured: wall force %.9f N %s the band, hand-derived %.9f N\n",
                    -s.wall_force().y(), in_band ? "inside" : "without", want);
        EXPECT_NEAR(-s.wall_force().y(), want, 1e-6 * want);
        EXPECT_NEAR(s.wall_force().x(), 0.0, 1e-9 * want);
    }
}

// Taking the band off (a = 0) restores the plain fall.
TEST_P(LoadBand, ABandWithNoLoadIsNoBand) {
    System with(lid_config(GetParam())), without(lid_config(GetParam()));
    with.set_load_band(-1.0, 1.0, 3.0 * g);
    with.set_load_band(-1.0, 1.0, 0.0);
    add_disk(with, Vec2(0.0, 0.0), d_large);
    add_disk(without, Vec2(0.0, 0.0), d_large);
    for (int k = 0; k < 2000; ++k) {
        with.step();
        without.step();
    }
    EXPECT_EQ(with.position(0).y(), without.position(0).y());
    EXPECT_EQ(with.velocity(0).y(), without.velocity(0).y());
}

INSTANTIATE_TEST_SUITE_P(BothSchemes, LoadBand, ::testing::Values(Scheme::verlet, Scheme::gear4),
                         [](const ::testing::TestParamInfo<Scheme>& p) {
                             return to_string(p.param);
                         });

// A pile of disks falling into a box through a band, with plate friction too (the body forces'
// one order): the reference path, each SIMD path (where the CPU has it) and the fused
// arrangements of the step give the same bits, with both integrators.
TEST(LoadBand, EveryPathAndArrangementGivesTheSameBits) {
    for (const Scheme scheme : {Scheme::verlet, Scheme::gear4}) {
        auto run = [scheme](KernelPath path, StepFusion fusion) {
            SystemConfig c = lid_config(scheme);
            c.kernel = path;
            c.plate_decel = 0.1 * g;
            System s(c);
            s.set_step_fusion(fusion);
            s.set_load_band(0.0, 0.03, 5.0 * g);
            EXPECT_GT(drop_pile(s), 20u) << "the pile must have landed";
            std::vector<double> out;
            for (int i = 0; i < s.mobile_count(); ++i) {
                out.push_back(s.position(i).x());
                out.push_back(s.position(i).y());
                out.push_back(s.velocity(i).y());
            }
            return out;
        };
        const auto ref = run(KernelPath::reference, StepFusion::none);
        for (auto path : {KernelPath::automatic, KernelPath::reference, KernelPath::baseline,
                          KernelPath::avx2, KernelPath::avx512, KernelPath::avx512_gather})
            for (auto fusion : {StepFusion::none, StepFusion::corrector, StepFusion::step}) {
                std::vector<double> got;
                try {
                    got = run(path, fusion);
                } catch (const hopper::core::ConfigError&) {
                    continue;  // a SIMD path this CPU lacks
                }
                EXPECT_EQ(got, ref)
                    << to_string(scheme) << " " << to_string(path) << " " << to_string(fusion);
            }
    }
}

}  // namespace
