// Special and distribution functions against closed forms and tabulated values.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "hopper/stats/distributions.hpp"
#include "hopper/stats/special_functions.hpp"

using namespace hopper::stats;

TEST(IncompleteGamma, ClosedFormsForAOneAndAHalf) {
    // P(1, x) = 1 - e^-x;  P(1/2, x) = erf(sqrt x). Both branches (series x < a+1, fraction above).
    for (double x : {1e-6, 0.1, 0.9, 1.5, 3.0, 10.0, 40.0}) {
        EXPECT_NEAR(gamma_p(1.0, x), -std::expm1(-x), 1e-14) << x;
        EXPECT_NEAR(gamma_q(1.0, x) / std::exp(-x), 1.0, 1e-12) << x;
        EXPECT_NEAR(gamma_p(0.5, x), std::erf(std::sqrt(x)), 1e-14) << x;
    }
}

TEST(IncompleteGamma, IntegerAMatchesPoissonSums) {
    // For integer a: Q(a, x) = P(Poisson(x) <= a - 1) = e^-x sum_{j<a} x^j/j!  (values from the
    // finite sums).
    EXPECT_NEAR(gamma_q(10.0, 5.0), 0.968171942693795, 1e-13);
    EXPECT_NEAR(gamma_p(3.0, 0.5), 0.0143876779669706, 1e-14);
    EXPECT_NEAR(gamma_q(100.0, 100.0), 0.486701201720851335, 1e-14);
    // Large a (Stirling-series prefactor); references from the Poisson sums in 50-digit decimals.
    EXPECT_NEAR(gamma_q(1000.0, 1000.0), 0.495794755819784491, 1e-14);
    EXPECT_NEAR(gamma_q(1000.0, 1100.0) / 0.00105932325392997735, 1.0, 1e-12);
    EXPECT_NEAR(gamma_p(5000.0, 4800.0) / (1.0 - 0.997897204519269527), 1.0, 1e-11);
    // Deep upper tail, where 1 - P would lose every digit: relative accuracy.
    EXPECT_NEAR(gamma_q(30.0, 60.0) / 6.87626496873209e-06, 1.0, 1e-10);
    EXPECT_NEAR(gamma_p(7.5, 3.0) + gamma_q(7.5, 3.0), 1.0, 1e-15);
}

TEST(IncompleteGamma, InverseRoundTripsAndRejectsBadInput) {
    for (double a : {0.05, 0.5, 1.0, 2.5, 10.0, 99.9, 100.0, 5000.0, 1e5})
        for (double p : {1e-10, 1e-4, 0.025, 0.3, 0.5, 0.9, 0.975, 0.999999}) {
            const double x = gamma_p_inverse(a, p);
            // The round trip is as good as P itself (special_functions.hpp): 1e-13 up to
            // a = 1e4, 1e-12 beyond.
            const double tol = (a <= 1e4 ? 1e-13 : 1e-12) * std::max(p, 1e-3);
            EXPECT_NEAR(gamma_p(a, x), p, tol) << "a=" << a << " p=" << p;
        }
    EXPECT_EQ(gamma_p_inverse(2.0, 0.0), 0.0);
    EXPECT_TRUE(std::isinf(gamma_p_inverse(2.0, 1.0)));
    EXPECT_THROW(gamma_p(-1.0, 1.0), std::invalid_argument);
    EXPECT_THROW(gamma_p(1.0, -1.0), std::invalid_argument);
    EXPECT_THROW(gamma_p(1.0, std::nan("")), std::invalid_argument);
    EXPECT_THROW(gamma_p_inverse(1.0, 1.5), std::invalid_argument);
}

TEST(ChiSquare, QuantilesMatchTables) {
    // Tabulated (e.g. Abramowitz & Stegun table 26.8); 2 dof is exact: -2 ln(1 - p).
    EXPECT_NEAR(chi2_quantile(0.975, 2), 2.0 * std::log(40.0), 1e-12);
    EXPECT_NEAR(chi2_quantile(0.975, 2), 7.3778, 5e-5);
    EXPECT_NEAR(chi2_quantile(0.025, 2), 0.050636, 5e-7);
    EXPECT_NEAR(chi2_quantile(0.975, 20), 34.170, 5e-4);
    EXPECT_NEAR(chi2_quantile(0.025, 20), 9.5908, 5e-5);
    EXPECT_NEAR(chi2_quantile(0.95, 1), 3.841459, 1e-6);
    EXPECT_NEAR(chi2_quantile(0.99, 10), 23.2093, 1e-4);
    EXPECT_NEAR(chi2_quantile(0.005, 100), 67.3276, 1e-4);
    EXPECT_NEAR(chi2_cdf(3.841459, 1), 0.95, 1e-7);
    EXPECT_NEAR(chi2_sf(23.2093, 10), 0.01, 1e-6);
}

TEST(Normal, DistributionAndQuantile) {
    EXPECT_NEAR(normal_cdf(0.0), 0.5, 1e-16);
    EXPECT_NEAR(normal_cdf(-3.0), 0.0013498980316301, 1e-16);
    EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 1e-13);
    EXPECT_NEAR(normal_quantile(0.8413447460685429), 1.0, 1e-13);
    EXPECT_NEAR(normal_quantile(1e-10), -6.361340902404056, 1e-10);
    EXPECT_NEAR(normal_quantile(0.5), 0.0, 1e-15);
    EXPECT_THROW(normal_quantile(0.0), std::invalid_argument);
}

TEST(Kolmogorov, TabulatedCriticalValues) {
    // Asymptotic critical values of sqrt(n) D: 1.2238 (10 %), 1.3581 (5 %), 1.6276 (1 %).
    EXPECT_NEAR(kolmogorov_q(1.36), 0.0494, 2e-4);
    EXPECT_NEAR(kolmogorov_q(1.3581), 0.05, 1e-4);
    EXPECT_NEAR(kolmogorov_q(1.2238), 0.10, 1e-4);
    EXPECT_NEAR(kolmogorov_q(1.6276), 0.01, 1e-4);
    EXPECT_NEAR(kolmogorov_q(0.5), 0.9639452436648751, 1e-12);
    EXPECT_EQ(kolmogorov_q(0.0), 1.0);
    // The two series agree where the implementation switches between them.
    // (slope dQ/dlambda ~ -0.6 there, so 1e-12 apart they differ by ~1e-12 if both are right).
    EXPECT_NEAR(kolmogorov_q(1.18 - 1e-12), kolmogorov_q(1.18 + 1e-12), 1e-11);
}

TEST(Binomial, PmfAndExactTwoSidedTest) {
    EXPECT_NEAR(binomial_pmf(2, 4, 0.5), 6.0 / 16.0, 1e-15);
    EXPECT_NEAR(binomial_pmf(0, 10, 0.3), std::pow(0.7, 10), 1e-15);
    EXPECT_NEAR(binomial_two_sided_p(0, 10, 0.5), 2.0 / 1024.0, 1e-15);
    EXPECT_NEAR(binomial_two_sided_p(5, 10, 0.5), 1.0, 1e-15);
    // n = 10, p0 = 0.5, k = 2: P(X <= 2) + P(X >= 8) = 2 (1 + 10 + 45) / 1024.
    EXPECT_NEAR(binomial_two_sided_p(2, 10, 0.5), 112.0 / 1024.0, 1e-14);
}
