// The arch finder (arch.hpp) on hand-built contact networks. Disks of radius 1/2 (diameter 1)
// on walls of touching disks of radius 1/2 that rise at 45 deg from the edge disks at
// (-X, 0) and (X, 0); every expected value is derived by hand in the comments.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "hopper/engine/arch.hpp"

namespace {

using hopper::engine::Arch;
using hopper::engine::ArchDisk;
using hopper::engine::find_arch;

constexpr double pi = std::numbers::pi;
constexpr double deg = pi / 180.0;

// Wall disks: the edge disks at (-+X, 0) and four more up each wall at 45 deg, touching.
std::vector<ArchDisk> walls(double X) {
    std::vector<ArchDisk> d;
    int id = 1000;
    for (int k = 0; k < 5; ++k) {
        const double s = k * std::sqrt(0.5);
        d.push_back({id++, -X - s, s, 0.5, true});
        d.push_back({id++, X + s, s, 0.5, true});
    }
    return d;
}

ArchDisk disk(int id, double x, double y) {
    return {id, x, y, 0.5, false};
}

// Three disks: the side disks touch the edge disks at 120 deg from +x (right side; mirrored on
// the left): side = (X - 1/2, sqrt(3)/2) with X = 1.25, so s = 0.75 from the axis. The middle
// disk at (0, h) touches both: 0.75^2 + (h - sqrt3/2)^2 = 1, h = sqrt3/2 + sqrt(0.4375).
struct Three {
    double X = 1.25, s = 0.75, t = std::sqrt(3.0) / 2, h = t + std::sqrt(1.0 - s * s);
    std::vector<ArchDisk> d = [this] {
        auto v = walls(X);
        v.push_back(disk(1, -s, t));
        v.push_back(disk(2, 0.0, h));
        v.push_back(disk(3, s, t));
        return v;
    }();
};

TEST(ArchFinder, ThreeDiskArchIsFoundExactly) {
    Three a;
    // A disk resting on the arch must not belong to it.
    a.d.push_back(disk(10, 0.0, a.h + 1.0));
    const Arch arch = find_arch(a.d, -1.0);
    ASSERT_TRUE(arch.found());
    EXPECT_EQ(arch.ids, (std::vector<int>{1, 2, 3}));
    EXPECT_DOUBLE_EQ(arch.x[0], -a.s);
    EXPECT_DOUBLE_EQ(arch.y[1], a.h);
    // Contact points with the walls: halfway between the side disk and the edge disk (equal
    // radii), at x = +-(0.75 + 1.25)/2 = +-1: span 2.
    EXPECT_NEAR(arch.span, 2.0, 1e-12);
    // Angles through the outlet side. Middle disk: bonds at -beta and pi + beta with
    // beta = atan((h - t)/0.75) = 41.41 deg: pi - 2 beta = 97.2 deg. Side disk: bond to the
    // wall at -60 deg, to the middle at pi - beta: 2 pi - (60 deg + pi - beta) = 120 deg + beta
    // = 161.4 deg, the largest.
    const double beta = std::atan((a.h - a.t) / a.s);
    EXPECT_NEAR(arch.max_angle, 120.0 * deg + beta, 1e-12);
    EXPECT_NEAR(arch.max_angle / deg, 161.41, 0.01);
}

// Four disks: inner pair touching at (+-1/2, h), outer disks 45 deg down from them at
// (+-(1/2 + sqrt(1/2)), h - sqrt(1/2)), the edge disks 60 deg down from those:
// X = 1/2 + sqrt(1/2) + 1/2, 0 = h - sqrt(1/2) - sqrt(3)/2.
TEST(ArchFinder, FourDiskArchIsFoundExactly) {
    const double c = std::sqrt(0.5), h = c + std::sqrt(3.0) / 2, X = 1.0 + c;
    auto d = walls(X);
    // Listed out of order: the finder orders them left to right along the chain.
    d.push_back(disk(7, 0.5, h));
    d.push_back(disk(5, -0.5 - c, h - c));
    d.push_back(disk(8, 0.5 + c, h - c));
    d.push_back(disk(6, -0.5, h));
    d.push_back(disk(20, 0.0, h + std::sqrt(0.75)));  // in the hollow above the inner pair
    const Arch arch = find_arch(d, -1.0);
    ASSERT_TRUE(arch.found());
    EXPECT_EQ(arch.ids, (std::vector<int>{5, 6, 7, 8}));
    // Contact points at outer + (cos -60, sin -60)/2: x = +-(1/2 + c + 1/4); span 1.5 + 2c.
    EXPECT_NEAR(arch.span, 1.5 + 2 * c, 1e-12);
    // Inner disk: bonds at -45 deg and 180 deg: 135 deg. Outer disk: bonds at -60 deg (wall)
    // and 135 deg (inner): 360 - 195 = 165 deg, the largest.
    EXPECT_NEAR(arch.max_angle, 165.0 * deg, 1e-12);
}

TEST(ArchFinder, DanglingDiskBelowTheArchIsNotPartOfIt) {
    Three a;
    // A small disk (radius 0.2) hanging from the middle disk only: centre (0, h - 0.7), 0.751
    // from the side disks' centres (more than 0.5 + 0.2).
    a.d.push_back({12, 0.0, a.h - 0.7, 0.2, false});
    const Arch arch = find_arch(a.d, -1.0);
    ASSERT_TRUE(arch.found());
    EXPECT_EQ(arch.ids, (std::vector<int>{1, 2, 3}));
}

TEST(ArchFinder, BrokenChainIsNotAnArch) {
    Three a;
    a.d[a.d.size() - 2].y += 0.01;  // lift the middle disk: it touches neither side disk
    EXPECT_FALSE(find_arch(a.d, -1.0).found());
}

TEST(ArchFinder, ChainHeldByOneWallOnlyIsNotAnArch) {
    // The left side disk of the three-disk arch and a second disk touching it 31.8 deg up from
    // +x, reaching across the axis to x = 0.1 (cos a = 0.85); nothing holds it on the right.
    Three a;
    auto d = walls(a.X);
    d.push_back(disk(1, -a.s, a.t));
    d.push_back(disk(2, -a.s + 0.85, a.t + std::sqrt(1.0 - 0.85 * 0.85)));
    EXPECT_FALSE(find_arch(d, -1.0).found());
}

TEST(ArchFinder, NothingAcrossTheOutletIsNotAnArch) {
    auto d = walls(1.25);
    d.push_back(disk(1, -0.75, std::sqrt(3.0) / 2));  // a disk on the left wall only
    EXPECT_FALSE(find_arch(d, -1.0).found());
    EXPECT_FALSE(find_arch(walls(1.25), -1.0).found());
}

TEST(ArchFinder, DisksBelowTheFloorAreIgnored) {
    Three a;
    // The floor above the side disks: their bonds are ignored, so no arch is left.
    EXPECT_FALSE(find_arch(a.d, a.t + 0.1).found());
}

TEST(ArchFinder, SingleDiskBlockingTheOutlet) {
    // One disk touching both edge disks: centre (0, y) with X^2 + y^2 = 1, X = 0.6: y = 0.8.
    auto d = walls(0.6);
    d.push_back(disk(1, 0.0, 0.8));
    const Arch arch = find_arch(d, -1.0);
    ASSERT_TRUE(arch.found());
    EXPECT_EQ(arch.ids, (std::vector<int>{1}));
    // Contact points at (+-0.3, 0.4): span 0.6; the angle between the bonds to the walls
    // through below: 2 atan(0.6/0.8) = 73.74 deg.
    EXPECT_NEAR(arch.span, 0.6, 1e-12);
    EXPECT_NEAR(arch.max_angle, 2 * std::atan(0.75), 1e-12);
}

}  // namespace

