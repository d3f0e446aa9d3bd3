// System-level checks of a static packing and of the System's bookkeeping.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

// A box open at the top, of inner width W and wall height H: floor and side walls of wall disks
// of d_large at a centre spacing of 0.5 d_large, the inner floor at y = 0 from x = 0 to W.
void add_open_box(System& s, double W, double H) {
    const double dw = d_large;
    for (double x = -0.5 * dw; x <= W + 0.5 * dw + 1e-12; x += 0.5 * dw)
        s.add_wall(Vec2(x, -0.5 * dw), dw);
    for (double y = 0.0; y <= H; y += 0.5 * dw) {
        s.add_wall(Vec2(-0.5 * dw, y), dw);
        s.add_wall(Vec2(W + 0.5 * dw, y), dw);
    }
}

// A box open at the top: floor and two side walls of wall disks (d_large, centre spacing
// 0.5 d_large), inner width W = 20 d_large; 300 bidisperse disks (62 % small) dropped from a
// lattice (spacing 1.05 d_large) with small random velocities, damped (e_n = 0.5, mu = 0.5),
// run until at rest.
//
// At rest every particle is in equilibrium, so the sum over particles of (contact forces +
// weight) is zero; the particle-particle forces cancel in pairs (Newton's third law), so the
// walls push on the particles with -sum(m g) in total, and by the third law again the particles
// push on the walls with F_walls = sum(m) g = (0, -M g). What is left of the motion contributes
// sum(m a), which "at rest" (kinetic energy per particle below 1e-9 m_large g d_large, i.e.
// speeds ~ 4e-6 m/s) is far below 1e-3 M g; averaged over 200 steps it is smaller still. 1 %.
TEST(SettledColumn, WallsCarryTheWholeWeight) {
    for (Scheme scheme : {Scheme::verlet, Scheme::gear4}) {
        const ContactParams cp = contact_params(0.5, 0.5);
        System s(system_config(scheme, 50.0, cp, cp));
        const double W = 20.0 * d_large, H = 45.0 * d_large;
        add_open_box(s, W, H);
        std::mt19937_64 gen(2024);
        std::uniform_real_distribution<double> U(0.0, 1.0);
        const double a = 1.05 * d_large;
        const int per_row = int(W / a);
        double M = 0.0;
        for (int k = 0; k < 300; ++k) {
            const double d = U(gen) < 0.62 ? d_small : d_large;
            const Vec2 p((k % per_row + 0.5) * a + 0.02 * d_large * (U(gen) - 0.5),
                         (k / per_row + 0.5) * a + 0.5 * d_large);
            add_disk(s, p, d, Vec2(0.05 * (U(gen) - 0.5), 0.05 * (U(gen) - 0.5)));
            M += disk_mass(d);
        }
        const double ke_rest = 1e-9 * m_large * g * d_large * 300;
        double t_rest = -1.0;
        int quiet = 0;
        while (s.time() < 3.0) {
            s.run(500);
            quiet = s.kinetic_energy() < ke_rest ? quiet + 1 : 0;
            if (quiet >= 10) {  // 5000 steps = 0.08 s below the threshold
                t_rest = s.time();
                break;
            }
        }
        Vec2 F = Vec2::Zero();
        for (int k = 0; k < 200; ++k) {
            s.step();
            F += s.wall_force();
        }
        F /= 200.0;
        std::printf(
            "[ measured ] %s: at rest after %.3f s; F_walls = (%.4e, %.4e) N, "
            "-M g = %.4e N, ratio %.5f\n",
            to_string(scheme).c_str(), t_rest, F.x(), F.y(), -M * g, F.y() / (-M * g));
        ASSERT_GT(t_rest, 0.0) << "not at rest after 3 s";
        EXPECT_NEAR(F.y(), -M * g, 0.01 * M * g);
        // The side walls push in opposite directions; their sum is zero at rest.
        EXPECT_NEAR(F.x(), 0.0, 0.01 * M * g);
        // Instantaneous value too.
        EXPECT_NEAR(s.wall_force().y(), -M * g, 0.01 * M * g);
    }
}

