// Censored exponential MLE and its chi-square confidence interval.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/stats/distributions.hpp"
#include "hopper/stats/exponential_fit.hpp"
#include "hopper/stats/sampling.hpp"

using namespace hopper::stats;
using hopper::core::Rng;

namespace {

// One campaign point: `realizations` Poisson processes of jams (mean interval tau) watched for
// `window` seconds each; each realization's last interval is right-censored (type-I, as in the
// engine: the hopper empties after a flow time that does not depend on the jams).
void simulate_point(Rng& rng, double tau, double window, int realizations, std::vector<double>& t,
                    std::vector<bool>& c) {
    t.clear();
    c.clear();
    for (int k = 0; k < realizations; ++k) {
        double elapsed = 0.0;
        while (true) {
            const double e = draw_exponential(rng, tau);
            if (elapsed + e >= window) {
                t.push_back(window - elapsed);
                c.push_back(true);
                break;
            }
            t.push_back(e);
            c.push_back(false);
            elapsed += e;
        }
    }
}

}  // namespace

TEST(ExponentialFit, MleIsTotalTimeOverUncensoredCount) {
    const std::vector<double> t = {1.5, 0.25, 3.0, 2.0, 0.75, 4.5};
    const std::vector<bool> c = {false, false, true, false, false, true};
    const ExponentialFit f = fit_censored_exponential(t, c);
    ASSERT_TRUE(f.tau.has_value());
    EXPECT_EQ(f.n_intervals, 6);
    EXPECT_EQ(f.n_uncensored, 4);
    EXPECT_EQ(f.total_observed_time, 12.0);
    EXPECT_EQ(*f.tau, 12.0 / 4.0);  // exact: T / r
    EXPECT_EQ(*f.mean_all, 12.0 / 6.0);
    // Interval from the pivot with 2r = 8 dof: chi2_{0.975}(8) = 17.5345, chi2_{0.025}(8)
    // = 2.17973.
    EXPECT_NEAR(*f.tau_lo, 24.0 / 17.5345, 1e-4);
    EXPECT_NEAR(*f.tau_hi, 24.0 / 2.17973, 1e-4);
    EXPECT_NEAR(*f.sigma_log_tau, 0.5, 1e-15);
    EXPECT_TRUE(f.reason.empty());
}

TEST(ExponentialFit, MleEqualsTotalOverUncensoredOnRandomSamples) {
    Rng rng(11);
    std::vector<double> t;
    std::vector<bool> c;
    for (int trial = 0; trial < 50; ++trial) {
        simulate_point(rng, 2.0, 7.0, 5, t, c);
        double T = 0.0;
        int r = 0;
        for (std::size_t i = 0; i < t.size(); ++i) {
            T += t[i];
            r += c[i] ? 0 : 1;
        }
        const ExponentialFit f = fit_censored_exponential(t, c);
        EXPECT_NEAR(f.total_observed_time, T, 1e-12 * T);
        EXPECT_NEAR(f.total_observed_time, 5 * 7.0, 1e-9);  // the windows add up to T
        if (r > 0) {
            EXPECT_EQ(*f.tau, f.total_observed_time / r);
        }
    }
}

// Coverage of the 95 % interval over 2000 seeded trials must be 95 +- 2 % (binomial sd 0.49 %,
// so the band is 4 sd wide on each side).
TEST(ExponentialFit, IntervalCoverageTypeOneCensoring) {
    Rng rng(2024);
    const double tau = 1.3;
    std::vector<double> t;
    std::vector<bool> c;
    int covered = 0, trials = 2000;
    for (int trial = 0; trial < trials; ++trial) {
        // 8 realizations of 4 tau each: about 32 jams and 8 censored intervals per point.
        simulate_point(rng, tau, 4.0 * tau, 8, t, c);
        const ExponentialFit f = fit_censored_exponential(t, c);
        ASSERT_TRUE(f.tau_lo && f.tau_hi);
        if (*f.tau_lo <= tau && tau <= *f.tau_hi) ++covered;
    }
    const double coverage = static_cast<double>(covered) / trials;
    RecordProperty("coverage_type_one", std::to_string(coverage));
    EXPECT_NEAR(coverage, 0.95, 0.02);
}

TEST(ExponentialFit, IntervalCoverageFewJamsPerRealization) {
    // Heavy censoring: windows of 0.7 tau, ~0.7 jams per realization and 40 realizations.
    Rng rng(77);
    const double tau = 5.0;
    std::vector<double> t;
    std::vector<bool> c;
    int covered = 0, trials = 2000;
    for (int trial = 0; trial < trials; ++trial) {
        simulate_point(rng, tau, 0.7 * tau, 40, t, c);
        const ExponentialFit f = fit_censored_exponential(t, c);
        ASSERT_TRUE(f.tau_lo && f.tau_hi);
        if (*f.tau_lo <= tau && tau <= *f.tau_hi) ++covered;
    }
    const double coverage = static_cast<double>(covered) / trials;
    RecordProperty("coverage_heavy_censoring", std::to_string(coverage));
    EXPECT_NEAR(coverage, 0.95, 0.02);
}

TEST(ExponentialFit, IntervalCoverageIsExactForTypeTwo) {
    // Complete samples of fixed size r: 2 T / tau ~ chi2(2r) exactly.
    Rng rng(5);
    const double tau = 0.4;
    int covered = 0, trials = 2000;
    for (int trial = 0; trial < trials; ++trial) {
        std::vector<double> t(6);
        for (double& v : t)
            v = draw_exponential(rng, tau);
        const ExponentialFit f = fit_censored_exponential(t, std::vector<bool>(6, false));
        if (*f.tau_lo <= tau && tau <= *f.tau_hi) ++covered;
    }
    EXPECT_NEAR(static_cast<double>(covered) / trials, 0.95, 0.02);
}

TEST(ExponentialFit, NoJamGivesOnlyALowerBound) {
    const ExponentialFit f =
        fit_censored_exponential(std::vector<double>{10.0, 20.0}, std::vector<bool>{true, true});
    EXPECT_FALSE(f.tau.has_value());
    EXPECT_FALSE(f.tau_hi.has_value());
    ASSERT_TRUE(f.tau_lo.has_value());
    // P(no jam in T = 30 s) = exp(-30/tau) >= 0.05  <=>  tau >= 30 / ln 20.
    EXPECT_NEAR(*f.tau_lo, 30.0 / std::log(20.0), 1e-10);
    EXPECT_FALSE(f.reason.empty());
    EXPECT_EQ(*f.mean_all, 15.0);
}

TEST(ExponentialFit, EmptyAndBadInput) {
    const ExponentialFit f = fit_censored_exponential(std::vector<double>{}, std::vector<bool>{});
    EXPECT_FALSE(f.mean_all || f.tau || f.tau_lo || f.tau_hi);
    EXPECT_FALSE(f.reason.empty());
    EXPECT_THROW(fit_censored_exponential(std::vector<double>{1.0}, std::vector<bool>{}),
                 std::invalid_argument);
    EXPECT_THROW(fit_censored_exponential(std::vector<double>{-1.0}, std::vector<bool>{false}),
                 std::invalid_argument);
}
