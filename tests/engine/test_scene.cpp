// The hopper scene: wall outline, gate and fill lattice (docs/model.md, geometry and step 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/engine/scene.hpp"

using namespace hopper::engine;
using hopper::core::Rng;

namespace {

SceneParams scene(double D_cm, double theta_deg, int n = 600, double width_cm = 15.0) {
    SceneParams p;
    p.hopper.width = width_cm * cm;
    p.hopper.outlet = D_cm * cm;
    p.hopper.theta = theta_deg * deg;
    p.particles.count = n;
    return p;
}

// Smallest surface-to-surface gap between a fill particle and anything else (walls, gate,
// other fill particles); negative means overlap.
double smallest_gap(const SceneLayout& s) {
    double gap = 1e9;
    for (std::size_t i = 0; i < s.fill.size(); ++i) {
        const auto& f = s.fill[i];
        for (std::size_t j = i + 1; j < s.fill.size(); ++j)
            gap = std::min(gap,
                           (f.pos - s.fill[j].pos).norm() - (f.diameter + s.fill[j].diameter) / 2);
        for (const auto* walls : {&s.walls, &s.gate})
            for (const auto& w : *walls)
                gap = std::min(gap, (f.pos - w.pos).norm() - (f.diameter + w.diameter) / 2);
    }
    return gap;
}

}  // namespace

class SceneAngles : public ::testing::TestWithParam<double> {};

TEST_P(SceneAngles, OutletIsTheFreeGapBetweenTheInnermostWallParticles) {
    const double theta = GetParam();
    const SceneParams p = scene(2.7, theta);
    Rng rng(1);
    const SceneLayout s = build_scene(p, rng);
    // The free gap at the outlet: innermost wall particles on each side, surface to surface.
    double right = 1e9, left = -1e9;
    for (const auto& w : s.walls) {
        if (w.pos.y() > 1e-12) continue;
        if (w.pos.x() > 0) right = std::min(right, w.pos.x() - w.diameter / 2);
        if (w.pos.x() < 0) left = std::max(left, w.pos.x() + w.diameter / 2);
    }
    EXPECT_NEAR(right - left, p.hopper.outlet, 1e-12);
    // No wall particle is closer to the axis than the outlet edge (the gap is the narrowest).
    for (const auto& w : s.walls)
        EXPECT_GE(std::abs(w.pos.x()) - w.diameter / 2, p.hopper.outlet / 2 - 1e-12);
}

TEST_P(SceneAngles, WallsLeaveNoGapASmallParticleCouldSlipThrough) {
    const SceneParams p = scene(2.7, GetParam());
    Rng rng(1);
    const SceneLayout s = build_scene(p, rng);
    // Every wall particle has a neighbour within spacing * d_w (same side).
    const double spacing = p.hopper.wall_spacing * p.hopper.wall_diameter;
    for (const auto& a : s.walls) {
        double nearest = 1e9;
        for (const auto& b : s.walls)
            if (&a != &b && a.pos.x() * b.pos.x() > 0)
                nearest = std::min(nearest, (a.pos - b.pos).norm());
        EXPECT_LE(nearest, spacing + 1e-12);
    }
    // The gate closes the outlet: gaps between consecutive gate/edge particles < d_small.
    std::vector<double> xs;
    for (const auto& g : s.gate)
        xs.push_back(g.pos.x());
    xs.push_back(-(p.hopper.outlet / 2 + p.hopper.wall_diameter / 2));
    xs.push_back(+(p.hopper.outlet / 2 + p.hopper.wall_diameter / 2));
    std::sort(xs.begin(), xs.end());
    for (std::size_t k = 1; k < xs.size(); ++k)
        EXPECT_LT(xs[k] - xs[k - 1] - p.hopper.wall_diameter, p.particles.d_small);
}

TEST_P(SceneAngles, FillHasNoOverlapAndStaysInsideTheWalls) {
    const SceneParams p = scene(2.7, GetParam(), 400);
    Rng rng(3);
    const SceneLayout s = build_scene(p, rng);
    ASSERT_EQ(int(s.fill.size()), p.particles.count);
    // The lattice keeps fill_gap * d_large of clearance from everything.
    EXPECT_GE(smallest_gap(s), p.protocol.fill_gap * p.particles.d_large * 0.999);
    for (const auto& f : s.fill) {
        EXPECT_GT(f.pos.y(), 0.0);
        EXPECT_LT(std::abs(f.pos.x()) + f.diameter / 2, inner_half_width(p.hopper, f.pos.y()));
        EXPECT_LE(f.pos.y(), s.wall_top);
    }
}

INSTANTIATE_TEST_SUITE_P(Theta, SceneAngles, ::testing::Values(0.0, 15.0, 45.0, 60.0, 89.0, 90.0));

