// Rolling resistance (issue 28; docs/model.md, "Rolling resistance"): a disk rolling down an
// incline against the constant torque mu_r R* |F_n|, with answers derived by hand.
//
// The incline: a floor of wall disks (diameter 10 cm, 0.5 mm apart, tops at y = 0) under gravity
// tilted by beta, g = g (sin beta, -cos beta): downhill is +x. A large disk (m, R, I = m R^2/2)
// rolls without slipping (v = -w R). Its rolling resistance against the wall disks it touches is
// M = mu_r R* N with R* = R R_w / (R + R_w) and N = m g cos beta (the bumps of the floor tilt
// the contacts by at most 0.005 rad and rise 0.6 micrometres: a nearly flat floor). Newton and
// Euler with the friction force F at the contact: m a = m g sin beta - F, I (-dw/dt) = F R - M, a =
// -R dw/dt:
//   a = (g sin beta - M / (m R)) / (1 + I / (m R^2)) = (2/3) g (sin beta - mu_r (R*/R) cos beta).
// With mu_r (R*/R) = 2 tan beta the disk decelerates at (2/3) g sin beta, stops after
// v0^2 / (2 |a|) and stays (the torque needed to hold it, m g sin beta R, is half the largest
// resistance); with mu_r (R*/R) = tan beta / 2 it accelerates at (1/3) g sin beta.
//
// The rolling spring (issue 39, material.rolling_law = spring) sits at its cap while the disk
// rolls one way (each contact's torque grows by k_r w dt per step up to mu_r R* N), so the same
// answers hold for a rolling disk; at rest it differs: the spring holds the static torque
// m g sin beta R elastically, with no creep at all, where the constant torque jitters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

constexpr double beta = 5.0 * pi / 180.0;
constexpr double R_w = 0.05, R = 0.5 * d_large;
const double rstar = R * R_w / (R + R_w);

struct Roll {
    double stop_x = -1;           // where the speed first fell below 1 mm/s (-1: never)
    double x_end = 0, slope = 0;  // final position; acceleration fitted over 0.02-0.15 s
    double v_after = 0;           // the largest speed from 0.05 s after the stop on
    double v_chatter = 0;         // R M dt / I: the spin one step of the torque M gives
    double x_after = 0;           // the position 0.05 s after the stop (or after the start)
};

Roll roll(double mu_r_over, double v0, bool spring = false) {
    ContactParams cp = contact_params(0.5, 0.8);
    cp.mu_r = mu_r_over * std::tan(beta) * R / rstar;
    SystemConfig c =
        system_config(Scheme::verlet, 50.0, cp, cp, Vec2(g * std::sin(beta), -g * std::cos(beta)));
    c.rolling = true;
    c.rolling_spring = spring;
    System s(c);
    for (double x = -0.05; x <= 0.15; x += 0.0005)
        s.add_wall(Vec2(x, -R_w), 2 * R_w);
    const int id = add_disk(s, Vec2(0.0, R), d_large, Vec2(v0, 0.0));
    s.set_velocity(s.index_of(id), Vec2(v0, 0.0), -v0 / R);
    Roll out;
    const double M = cp.mu_r * rstar * m_large * g * std::cos(beta);
    out.v_chatter = R * M * c.dt / disk_inertia(d_large);
    double st = 0, sv = 0, stt = 0, stv = 0, t_stop = 0;
    int n = 0;
    while (s.time() < 0.4) {
        s.step();
        const int i = s.index_of(id);
        const double t = s.time(), v = s.velocity(i).x();
        if (out.stop_x >= 0 && t > t_stop + 0.05) out.v_after = std::max(out.v_after, std::abs(v));
        if (out.stop_x >= 0 && t <= t_stop + 0.05) out.x_after = s.position(i).x();
        if (out.stop_x < 0 && t > 0.01 && std::abs(v) < 1e-3) {
            out.stop_x = s.position(i).x();
            t_stop = t;
        }
        if (t > 0.02 && t < 0.15) {
            st += t, sv += v, stt += t * t, stv += t * v;
            ++n;
        }
        out.x_end = s.position(i).x();
    }
    out.slope = (n * stv - st * sv) / (n * stt - st * st);
    return out;
}

TEST(RollingResistance, ADiskOnAnInclineStopsWhereTheTorqueSays) {
    const double v0 = 0.1;
    const double a = 2.0 / 3.0 * g * (std::sin(beta) - 2.0 * std::tan(beta) * std::cos(beta));
    const Roll r = roll(2.0, v0);
    ASSERT_GE(r.stop_x, 0.0) << "the disk never stopped";
    EXPECT_NEAR(r.stop_x / (v0 * v0 / (2 * std::abs(a))), 1.0, 0.03);
    EXPECT_NEAR(r.slope / a, 1.0, 0.03);
    // And it stays: the constant torque flips with the spin's sign from one step to the next, so
    // a disk at rest jitters (and creeps) at most at the speed one step of it gives, R M dt / I
    // (4e-5 m/s here: docs/model.md), never rolling away.
    EXPECT_LT(r.v_after, 2.0 * r.v_chatter);
    EXPECT_LT(std::abs(r.x_end - r.stop_x), 2.0 * r.v_chatter * 0.4);
}