// Issue 26: what protocol.unjam = remove_arch takes out of the hopper.
namespace {

using hopper::engine::arch_removal;

TEST(ArchRemoval, TakesTheArchsDisksAndNothingAboveThem) {
    Three a;
    a.d.push_back(disk(10, 0.0, a.h + 1.0));  // resting on the arch: stays
    EXPECT_EQ(arch_removal(a.d, -1.0, 0.0, 5.0), (std::vector<int>{1, 2, 3}));
}

TEST(ArchRemoval, WithoutAnArchTakesTheDiskNearestAboveTheOutletCentre) {
    // A chain held by the left wall only (the right side disk is missing): no arch. Disk 1 at
    // (-0.75, sqrt3/2) is 1.146 from the outlet centre (0, 0), disk 2 at (0, h) h = 1.527: disk
    // 1 goes.
    Three a;
    a.d.erase(std::remove_if(a.d.begin(), a.d.end(), [](const ArchDisk& d) { return d.id == 3; }),
              a.d.end());
    ASSERT_FALSE(find_arch(a.d, -1.0).found());
    EXPECT_EQ(arch_removal(a.d, -1.0, 0.0, 5.0), (std::vector<int>{1}));
    // A disk below the outlet plane (falling) or beyond the reach is never taken.
    a.d.push_back(disk(20, 0.0, -0.2));
    a.d.push_back(disk(21, 3.0, 0.1));
    EXPECT_EQ(arch_removal(a.d, -1.0, 0.0, 1.0), (std::vector<int>{1}));
    // Within |x| <= 0.5 only disk 2 (on the axis) is left to take; within 0.1 of an axis
    // emptied of it, nothing.
    EXPECT_EQ(arch_removal(a.d, -1.0, 0.0, 0.5), (std::vector<int>{2}));
    a.d.erase(std::remove_if(a.d.begin(), a.d.end(), [](const ArchDisk& d) { return d.id == 2; }),
              a.d.end());
    EXPECT_TRUE(arch_removal(a.d, -1.0, 0.0, 0.1).empty());
}

}  // namespace