// Both integrators are exact for a constant acceleration: Verlet's x += v dt + a dt^2 / 2 and
// Gear's Taylor predictor with r_2 = a dt^2 / 2 (r_3 = r_4 = 0) reproduce y0 + v0 t - g t^2 / 2
// to round-off. Particles below the removal floor leave at the next rebuild or flush and are
// reported once, with a time after they crossed it.
TEST(FreeFall, IsExactAndRemovalReportsTheParticle) {
    for (Scheme scheme : {Scheme::verlet, Scheme::gear4}) {
        const ContactParams cp = contact_params(0.5, 0.5);
        System s(system_config(scheme, 50.0, cp, cp));
        const int a = add_disk(s, Vec2(0.0, 0.0), d_large, Vec2(0.1, 0.2));
        const int b = add_disk(s, Vec2(0.5, 1.0), d_small);
        s.set_removal_floor(-0.05);
        const std::int64_t steps = 9375;  // 0.15 s
        s.run(steps);
        const double t = steps * s.dt();
        EXPECT_NEAR(s.time(), t, 1e-12);  // time_ accumulates dt: round-off only
        // Disk a crosses y = -0.05 when 0.2 t - g t^2 / 2 = -0.05: t_cross = 0.1234 s.
        const double t_cross = (0.2 + std::sqrt(0.04 + 2.0 * g * 0.05)) / g;
        ASSERT_LT(t_cross, t);
        s.flush_removals();
        const auto removed = s.take_removals();
        ASSERT_EQ(removed.size(), 1u);
        EXPECT_EQ(removed[0].id, a);
        EXPECT_GE(removed[0].time, t_cross - s.dt());
        EXPECT_LE(removed[0].time, t);
        EXPECT_TRUE(s.take_removals().empty());  // reported once
        EXPECT_EQ(s.index_of(a), -1);
        EXPECT_EQ(s.mobile_count(), 1);
        const int i = s.index_of(b);
        ASSERT_GE(i, 0);
        EXPECT_NEAR(s.position(i).y(), 1.0 - 0.5 * g * t * t, 1e-12);
        EXPECT_NEAR(s.velocity(i).y(), -g * t, 1e-12);
        EXPECT_EQ(s.position(i).x(), 0.5);
    }
}

// Issue 26: discard_particles takes particles out at once without reporting them as removals
// (an arch's disks leave through the top, not the outlet); the others move on unchanged, in
// free fall, before and after the first step.
TEST(Discard, TakesParticlesOutUnreportedAndLeavesTheRestAlone) {
    for (bool stepped : {false, true}) {
        const ContactParams cp = contact_params(0.5, 0.5);
        System s(system_config(Scheme::verlet, 50.0, cp, cp));
        const int a = add_disk(s, Vec2(0.0, 0.0), d_large);
        const int b = add_disk(s, Vec2(0.5, 1.0), d_small);
        const int c = add_disk(s, Vec2(-0.5, 2.0), d_large);
        s.set_removal_floor(-10.0);
        if (stepped) s.run(100);
        const std::vector<int> gone{a, c, 12345};  // an unknown id is ignored
        s.discard_particles(gone);
        EXPECT_TRUE(s.take_removals().empty());
        EXPECT_EQ(s.mobile_count(), 1);
        EXPECT_EQ(s.index_of(a), -1);
        EXPECT_EQ(s.index_of(c), -1);
        ASSERT_GE(s.index_of(b), 0);
        s.run(100);
        const double t = s.time();
        const int i = s.index_of(b);
        EXPECT_NEAR(s.position(i).y(), 1.0 - 0.5 * g * t * t, 1e-12);
        EXPECT_TRUE(s.take_removals().empty());
    }
}

