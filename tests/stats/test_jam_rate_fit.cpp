// Jam rate versus outlet: exponential versus power-law divergence, compared by AIC.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/stats/jam_rate_fit.hpp"
#include "hopper/stats/sampling.hpp"

using namespace hopper::stats;
using hopper::core::Rng;

namespace {

std::vector<double> outlets(int n) {  // 1.0 cm ... in 0.5 cm steps
    std::vector<double> D;
    for (int i = 0; i < n; ++i)
        D.push_back(0.010 + 0.005 * i);
    return D;
}

}  // namespace

TEST(JamRateFit, ExactExponentialIsPreferredAndRecovered) {
    const double A = 40.0, B = 150.0;  // 1/s, 1/m
    const auto D = outlets(6);
    std::vector<double> rate, sig(D.size(), 0.1);
    for (double x : D)
        rate.push_back(A * std::exp(-B * x));
    const JamRateFits f = fit_jam_rate(D, rate, sig);
    ASSERT_TRUE(f.exponential.valid);
    EXPECT_NEAR(f.exponential.ln_A, std::log(A), 1e-9);
    EXPECT_NEAR(f.exponential.B, B, 1e-7);
    EXPECT_NEAR(f.exponential.chi2, 0.0, 1e-12);
    EXPECT_EQ(f.preferred, "exponential");
    EXPECT_FALSE(f.power_law.valid);  // its best Dc runs off to infinity
    EXPECT_FALSE(f.power_law.reason.empty());
}

TEST(JamRateFit, NoisyExponentialWithinStatedErrors) {
    Rng rng(51);
    const double A = 40.0, B = 150.0;
    const auto D = outlets(7);
    std::vector<double> rate, sig;
    for (double x : D) {
        sig.push_back(0.15);
        rate.push_back(A * std::exp(-B * x + 0.15 * draw_normal(rng)));
    }
    const JamRateFits f = fit_jam_rate(D, rate, sig);
    ASSERT_TRUE(f.exponential.valid);
    EXPECT_LT(std::abs(f.exponential.B - B), 3.0 * f.exponential.B_err);
    EXPECT_LT(std::abs(f.exponential.ln_A - std::log(A)), 3.0 * f.exponential.ln_A_err);
    EXPECT_NE(f.preferred, "power_law");
}

TEST(JamRateFit, ExactPowerLawIsPreferredAndRecovered) {
    const double A = 2e5, gamma = 2.5, Dc = 0.050;
    const auto D = outlets(7);  // up to 4 cm, Dc = 5 cm
    std::vector<double> rate, sig(D.size(), 0.05);
    for (double x : D)
        rate.push_back(A * std::pow(Dc - x, gamma));
    const JamRateFits f = fit_jam_rate(D, rate, sig);
    ASSERT_TRUE(f.power_law.valid) << f.power_law.reason;
    EXPECT_NEAR(f.power_law.Dc, Dc, 1e-7);
    EXPECT_NEAR(f.power_law.gamma, gamma, 1e-5);
    EXPECT_NEAR(f.power_law.ln_A, std::log(A), 1e-4);
    EXPECT_GT(f.power_law.Dc_err, 0.0);
    EXPECT_EQ(f.preferred, "power_law");
    EXPECT_TRUE(f.has_delta_aic);
    EXPECT_LT(f.delta_aic, -2.0);
}

TEST(JamRateFit, TooFewPointsToDecide) {
    const auto D = outlets(4);
    std::vector<double> rate, sig(D.size(), 0.1);
    for (double x : D)
        rate.push_back(40.0 * std::exp(-150.0 * x));
    const JamRateFits f = fit_jam_rate(D, rate, sig);
    EXPECT_TRUE(f.exponential.valid);
    EXPECT_EQ(f.preferred, "undecided");
    EXPECT_NE(f.decision.find("too few points to decide"), std::string::npos);
    const auto D2 = outlets(2);
    const JamRateFits g =
        fit_jam_rate(D2, std::vector<double>{1.0, 0.5}, std::vector<double>{0.1, 0.1});
    EXPECT_FALSE(g.exponential.valid);
    EXPECT_FALSE(g.power_law.valid);
    const JamRateFits z =
        fit_jam_rate(D2, std::vector<double>{1.0, 0.0}, std::vector<double>{0.1, 0.1});
    EXPECT_FALSE(z.exponential.valid);
    EXPECT_FALSE(z.decision.empty());
}
