#include "hopper/stats/exponential_fit.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "hopper/stats/distributions.hpp"

namespace hopper::stats {

ExponentialFit fit_censored_exponential(std::span<const double> t,
                                        const std::vector<bool>& censored, double confidence) {
    if (t.size() != censored.size())
        throw std::invalid_argument("fit_censored_exponential: " + std::to_string(t.size()) +
                                    " intervals but " + std::to_string(censored.size()) +
                                    " censoring flags");
    if (!(confidence > 0.0 && confidence < 1.0))
        throw std::invalid_argument("fit_censored_exponential: confidence must be in (0, 1)");

    ExponentialFit f;
    f.confidence = confidence;
    f.n_intervals = static_cast<int>(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
        if (!(t[i] >= 0.0) || !std::isfinite(t[i]))
            throw std::invalid_argument("fit_censored_exponential: interval " + std::to_string(i) +
                                        " is negative or not finite");
        f.total_observed_time += t[i];
        if (!censored[i]) ++f.n_uncensored;
    }
    if (f.n_intervals == 0) {
        f.reason = "no survival intervals";
        return f;
    }
    f.mean_all = f.total_observed_time / f.n_intervals;

    const double T = f.total_observed_time;
    const int r = f.n_uncensored;
    if (r == 0) {
        if (T > 0.0) {
            // One-sided bound: P(no jam in T | tau) = exp(-T/tau) >= 1 - c
            //   <=> tau >= T / ln(1/(1-c)) = 2T / chi2_c(2).
            f.tau_lo = 2.0 * T / chi2_quantile(confidence, 2.0);
            f.reason =
                "no uncensored interval (no jam): tau is unbounded above; only the "
                "one-sided lower bound is given";
        } else {
            f.reason = "no uncensored interval and no observed time";
        }
        return f;
    }
    if (T == 0.0) {
        f.reason = "all intervals have zero length: tau = 0 is degenerate";
        return f;
    }
    // tau_hat = T / r (maximum of -r ln tau - T/tau).
    f.tau = T / r;
    // 2T/tau ~ chi2(2r) => P(chi2_{(1-c)/2} <= 2T/tau <= chi2_{(1+c)/2}) = c.
    const double alpha = 1.0 - confidence;
    f.tau_lo = 2.0 * T / chi2_quantile(1.0 - 0.5 * alpha, 2.0 * r);
    f.tau_hi = 2.0 * T / chi2_quantile(0.5 * alpha, 2.0 * r);
    // Var(ln tau_hat) -> 1/r (Fisher information of ln tau is r).
    f.sigma_log_tau = 1.0 / std::sqrt(static_cast<double>(r));
    return f;
}

}  // namespace hopper::stats
