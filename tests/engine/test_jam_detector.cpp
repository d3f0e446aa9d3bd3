// The jam detector's region (docs/model.md, step 4) on hand-placed disks: a disk counts while
// it is inside the region and moves at least protocol.jam_min_speed sqrt(g d_large); a disk
// lodged there at rest does not hide a jam, nor fake a restart after a shake (issue 39).
#include <gtest/gtest.h>

#include <cmath>

#include "hopper/engine/params.hpp"
#include "hopper/engine/scene.hpp"
#include "hopper/engine/system.hpp"
#include "observers.hpp"
#include "physics_fixture.hpp"

namespace hopper::engine {
namespace {

using detail::JamDetector;
using testing::add_disk;
using testing::contact_params;
using testing::system_config;

SceneParams scene() {
    SceneParams p;
    p.hopper.width = 0.43;
    p.hopper.outlet = 0.027;
    p.hopper.theta = 45.0 * core::deg;
    return p;
}

// A disk in the middle of the region: on the axis, one d_large below the edge disks' centres.
Vec2 in_region(const JamDetector& det, const SceneParams& p) {
    return {0.0, det.y_outlet - 0.5 * p.protocol.jam_region_height * p.particles.d_large};
}

double floor_speed(const SceneParams& p) {
    return p.protocol.jam_min_speed * std::sqrt(p.gravity * p.particles.d_large);
}

TEST(JamDetector, TheFloorIsAHundredthOfTheFreeFallScale) {
    const SceneParams p = scene();
    EXPECT_EQ(p.protocol.jam_min_speed, 0.01);
    const JamDetector det(p);
    // (0.01)^2 g d_large.
    EXPECT_NEAR(det.min_speed2, 1e-4 * p.gravity * p.particles.d_large, 1e-15);
}

TEST(JamDetector, ADiskAtRestInTheRegionCountsOnlyWithoutTheFloor) {
    SceneParams p = scene();
    System s(
        system_config(Scheme::verlet, 50.0, contact_params(0.5, 0.8), contact_params(0.5, 0.8)));
    const JamDetector with_floor(p);
    add_disk(s, in_region(with_floor, p), testing::d_small);
    EXPECT_FALSE(with_floor.occupied(s));
    p.protocol.jam_min_speed = 0.0;  // the detector of 0.4.0
    EXPECT_TRUE(JamDetector(p).occupied(s));
}

TEST(JamDetector, AMovingDiskCountsFromTheFloorUpAndOnlyInsideTheRegion) {
    const SceneParams p = scene();
    const JamDetector det(p);
    const double v = floor_speed(p);
    auto occupied_with = [&](Vec2 pos, Vec2 vel) {
        System s(system_config(Scheme::verlet, 50.0, contact_params(0.5, 0.8),
                               contact_params(0.5, 0.8)));
        add_disk(s, pos, testing::d_small, vel);
        return det.occupied(s);
    };
    const Vec2 centre = in_region(det, p);
    EXPECT_TRUE(occupied_with(centre, {0.0, -1.01 * v}));
    EXPECT_TRUE(occupied_with(centre, {0.8 * v, -0.8 * v}));  // |v| = 1.13 floor
    EXPECT_FALSE(occupied_with(centre, {0.0, -0.99 * v}));
    // Fast, but outside: beside the gap, above the edge disks' centres, below the region.
    EXPECT_FALSE(occupied_with({1.01 * det.half_gap, centre.y()}, {0.0, -1.0}));
    EXPECT_FALSE(occupied_with({0.0, det.y_outlet + 1e-4}, {0.0, -1.0}));
    EXPECT_FALSE(occupied_with({0.0, det.y_region - 1e-4}, {0.0, -1.0}));
}

// The protocol's looks: a lodged disk at rest lets the jam be declared t_check after the last
// moving disk, with that disk's time as the onset; after a shake it is not a restart, a
// falling one is.
TEST(JamDetector, ALodgedDiskNeitherHidesAJamNorFakesARestart) {
    const SceneParams p = scene();
    const double t_check = 0.056, dt = 1e-4;
    System s(
        system_config(Scheme::verlet, 50.0, contact_params(0.5, 0.8), contact_params(0.5, 0.8)));
    JamDetector det(p);
    const Vec2 centre = in_region(det, p);
    add_disk(s, centre, testing::d_small, {0.0, -0.5});  // falling through
    EXPECT_EQ(det.look(s, 1.0, t_check), JamDetector::Look::nothing);
    EXPECT_EQ(det.last_occupied, 1.0);
    s.set_velocity(0, Vec2::Zero(), 0.0);  // it comes to rest there, lodged
    double td = 1.0;
    JamDetector::Look seen = JamDetector::Look::nothing;
    while (seen == JamDetector::Look::nothing && td < 2.0) {
        td += dt;
        seen = det.look(s, td, t_check);
    }
    ASSERT_EQ(seen, JamDetector::Look::jammed);
    EXPECT_NEAR(td - 1.0, t_check, 1.5 * dt);
    ASSERT_EQ(det.jammed.size(), 1u);
    EXPECT_EQ(det.jammed.back().first, 1.0);  // the onset: the last look with a moving disk

    // A shake ended (the protocol sets checking); the lodged disk is still there at rest.
    det.flow = JamDetector::Flow::checking;
    det.check_start = td;
    EXPECT_EQ(det.look(s, td + dt, t_check), JamDetector::Look::nothing);
    EXPECT_EQ(det.look(s, td + t_check, t_check), JamDetector::Look::still_jammed);
    // Another shake sets it falling: the flow restarted.
    det.check_start = td + 0.1;
    s.set_velocity(0, {0.0, -0.2}, 0.0);
    EXPECT_EQ(det.look(s, td + 0.1 + dt, t_check), JamDetector::Look::restarted);
    EXPECT_EQ(det.flow, JamDetector::Flow::flowing);
}

}  // namespace
}  // namespace hopper::engine
