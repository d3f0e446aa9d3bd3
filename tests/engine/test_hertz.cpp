// The Hertz law (issue 28; docs/model.md, "The Hertz law") in binary collisions integrated by
// System, against hand-derived answers. Two disks closing head on at v with F = K x^(3/2):
// energy conservation gives the largest overlap x_m = (5 mbar v^2 / (4 K))^(2/5) and the duration
//   t = 2 int_0^x_m dx / sqrt(v^2 - 4 K x^(5/2) / (5 mbar)) = I(1/2) x_m / v,
//   I(1/2) = 2 int_0^1 dy / sqrt(1 - y^(5/2)) = (2/p) B(1/p, 1/2), p = 5/2,
// which for two large disks at v0 = sqrt(2 g d_large) is the specification's Hertz collision
// time (hertz_collision_time): the law's K = (5/3) E sqrt(R*) was chosen so. With the damping
// -alpha sqrt(mbar K) x^(1/4) v_n the restitution is a function of alpha alone
// (hertz_restitution): the same at every impact speed.
#include <gtest/gtest.h>

#include <cmath>

#include "hopper/core/error.hpp"
#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

constexpr double Y = 4.8e6, sigma = 0.5;
const double E = Y / (3.0 * (1.0 - sigma * sigma));
const double hertz_k = 5.0 / 3.0 * E;

ContactParams hertz_params(double e_n, double mu) {
    ContactParams p = contact_params(e_n, mu);  // linear coefficients: unused by the Hertz law
    p.hertz_k = hertz_k;
    p.hertz_alpha = hertz_damping_alpha(e_n);
    p.hertz_kt_ratio = 0.8;
    p.hertz_gt_ratio = 0.5;
    return p;
}

struct Collision {
    double e, t_contact;
};

// Two large disks (or a large disk and a large wall disk) closing at v; dt = t_hertz(v) / 400.
Collision head_on(Scheme scheme, double e_n, bool wall, double v) {
    const double t_ref = hertz_collision_time(m_large, d_large, Y, sigma, v);
    const ContactParams cp = hertz_params(e_n, 0.5);
    SystemConfig c = system_config(scheme, 400.0, cp, cp, Vec2::Zero());
    c.dt = t_ref / 400.0;
    c.normal_law = NormalLaw::hertz;
    System s(c);
    const double R = 0.5 * d_large, gap = 3.37 * v * c.dt;
    int a, b = -1;
    if (wall) {
        a = add_disk(s, Vec2(-(2 * R + gap), 0.0), d_large, Vec2(v, 0.0));
        s.add_wall(Vec2::Zero(), d_large);
    } else {
        a = add_disk(s, Vec2(-(2 * R + gap), 0.0), d_large, Vec2(0.5 * v, 0.0));
        b = add_disk(s, Vec2::Zero(), d_large, Vec2(-0.5 * v, 0.0));
    }
    auto x_of = [&](int id) { return s.position(s.index_of(id)).x(); };
    auto v_of = [&](int id) { return s.velocity(s.index_of(id)).x(); };
    auto overlap = [&] { return 2 * R - ((wall ? 0.0 : x_of(b)) - x_of(a)); };
    double t0 = -1, t1 = -1, prev = overlap();
    for (int k = 0; k < 4000 && t1 < 0; ++k) {
        s.step();
        const double now = overlap();
        const double t = s.time();
        if (prev <= 0 && now > 0) t0 = t - c.dt * now / (now - prev);
        if (prev > 0 && now <= 0 && t0 >= 0) t1 = t - c.dt * now / (now - prev);
        prev = now;
    }
    for (int k = 0; k < 20; ++k)
        s.step();
    const double v_after = (wall ? 0.0 : v_of(b)) - v_of(a);
    return {v_after / v, t1 - t0};
}

TEST(Hertz, TheSceneDerivesKAlphaAndTheTimeStepFromTheMaterial) {
    SceneParams p;
    p.material.normal_law = NormalLaw::hertz;
    p.material.system.e_n = 0.5;
    p.material.wall.e_n = 0.8;
    const DerivedConstants c = derive_constants(p);
    EXPECT_DOUBLE_EQ(c.hertz_k, hertz_k);
    EXPECT_DOUBLE_EQ(c.hertz_alpha_system, hertz_damping_alpha(0.5));
    EXPECT_DOUBLE_EQ(c.hertz_alpha_wall, hertz_damping_alpha(0.8));
    EXPECT_DOUBLE_EQ(c.tau_c, c.hertz_time);
    EXPECT_DOUBLE_EQ(c.dt, c.hertz_time / p.integrator.steps_per_collision);
    // The linear law's collision time cannot be given as well; the tangential spring is needed.
    p.material.collision_time = 8e-4;
    EXPECT_THROW(validate_scene(p), hopper::core::ConfigError);
    p.material.collision_time.reset();
    p.material.kt_over_kn = 0.0;
    EXPECT_THROW(validate_scene(p), hopper::core::ConfigError);
}

TEST(Hertz, UndampedCollisionLastsTheHertzTimeAndRebounds) {
    const double v0 = std::sqrt(2.0 * g * d_large);
    for (Scheme scheme : {Scheme::verlet, Scheme::gear4}) {
        for (double v : {v0, 4.0 * v0}) {
            const Collision c = head_on(scheme, 1.0, false, v);
            const double t_ref = hertz_collision_time(m_large, d_large, Y, sigma, v);
            EXPECT_NEAR(c.t_contact / t_ref, 1.0, 2e-3) << to_string(scheme) << " v = " << v;
            EXPECT_NEAR(c.e, 1.0, 1e-3) << to_string(scheme) << " v = " << v;
        }
    }
    // The duration scales as v^(-1/5): four times faster, 4^(-1/5) = 0.758 times as long.
    const double r = head_on(Scheme::verlet, 1.0, false, 4.0 * v0).t_contact /
                     head_on(Scheme::verlet, 1.0, false, v0).t_contact;
    EXPECT_NEAR(r, std::pow(4.0, -0.2), 2e-3);
}

TEST(Hertz, RestitutionIsTheGivenOneAtEverySpeed) {
    const double v0 = std::sqrt(2.0 * g * d_large);
    for (double e_n : {0.5, 0.8}) {
        // The damping constant reproduces e_n in the dimensionless collision.
        EXPECT_NEAR(hertz_restitution(hertz_damping_alpha(e_n)), e_n, 1e-6);
        for (double v : {0.5 * v0, v0, 4.0 * v0}) {
            EXPECT_NEAR(head_on(Scheme::verlet, e_n, false, v).e, e_n, 5e-3) << "v = " << v;
            // A disk against a wall disk: R* = R/2 and mbar = m as against an immobile disk,
            // the same dimensionless collision: the same restitution.
            EXPECT_NEAR(head_on(Scheme::gear4, e_n, true, v).e, e_n, 5e-3) << "wall, v = " << v;
        }
    }
    // More damping, less rebound; none, all of it.
    EXPECT_GT(hertz_restitution(0.1), hertz_restitution(0.5));
    EXPECT_DOUBLE_EQ(hertz_damping_alpha(1.0), 0.0);
}

}  // namespace
