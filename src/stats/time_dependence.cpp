#include "hopper/stats/time_dependence.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hopper/stats/distributions.hpp"

namespace hopper::stats {

namespace {

// Length of the overlap of [a0, a1) and [b0, b1).
double overlap(double a0, double a1, double b0, double b1) {
    return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

}  // namespace

EarlyLateTest early_late_rate_test(std::span<const JamHistory> histories, double split) {
    if (!(split > 0.0 && split < 1.0))
        throw std::invalid_argument("early_late_rate_test: split must be in (0, 1)");
    EarlyLateTest r;
    r.split = split;
    for (std::size_t k = 0; k < histories.size(); ++k) {
        const JamHistory& h = histories[k];
        const std::string where = "early_late_rate_test: realization " + std::to_string(k) + ": ";
        if (!(h.window > 0.0) || !std::isfinite(h.window))
            throw std::invalid_argument(where + "window must be finite and > 0");
        const double cut = split * h.window;
        double early = cut, late = h.window - cut;
        for (const auto& [a, b] : h.not_at_risk) {
            if (!(a >= 0.0 && b >= a && b <= h.window))
                throw std::invalid_argument(where + "not-at-risk period outside [0, window]");
            early -= overlap(a, b, 0.0, cut);
            late -= overlap(a, b, cut, h.window);
        }
        r.exposure_early += std::max(early, 0.0);
        r.exposure_late += std::max(late, 0.0);
        for (double t : h.onsets) {
            if (!(t >= 0.0 && t <= h.window))
                throw std::invalid_argument(where + "jam onset outside [0, window]");
            (t < cut ? r.n_early : r.n_late) += 1;
        }
    }
    if (r.exposure_early > 0.0) r.rate_early = r.n_early / r.exposure_early;
    if (r.exposure_late > 0.0) r.rate_late = r.n_late / r.exposure_late;
    const int N = r.n_early + r.n_late;
    if (N == 0) {
        r.reason = "no jams: nothing to compare";
        return r;
    }
    if (r.exposure_early <= 0.0 || r.exposure_late <= 0.0) {
        r.reason = "no exposure in the early or the late part";
        return r;
    }
    const double p0 = r.exposure_early / (r.exposure_early + r.exposure_late);
    r.p_value = binomial_two_sided_p(r.n_early, N, p0);

    // G = 2 sum O ln(O / E) over the two cells, E = N p0 and N (1 - p0).
    auto cell = [](int o, double e) { return o > 0 ? o * std::log(o / e) : 0.0; };
    r.lr_statistic =
        std::max(0.0, 2.0 * (cell(r.n_early, N * p0) + cell(r.n_late, N * (1.0 - p0))));
    r.p_value_lr = chi2_sf(r.lr_statistic, 1.0);

    if (r.n_early > 0 && r.n_late > 0) {
        const double rr = *r.rate_late / *r.rate_early;
        const double se = std::sqrt(1.0 / r.n_early + 1.0 / r.n_late);
        const double z = normal_quantile(0.975);
        r.rate_ratio = rr;
        r.rate_ratio_lo = rr * std::exp(-z * se);
        r.rate_ratio_hi = rr * std::exp(z * se);
    }
    r.valid = true;
    return r;
}

}  // namespace hopper::stats
