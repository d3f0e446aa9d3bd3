#pragma once
// Does the jam rate depend on elapsed time (on how much material is left)? Early-versus-late
// comparison of two Poisson rates.
//
// Each realization is watched over a window [0, W] (discharge time, shaking excluded); jams start
// at the given onsets; optional "not at risk" periods (the hopper is jammed, from onset until the
// flow restarts) are removed from the exposure. The window is cut at s W (s = split, 1/2 by
// default) into an early part [0, sW) and a late part [sW, W]. Summed over realizations:
//   n_e, n_l  = jams starting in each part,    E_e, E_l = exposure (time at risk) in each part.
// Under H0 (one constant rate lambda) n_e ~ Poisson(lambda E_e), n_l ~ Poisson(lambda E_l), and
// conditionally on N = n_e + n_l,
//   n_e ~ Binomial(N, p0),   p0 = E_e / (E_e + E_l),
// which is free of lambda: the exact conditional test of two Poisson rates (Przyborowski &
// Wilenski 1940; Lehmann & Romano, "Testing Statistical Hypotheses", 3rd ed., sec. 4.6).
// p_value is its two-sided exact p (binomial_two_sided_p; conservative, size <= alpha). We also
// give the likelihood-ratio statistic
//   G = 2 [ n_e ln(n_e / (N p0)) + n_l ln(n_l / (N (1 - p0))) ]   ~ chi2(1) under H0,
// (terms with a zero count are 0) and its p-value, and the rate ratio late/early
//   RR = (n_l / E_l) / (n_e / E_e),  95 % CI exp( ln RR -+ 1.96 sqrt(1/n_e + 1/n_l) )  (Wald on
// ln RR; only when both counts are > 0).
// The time axis is whatever the caller passes: discharge time, or (to ask about "material left")
// the number of particles discharged, with windows and onsets in that unit.

#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace hopper::stats {

struct JamHistory {
    double window = 0.0;         // W: length of the observation (s of discharge time), > 0
    std::vector<double> onsets;  // jam onset times in [0, W]
    // Periods [start, end) inside [0, W] during which no new jam can start (the outlet is already
    // jammed: onset to flow restart). Empty: the whole window counts as exposure.
    std::vector<std::pair<double, double>> not_at_risk;
};

struct EarlyLateTest {
    bool valid = false;
    std::string reason;
    double split = 0.5;
    int n_early = 0, n_late = 0;
    double exposure_early = 0.0, exposure_late = 0.0;  // s
    std::optional<double> rate_early, rate_late;       // jams per s (exposure > 0)
    std::optional<double> rate_ratio;                  // late / early (both counts > 0)
    std::optional<double> rate_ratio_lo, rate_ratio_hi;
    double p_value = 1.0;       // exact conditional binomial test, two-sided
    double lr_statistic = 0.0;  // G
    double p_value_lr = 1.0;    // P(chi2(1) >= G)
};

// Bad input (window <= 0, onsets outside [0, W], split outside (0, 1), a not-at-risk period
// outside the window or reversed) throws std::invalid_argument. No jams at all, or no exposure in
// one part, gives valid = false with the reason.
EarlyLateTest early_late_rate_test(std::span<const JamHistory> histories, double split = 0.5);

}  // namespace hopper::stats
