// No silent mixing (campaign/mixing.hpp): new points whose physics differs from stored points in
// something their labels do not show are found; differences the labels tell are not.
#include "hopper/campaign/mixing.hpp"

#include <gtest/gtest.h>

namespace hopper::campaign {
namespace {

store::PointPlan point(const std::string& label, const std::string& scene) {
    store::PointPlan p;
    p.label = label;
    p.scene = scene;
    p.seeds = {1, 2};
    return p;
}

store::CampaignPlan plan(std::vector<store::PointPlan> points) {
    store::CampaignPlan c;  // (no name: assigning a short literal makes GCC 12 warn falsely)
    c.points = std::move(points);
    return c;
}

const std::string base = "hopper.theta_rad=1\nmaterial.mu=0.8\nwalls.mu=0.8\n";

// The base scene with an outlet line first.
std::string base_at(const char* outlet_line) {
    std::string s(outlet_line);
    s.append(base);
    return s;
}

TEST(Mixing, NewOutletsOfTheSamePhysicsAreFine) {
    const auto stored = plan({point("D_cm=2 theta_deg=60", base_at("hopper.outlet_m=0.02\n"))});
    const auto sweep = plan({point("D_cm=3 theta_deg=60", base_at("hopper.outlet_m=0.03\n"))});
    EXPECT_TRUE(mixed_settings(stored, sweep).empty());
}

TEST(Mixing, AnUnvariedSettingThatDiffersIsFound) {
    const auto stored = plan({point("D_cm=2 theta_deg=60", base_at("hopper.outlet_m=0.02\n"))});
    const auto sweep = plan({point("D_cm=3 theta_deg=60",
                                   "hopper.outlet_m=0.03\nhopper.theta_rad=1\nmaterial.mu=0.5\n"
                                   "walls.mu=0.5\nprotocol.max_time_s=9\n")});
    const auto m = mixed_settings(stored, sweep);
    ASSERT_EQ(m.size(), 3u);
    EXPECT_EQ(m[0].name, "material.mu");
    EXPECT_EQ(m[0].sweep_value, "0.5");
    EXPECT_EQ(m[0].store_values, std::vector<std::string>{"0.8"});
    EXPECT_EQ(m[0].store_point, "D_cm=2 theta_deg=60");
    EXPECT_EQ(m[1].name, "protocol.max_time_s");
    EXPECT_EQ(m[1].store_values, std::vector<std::string>{"absent"});
    EXPECT_EQ(m[2].name, "walls.mu");
    const std::string text = describe(m);
    EXPECT_NE(text.find("material.mu = 0.5 in this sweep, 0.8 in the store"), std::string::npos)
        << text;
}

TEST(Mixing, DifferencesTheLabelsTellAreFine) {
    // a new wall angle, and a material setting that is in the labels (walls follow it)
    const auto stored =
        plan({point("D_cm=2 theta_deg=60 material.mu=0.8", base_at("hopper.outlet_m=0.02\n"))});
    const auto sweep = plan({point("D_cm=2 theta_deg=45 material.mu=0.5",
                                   "hopper.outlet_m=0.02\nhopper.theta_rad=0.7\nmaterial.mu=0.5\n"
                                   "walls.mu=0.5\n")});
    EXPECT_TRUE(mixed_settings(stored, sweep).empty());
    // ... but a changed wall angle does not account for a changed friction
    const auto sweep2 = plan({point("D_cm=2 theta_deg=45",
                                    "hopper.outlet_m=0.02\nhopper.theta_rad=0.7\nmaterial.mu=0.5\n"
                                    "walls.mu=0.8\n")});
    const auto stored2 = plan({point("D_cm=2 theta_deg=60", base_at("hopper.outlet_m=0.02\n"))});
    const auto m = mixed_settings(stored2, sweep2);
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].name, "material.mu");
}

TEST(Mixing, AResumeNeverMixes) {
    const auto stored = plan({point("D_cm=2 theta_deg=60", base_at("hopper.outlet_m=0.02\n"))});
    EXPECT_TRUE(mixed_settings(stored, stored).empty());
    EXPECT_TRUE(mixed_settings(plan({}), stored).empty());
}

}  // namespace
}  // namespace hopper::campaign