// Round 3 (docs/performance.md, phase 6): the tangential springs are carried across a rebuild
// by the particles' old indices, through the removal's compaction and the new cell order. A
// loaded packing in the box of SettledColumn, with three disks falling freely outside it (far
// below it after 0.4 s: the first in cell order); taking them out rebuilds the list with every
// other particle's index shifted and re-sorted. They touch nothing, so every contact and its
// spring must survive: the elastic energy (normal and spring parts, summed in the new order)
// agrees to round-off, and the springs' part of it is far above that.
TEST(Springs, SurviveARebuildThatCompactsAndReorders) {
    const ContactParams cp = contact_params(0.5, 0.5);
    System s(system_config(Scheme::gear4, 50.0, cp, cp));
    const double dw = d_large, W = 20.0 * d_large, H = 45.0 * d_large;
    add_open_box(s, W, H);
    std::vector<int> outside;
    for (int k = 0; k < 3; ++k)
        outside.push_back(add_disk(s, Vec2(-10.0 * dw - 2.0 * k * dw, 5.0 * dw), d_small));
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const double a = 1.05 * d_large;
    const int per_row = int(W / a);
    for (int k = 0; k < 300; ++k) {
        const double d = U(gen) < 0.62 ? d_small : d_large;
        add_disk(s, Vec2((k % per_row + 0.5) * a, (k / per_row + 0.5) * a + 0.5 * d_large), d);
    }
    s.run(std::int64_t(0.4 / s.dt()));
    for (int id : outside)
        ASSERT_LT(s.index_of(id), 3) << "the falling disks must come first in cell order";
    const double e0 = s.elastic_energy();
    const int n0 = s.contact_count();
    s.discard_particles(outside);
    ASSERT_EQ(s.mobile_count(), 300);
    const double e1 = s.elastic_energy();
    // The springs' share: the elastic energy minus its normal part, k_n x^2 / 2 per contact.
    double normal = 0.0;
    const auto wid = s.wall_ids();
    for (const auto& [a_id, b_id] : s.contacts_from_list()) {
        const int i = s.index_of(a_id);
        const int j = s.index_of(b_id);
        Vec2 pj;
        double rj;
        if (j >= 0) {
            pj = s.position(j);
            rj = s.radius(j);
        } else {
            const auto w = std::size_t(std::find(wid.begin(), wid.end(), b_id) - wid.begin());
            pj = Vec2(s.wall_x()[w], s.wall_y()[w]) + s.wall_offset();
            rj = s.wall_r()[w];
        }
        const double x = s.radius(i) + rj - (s.position(i) - pj).norm();
        normal += 0.5 * cp.k_n * x * x;
    }
    std::printf(
        "[ measured ] elastic energy %.17g J before, %.17g J after (%d contacts); "
        "springs %.3g J\n",
        e0, e1, n0, e1 - normal);
    EXPECT_NEAR(e1, e0, 1e-12 * e0);
    EXPECT_GT(e1 - normal, 1e-4 * e0) << "the springs must hold energy for the test to bite";
}

// The energy observables on a state computed by hand: disk a pressed into a wall disk below it
// (overlap 2e-5 m) and touched by disk b from the side (overlap 1e-5 m), both moving and
// spinning. Particle-particle contacts are frictionless (mu = 0: no spring energy), the wall
// contact has friction (mu = 0.5, k_t = 0.8 k_n, e_n = 1 so gamma_t = 0). After one step:
//   kinetic   = sum (m v^2 + I w^2) / 2,   I = m d^2 / 8
//   potential = -sum m g.r = sum m g y
//   elastic   = k_n (x_w^2 + x_p^2) / 2 + k_t xi^2 / 2,
// where the wall spring, born at this contact's first step, has grown once: xi = v_t dt with
// v_t the slip velocity of the contact point during the step, v_x + w R for n = +y (the cap
// mu k_n x_w = 0.012 N is far above k_t |xi| = 1.6e-3 N). Velocity Verlet uses the mid-step
// velocity, which the mean of the slip before and after the step gives to O(dt^2) (1e-5
// relative here). The spring part is only 0.4 % of the elastic energy, so it is checked on its
// own: elastic - normal part = k_t xi^2 / 2 within 1 %.
TEST(Observables, EnergiesOfAHandMadeState) {
    const ContactParams cp = contact_params(1.0, 0.0);
    const ContactParams wp = contact_params(1.0, 0.5);
    System s(system_config(Scheme::verlet, 50.0, cp, wp));
    const double R = 0.5 * d_large, Rs = 0.5 * d_small;
    s.add_wall(Vec2(0.0, -R), d_large);
    const Vec2 va0(0.1, -0.05);
    const double wa0 = 3.0;
    const int a = add_disk(s, Vec2(0.0, R - 2e-5), d_large, va0, wa0);
    const int b = add_disk(s, Vec2(R + Rs - 1e-5, R), d_small, Vec2(-0.2, 0.0), -1.0);
    s.step();
    const int i = s.index_of(a), j = s.index_of(b);
    double ke = 0.0, pe = 0.0;
    for (int k : {i, j}) {
        const double m = s.mass(k), d = 2.0 * s.radius(k);
        ke += 0.5 * m * s.velocity(k).squaredNorm() +
              0.5 * (m * d * d / 8.0) * s.omega(k) * s.omega(k);
        pe += m * g * s.position(k).y();
    }
    EXPECT_NEAR(s.kinetic_energy(), ke, 1e-12 * ke);
    EXPECT_NEAR(s.potential_energy(), pe, 1e-12 * std::abs(pe));
    EXPECT_EQ(s.contact_count(), 2);

    const double x_w = 2.0 * R - (s.position(i) - Vec2(0.0, -R)).norm();
    const double x_p = R + Rs - (s.position(i) - s.position(j)).norm();
    ASSERT_GT(x_w, 0.0);
    ASSERT_GT(x_p, 0.0);
    const double normal = 0.5 * k_n * (x_w * x_w + x_p * x_p);
    const double slip = 0.5 * ((va0.x() + wa0 * R) + (s.velocity(i).x() + s.omega(i) * R));
    const double xi = slip * s.dt();
    const double spring = 0.5 * 0.8 * k_n * xi * xi;
    std::printf(
        "[ measured ] elastic energy %.4e J = normal part %.4e J + spring part %.4e J "
        "(expected k_t (v_t dt)^2 / 2 = %.4e J)\n",
        s.elastic_energy(), normal, s.elastic_energy() - normal, spring);
    EXPECT_NEAR(s.elastic_energy() - normal, spring, 0.01 * spring)
        << "the wall contact's tangential spring after its first step is not v_t dt";
}

