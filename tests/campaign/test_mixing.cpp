// No silent mixing (campaign/mixing.hpp): new points whose physics differs from stored points in
// something their labels do not show are found; differences the labels tell are not. Points are
// compared by their typed settings (the label's) and parameters (every scene key).
#include "hopper/campaign/mixing.hpp"

#include <gtest/gtest.h>

#include "hopper/config/sweep.hpp"

namespace hopper::campaign {
namespace {

using Settings = std::vector<core::Setting>;

store::PointPlan point(const Settings& settings, Settings parameters) {
    store::PointPlan p;
    for (const auto& s : settings) {
        if (!p.label.empty()) p.label += ' ';
        p.label += config::to_string(s);
    }
    p.settings = settings;
    p.parameters = std::move(parameters);
    p.seeds = {1, 2};
    return p;
}

store::CampaignPlan plan(std::vector<store::PointPlan> points) {
    store::CampaignPlan c;  // (no name: assigning a short literal makes GCC 12 warn falsely)
    c.points = std::move(points);
    return c;
}

// The base scene's parameters at outlet D.
Settings base_at(double D) {
    return {{"D_cm", D}, {"theta_deg", 60.0}, {"material.mu", 0.8}, {"walls.mu", 0.8}};
}

Settings label(double D, double theta) {
    return {{"D_cm", D}, {"theta_deg", theta}};
}

TEST(Mixing, NewOutletsOfTheSamePhysicsAreFine) {
    const auto stored = plan({point(label(2, 60), base_at(2))});
    const auto sweep = plan({point(label(3, 60), base_at(3))});
    EXPECT_TRUE(mixed_settings(stored, sweep).empty());
}

TEST(Mixing, AnUnvariedSettingThatDiffersIsFound) {
    const auto stored = plan({point(label(2, 60), base_at(2))});
    const auto sweep = plan({point(label(3, 60), {{"D_cm", 3.0},
                                                  {"theta_deg", 60.0},
                                                  {"material.mu", 0.5},
                                                  {"walls.mu", 0.5},
                                                  {"protocol.max_time_s", 9.0}})});
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

TEST(Mixing, ASettingNewerThanTheStoreIsFineAtItsDefault) {
    // Points stored before material.mu_r and protocol.unjam existed have no value for them and
    // ran with their defaults (no rolling resistance, shaking): a new point at the defaults is
    // the same physics (before: "material.mu_r = 0 in this sweep, absent in the store").
    const auto stored = plan({point(label(2, 60), base_at(2))});
    Settings same = base_at(3);
    same.push_back({"material.mu_r", 0.0});
    same.push_back({"protocol.unjam", std::string("shake")});
    EXPECT_TRUE(mixed_settings(stored, plan({point(label(3, 60), same)})).empty());
    // ... and one away from a default is found
    Settings other = base_at(3);
    other.push_back({"material.mu_r", 0.1});
    other.push_back({"protocol.unjam", std::string("remove_arch")});
    const auto m = mixed_settings(stored, plan({point(label(3, 60), other)}));
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].name, "material.mu_r");
    EXPECT_EQ(m[0].store_values, std::vector<std::string>{"absent"});
    EXPECT_EQ(m[1].name, "protocol.unjam");
    ASSERT_TRUE(config::default_parameter("material.mu_r").has_value());
    EXPECT_EQ(config::value_text(*config::default_parameter("protocol.unjam")), "shake");
    EXPECT_FALSE(config::default_parameter("no.such_key").has_value());
}

TEST(Mixing, DifferencesTheLabelsTellAreFine) {
    // a new wall angle, and a material setting that is in the labels (walls follow it)
    Settings with_mu = label(2, 60);
    with_mu.push_back({"material.mu", 0.8});
    const auto stored = plan({point(with_mu, base_at(2))});
    Settings other = label(2, 45);
    other.push_back({"material.mu", 0.5});
    const auto sweep = plan({point(
        other, {{"D_cm", 2.0}, {"theta_deg", 45.0}, {"material.mu", 0.5}, {"walls.mu", 0.5}})});
    EXPECT_TRUE(mixed_settings(stored, sweep).empty());
    // ... but a changed wall angle does not account for a changed friction
    const auto sweep2 = plan(
        {point(label(2, 45),
               {{"D_cm", 2.0}, {"theta_deg", 45.0}, {"material.mu", 0.5}, {"walls.mu", 0.8}})});
    const auto stored2 = plan({point(label(2, 60), base_at(2))});
    const auto m = mixed_settings(stored2, sweep2);
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].name, "material.mu");
}

TEST(Mixing, AResumeNeverMixes) {
    const auto stored = plan({point(label(2, 60), base_at(2))});
    EXPECT_TRUE(mixed_settings(stored, stored).empty());
    EXPECT_TRUE(mixed_settings(plan({}), stored).empty());
}

}  // namespace
}  // namespace hopper::campaign
