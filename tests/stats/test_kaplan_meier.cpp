#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hopper/stats/kaplan_meier.hpp"

using namespace hopper::stats;

TEST(KaplanMeier, HandComputedCurveWithGreenwoodErrors) {
    // Events at 1, 2, 2, 4; censored at 3 and 5 (given out of order).
    const std::vector<double> t = {4.0, 2.0, 5.0, 1.0, 3.0, 2.0};
    const std::vector<bool> c = {false, false, true, false, true, false};
    const KaplanMeierCurve km = kaplan_meier(t, c);
    ASSERT_EQ(km.time.size(), 3u);
    EXPECT_EQ(km.time, (std::vector<double>{1.0, 2.0, 4.0}));
    EXPECT_EQ(km.at_risk, (std::vector<int>{6, 5, 2}));
    EXPECT_EQ(km.events, (std::vector<int>{1, 2, 1}));
    // S = 5/6, 5/6 * 3/5 = 1/2, 1/2 * 1/2 = 1/4.
    EXPECT_DOUBLE_EQ(km.survival[0], 5.0 / 6.0);
    EXPECT_DOUBLE_EQ(km.survival[1], 0.5);
    EXPECT_DOUBLE_EQ(km.survival[2], 0.25);
    // Greenwood sums: 1/30; 1/30 + 2/15 = 1/6; 1/6 + 1/2 = 2/3.
    EXPECT_DOUBLE_EQ(km.std_err[0], 5.0 / 6.0 * std::sqrt(1.0 / 30.0));
    EXPECT_DOUBLE_EQ(km.std_err[1], 0.5 * std::sqrt(1.0 / 6.0));
    EXPECT_DOUBLE_EQ(km.std_err[2], 0.25 * std::sqrt(2.0 / 3.0));
    EXPECT_EQ(km.last_time, 5.0);
}

TEST(KaplanMeier, CensoredTieIsAtRiskAndCompleteSampleIsEmpirical) {
    // A censored interval tied with an event counts as at risk at that event.
    const KaplanMeierCurve tie =
        kaplan_meier(std::vector<double>{1.0, 1.0, 2.0}, std::vector<bool>{false, true, false});
    EXPECT_EQ(tie.at_risk[0], 3);
    EXPECT_DOUBLE_EQ(tie.survival[0], 2.0 / 3.0);
    EXPECT_DOUBLE_EQ(tie.survival[1], 0.0);
    EXPECT_EQ(tie.std_err[1], 0.0);  // S = 0: stored as 0, not 0 * inf
    // Without censoring, S(t_(i)) = 1 - i/n.
    const KaplanMeierCurve full =
        kaplan_meier(std::vector<double>{3.0, 1.0, 2.0, 4.0}, std::vector<bool>(4, false));
    for (int i = 0; i < 4; ++i)
        EXPECT_DOUBLE_EQ(full.survival[i], 1.0 - (i + 1) / 4.0);
}