TEST(RollingResistance, ADiskOnASteeperInclineRollsOnMoreSlowly) {
    for (double k : {0.0, 0.5}) {
        const double a = 2.0 / 3.0 * g * (std::sin(beta) - k * std::tan(beta) * std::cos(beta));
        const Roll r = roll(k, 0.05);
        EXPECT_LT(r.stop_x, 0.0) << "k = " << k;
        EXPECT_NEAR(r.slope / a, 1.0, 0.03) << "k = " << k;
    }
}

// Issue 39: the rolling spring. Rolling, it gives the constant torque's answers (the stop, and
// the acceleration on the steeper incline); stopped, it holds: the ringing of the stop (the
// spring is undamped below its cap) is gone 0.05 s later, and from then on the disk stays
// put to 1e-9 m, where the constant torque lets it jitter at up to R M dt / I.
TEST(RollingSpring, ADiskOnAnInclineStopsWhereTheTorqueSaysAndThenHoldsWithoutCreep) {
    const double v0 = 0.1;
    const double a = 2.0 / 3.0 * g * (std::sin(beta) - 2.0 * std::tan(beta) * std::cos(beta));
    const Roll r = roll(2.0, v0, true);
    ASSERT_GE(r.stop_x, 0.0) << "the disk never stopped";
    EXPECT_NEAR(r.stop_x / (v0 * v0 / (2 * std::abs(a))), 1.0, 0.03);
    EXPECT_NEAR(r.slope / a, 1.0, 0.03);
    EXPECT_LT(r.v_after, 1e-3 * r.v_chatter);
    EXPECT_LT(std::abs(r.x_end - r.x_after), 1e-9);
    const Roll c = roll(2.0, v0, false);  // the constant torque, for comparison
    std::printf(
        "after the stop: largest speed %.3g m/s (constant torque %.3g, R M dt / I %.3g); "
        "moved %.3g m in 0.35 s (constant torque %.3g)\n",
        r.v_after, c.v_after, r.v_chatter, std::abs(r.x_end - r.x_after),
        std::abs(c.x_end - c.x_after));
    EXPECT_GT(c.v_after, 100.0 * r.v_after) << "the comparison has no teeth";
}

TEST(RollingSpring, ADiskOnASteeperInclineRollsOnMoreSlowly) {
    const double a = 2.0 / 3.0 * g * (std::sin(beta) - 0.5 * std::tan(beta) * std::cos(beta));
    const Roll r = roll(0.5, 0.05, true);
    EXPECT_LT(r.stop_x, 0.0);
    EXPECT_NEAR(r.slope / a, 1.0, 0.03);
}

// The law by itself: M' = M - k_r w dt, k_r = k_t R*^2, capped at mu_r R* |F_n| with the sign
// kept; rolled back from the cap it unloads elastically; the dashpot -gm R*^2 w acts below the
// cap only.
TEST(RollingSpring, TheTorqueGrowsElasticallyUpToTheCapAndUnloadsFromIt) {
    const double k_t = 2.0e3, gm = 0.3, rs = 2e-3, fn = -0.5, mu_r = 0.1, dt = 1e-5;
    const double k_r = k_t * rs * rs, cap = mu_r * rs * 0.5, c_r = gm * rs * rs;
    double M = 0.0;
    EXPECT_DOUBLE_EQ(rolling_spring_torque(mu_r, k_t, 0.0, rs, fn, 1.0, 1.0, dt, M), -k_r * dt);
    EXPECT_DOUBLE_EQ(M, -k_r * dt);
    M = 0.0;  // the dashpot: the spin it damps (w_d) need not be the one that grows the spring
    EXPECT_DOUBLE_EQ(rolling_spring_torque(mu_r, k_t, gm, rs, fn, 1.0, 3.0, dt, M),
                     -k_r * dt - 3.0 * c_r);
    EXPECT_DOUBLE_EQ(M, -k_r * dt);
    for (int k = 0; k < 100000; ++k)
        rolling_spring_torque(mu_r, k_t, gm, rs, fn, 1.0, 1.0, dt, M);
    EXPECT_EQ(M, -cap);
    // At the cap: the cap alone, no dashpot.
    EXPECT_EQ(rolling_spring_torque(mu_r, k_t, gm, rs, fn, 1.0, 1.0, dt, M), -cap);
    EXPECT_DOUBLE_EQ(rolling_spring_torque(mu_r, k_t, 0.0, rs, fn, -2.0, -2.0, dt, M),
                     -cap + 2 * k_r * dt);
    EXPECT_EQ(rolling_spring_torque(mu_r, k_t, gm, rs, fn, -1e9, -1e9, dt, M), cap);
    EXPECT_EQ(rolling_spring_torque(mu_r, k_t, gm, rs, 0.0, 0.0, 0.0, dt, M), 0.0);  // no load
}

}  // namespace
