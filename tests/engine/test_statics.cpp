// Statics (issue 39, part 1): does the contact model hold what it should? Before any clogging
// campaign is trusted, a grain at rest must stay at rest where Coulomb friction says it can, and
// an arch that holds must hold without creeping.
//
// 1. A block on an incline. A disk whose moment of inertia is made enormous (1e16 m R^2) cannot
//    turn: it is a block that can only stick or slide (with 1e9 m R^2 it still rolls off at
//    g sin beta / 1e9, 4e-8 m/s after 10 s, with its contact stuck: measured while writing this).
//    On a floor tilted by beta (gravity g (sin beta, -cos beta), downhill +x) the static tangential
//    spring must carry m g sin beta as long as that is below the Coulomb limit mu m g cos beta,
//    i.e. for tan beta < mu. Below: after the spring has loaded (0.5 s), the block must not move
//    (creep measured over 10 s). Above: it slides with a = g (sin beta - mu cos beta), the
//    kinetic friction of the capped spring (docs/model.md, tangential force). The sliding cases
//    take e_n = 1 (no dashpots): a floor of disks is not flat for a sliding block, which
//    climbs onto the next floor disk while it leaves the last, and with a normal dashpot the
//    approaching contact pushes back harder than the receding one pushes on. That drag grows
//    with the speed (with e_n = 0.5: a falls from 0.83 to 0.64 m/s^2 as v grows to 0.3 m/s,
//    more with more floor disks under the block): a property of a floor made of disks, not of
//    friction.
//    The floor: wall disks of diameter 10 cm, 0.5 mm apart, tops at y = 0 (the floor of
//    test_rolling_resistance.cpp; its bumps rise 0.6 micrometres and tilt the contact normal by
//    at most 0.005 rad, which changes a by at most 0.005 (1 + mu^2) g: 0.1 % here).
// 2. An arch over a gap. A flat floor of wall disks (d_large, touching) with a gap of 2.5
//    d_large (free surface gap between the two edge disks), side walls 6 d_large away, 40 large
//    disks dropped from a lattice above the gap. The gap is narrow enough that they clog within
//    the first second (what falls through is removed 4 d below the floor); the arch then
//    carries the pile. Held 10 s of simulated time, the largest displacement of any disk over
//    the last 9 s is measured (the creep), and nothing may fall through. At the stiffness and
//    restitution of each shipped campaign: the silo's (Hertz collision time 7.3e-4 s, e_n 0.2,
//    mu 0.5) and the calibrated hopper's (8.0e-4 s, e_n 0.5, mu 0.8). A linear spring-dashpot
//    with a Cundall-Strack spring has a static equilibrium: the only motion left once the
//    packing is at rest is round-off, so the bound (1e-6 d_large over 9 s) is far above what a
//    correct model gives and far below any creep that could open an arch within a clog window.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

constexpr double R_w = 0.05;  // floor disks of the incline

struct BlockRun {
    double x_loaded = 0.0;  // position once the spring has loaded (0.5 s)
    double x_end = 0.0;     // at t_end
    double accel = 0.0;     // fitted over 0.1 s to t_end (slide) or 0 (stick)
    double v_max_late = 0.0;
};

// A non-rotating large disk resting at its equilibrium overlap on the tilted floor.
BlockRun block_on_incline(Scheme scheme, double mu, double tan_beta, double t_end, double e_n) {
    const double beta = std::atan(tan_beta);
    const ContactParams cp = contact_params(e_n, mu);
    System s(system_config(scheme, 50.0, cp, cp, Vec2(g * std::sin(beta), -g * std::cos(beta))));
    for (double x = -0.05; x <= 0.6; x += 0.0005)
        s.add_wall(Vec2(x, -R_w), 2 * R_w);
    const double R = 0.5 * d_large, m = m_large;
    const double overlap = m * g * std::cos(beta) / cp.k_n;
    const int id = s.add_particle(Vec2(0.0, R - overlap), d_large, m, 1e16 * m * R * R);
    BlockRun out;
    double st = 0, sv = 0, stt = 0, stv = 0;
    int n = 0;
    while (s.time() < t_end) {
        s.step();
        const int i = s.index_of(id);
        const double t = s.time(), v = s.velocity(i).x();
        if (out.x_loaded == 0.0 && t >= 0.5) out.x_loaded = s.position(i).x();
        if (t >= 0.5) out.v_max_late = std::max(out.v_max_late, std::abs(v));
        if (t > 0.1) {
            st += t, sv += v, stt += t * t, stv += t * v;
            ++n;
        }
    }
    out.x_end = s.position(s.index_of(id)).x();
    out.accel = (n * stv - st * sv) / (n * stt - st * st);
    return out;
}

