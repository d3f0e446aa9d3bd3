#pragma once
// Maximum-likelihood mean of an exponential survival-time law from right-censored intervals.
//
// Model: each survival interval (flow start -> jam) is Exp(tau); a realization's last interval
// is right-censored (the hopper emptied or the run stopped while flowing). With r uncensored
// intervals and total observed time T = sum of ALL intervals, the log-likelihood is
//   ln L(tau) = -r ln tau - T / tau,   maximized by   tau_hat = T / r.
// (Lawless, "Statistical Models and Methods for Lifetime Data", 2nd ed. 2003, sec. 2.2;
//  Cox & Oakes, "Analysis of Survival Data", 1984, ch. 3.)

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace hopper::stats {

struct ExponentialFit {
    int n_intervals = 0;               // all intervals, censored or not
    int n_uncensored = 0;              // r: intervals that ended in a jam
    double total_observed_time = 0.0;  // T = sum of all intervals (s)
    // Algebraic mean over ALL intervals, sum t_i / n, as published studies report it. Censored
    // intervals are shorter than the survival time they hide, so this is biased low whenever
    // censoring matters (when the hopper empties after few jams).
    std::optional<double> mean_all;
    std::optional<double> tau;            // MLE tau_hat = T / r            (r >= 1)
    std::optional<double> tau_lo;         // lower confidence limit          (r >= 1, or the
                                          //   one-sided bound when r = 0 and T > 0)
    std::optional<double> tau_hi;         // upper confidence limit          (r >= 1)
    std::optional<double> sigma_log_tau;  // large-sample s.e. of ln tau_hat = 1/sqrt(r)
    double confidence = 0.95;
    std::string reason;  // why a field is missing; empty when all are set
};

// Fits tau by maximum likelihood with a confidence interval from the chi-square pivot
//   2 T / tau ~ chi2(2r):   [ 2T / chi2_{(1+c)/2}(2r),  2T / chi2_{(1-c)/2}(2r) ].
// The pivot is EXACT for type-II censoring (observation stops at the r-th failure) and for a
// fixed number r of complete intervals; for our time-truncated (type-I-like) censoring, where
// each realization is watched for a flow time fixed by the discharge and r is random, it is the
// standard approximation (Lawless 2003, sec. 2.2; Cox & Oakes 1984, sec. 3.2). Its coverage for
// that case is measured in tests/stats/test_exponential_fit.cpp. With r = 0 the likelihood has no
// maximum: only the one-sided bound tau > 2T / chi2_c(2) = T / ln(1/(1-c)) is given (the largest
// tau for which seeing no jam in T has probability >= 1 - c).
//
// t: interval lengths (s, finite, >= 0); censored[i]: interval i is right-censored.
// confidence in (0, 1). Sizes must match. Bad input throws std::invalid_argument.
ExponentialFit fit_censored_exponential(std::span<const double> t,
                                        const std::vector<bool>& censored,
                                        double confidence = 0.95);

}  // namespace hopper::stats
