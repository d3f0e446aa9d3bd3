#include "hopper/stats/distributions.hpp"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "hopper/stats/special_functions.hpp"

namespace hopper::stats {

namespace {

void check_dof(double k, const char* fn) {
    if (!(k > 0.0) || !std::isfinite(k))
        throw std::invalid_argument(std::string(fn) + ": degrees of freedom must be > 0, got " +
                                    std::to_string(k));
}

}  // namespace

double normal_cdf(double x) {
    if (std::isnan(x)) throw std::invalid_argument("normal_cdf: x is NaN");
    return 0.5 * std::erfc(-x / std::numbers::sqrt2);
}

double normal_quantile(double p) {
    if (!(p > 0.0 && p < 1.0))
        throw std::invalid_argument("normal_quantile: p must be in (0, 1), got " +
                                    std::to_string(p));
    return boost::math::quantile(boost::math::normal_distribution<double>(), p);
}

double chi2_cdf(double x, double k) {
    check_dof(k, "chi2_cdf");
    if (std::isnan(x)) throw std::invalid_argument("chi2_cdf: x is NaN");
    if (x <= 0.0) return 0.0;
    return gamma_p(0.5 * k, 0.5 * x);
}

double chi2_sf(double x, double k) {
    check_dof(k, "chi2_sf");
    if (std::isnan(x)) throw std::invalid_argument("chi2_sf: x is NaN");
    if (x <= 0.0) return 1.0;
    return gamma_q(0.5 * k, 0.5 * x);
}

double chi2_quantile(double p, double k) {
    check_dof(k, "chi2_quantile");
    return 2.0 * gamma_p_inverse(0.5 * k, p);
}

double kolmogorov_q(double lambda) {
    if (std::isnan(lambda)) throw std::invalid_argument("kolmogorov_q: lambda is NaN");
    if (lambda <= 0.0) return 1.0;
    constexpr double pi = std::numbers::pi;
    if (lambda < 1.18) {
        // K(lambda) = sqrt(2 pi)/lambda sum exp(-(2j-1)^2 pi^2 / (8 lambda^2)).
        const double w = -pi * pi / (8.0 * lambda * lambda);
        double sum = 0.0;
        for (int j = 1; j <= 50; ++j) {
            const double term = std::exp(w * (2 * j - 1) * (2 * j - 1));
            sum += term;
            if (term < 1e-17 * sum) break;
        }
        return std::clamp(1.0 - std::sqrt(2.0 * pi) / lambda * sum, 0.0, 1.0);
    }
    double sum = 0.0;
    double sign = 1.0;
    for (int j = 1; j <= 100; ++j) {
        const double term = std::exp(-2.0 * j * j * lambda * lambda);
        sum += sign * term;
        if (term < 1e-17 * std::abs(sum)) break;
        sign = -sign;
    }
    return std::clamp(2.0 * sum, 0.0, 1.0);
}

double ks_p_value(double D, int n) {
    if (n < 1) throw std::invalid_argument("ks_p_value: n must be >= 1");
    if (!(D >= 0.0 && D <= 1.0))
        throw std::invalid_argument("ks_p_value: D must be in [0, 1], got " + std::to_string(D));
    const double sn = std::sqrt(static_cast<double>(n));
    return kolmogorov_q((sn + 0.12 + 0.11 / sn) * D);
}

double binomial_pmf(int k, int n, double p) {
    if (n < 0 || k < 0 || k > n) throw std::invalid_argument("binomial_pmf: need 0 <= k <= n");
    if (!(p >= 0.0 && p <= 1.0))
        throw std::invalid_argument("binomial_pmf: p must be in [0, 1], got " + std::to_string(p));
    if (p == 0.0) return k == 0 ? 1.0 : 0.0;
    if (p == 1.0) return k == n ? 1.0 : 0.0;
    // C(n, k) p^k (1-p)^(n-k) in logs: lnC = lnGamma(n+1) - lnGamma(k+1) - lnGamma(n-k+1).
    const double log_c = std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0);
    return std::exp(log_c + k * std::log(p) + (n - k) * std::log1p(-p));
}

double binomial_two_sided_p(int k, int n, double p0) {
    const double pk = binomial_pmf(k, n, p0);
    const double limit = pk * (1.0 + 1e-7);
    double sum = 0.0;
    for (int j = 0; j <= n; ++j) {
        const double pj = binomial_pmf(j, n, p0);
        if (pj <= limit) sum += pj;
    }
    return std::min(sum, 1.0);
}

}  // namespace hopper::stats
