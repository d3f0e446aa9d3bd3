#include "hopper/stats/special_functions.hpp"

#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hopper::stats {

namespace {

void check_a(double a, const char* fn) {
    if (!(a > 0.0) || !std::isfinite(a))
        throw std::invalid_argument(std::string(fn) + ": a must be finite and > 0, got " +
                                    std::to_string(a));
}

void check_args(double a, double x, const char* fn) {
    check_a(a, fn);
    if (!(x >= 0.0))  // also rejects NaN
        throw std::invalid_argument(std::string(fn) + ": x must be >= 0, got " + std::to_string(x));
}

}  // namespace

double gamma_p(double a, double x) {
    check_args(a, x, "gamma_p");
    if (std::isinf(x)) return 1.0;
    return boost::math::gamma_p(a, x);
}

double gamma_q(double a, double x) {
    check_args(a, x, "gamma_q");
    if (std::isinf(x)) return 0.0;
    return boost::math::gamma_q(a, x);
}

double gamma_p_inverse(double a, double p) {
    check_a(a, "gamma_p_inverse");
    if (!(p >= 0.0 && p <= 1.0))
        throw std::invalid_argument("gamma_p_inverse: p must be in [0, 1], got " +
                                    std::to_string(p));
    if (p == 0.0) return 0.0;
    if (p == 1.0) return std::numeric_limits<double>::infinity();  // Boost reports an overflow
    return boost::math::gamma_p_inv(a, p);
}

}  // namespace hopper::stats
