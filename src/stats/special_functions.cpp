#include "hopper/stats/special_functions.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hopper::stats {

namespace {

constexpr double kEps = 1e-16;    // relative accuracy targeted by the series and fraction
constexpr double kTiny = 1e-300;  // Lentz's guard against a zero denominator
constexpr int kMaxTerms = 100000;

void check_args(double a, double x, const char* fn) {
    if (!(a > 0.0) || !std::isfinite(a))
        throw std::invalid_argument(std::string(fn) + ": a must be finite and > 0, got " +
                                    std::to_string(a));
    if (!(x >= 0.0))  // also rejects NaN
        throw std::invalid_argument(std::string(fn) + ": x must be >= 0, got " + std::to_string(x));
}

// log of the common prefactor e^(-x) x^a / Gamma(a).
// Formed directly, the terms -x, a ln x and ln Gamma(a) are each ~a ln a and cancel, losing
// ~eps a ln a. For large a we use Stirling's series (A&S 6.1.41) instead,
//   ln Gamma(a+1) = (a + 1/2) ln a - a + ln(2 pi)/2 + 1/(12a) - 1/(360a^3) + 1/(1260a^5) - ...,
// which gives with t = (x - a)/a
//   ln(e^-x x^a / Gamma(a)) = ln a - a (t - ln(1 + t)) - ln(2 pi a)/2 - [series],
// where nothing large cancels (the error is ~eps |x - a|).
double log_prefactor(double a, double x) {
    if (a < 100.0) return -x + a * std::log(x) - std::lgamma(a);
    const double t = (x - a) / a;
    const double ia = 1.0 / a, ia2 = ia * ia;
    const double series = ia * (1.0 / 12 - ia2 * (1.0 / 360 - ia2 * (1.0 / 1260 - ia2 / 1680)));
    return std::log(a) - a * (t - std::log1p(t)) - 0.5 * std::log(2.0 * std::numbers::pi * a) -
           series;
}

// P(a, x) by the series A&S 6.5.29; meant for x < a + 1 where it converges quickly.
double p_series(double a, double x) {
    double term = 1.0 / a;  // x^0 / a
    double sum = term;
    for (int n = 1; n < kMaxTerms; ++n) {
        term *= x / (a + n);
        sum += term;
        if (std::abs(term) < std::abs(sum) * kEps) break;
    }
    return sum * std::exp(log_prefactor(a, x));
}

// Q(a, x) by the continued fraction A&S 6.5.31 (modified Lentz); meant for x >= a + 1.
// Written as b0 + a1/(b1 + a2/(b2 + ...)) with b_n = x + 2n + 1 - a, a_n = -n (n - a).
double q_fraction(double a, double x) {
    double b = x + 1.0 - a;
    double c = 1.0 / kTiny;
    double d = 1.0 / b;
    double h = d;
    for (int n = 1; n < kMaxTerms; ++n) {
        const double an = -n * (n - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1.0) < kEps) break;
    }
    return std::exp(log_prefactor(a, x)) * h;
}

}  // namespace

double gamma_p(double a, double x) {
    check_args(a, x, "gamma_p");
    if (x == 0.0) return 0.0;
    if (std::isinf(x)) return 1.0;
    if (x < a + 1.0) return p_series(a, x);
    return 1.0 - q_fraction(a, x);
}

double gamma_q(double a, double x) {
    check_args(a, x, "gamma_q");
    if (x == 0.0) return 1.0;
    if (std::isinf(x)) return 0.0;
    if (x < a + 1.0) return 1.0 - p_series(a, x);
    return q_fraction(a, x);
}

double gamma_p_inverse(double a, double p) {
    if (!(a > 0.0) || !std::isfinite(a))
        throw std::invalid_argument("gamma_p_inverse: a must be finite and > 0, got " +
                                    std::to_string(a));
    if (!(p >= 0.0 && p <= 1.0))
        throw std::invalid_argument("gamma_p_inverse: p must be in [0, 1], got " +
                                    std::to_string(p));
    if (p == 0.0) return 0.0;
    if (p == 1.0) return std::numeric_limits<double>::infinity();

    // Starting point. Wilson–Hilferty (A&S 26.4.17) for chi^2 with nu = 2a degrees of freedom:
    //   chi2_p ~ nu (1 - 2/(9 nu) + z_p sqrt(2/(9 nu)))^3, and x = chi2_p / 2.
    // z_p, the standard normal quantile, from the rational approximation
    // A&S 26.2.23 (|error| < 4.5e-4), good enough for a starting point.
    const double q = p < 0.5 ? p : 1.0 - p;
    const double t = std::sqrt(-2.0 * std::log(q));
    double z = t - (2.515517 + 0.802853 * t + 0.010328 * t * t) /
                       (1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t);
    if (p < 0.5) z = -z;
    const double nu = 2.0 * a;
    const double wh = 1.0 - 2.0 / (9.0 * nu) + z * std::sqrt(2.0 / (9.0 * nu));
    double x = wh > 0.0 ? 0.5 * nu * wh * wh * wh : 0.0;
    if (!(x > 0.0)) {
        // Small-x limit P(a, x) ~ x^a / Gamma(a + 1).
        x = std::exp((std::log(p) + std::lgamma(a + 1.0)) / a);
    }

    // Bracket [lo, hi] with P(lo) <= p <= P(hi).
    double lo = 0.0;
    double hi = std::max(x, 1.0);
    while (gamma_p(a, hi) < p) {
        lo = hi;
        hi *= 2.0;
    }

    for (int it = 0; it < 200; ++it) {
        const double f = gamma_p(a, x) - p;
        if (f == 0.0) return x;
        if (f < 0.0)
            lo = std::max(lo, x);
        else
            hi = std::min(hi, x);
        // Newton step with dP/dx = x^(a-1) e^(-x) / Gamma(a).
        const double dfdx = std::exp(log_prefactor(a, x)) / x;
        double next = (dfdx > 0.0 && std::isfinite(dfdx)) ? x - f / dfdx : lo - 1.0;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // bisection safeguard
        if (std::abs(next - x) <= 1e-15 * std::max(next, 1e-300) || hi - lo <= 1e-15 * hi)
            return next;
        x = next;
    }
    return x;
}

}  // namespace hopper::stats
