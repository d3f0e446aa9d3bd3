#pragma once
// The regularized incomplete gamma functions and the inverse of P, as the statistics layer uses
// them (chi-square distribution, distributions.hpp). Computed by Boost.Math (header-only, used in
// special_functions.cpp only, so this header needs no Boost); until issue 17 they were written
// here by hand (A&S 6.5.29 series and 6.5.31 continued fraction), and tests/stats
// test_pinned_values.cpp holds that implementation's values, which these agree with to 1e-12
// relative.
//
// Invalid arguments (a <= 0, x < 0, p outside [0, 1], non-finite input) throw
// std::invalid_argument: they are programming errors, never data, and must not become NaN.

namespace hopper::stats {

// Regularized lower incomplete gamma function
//   P(a, x) = gamma(a, x) / Gamma(a) = 1/Gamma(a) * int_0^x s^(a-1) e^(-s) ds,   a > 0, x >= 0.
// x = +inf gives 1.
double gamma_p(double a, double x);

// Regularized upper incomplete gamma function Q(a, x) = 1 - P(a, x), computed directly (no
// cancellation when P is close to 1). x = +inf gives 0.
double gamma_q(double a, double x);

// Inverse of P in its second argument: the x >= 0 with P(a, x) = p, for 0 <= p <= 1.
// p = 0 gives 0 and p = 1 gives +inf.
double gamma_p_inverse(double a, double p);

}  // namespace hopper::stats
