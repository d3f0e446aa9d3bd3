#pragma once
// Goodness of fit of the exponential survival law.
//
// The Kolmogorov–Smirnov distance is measured against the exponential whose mean was FITTED to
// the same data, so the classical Kolmogorov p-value (distributions.hpp, ks_p_value) would be far
// too large (Lilliefors 1969; Stephens 1974, J. Am. Stat. Assoc. 69, 730). We obtain p-values by
// a parametric bootstrap (Efron & Tibshirani, "An Introduction to the Bootstrap", 1993, ch. 16):
// simulate B data sets from the fitted exponential under the same sampling scheme, refit each,
// recompute the distance, and report
//   p = (1 + #{D_b >= D_obs}) / (B + 1).
// For a complete sample the null law of D is free of the scale (D is invariant under t -> c t), so
// this is the exact Lilliefors test for the exponential up to Monte Carlo error (sd of p at most
// sqrt(p(1-p)/B), 0.007 at p = 0.05 with B = 999). The generator is hopper::core::Rng seeded from
// GofOptions::seed, so the p-value is reproducible bit for bit.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hopper::stats {

// Fewer events than this and no goodness-of-fit test is attempted (the test has no power and
// the bootstrap null law is dominated by the discreteness of tiny samples).
inline constexpr int kMinGofEvents = 5;

struct GofOptions {
    int n_bootstrap = 999;                       // B
    std::uint64_t seed = 0x5eed'0f'600d'f17ULL;  // bootstrap seed (pass a per-point seed)
};

struct GofResult {
    bool valid = false;
    std::string reason;      // why not valid
    std::string method;      // what was computed, in words (for tables and --json)
    int n = 0;               // intervals used
    int n_events = 0;        // uncensored intervals among them
    double tau = 0.0;        // fitted mean of the null exponential (s)
    double statistic = 0.0;  // D
    double p_value = 0.0;    // bootstrap p-value
    int n_bootstrap = 0;
};

// Complete (uncensored) sample x_1..x_n, H0: x_i iid Exp(tau), tau unknown.
//   tau_hat = mean(x);  F0(x) = 1 - exp(-x / tau_hat);
//   D = max_i max( i/n - F0(x_(i)),  F0(x_(i)) - (i-1)/n )     (x_(i) sorted ascending).
// Null law by parametric bootstrap (scale-free, see above). Needs n >= kMinGofEvents.
// Use it for samples without censoring. Applied to only the uncensored intervals of a censored
// campaign it is biased toward rejection: an interval that ends in a jam before its realization
// ends is, given that, shorter than an exponential one. Prefer ks_exponential_censored there.
GofResult ks_exponential(std::span<const double> x, const GofOptions& opt = {});

// Censored intervals from several realizations, H0: jams form a Poisson process of rate 1/tau in
// flowing time, each realization being watched for its flow time W_k (its "window"), which ends
// its last interval (right-censored). The distance is the Kolmogorov–Smirnov-type sup distance
// between the Kaplan–Meier estimate and the fitted exponential survival function,
//   D = sup_{0 <= t <= t_max} | S_KM(t) - exp(-t / tau_hat) |,   tau_hat = T / r (censored MLE),
// over the range where S_KM is defined (t_max = largest observed interval). The bootstrap
// replays the same windows: for each W_k, Exp(tau_hat) intervals until the window is used up, the
// last one censored; replicates with fewer than kMinGofEvents events are redrawn (the observed
// data are conditioned on the same). This reproduces the censoring, unlike a test on the
// uncensored intervals alone.
//
// t, censored: all intervals (any order); windows: the flow time of each realization (s), which
// must sum to sum(t) (relative tolerance 1e-6) — i.e. each realization's window is the sum of its
// intervals. A realization stopped at an unclearable jam (arrested) ends in an event rather than
// a censored interval; the bootstrap treats its window like any other (a small approximation).
GofResult ks_exponential_censored(std::span<const double> t, const std::vector<bool>& censored,
                                  std::span<const double> windows, const GofOptions& opt = {});

// What published studies quote: the straight line ln S(t) = a + b t fitted by ordinary least
// squares to the points (t_j, ln S(t_j)) of the empirical survival function (Kaplan–Meier, which
// is 1 - i/n at the i-th sorted interval when nothing is censored; points with S = 0 dropped), and
// its coefficient of determination R^2 = 1 - SS_res / SS_tot. Descriptive only: R^2 close to 1 is
// weak evidence (the points are cumulative, hence strongly correlated); use the p-value to test.
struct LogSurvivalLine {
    bool valid = false;
    std::string reason;
    int n_points = 0;
    double r2 = 0.0;
    double slope = 0.0;      // b (1/s); -1/slope estimates tau when the law is exponential
    double intercept = 0.0;  // a (0 for an exact exponential)
};
LogSurvivalLine log_survival_line(std::span<const double> t, const std::vector<bool>& censored);

}  // namespace hopper::stats