class Incline : public ::testing::TestWithParam<Scheme> {};

TEST_P(Incline, ABlockBelowTheFrictionAngleStaysAtRest) {
    const double mu = 0.5, tan_beta = 0.8 * mu;  // beta = 21.8 deg < atan(0.5) = 26.6 deg
    const BlockRun r = block_on_incline(GetParam(), mu, tan_beta, 10.5, 0.5);
    const double creep = std::abs(r.x_end - r.x_loaded);
    std::printf(
        "[ measured ] %s, tan beta = 0.8 mu: moved %.3g d_large in 10 s after loading "
        "(spring stretch m g sin beta / k_t = %.3g d_large); largest speed %.3g m/s\n",
        to_string(GetParam()).c_str(), creep / d_large,
        m_large * g * std::sin(std::atan(tan_beta)) / (0.8 * k_n) / d_large, r.v_max_late);
    EXPECT_LT(creep, 1e-6 * d_large) << "a block that Coulomb friction holds crept";
    EXPECT_LT(r.v_max_late, 1e-6);
}

TEST_P(Incline, ABlockAboveTheFrictionAngleSlidesAtTheKineticRate) {
    const double mu = 0.5, tan_beta = 1.2 * mu;  // beta = 31.0 deg > 26.6 deg
    const double beta = std::atan(tan_beta);
    const BlockRun r = block_on_incline(GetParam(), mu, tan_beta, 0.4, 1.0);
    const double a = g * (std::sin(beta) - mu * std::cos(beta));
    std::printf(
        "[ measured ] %s, tan beta = 1.2 mu: a = %.6g m/s^2, expected g (sin beta - "
        "mu cos beta) = %.6g\n",
        to_string(GetParam()).c_str(), r.accel, a);
    EXPECT_NEAR(r.accel, a, 0.005 * a);
}

TEST_P(Incline, TheThresholdIsTheFrictionAngle) {
    // Just below and just above tan beta = mu: stick at 0.98 mu, slide at 1.02 mu.
    const double mu = 0.5;
    const BlockRun below = block_on_incline(GetParam(), mu, 0.98 * mu, 2.0, 0.5);
    const BlockRun above = block_on_incline(GetParam(), mu, 1.02 * mu, 1.0, 1.0);
    const double a_above =
        g * (std::sin(std::atan(1.02 * mu)) - mu * std::cos(std::atan(1.02 * mu)));
    std::printf(
        "[ measured ] %s: at 0.98 mu moved %.3g d_large after loading; at 1.02 mu "
        "a = %.4g m/s^2 (expected %.4g)\n",
        to_string(GetParam()).c_str(), std::abs(below.x_end - below.x_loaded) / d_large,
        above.accel, a_above);
    EXPECT_LT(std::abs(below.x_end - below.x_loaded), 1e-6 * d_large);
    EXPECT_NEAR(above.accel, a_above, 0.01 * a_above);
}

INSTANTIATE_TEST_SUITE_P(BothSchemes, Incline, ::testing::Values(Scheme::verlet, Scheme::gear4),
                         [](const auto& p) { return to_string(p.param); });

struct Material {
    const char* name;
    double tau_c, e_n, mu;
    double mu_r = 0.0;            // rolling resistance (issue 39), with
    bool rolling_spring = false;  // its law: the constant torque or the spring
};

// The campaign's contact constants for collision time tau (k_n from two large disks, as
// docs/model.md: k_n = pi^2 m_large / (2 tau^2); gamma_n = -2 ln(e_n) / tau).
ContactParams campaign_contact(const Material& m) {
    ContactParams p;
    p.k_n = pi * pi * m_large / (2.0 * m.tau_c * m.tau_c);
    p.gamma_n = -2.0 * std::log(m.e_n) / m.tau_c;
    p.k_t = 0.8 * p.k_n;
    p.gamma_t = 0.5 * p.gamma_n;
    p.mu = m.mu;
    p.mu_r = m.mu_r;
    return p;
}

