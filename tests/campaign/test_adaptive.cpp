// Campaigns that stop when good enough (adaptive.hpp): the rounds replayed from hand-made
// results. A fake realization has 50 jams after 1 s of flow each and a final censored interval
// of 0 s, so n realizations give r = 50 n jams in T = 50 n s: tau = 1 s and the chi-square
// interval [2T/chi2_0.975(2r), 2T/chi2_0.025(2r)] has relative half-width 0.1997 at r = 100,
// 0.1139 at r = 300 and 0.0985 at r = 400 (scipy.stats.chi2.ppf).
#include <gtest/gtest.h>

#include "hopper/campaign/adaptive.hpp"
#include "hopper/core/error.hpp"

using namespace hopper;
using campaign::PointResults;
using campaign::replay_rounds;

namespace {

config::CampaignSpec spec_of(const std::string& campaign_keys, const std::string& sweep) {
    const std::string text = R"([hopper]
width_cm = 12.0
particles = 250
theta_deg = 45.0
[campaign]
name = "t"
)" + campaign_keys + "\n[sweep]\n" +
                             sweep + "\n";
    return config::parse_sweep(text, "<test>").campaign;
}

engine::RealizationResult fake(int jams, double interval = 1.0) {
    engine::RealizationResult r;
    r.status = engine::Status::complete;
    for (int k = 0; k < jams; ++k) {
        r.survival_times.push_back(interval);
        r.censored.push_back(false);
        r.avalanche_sizes.push_back(10);
    }
    r.survival_times.push_back(0.0);
    r.censored.push_back(true);
    r.avalanche_sizes.push_back(0);
    r.n_jams = jams;
    return r;
}

PointResults first_n(int n, int jams = 50) {
    PointResults p;
    for (int i = 0; i < n; ++i)
        p[i] = fake(jams);
    return p;
}

TEST(Adaptive, PrecisionIsTheChiSquareHalfWidth) {
    const auto q = campaign::precision(first_n(2), 2, config::CampaignTarget::Quantity::tau);
    ASSERT_TRUE(q.has_estimate);
    EXPECT_EQ(q.jams, 100);
    EXPECT_DOUBLE_EQ(q.estimate, 1.0);
    EXPECT_NEAR(q.rel_half_width, 0.19968, 1e-4);
    // Only realizations below the allotment count, failed ones never.
    PointResults p = first_n(3);
    p[1].status = engine::Status::failed;
    EXPECT_EQ(campaign::precision(p, 3, config::CampaignTarget::Quantity::tau).jams, 100);
    // <s>: 10 grains per completed avalanche -> <s> = 10.
    const auto s = campaign::precision(first_n(2), 2, config::CampaignTarget::Quantity::mean_s);
    EXPECT_DOUBLE_EQ(s.estimate, 10.0);
    EXPECT_NEAR(s.rel_half_width, 0.19968, 1e-4);
}

TEST(Adaptive, StopsAtTheFirstCompleteRoundThatMeetsTheTarget) {
    // First round 2, then 2 more per round: the target 10 % is met at r = 400 (8 realizations,
    // 0.0985) and not at 6 (0.1139).
    const auto spec = spec_of(
        "realizations = 2\ntarget = \"tau\"\ntarget_rel_ci = 0.1\nmax_realizations = 20\n"
        "round_realizations = 2",
        "D_cm = [2.0]");
    ASSERT_EQ(spec.points.size(), 1u);
    EXPECT_EQ(spec.points[0].realizations, 20);  // the plan holds max_realizations
    EXPECT_EQ(spec.points[0].first_round, 2);
    const std::vector<double> cost{1.0};
    for (int stored = 0; stored <= 8; ++stored) {
        const auto s = replay_rounds(spec, {{spec.points[0].label, first_n(stored)}}, cost);
        if (stored == 8) {
            EXPECT_TRUE(s.finished);
            EXPECT_EQ(s.points[0].allotted, 8);
            EXPECT_NE(s.points[0].why.find("target met"), std::string::npos) << s.points[0].why;
        } else {
            ASSERT_FALSE(s.finished) << stored;
            // The round in progress: up to the next even count.
            const int allotted = std::max(2, stored + stored % 2 + (stored % 2 == 0 ? 2 : 0));
            EXPECT_EQ(s.points[0].allotted, stored == 0 ? 2 : allotted) << stored;
            ASSERT_FALSE(s.missing.empty());
            EXPECT_EQ(s.missing.front().second, stored);  // the first index not stored
        }
    }
    // Results beyond the allotment (from an earlier sweep with more realizations) are not used
    // for decisions: 2 stored + index 5 stored is still round 2 missing 2 and 3.
    PointResults gap = first_n(2);
    gap[5] = fake(50);
    const auto s = replay_rounds(spec, {{spec.points[0].label, gap}}, cost);
    ASSERT_EQ(s.missing.size(), 2u);
    EXPECT_EQ(s.missing[0].second, 2);
    EXPECT_EQ(s.missing[1].second, 3);
}

