// Goodness of fit of the exponential law: size under H0, power against clear alternatives.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/stats/gof.hpp"
#include "hopper/stats/sampling.hpp"

using namespace hopper::stats;
using hopper::core::Rng;

namespace {

constexpr double kAlpha = 0.05;

double gamma4(Rng& rng) {  // Gamma(shape 4, scale 1) as a sum of 4 exponentials
    double s = 0.0;
    for (int i = 0; i < 4; ++i)
        s += draw_exponential(rng, 1.0);
    return s;
}

// Realizations watched for `window` each; intervals drawn from `draw` until the window is used
// up, the last one censored. windows[k] is each realization's flow time.
template <class Draw>
void censored_point(Rng& rng, Draw draw, double window, int realizations, std::vector<double>& t,
                    std::vector<bool>& c, std::vector<double>& windows) {
    t.clear();
    c.clear();
    windows.assign(realizations, window);
    for (int k = 0; k < realizations; ++k) {
        double elapsed = 0.0;
        while (true) {
            const double e = draw(rng);
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

// Binomial tolerance for a rejection rate estimated from `trials`: 3.5 sd of the estimate.
double tolerance(double rate, int trials) {
    return 3.5 * std::sqrt(rate * (1 - rate) / trials);
}

}  // namespace

TEST(GofComplete, SizeOnExponentialSamplesIsAlpha) {
    Rng rng(1);
    const GofOptions opt{199, 99};  // p-values in steps of 1/200; P(p <= 0.05) = 0.05 exactly
    const int trials = 400;
    int rejected = 0;
    std::vector<double> x(50);
    for (int trial = 0; trial < trials; ++trial) {
        for (double& v : x)
            v = draw_exponential(rng, 3.7);
        GofOptions o = opt;
        o.seed = 1000 + trial;
        const GofResult g = ks_exponential(x, o);
        ASSERT_TRUE(g.valid);
        if (g.p_value <= kAlpha) ++rejected;
    }
    const double rate = static_cast<double>(rejected) / trials;
    RecordProperty("rejection_exponential", std::to_string(rate));
    EXPECT_NEAR(rate, kAlpha, tolerance(kAlpha, trials));
}

TEST(GofComplete, RejectsUniformAndGammaFour) {
    Rng rng(2);
    const int trials = 100;
    int rej_uniform = 0, rej_gamma = 0;
    std::vector<double> x(50);
    for (int trial = 0; trial < trials; ++trial) {
        const GofOptions o{199, static_cast<std::uint64_t>(trial)};
        for (double& v : x)
            v = rng.uniform(0.0, 2.0);
        if (ks_exponential(x, o).p_value <= kAlpha) ++rej_uniform;
        for (double& v : x)
            v = gamma4(rng);
        if (ks_exponential(x, o).p_value <= kAlpha) ++rej_gamma;
    }
    RecordProperty("rejection_uniform", std::to_string(rej_uniform / double(trials)));
    RecordProperty("rejection_gamma4", std::to_string(rej_gamma / double(trials)));
    EXPECT_GE(rej_uniform, 85);  // power of the test at n = 50
    EXPECT_GE(rej_gamma, 98);
}

TEST(GofComplete, StatisticByHandAndReproducible) {
    // Mean 2.1, F0 = 1 - e^(-x/2.1); D = max over sorted x_(i) of i/n - F0 and F0 - (i-1)/n.
    const std::vector<double> x = {3.0, 1.0, 2.0, 0.5, 4.0};
    double D = 0.0;
    const std::vector<double> s = {0.5, 1.0, 2.0, 3.0, 4.0};
    for (int i = 0; i < 5; ++i) {
        const double F0 = 1.0 - std::exp(-s[i] / 2.1);
        D = std::max({D, (i + 1) / 5.0 - F0, F0 - i / 5.0});
    }
    const GofResult a = ks_exponential(x), b = ks_exponential(x);
    EXPECT_NEAR(a.statistic, D, 1e-15);
    EXPECT_NEAR(a.tau, 2.1, 1e-15);
    EXPECT_EQ(a.p_value, b.p_value);  // seeded: identical
    EXPECT_FALSE(ks_exponential(std::vector<double>{1.0, 2.0}).valid);
}

TEST(GofCensored, SizeOnCensoredExponentialData) {
    Rng rng(3);
    const int trials = 300;
    int rejected = 0;
    std::vector<double> t, w;
    std::vector<bool> c;
    for (int trial = 0; trial < trials; ++trial) {
        // 15 realizations of 3 tau: ~45 jams, 15 censored intervals.
        censored_point(
            rng, [](Rng& r) { return draw_exponential(r, 2.0); }, 6.0, 15, t, c, w);
        const GofResult g = ks_exponential_censored(t, c, w, {199, 500u + trial});
        ASSERT_TRUE(g.valid) << g.reason;
        if (g.p_value <= kAlpha) ++rejected;
    }
    const double rate = static_cast<double>(rejected) / trials;
    RecordProperty("rejection_censored_exponential", std::to_string(rate));
    EXPECT_NEAR(rate, kAlpha, tolerance(kAlpha, trials));
}

TEST(GofCensored, RejectsCensoredGammaFourAndUniform) {
    Rng rng(4);
    const int trials = 60;
    int rej_gamma = 0, rej_uniform = 0;
    std::vector<double> t, w;
    std::vector<bool> c;
    for (int trial = 0; trial < trials; ++trial) {
        const GofOptions o{199, static_cast<std::uint64_t>(trial)};
        censored_point(rng, gamma4, 16.0, 15, t, c, w);  // ~60 intervals of mean 4
        if (ks_exponential_censored(t, c, w, o).p_value <= kAlpha) ++rej_gamma;
        censored_point(
            rng, [](Rng& r) { return r.uniform(0.0, 2.0); }, 4.0, 15, t, c, w);
        if (ks_exponential_censored(t, c, w, o).p_value <= kAlpha) ++rej_uniform;
    }
    RecordProperty("rejection_censored_gamma4", std::to_string(rej_gamma / double(trials)));
    RecordProperty("rejection_censored_uniform", std::to_string(rej_uniform / double(trials)));
    EXPECT_GE(rej_gamma, 57);
    EXPECT_GE(rej_uniform, 48);
}

// Why the censored test exists: the uncensored intervals of censored exponential data are not an
// exponential sample (each one is known to have ended before its realization did), so the
// complete-sample test applied to them rejects true exponential data far too often when there are
// few jams per realization.
TEST(GofCensored, UncensoredOnlyTestIsBiasedUnderHeavyCensoring) {
    Rng rng(6);
    const int trials = 100;
    int rejected = 0;
    std::vector<double> t, w, unc;
    std::vector<bool> c;
    for (int trial = 0; trial < trials; ++trial) {
        censored_point(
            rng, [](Rng& r) { return draw_exponential(r, 1.0); }, 1.5, 150, t, c, w);
        unc.clear();
        for (std::size_t i = 0; i < t.size(); ++i)
            if (!c[i]) unc.push_back(t[i]);
        if (ks_exponential(unc, {199, static_cast<std::uint64_t>(trial)}).p_value <= kAlpha)
            ++rejected;
    }
    RecordProperty("rejection_uncensored_only", std::to_string(rejected / double(trials)));
    EXPECT_GT(rejected / double(trials), 0.5);
}

TEST(GofCensored, WindowsMustMatchTheIntervals) {
    const std::vector<double> t = {1.0, 2.0, 0.5};
    const std::vector<bool> c = {false, false, true};
    EXPECT_THROW(ks_exponential_censored(t, c, std::vector<double>{2.0}), std::invalid_argument);
    const GofResult g = ks_exponential_censored(t, c, std::vector<double>{3.5});
    EXPECT_FALSE(g.valid);  // 2 jams < kMinGofEvents
    EXPECT_FALSE(g.reason.empty());
}

TEST(LogSurvivalLine, ExactExponentialQuantilesGiveRSquaredOne) {
    // Empirical S(t_(i)) = 1 - i/n; put t_(i) = -tau ln(1 - i/n) so that every point with S > 0
    // lies on ln S = -t/tau exactly (the last one, S = 0, is dropped).
    const int n = 40;
    std::vector<double> t;
    for (int i = 1; i < n; ++i)
        t.push_back(-2.0 * std::log(1.0 - static_cast<double>(i) / n));
    t.push_back(100.0);
    const LogSurvivalLine line = log_survival_line(t, std::vector<bool>(n, false));
    ASSERT_TRUE(line.valid);
    EXPECT_EQ(line.n_points, n - 1);
    EXPECT_NEAR(line.r2, 1.0, 1e-13);
    EXPECT_NEAR(line.slope, -0.5, 1e-13);
    EXPECT_NEAR(line.intercept, 0.0, 1e-12);
    // Gamma(4)-like, strongly curved ln S gives a clearly lower R^2.
    Rng rng(8);
    std::vector<double> g(200);
    for (double& v : g)
        v = gamma4(rng);
    const LogSurvivalLine curved = log_survival_line(g, std::vector<bool>(200, false));
    ASSERT_TRUE(curved.valid);
    EXPECT_LT(curved.r2, 0.98);
}
