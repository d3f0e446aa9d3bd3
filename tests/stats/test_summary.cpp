#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hopper/stats/summary.hpp"

using namespace hopper::stats;

TEST(Summary, MeanStdAndStandardError) {
    const std::vector<double> x = {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0};
    const SampleSummary s = summarize(x);
    EXPECT_EQ(s.n, 8);
    EXPECT_DOUBLE_EQ(*s.mean, 5.0);
    // sum of squared deviations = 32, s^2 = 32/7.
    EXPECT_DOUBLE_EQ(*s.std_dev, std::sqrt(32.0 / 7.0));
    EXPECT_DOUBLE_EQ(*s.std_err, std::sqrt(32.0 / 7.0) / std::sqrt(8.0));
}

TEST(Summary, TooFewValuesGiveReasonsNotNumbers) {
    const SampleSummary one = summarize(std::vector<double>{3.0});
    EXPECT_DOUBLE_EQ(*one.mean, 3.0);
    EXPECT_FALSE(one.std_dev || one.std_err);
    EXPECT_FALSE(one.reason.empty());
    const SampleSummary none = summarize(std::vector<double>{});
    EXPECT_FALSE(none.mean);
    EXPECT_FALSE(none.reason.empty());
    EXPECT_THROW(summarize(std::vector<double>{1.0, std::nan("")}), std::invalid_argument);
}
