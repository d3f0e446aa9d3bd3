#pragma once
// Distribution functions used by the statistics layer: normal, chi-square, Kolmogorov and
// binomial. The normal quantile comes from Boost.Math and the chi-square functions from
// special_functions.hpp (Boost.Math too); the Kolmogorov and binomial ones are written here
// (Boost 1.74 has no Kolmogorov distribution; the binomial test's tie rule is our own).
//
// Invalid arguments throw std::invalid_argument (programming errors, never data).

namespace hopper::stats {

// Standard normal distribution function Phi(x) = 1/2 erfc(-x / sqrt 2).
double normal_cdf(double x);

// Standard normal quantile z_p = Phi^-1(p), 0 < p < 1 (Boost.Math: -sqrt 2 erfc^-1(2p)).
double normal_quantile(double p);

// Chi-square distribution function with k > 0 degrees of freedom: F(x; k) = P(k/2, x/2).
double chi2_cdf(double x, double k);

// Chi-square upper tail 1 - F(x; k) = Q(k/2, x/2), accurate far in the tail.
double chi2_sf(double x, double k);

// Chi-square quantile: the x with F(x; k) = p, i.e. x = 2 P^-1(k/2, p); p = 1 gives +inf.
double chi2_quantile(double p, double k);

// Complement of the Kolmogorov distribution (the limit law of sqrt(n) D_n for a fully
// specified continuous F):
//   Q_KS(lambda) = 2 sum_{j>=1} (-1)^(j-1) exp(-2 j^2 lambda^2)                (lambda >= 1.18)
//                = 1 - sqrt(2 pi)/lambda sum_{j>=1} exp(-(2j-1)^2 pi^2 / (8 lambda^2))  (below)
// (the two forms are equal, by the Jacobi theta transformation; each converges fast in its range).
// Q_KS(lambda <= 0) = 1.
double kolmogorov_q(double lambda);

// p-value of the one-sample Kolmogorov–Smirnov statistic D from n observations against a FULLY
// SPECIFIED continuous distribution, with Stephens's (1970) finite-n scaling:
//   p ~ Q_KS((sqrt(n) + 0.12 + 0.11/sqrt(n)) D).
// Not valid when a parameter was estimated from the same data (see gof.hpp).
double ks_p_value(double D, int n);

// Binomial probability P(X = k) for X ~ Binomial(n, p), 0 <= k <= n, 0 <= p <= 1.
double binomial_pmf(int k, int n, double p);

// Exact two-sided binomial test of H0: X ~ Binomial(n, p0) after observing k: the total
// probability of all outcomes no more likely than k,
//   p = sum_{j : P(j) <= P(k)} P(j)     (relative tolerance 1e-7 for ties),
// capped at 1. Conservative (its size is at most the nominal level).
double binomial_two_sided_p(int k, int n, double p0);

}  // namespace hopper::stats
