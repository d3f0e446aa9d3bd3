// Plate friction (issue 39; docs/model.md, "Plate friction"): the force m a v / max(|v|, v_c)
// against each mobile disk's velocity, with answers derived by hand.
//
// A disk sliding freely (no gravity, nothing to touch) at v0 > v_c decelerates at a until its
// speed is v_c, then decays as exp(-a t / v_c): it stops after (v0^2 - v_c^2) / (2 a) + v_c^2 / a
// = (v0^2 + v_c^2) / (2 a). A disk falling from rest under gravity feels the viscous part first,
// then falls at g - a. Every force path and every arrangement of the step's passes gives the
// same bits with it, and a plate_decel of 0 spends nothing (the golden files hold the default).
#include <gtest/gtest.h>

#include <cmath>

#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

constexpr double v_c = 0.01;

SystemConfig plate_config(Scheme scheme, double a, Vec2 gravity) {
    SystemConfig c =
        system_config(scheme, 50.0, contact_params(0.5, 0.5), contact_params(0.5, 0.5), gravity);
    c.plate_decel = a;
    c.plate_speed = v_c;
    return c;
}

class PlateFriction : public ::testing::TestWithParam<Scheme> {};

TEST_P(PlateFriction, AFreeDiskStopsWhereCoulombAndTheViscousTailSay) {
    const double a = 0.3 * g, v0 = 0.5;
    System s(plate_config(GetParam(), a, Vec2::Zero()));
    const int id = add_disk(s, Vec2(0.0, 0.0), d_large, Vec2(v0, 0.0));
    double v_mid = -1, t_mid = 0;
    while (s.time() < 1.0) {
        s.step();
        if (v_mid < 0 && s.time() >= 0.05) {
            v_mid = s.velocity(s.index_of(id)).x();
            t_mid = s.time();
        }
    }
    // Coulomb while fast: v(t) = v0 - a t, to a * dt: the first step starts from the forces the
    // disk was added with, before the plate force had a velocity to act on.
    EXPECT_NEAR(v_mid, v0 - a * t_mid, a * s.config().dt);
    const double x_stop = (v0 * v0 + v_c * v_c) / (2 * a);
    const double x = s.position(s.index_of(id)).x();
    std::printf("measured: free slide stops at %.6f m, hand-derived %.6f m\n", x, x_stop);
    EXPECT_NEAR(x, x_stop, 1e-3 * x_stop);
    EXPECT_NEAR(s.velocity(s.index_of(id)).norm(), 0.0, 1e-6);
    EXPECT_EQ(s.position(s.index_of(id)).y(), 0.0) << "the force is along the velocity";
}

TEST_P(PlateFriction, AFallingDiskFallsAtGMinusA) {
    const double a = 0.3 * g;
    System s(plate_config(GetParam(), a, Vec2(0.0, -g)));
    const int id = add_disk(s, Vec2(0.0, 0.0), d_large);
    double t1 = 0, v1 = 0;
    while (s.time() < 0.3) {
        s.step();
        if (t1 == 0 && s.time() >= 0.1) {
            t1 = s.time();
            v1 = s.velocity(s.index_of(id)).y();
        }
    }
    const double slope = (s.velocity(s.index_of(id)).y() - v1) / (s.time() - t1);
    std::printf("measured: falling at %.6f m/s^2, hand-derived %.6f\n", -slope, g - a);
    EXPECT_NEAR(-slope, g - a, 1e-9 * g);
}

INSTANTIATE_TEST_SUITE_P(BothSchemes, PlateFriction,
                         ::testing::Values(Scheme::verlet, Scheme::gear4),
                         [](const ::testing::TestParamInfo<Scheme>& p) {
                             return to_string(p.param);
                         });

// A pile of disks falling into a box with plate friction: the reference path, each SIMD path
// (where the CPU has it) and the fused arrangements of the step give the same bits.
TEST(PlateFriction, EveryPathAndArrangementGivesTheSameBits) {
    auto run = [](KernelPath path, StepFusion fusion) {
        SystemConfig c = plate_config(Scheme::verlet, 0.2 * g, Vec2(0.0, -g));
        c.kernel = path;
        System s(c);
        s.set_step_fusion(fusion);
        EXPECT_GT(drop_pile(s), 20u) << "the pile must have landed";
        std::vector<double> out;
        for (int i = 0; i < s.mobile_count(); ++i) {
            out.push_back(s.position(i).x());
            out.push_back(s.velocity(i).y());
        }
        return out;
    };
    const auto ref = run(KernelPath::reference, StepFusion::none);
    for (auto path : {KernelPath::automatic, KernelPath::reference})
        for (auto fusion : {StepFusion::none, StepFusion::corrector, StepFusion::step})
            EXPECT_EQ(run(path, fusion), ref) << to_string(path) << " " << to_string(fusion);
}

}  // namespace