struct ArchRun {
    int held = 0, fell = 0;   // disks left at the end; fallen through during the hold
    double creep = 0.0;       // largest displacement over the last 9 s, m
    double v_max_late = 0.0;  // largest speed over the last 9 s, m/s
    double kappa = 0.0;       // k_n d / (m g)
};

ArchRun arch_over_gap(const Material& mat) {
    const ContactParams cp = campaign_contact(mat);
    SystemConfig c = system_config(Scheme::verlet, 75.0, cp, cp);
    c.dt = mat.tau_c / 75.0;
    c.rolling = mat.mu_r > 0.0;
    c.rolling_spring = mat.rolling_spring;
    System s(c);
    const double d = d_large, gap = 2.5 * d, half_w = 6.0 * d;
    // Floor: touching wall disks from the edge disks (centres at +-(gap/2 + d/2)) outwards.
    for (double x = 0.5 * (gap + d); x <= half_w + 0.5 * d + 1e-12; x += d) {
        s.add_wall(Vec2(x, 0.0), d);
        s.add_wall(Vec2(-x, 0.0), d);
    }
    for (double y = d; y <= 30.0 * d; y += d) {
        s.add_wall(Vec2(half_w + d, y), d);
        s.add_wall(Vec2(-half_w - d, y), d);
    }
    s.set_removal_floor(-4.0 * d);
    std::vector<int> ids;
    const double a = 1.05 * d;
    const int per_row = int(2.0 * half_w / a);
    for (int k = 0; k < 40; ++k)
        ids.push_back(
            add_disk(s, Vec2(-half_w + (k % per_row + 0.5) * a, 1.5 * d + (k / per_row) * a), d));
    const auto steps_per_s = std::int64_t(std::llround(1.0 / s.dt()));
    s.run(steps_per_s);  // 1 s: fallen, clogged, settling
    std::vector<Vec2> p0;
    for (int id : ids) {
        const int i = s.index_of(id);
        p0.push_back(i >= 0 ? s.position(i) : Vec2(NAN, NAN));
    }
    ArchRun out;
    out.kappa = cp.k_n * d / (m_large * g);
    for (int second = 0; second < 9; ++second) {
        for (std::int64_t k = 0; k < steps_per_s; ++k) {
            s.step();
            if (k % 100 == 0)
                for (int i = 0; i < s.mobile_count(); ++i)
                    out.v_max_late = std::max(out.v_max_late, s.velocity(i).norm());
        }
    }
    for (std::size_t k = 0; k < ids.size(); ++k) {
        const int i = s.index_of(ids[k]);
        if (i < 0) {
            if (std::isfinite(p0[k].x())) ++out.fell;  // was there at 1 s
            continue;
        }
        ++out.held;
        if (std::isfinite(p0[k].x()))
            out.creep = std::max(out.creep, (s.position(i) - p0[k]).norm());
    }
    return out;
}

class Arch : public ::testing::TestWithParam<Material> {};

TEST_P(Arch, ALoadedArchOverAGapHoldsWithoutCreep) {
    const Material& m = GetParam();
    const ArchRun r = arch_over_gap(m);
    std::printf(
        "[ measured ] %s (kappa = k_n d / (m g) = %.3g): %d disks held, %d fell; "
        "largest displacement over 9 s %.3g d_large (%.3g d_large per s); largest "
        "speed %.3g m/s\n",
        m.name, r.kappa, r.held, r.fell, r.creep / d_large, r.creep / d_large / 9.0, r.v_max_late);
    ASSERT_GE(r.held, 20) << "the pile did not clog over the gap: no arch to test";
    EXPECT_EQ(r.fell, 0) << "the arch broke during the hold";
    EXPECT_LT(r.creep, 1e-6 * d_large) << "the arch crept";
}

INSTANTIATE_TEST_SUITE_P(Campaigns, Arch,
                         ::testing::Values(Material{"silo", 7.3e-4, 0.2, 0.5},
                                           Material{"hopper_calibrated", 8.0e-4, 0.5, 0.8},
                                           // issue 39: the silo with the rolling spring
                                           Material{"silo_rolling_spring", 7.3e-4, 0.2, 0.5, 0.05,
                                                    true}),
                         [](const auto& p) { return std::string(p.param.name); });

}  // namespace
