// Coarse-grained fields (issue 7): the accumulator against hand-derived answers, the normal
// force sums of a static stack, a settled hopper, exact merging, and the observer inside a
// realization (off = nothing; on = does not change the dynamics).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/engine/fields.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"
#include "physics_fixture.hpp"

namespace hopper::engine {
namespace {

using namespace hopper::engine::testing;

FieldGrid grid(double x0, double y0, double cell, int nx, int ny, FieldKernel k = FieldKernel::cell,
               double width = 0.0) {
    FieldGrid g;
    g.x0 = x0;
    g.y0 = y0;
    g.cell = cell;
    g.nx = nx;
    g.ny = ny;
    g.kernel = k;
    g.kernel_width = width;
    return g;
}

// Samples a system into an accumulator (pressure in units of m g, as the realization does).
void sample(System& s, FieldAccumulator& acc, double t) {
    std::vector<double> p(std::size_t(s.mobile_count()));
    s.normal_force_sums(p, {});
    for (int i = 0; i < s.mobile_count(); ++i)
        p[i] /= s.mass(i) * g;
    acc.sample(t, s.x(), s.y(), s.vx(), s.vy(), p);
}

// ---- a uniformly translating block -----------------------------------------------------------

class TranslatingBlock : public ::testing::TestWithParam<FieldKernel> {};

// A block of 12 x 8 disks, 1.3 d apart (no contacts), no gravity, moving with v: every cell and
// every node that receives particles sees exactly v, |v| and zero pressure, in every window, so
// the mean is v and the fluctuation zero. The block crosses cells, so cells gain and lose
// particles between windows; that must not matter.
TEST_P(TranslatingBlock, GivesTheExactVelocityAndZeroFluctuation) {
    SystemConfig c;
    c.dt = tau_c / 50;
    c.particle = c.wall = contact_params(0.5, 0.8);
    c.gravity = Vec2::Zero();
    c.skin = 0.4 * d_small;
    System s(c);
    const Vec2 v(0.30, -0.20);
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 8; ++j)
            s.add_particle(Vec2(0.02 + 1.3 * d_large * i, 0.10 + 1.3 * d_large * j), d_large,
                           m_large, disk_inertia(d_large), v);
    const double h = 2.0 * d_large;
    FieldAccumulator acc(grid(0.0, 0.0, h, 20, 16, GetParam(), d_large), 0.01, 0.0);
    const int every = 25;  // 0.4 ms between samples
    for (int k = 0; k < 200 * every; ++k) {
        s.step();
        if (k % every == 0) sample(s, acc, s.time());
    }
    acc.close_window();
    const FieldMoments& m = acc.moments();
    EXPECT_GE(m.total_windows, 7);
    int with_data = 0, several = 0;
    for (int c2 = 0; c2 < m.grid.size(); ++c2) {
        if (m.windows[c2] == 0) continue;
        ++with_data;
        several += m.windows[c2] >= 2;
        EXPECT_NEAR(m.mean[int(Field::vx)][c2], v.x(), 1e-12) << "node " << c2;
        EXPECT_NEAR(m.mean[int(Field::vy)][c2], v.y(), 1e-12);
        EXPECT_NEAR(m.mean[int(Field::speed)][c2], v.norm(), 1e-12);
        EXPECT_EQ(m.mean[int(Field::pressure)][c2], 0.0);
        for (int f = 0; f < field_count; ++f)
            EXPECT_LT(m.fluctuation(Field(f), c2), 1e-12);
    }
    EXPECT_GT(with_data, 20);
    EXPECT_GT(several, 10);
}

INSTANTIATE_TEST_SUITE_P(Kernels, TranslatingBlock,
                         ::testing::Values(FieldKernel::cell, FieldKernel::gaussian),
                         [](const auto& p) { return to_string(p.param); });

// ---- windows and the Welford summary, by hand ---------------------------------------------------

// One particle in one cell; windows of 1 s; values 1, 3 (window 0: samples 1 and 3 -> 2), 6
// (window 1), nothing in window 2, 10 (window 3): window values 2, 6, 10 -> mean 6, sample
// standard deviation 4, n = 3, 4 samples.
TEST(FieldAccumulator, WindowValuesMeanAndFluctuationByHand) {
    FieldAccumulator acc(grid(0.0, 0.0, 1.0, 1, 1), 1.0, 0.0);
    const std::vector<double> x{0.5}, y{0.5}, vy{0.0}, p{0.0};
    for (auto [t, vx] : {std::pair{0.1, 1.0}, {0.6, 3.0}, {1.2, 6.0}, {3.5, 10.0}})
        acc.sample(t, x, y, std::vector<double>{vx}, vy, p);
    acc.close_window();
    const FieldMoments& m = acc.moments();
    EXPECT_EQ(m.windows[0], 3);
    EXPECT_EQ(m.total_windows, 3);
    EXPECT_EQ(m.samples, 4);
    EXPECT_DOUBLE_EQ(m.weight[0], 4.0);
    EXPECT_DOUBLE_EQ(m.mean[int(Field::vx)][0], 6.0);
    EXPECT_DOUBLE_EQ(m.fluctuation(Field::vx, 0), 4.0);
    EXPECT_DOUBLE_EQ(m.mean[int(Field::speed)][0], 6.0);
    EXPECT_DOUBLE_EQ(m.t_first, 0.1);
    EXPECT_DOUBLE_EQ(m.t_last, 3.5);
}

// Samples before `start` belong to no window of the realization's interval: the realization
// never passes them, but the accumulator must place windows relative to start.
TEST(FieldAccumulator, WindowsAreMeasuredFromStart) {
    FieldAccumulator acc(grid(0.0, 0.0, 1.0, 1, 1), 1.0, 0.25);
    const std::vector<double> x{0.5}, y{0.5}, z{0.0};
    for (auto [t, vx] : {std::pair{0.3, 1.0}, {1.2, 3.0}, {1.3, 5.0}})
        acc.sample(t, x, y, std::vector<double>{vx}, z, z);
    acc.close_window();
    // [0.25, 1.25): 1 and 3 -> 2; [1.25, 2.25): 5.
    EXPECT_EQ(acc.moments().windows[0], 2);
    EXPECT_DOUBLE_EQ(acc.moments().mean[int(Field::vx)][0], 3.5);
}

// ---- normal forces and pressure of a static stack
// ------------------------------------------------

// N equal frictionless disks stacked vertically on one wall disk, at rest: the k-th disk from the
// top carries (k - 1) m g from above and k m g below, so sum |F_n| = (2k - 1) m g, i.e. its
// pressure is 2k - 1; the floor carries N m g. With cells of two disks (aligned with the stack),
// the cell pressure is the mean of two such values: 4 j + 2 for the j-th cell from the top.
TEST(NormalForceSums, StaticStackGivesTwoKMinusOne) {
    const int N = 8;
    SystemConfig c;
    c.dt = tau_c / 50;
    c.particle = c.wall = contact_params(0.3, 0.0);
    c.gravity = Vec2(0.0, -g);
    c.skin = 0.4 * d_small;
    System s(c);
    s.add_wall(Vec2::Zero(), d_large);
    for (int k = 0; k < N; ++k)
        s.add_particle(Vec2(0.0, (k + 1) * d_large * 0.999), d_large, m_large,
                       disk_inertia(d_large));
    s.run(std::int64_t(1.0 / c.dt));  // 1 s: long at rest (contact damping time ~ 1 ms)
    std::vector<double> mob(N), wall(1);
    s.normal_force_sums(mob, wall);
    const double W = m_large * g;
    EXPECT_NEAR(wall[0] / (N * W), 1.0, 1e-9);
    for (int i = 0; i < N; ++i) {
        const double y = s.position(i).y();
        const int k_from_top = N - int(std::lround(y / d_large)) + 1;
        EXPECT_NEAR(mob[i] / W, 2.0 * k_from_top - 1.0, 1e-8) << "disk at y = " << y;
    }
    // The field: cells of 2 d_large starting at y = d_large / 2 hold disks 2j+1, 2j+2 from the
    // bottom.
    FieldAccumulator acc(grid(-d_large, 0.5 * d_large, 2.0 * d_large, 1, N / 2), 0.01, 0.0);
    sample(s, acc, 0.0);
    acc.close_window();
    const FieldMoments& m = acc.moments();
    for (int j = 0; j < N / 2; ++j) {
        const int top_index = N / 2 - 1 - j;  // cell j from the bottom = top_index from the top
        EXPECT_NEAR(m.mean[int(Field::pressure)][j], 4.0 * top_index + 2.0, 1e-7) << "cell " << j;
    }
}

// ---- a settled hopper
// ------------------------------------------------------------------------------

SceneParams small_hopper() {
    SceneParams p;
    p.hopper.width = 12.0 * core::cm;
    p.hopper.outlet = 3.0 * core::cm;
    p.hopper.theta = 60.0 * core::deg;
    p.particles.count = 300;
    p.material.collision_time = tau_c;
    // The published integrator setting, pinned: these tests are about the protocol and need
    // speed, not the accuracy of the default (verlet, delta = 75, corrected; README,
    // "Accuracy").
    p.integrator.scheme = Scheme::gear4;
    p.integrator.steps_per_collision = 50.0;
    p.protocol.max_time = 20.0;
    return p;
}

// A settled packing at rest: every particle's contact forces balance its weight, so
// sum_j |F_n,ij| + sum_j |F_t,ij| >= m_i g; with mu = 0.8 and mostly sticking contacts this gives
// pressure >= 1 / (1 + mu) per particle, and in practice ~ 1 or more (documented tolerance: the
// 2nd percentile is above 0.9, the mean above 1). The mean pressure grows with depth: the
// bottom third of the packing is well above the top third and the cell rows increase on
// average (positive least-squares slope against depth).
TEST(Fields, SettledHopperPressureGrowsWithDepthAndBalancesTheWeight) {
    Realization r(small_hopper(), 3);
    r.settle();
    ASSERT_FALSE(r.finished()) << r.result().message;
    System& s = r.system();
    const int n = s.mobile_count();
    std::vector<double> p(std::size_t(n), 0.0);
    s.normal_force_sums(p, {});
    double mean = 0.0;
    for (int i = 0; i < n; ++i) {
        p[i] /= s.mass(i) * g;
        mean += p[i] / n;
    }
    std::vector<double> sorted = p;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_GT(sorted[std::size_t(0.02 * n)], 0.9);
    EXPECT_GE(sorted.front(), 1.0 / 1.8 - 1e-3);
    EXPECT_GT(mean, 1.0);

    const double h = 2.0 * d_large;
    FieldAccumulator acc(grid(-0.07, -0.01, h, int(0.14 / h) + 1, int(0.5 / h) + 1), 0.01, 0.0);
    acc.sample(0.0, s.x(), s.y(), s.vx(), s.vy(), p);
    acc.close_window();
    const FieldMoments& m = acc.moments();
    // Row means (over cells with particles) against height.
    std::vector<double> ys, ps;
    for (int j = 0; j < m.grid.ny; ++j) {
        double sum = 0.0;
        int cells = 0;
        for (int i = 0; i < m.grid.nx; ++i)
            if (m.windows[j * m.grid.nx + i] > 0) {
                sum += m.mean[int(Field::pressure)][j * m.grid.nx + i];
                ++cells;
            }
        if (cells == 0) continue;
        ys.push_back(m.grid.y0 + (j + 0.5) * h);
        ps.push_back(sum / cells);
    }
    ASSERT_GE(ys.size(), 6u);
    const std::size_t third = ys.size() / 3;
    double bottom = 0.0, top = 0.0;
    for (std::size_t k = 0; k < third; ++k) {
        bottom += ps[k] / double(third);
        top += ps[ps.size() - 1 - k] / double(third);
    }
    EXPECT_GT(bottom, 2.0 * top) << "bottom third " << bottom << ", top third " << top;
    double my = 0, mp = 0;
    for (std::size_t k = 0; k < ys.size(); ++k) {
        my += ys[k] / double(ys.size());
        mp += ps[k] / double(ys.size());
    }
    double sxy = 0, sxx = 0;
    for (std::size_t k = 0; k < ys.size(); ++k) {
        sxy += (ys[k] - my) * (ps[k] - mp);
        sxx += (ys[k] - my) * (ys[k] - my);
    }
    EXPECT_LT(sxy / sxx, 0.0) << "pressure must decrease with height";
}

// ---- exact merging
// -----------------------------------------------------------------------------------

// Random particles in 3 x 2 cells over windows: the pieces of two "realizations" merged with
// Chan's formula equal one accumulator fed both (the second shifted to later windows).
TEST(FieldMoments, MergingTwoPiecesEqualsAccumulatingBoth) {
    for (FieldKernel kernel : {FieldKernel::cell, FieldKernel::gaussian}) {
        const FieldGrid gr = grid(0.0, 0.0, 1.0, 3, 2, kernel, 0.7);
        FieldAccumulator a(gr, 1.0, 0.0), b(gr, 1.0, 0.0), both(gr, 1.0, 0.0);
        core::Rng rng(11);
        auto feed = [&](FieldAccumulator& one, double t0, int windows, double bias) {
            for (int k = 0; k < windows * 4; ++k) {
                const double t = t0 + 0.25 * k + 0.01;
                std::vector<double> x, y, vx, vy, p;
                for (int i = 0; i < 5; ++i) {
                    x.push_back(rng.uniform(0.0, 3.0));
                    y.push_back(rng.uniform(0.0, 2.0));
                    vx.push_back(bias + rng.uniform(-1.0, 1.0));
                    vy.push_back(rng.uniform(-2.0, 0.0));
                    p.push_back(rng.uniform(0.0, 50.0));
                }
                one.sample(t, x, y, vx, vy, p);
                both.sample(t, x, y, vx, vy, p);
            }
            one.close_window();
            both.close_window();
        };
        feed(a, 0.0, 7, 0.0);
        feed(b, 100.0, 11, 5.0);  // a different mean: the merge's delta term matters
        FieldMoments merged = a.moments();
        merged.merge(b.moments());
        const FieldMoments& ref = both.moments();
        EXPECT_EQ(merged.total_windows, ref.total_windows);
        EXPECT_EQ(merged.samples, ref.samples);
        for (int c = 0; c < gr.size(); ++c) {
            EXPECT_EQ(merged.windows[c], ref.windows[c]);
            EXPECT_NEAR(merged.weight[c], ref.weight[c], 1e-12 * ref.weight[c]);
            for (int f = 0; f < field_count; ++f) {
                EXPECT_NEAR(merged.mean[f][c], ref.mean[f][c],
                            1e-12 * (1 + std::abs(ref.mean[f][c])));
                EXPECT_NEAR(merged.m2[f][c], ref.m2[f][c], 1e-10 * (1 + ref.m2[f][c]));
            }
        }
        // Merging into empty moments is the identity.
        FieldMoments empty = FieldMoments::zero(gr);
        empty.merge(a.moments());
        EXPECT_EQ(empty.windows, a.moments().windows);
        EXPECT_EQ(empty.mean, a.moments().mean);
    }
}

TEST(FieldMoments, MergingDifferentGridsIsRefused) {
    FieldMoments a = FieldMoments::zero(grid(0.0, 0.0, 1.0, 3, 2));
    const FieldMoments b = FieldMoments::zero(grid(0.0, 0.0, 1.0, 3, 3));
    EXPECT_THROW(a.merge(b), std::invalid_argument);
}

// ---- the observer in a realization
// ---------------------------------------------------------------

// Off: nothing. On: a grid over the container, samples every sample_interval of discharge time
// in [start, end), windows of `window`; and the dynamics are identical (observing does not
// perturb the run). Deterministic.
TEST(Fields, ObserverInARealization) {
    SceneParams off = small_hopper();
    off.hopper.outlet = 4.5 * core::cm;
    const RealizationResult r_off = run_realization(off, 5);
    ASSERT_EQ(r_off.status, Status::complete) << r_off.message;
    EXPECT_FALSE(r_off.fields.has_value());

    SceneParams on = off;
    on.fields.enabled = true;
    on.fields.start = 0.1;
    on.fields.end = 0.6;
    const RealizationResult r_on = run_realization(on, 5);
    ASSERT_EQ(r_on.status, Status::complete);
    EXPECT_EQ(r_on.exit_times, r_off.exit_times);
    EXPECT_EQ(r_on.survival_times, r_off.survival_times);
    ASSERT_TRUE(r_on.fields.has_value());
    const FieldMoments& m = *r_on.fields;
    const double dl = on.particles.d_large;
    EXPECT_DOUBLE_EQ(m.grid.cell, 2.0 * dl);
    EXPECT_LE(m.grid.x0, -on.hopper.width / 2);
    EXPECT_LE(m.grid.y0, -on.protocol.exit_depth * dl);
    EXPECT_NEAR(std::fmod(-m.grid.y0, m.grid.cell), 0.0, 1e-12);  // outlet on a row boundary
    EXPECT_GE(m.t_first, 0.1);
    EXPECT_LT(m.t_last, 0.6);
    EXPECT_NEAR(double(m.samples), 0.5 / 1e-3, 0.5 / 1e-3 * 0.01);  // whole steps: 1.008 ms
    EXPECT_EQ(m.total_windows, 50);
    EXPECT_FALSE(m.outline_x.empty());
    // Material flows down through the outlet: the mean vy of the cells just above the outlet
    // (|x| < D/2, 0 < y < 2 cells) is negative, and somewhere the pressure is positive.
    double vy_outlet = 0.0, p_max = 0.0;
    for (int j = 0; j < m.grid.ny; ++j)
        for (int i = 0; i < m.grid.nx; ++i) {
            const int c = j * m.grid.nx + i;
            if (m.windows[c] == 0) continue;
            const double x = m.grid.x0 + (i + 0.5) * m.grid.cell;
            const double y = m.grid.y0 + (j + 0.5) * m.grid.cell;
            if (std::abs(x) < on.hopper.outlet / 2 && y > 0 && y < 2 * m.grid.cell)
                vy_outlet = std::min(vy_outlet, m.mean[int(Field::vy)][c]);
            p_max = std::max(p_max, m.mean[int(Field::pressure)][c]);
        }
    EXPECT_LT(vy_outlet, -0.1);
    EXPECT_GT(p_max, 1.0);

    const RealizationResult again = run_realization(on, 5);
    ASSERT_TRUE(again.fields.has_value());
    EXPECT_EQ(again.fields->mean, m.mean);
    EXPECT_EQ(again.fields->windows, m.windows);
}

}  // namespace
}  // namespace hopper::engine