TEST(Scene, FlatBottomAtThetaZeroAndSlotAtNinety) {
    Rng rng(1);
    const SceneLayout flat = build_scene(scene(2.7, 0.0), rng);
    // theta = 0: the bottom is a row at y = 0 reaching the side walls at x = +-(W/2 + d_w/2).
    const double side = 15.0 * cm / 2 + 0.77 * cm / 2;
    int bottom = 0;
    for (const auto& w : flat.walls) {
        if (std::abs(w.pos.y()) < 1e-12) ++bottom;
        EXPECT_LE(std::abs(w.pos.x()), side + 1e-12);
    }
    EXPECT_GT(bottom, 2 * int((15.0 - 2.7) / 2 / 0.77));

    const SceneLayout slot = build_scene(scene(2.7, 90.0, 100), rng);
    // theta = 90: vertical walls at x = +-(D/2 + d_w/2); nothing at the side walls.
    for (const auto& w : slot.walls)
        EXPECT_NEAR(std::abs(w.pos.x()), 2.7 * cm / 2 + 0.77 * cm / 2, 1e-12);
    for (const auto& f : slot.fill)
        EXPECT_LT(std::abs(f.pos.x()), 2.7 * cm / 2);
}

// Issue 26: the flat-bottomed silo of the clogging literature: theta = 0, W = 25 d, an outlet
// of 3.5 d centred, monodisperse disks (small_fraction = 0: every disk d_large).
TEST(Scene, FlatSiloOfMonodisperseDisks) {
    const double d = 0.77 * cm, W = 25 * d, D = 3.5 * d;
    SceneParams p = scene(D / cm, 0.0, 600, W / cm);
    p.particles.small_fraction = 0.0;
    Rng rng(3);
    const SceneLayout s = build_scene(p, rng);
    // The edge disks (the first two walls) at (+-(D/2 + d_w/2), 0): the free gap is D, centred.
    ASSERT_GE(s.walls.size(), 2u);
    EXPECT_NEAR(s.walls[0].pos.x() + s.walls[1].pos.x(), 0.0, 1e-15);
    EXPECT_NEAR(std::abs(s.walls[0].pos.x()), D / 2 + d / 2, 1e-12);
    EXPECT_NEAR(s.walls[0].pos.y(), 0.0, 1e-15);
    // Nothing closes the outlet but the gate; the bottom reaches the side walls, which stand at
    // x = +-(W/2 + d_w/2) up to the top of the walls.
    // (Disks are laid along the outline at one wall spacing, d here: the corner's neighbours lie
    // within one spacing of it.)
    double widest = 0.0, lowest_side = 1e9;
    for (const auto& w : s.walls) {
        if (std::abs(w.pos.y()) < 1e-12) {
            EXPECT_GE(std::abs(w.pos.x()), D / 2 + d / 2 - 1e-12);
            widest = std::max(widest, std::abs(w.pos.x()));
        }
        if (std::abs(std::abs(w.pos.x()) - (W / 2 + d / 2)) < 1e-12)
            lowest_side = std::min(lowest_side, w.pos.y());
        EXPECT_LE(std::abs(w.pos.x()), W / 2 + d / 2 + 1e-12);
        EXPECT_LE(w.pos.y(), s.wall_top + 1e-12);
    }
    EXPECT_GT(widest, W / 2 + d / 2 - d - 1e-12);
    EXPECT_LT(lowest_side, d + 1e-12);
    for (const auto& g : s.gate)
        EXPECT_LT(std::abs(g.pos.x()), D / 2 + d / 2);
    // Monodisperse: every disk d_large, inside the walls and above the bottom.
    ASSERT_EQ(s.fill.size(), 600u);
    for (const auto& f : s.fill) {
        EXPECT_TRUE(f.large);
        EXPECT_EQ(f.diameter, p.particles.d_large);
        EXPECT_LE(std::abs(f.pos.x()) + f.diameter / 2, W / 2 + 1e-12);
        EXPECT_GT(f.pos.y() - f.diameter / 2, d / 2);
    }
}

TEST(Scene, SizesFollowTheSmallFractionAndTheSeed) {
    SceneParams p = scene(4.5, 60.0, 8750, 43.0);
    Rng a(11), b(11), c(12);
    const SceneLayout sa = build_scene(p, a), sb = build_scene(p, b), sc = build_scene(p, c);
    int small = 0, differ = 0;
    for (std::size_t i = 0; i < sa.fill.size(); ++i) {
        small += !sa.fill[i].large;
        EXPECT_EQ(sa.fill[i].large, sb.fill[i].large);
        EXPECT_EQ(sa.fill[i].vel, sb.fill[i].vel);
        differ += sa.fill[i].large != sc.fill[i].large;
    }
    // Binomial(8750, 0.62): standard deviation of the fraction 0.0052; allow 4 sigma.
    EXPECT_NEAR(double(small) / 8750, 0.62, 0.021);
    EXPECT_GT(differ, 1000);  // another seed: about 2 * 0.62 * 0.38 = 47 % differ
    // The full-size fill needs side walls taller than the packing.
    EXPECT_GT(sa.wall_top, sa.fill_top);
}

TEST(Scene, ImpossibleFillIsAClearError) {
    // A vertical slot narrower than one large particle cannot be filled.
    SceneParams p = scene(0.5, 90.0, 10);
    Rng rng(1);
    try {
        build_scene(p, rng);
        FAIL() << "expected ConfigError";
    } catch (const hopper::core::ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot place"), std::string::npos) << e.what();
    }
}