TEST(Adaptive, MaxRealizationsEndsAPointWithoutJams) {
    const auto spec =
        spec_of("realizations = 2\ntarget = \"tau\"\ntarget_rel_ci = 0.1\nmax_realizations = 4",
                "D_cm = [2.0]");
    const auto s = replay_rounds(spec, {{spec.points[0].label, first_n(4, 0)}}, {1.0});
    EXPECT_TRUE(s.finished);
    EXPECT_NE(s.points[0].why.find("max_realizations = 4 reached"), std::string::npos)
        << s.points[0].why;
}

TEST(Adaptive, CheapestInformationFirstWithinARound) {
    // Two points after round 1: A (cost 1) has 100 jams (needs about 8 realizations in all),
    // B (cost 1) has 50 (2 realizations of 25 jams: needs about 16). A's missing come first;
    // with B 10x cheaper, B's come first.
    const auto spec =
        spec_of("realizations = 2\ntarget = \"tau\"\ntarget_rel_ci = 0.1\nmax_realizations = 40",
                "D_cm = [2.0, 2.5]");
    const std::string a = spec.points[0].label, b = spec.points[1].label;
    const std::map<std::string, PointResults> stored{{a, first_n(2, 50)}, {b, first_n(2, 25)}};
    auto s = replay_rounds(spec, stored, {1.0, 1.0});
    ASSERT_EQ(s.missing.size(), 4u);
    EXPECT_EQ(s.missing[0].first, 0);
    EXPECT_EQ(s.missing[3].first, 1);
    s = replay_rounds(spec, stored, {1.0, 0.1});
    EXPECT_EQ(s.missing[0].first, 1);
    EXPECT_EQ(s.missing[3].first, 0);
}

TEST(Adaptive, TheFirstRoundSaysHowMuchOfItIsStored) {
    // Point A has its first round (2) stored, B 1 of 2: A waits for B's, B runs.
    const auto spec =
        spec_of("realizations = 2\ntarget = \"tau\"\ntarget_rel_ci = 0.1\nmax_realizations = 40",
                "D_cm = [2.0, 2.5]");
    const std::string a = spec.points[0].label, b = spec.points[1].label;
    const auto s = replay_rounds(spec, {{a, first_n(2)}, {b, first_n(1)}}, {1.0, 1.0});
    const std::string text = campaign::describe_rounds(s, config::CampaignTarget::Quantity::tau);
    EXPECT_NE(text.find(a + ": 2 realizations; first round stored; decided when every point's "
                            "first round is"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find(b + ": 2 realizations; first round running (1 of 2 stored)"),
              std::string::npos)
        << text;
}

std::string sweep_error(const std::string& keys) {
    try {
        spec_of("realizations = 2\n" + keys, "D_cm = [2.0]");
    } catch (const core::ConfigError& e) {
        return e.what();
    }
    return "(accepted)";
}

TEST(Adaptive, BadTargetsAreRefusedNamingWhatIsAllowed) {
    EXPECT_NE(sweep_error("target = \"time\"\nmax_realizations = 4")
                  .find("use \"tau\" (mean survival time) or \"mean_s\""),
              std::string::npos);
    EXPECT_NE(sweep_error("target = \"tau\"\ntarget_rel_ci = 1.5\nmax_realizations = 4")
                  .find("allowed (0, 1]"),
              std::string::npos);
    EXPECT_NE(sweep_error("target = \"tau\"").find("needs max_realizations"), std::string::npos);
    EXPECT_NE(sweep_error("max_realizations = 4").find("need target"), std::string::npos);
    EXPECT_NE(
        sweep_error("target = \"tau\"\nmax_realizations = 1").find("at most max_realizations"),
        std::string::npos);
}

}  // namespace