// A particle added to a running system (the steady state re-inserts every particle that leaves)
// must not erase the tangential springs of the contacts already there: the springs are saved
// at the next rebuild by the rows of the list that was built before the addition. (Found in
// round 3: the save compared the list's size with the grown particle count and gave up, so
// every re-insertion reset every spring of the packing; static friction then holds only what
// the next steps of sliding rebuild.) A settled, loaded packing of 120 disks in a box: its
// elastic energy over one step, with and without a disk added far above it, must agree.
TEST(Springs, SurviveTheAdditionOfAParticle) {
    for (Scheme scheme : {Scheme::verlet, Scheme::gear4}) {
        SCOPED_TRACE(scheme == Scheme::verlet ? "verlet" : "gear4");
        const ContactParams cp = contact_params(0.5, 0.5);
        System s(system_config(scheme, 50.0, cp, cp));
        const double W = 12.0 * d_large, H = 60.0 * d_large;
        add_open_box(s, W, H);
        std::mt19937_64 gen(7);
        std::uniform_real_distribution<double> U(0.0, 1.0);
        const double a = 1.05 * d_large;
        const int per_row = int(W / a);
        for (int k = 0; k < 120; ++k) {
            const double d = U(gen) < 0.62 ? d_small : d_large;
            add_disk(s, Vec2((k % per_row + 0.5) * a, (k / per_row + 0.5) * a + 0.5 * d_large), d);
        }
        s.run(40000);  // 0.64 s: settled under its own weight, the springs loaded
        ASSERT_LT(s.kinetic_energy(), 1e-6 * m_large * g * d_large * 120) << "not settled";
        const double e0 = s.elastic_energy();
        s.run(1);
        const double e_alone = s.elastic_energy();  // what one step changes by itself
        add_disk(s, Vec2(0.5 * W, H - 2.0 * d_large), d_large);
        s.run(1);
        const double e_added = s.elastic_energy();
        std::printf(
            "[ measured ] elastic energy %.6e J, after a step %.6e J, after a step with "
            "a disk added far above %.6e J\n",
            e0, e_alone, e_added);
        ASSERT_GT(e0, 0.0);
        EXPECT_LT(std::abs(e_alone - e0), 1e-3 * e0);
        EXPECT_LT(std::abs(e_added - e_alone), 2e-3 * e0)
            << "adding a disk far from the packing changed its stored elastic energy: the "
               "tangential springs were lost";
    }
}

}  // namespace
