// Beverloo fit: exact recovery, recovery within stated errors, coverage of the errors.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/stats/beverloo.hpp"
#include "hopper/stats/sampling.hpp"

using namespace hopper::stats;
using hopper::core::Rng;

namespace {

constexpr double kC = 0.72, kK = 1.45;   // true parameters
constexpr double kD = 4e-3, kRho = 8.0;  // particle diameter (m), 2D bulk density (kg/m^2)
constexpr double kG = 9.81;

std::vector<double> outlets() {  // 3 d ... 10 d
    std::vector<double> D;
    for (int i = 0; i < 8; ++i)
        D.push_back((3.0 + i) * kD);
    return D;
}

double beverloo(double D) {
    return kC * kRho * std::sqrt(kG) * std::pow(D - kK * kD, 1.5);
}

}  // namespace

TEST(Beverloo, NoiseFreeDataAreRecoveredExactly) {
    const auto D = outlets();
    std::vector<double> W;
    for (double x : D)
        W.push_back(beverloo(x));
    const BeverlooFit f = fit_beverloo(D, W, {}, kRho, kD);
    ASSERT_TRUE(f.valid) << f.reason;
    EXPECT_NEAR(f.C, kC, 1e-9);
    EXPECT_NEAR(f.k, kK, 1e-8);
    EXPECT_EQ(f.n_points, 8);
    EXPECT_EQ(f.dof, 6);
}

TEST(Beverloo, NoisyDataWithinThreeSigma) {
    Rng rng(41);
    const auto D = outlets();
    std::vector<double> W, s;
    for (double x : D) {
        s.push_back(0.03 * beverloo(x));
        W.push_back(beverloo(x) + s.back() * draw_normal(rng));
    }
    const BeverlooFit f = fit_beverloo(D, W, s, kRho, kD);
    ASSERT_TRUE(f.valid) << f.reason;
    EXPECT_LT(std::abs(f.C - kC), 3.0 * f.C_err);
    EXPECT_LT(std::abs(f.k - kK), 3.0 * f.k_err);
    EXPECT_GT(f.C_err, 0.0);
    // A larger k shrinks D - k d, which a larger C compensates: the estimates correlate positively.
    EXPECT_GT(f.corr_Ck, 0.0);
    EXPECT_LT(f.corr_Ck, 1.0);
}

// Over many trials the stated errors must be right: with absolute sigmas the standardized error
// is ~N(0,1) (95 % within 1.96 sigma); with residual-variance scaling and 6 dof it is ~Student t6
// (P(|t6| < 1.96) = 0.902). 500 trials: binomial sd ~1 %, tolerance 3.5 sd.
TEST(Beverloo, StatedErrorsHaveTheRightCoverage) {
    Rng rng(42);
    const auto D = outlets();
    const int trials = 500;
    int abs_C = 0, abs_k = 0, rel_C = 0, rel_k = 0;
    std::vector<double> W(D.size()), s(D.size());
    for (int trial = 0; trial < trials; ++trial) {
        for (std::size_t i = 0; i < D.size(); ++i) {
            s[i] = 0.03 * beverloo(D[i]);
            W[i] = beverloo(D[i]) + s[i] * draw_normal(rng);
        }
        const BeverlooFit a = fit_beverloo(D, W, s, kRho, kD, {kG, true});
        const BeverlooFit r = fit_beverloo(D, W, s, kRho, kD, {kG, false});
        ASSERT_TRUE(a.valid && r.valid);
        abs_C += std::abs(a.C - kC) < 1.96 * a.C_err;
        abs_k += std::abs(a.k - kK) < 1.96 * a.k_err;
        rel_C += std::abs(r.C - kC) < 1.96 * r.C_err;
        rel_k += std::abs(r.k - kK) < 1.96 * r.k_err;
    }
    RecordProperty("coverage_abs_C", std::to_string(abs_C / double(trials)));
    RecordProperty("coverage_abs_k", std::to_string(abs_k / double(trials)));
    RecordProperty("coverage_rel_C", std::to_string(rel_C / double(trials)));
    RecordProperty("coverage_rel_k", std::to_string(rel_k / double(trials)));
    const double tol95 = 3.5 * std::sqrt(0.95 * 0.05 / trials);
    const double tol90 = 3.5 * std::sqrt(0.902 * 0.098 / trials);
    EXPECT_NEAR(abs_C / double(trials), 0.95, tol95);
    EXPECT_NEAR(abs_k / double(trials), 0.95, tol95);
    EXPECT_NEAR(rel_C / double(trials), 0.902, tol90);
    EXPECT_NEAR(rel_k / double(trials), 0.902, tol90);
}

TEST(Beverloo, RefusesTooFewPointsAndNonsense) {
    const std::vector<double> D = {0.02, 0.03}, W = {1.0, 2.0};
    const BeverlooFit f = fit_beverloo(D, W, {}, kRho, kD);
    EXPECT_FALSE(f.valid);
    EXPECT_NE(f.reason.find("too few"), std::string::npos);
    const std::vector<double> D3 = {0.02, 0.03, 0.04}, Wdown = {3.0, 2.0, 1.0};
    EXPECT_FALSE(fit_beverloo(D3, Wdown, {}, kRho, kD).valid);
    const std::vector<double> Wbad = {1.0, 2.0, std::nan("")};
    EXPECT_THROW(fit_beverloo(D3, Wbad, {}, kRho, kD), std::invalid_argument);
}
