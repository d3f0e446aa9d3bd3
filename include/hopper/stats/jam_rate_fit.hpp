#pragma once
// The jam rate lambda = 1/tau versus the outlet size D at one wall angle: two candidate laws,
// both fitted by weighted least squares on y = ln lambda, compared by AIC.
//
//   exponential decay:      ln lambda = ln A - B D                       (2 parameters)
//   power-law divergence:   ln lambda = ln A + gamma ln(Dc - D),  Dc > max D  (3 parameters)
//                           i.e. tau ~ (Dc - D)^(-gamma) diverges at a critical outlet Dc.
// (Zuriguel et al., PRE 71, 051303 (2005) and Sci. Rep. 4, 7324 (2014) discuss both forms.)
//
// Weights: w_i = 1 / sigma_i^2 with sigma_i the standard error of ln lambda_i. For the censored
// exponential MLE, sigma(ln tau_hat) = 1/sqrt(r_i) with r_i the number of jams at that point
// (ExponentialFit::sigma_log_tau); sigma(ln lambda) is the same number. The sigmas are taken as
// absolute, so chi^2 = sum w_i (y_i - f_i)^2 has a known scale: chi^2/dof >> 1 means scatter
// beyond counting noise (then the parameter errors below are too small).
//   AIC = chi^2 + 2 p  (= -2 ln L + 2 p up to a constant common to both models; Akaike 1974;
//   Burnham & Anderson, "Model Selection and Multimodel Inference", 2nd ed. 2002, sec. 2.2).
// Delta = AIC_power - AIC_exponential; |Delta| <= 2 is "undecided" (Burnham & Anderson's rule of
// thumb), otherwise the model with the smaller AIC is preferred.
// Points with no jam have no ln lambda: the caller must leave them out and report them (they
// suggest the rate falls faster than any fitted law predicts at large D).

#include <span>
#include <string>

namespace hopper::stats {

// Below these point counts a model is not fitted / the comparison is not made.
inline constexpr int kMinPointsExponential = 3;  // 2 parameters + 1 degree of freedom
inline constexpr int kMinPointsPowerLaw = 4;     // 3 parameters + 1 degree of freedom
inline constexpr int kMinPointsDecision = 5;     // the power law keeps >= 2 degrees of freedom

struct ExponentialRateFit {
    bool valid = false;
    std::string reason;
    double ln_A = 0.0, ln_A_err = 0.0;  // A in 1/s
    double B = 0.0, B_err = 0.0;        // 1/m
    double corr = 0.0;                  // correlation of ln A and B
    double chi2 = 0.0;
    int dof = 0;
    double aic = 0.0;
};

struct PowerLawRateFit {
    bool valid = false;
    std::string reason;
    double ln_A = 0.0, ln_A_err = 0.0;  // A in 1/s per m^gamma
    double gamma = 0.0, gamma_err = 0.0;
    double Dc = 0.0, Dc_err = 0.0;  // m
    double chi2 = 0.0;
    int dof = 0;
    double aic = 0.0;
};

struct JamRateFits {
    int n_points = 0;
    ExponentialRateFit exponential;
    PowerLawRateFit power_law;
    std::string preferred;  // "exponential", "power_law" or "undecided"
    bool has_delta_aic = false;
    double delta_aic = 0.0;  // AIC_power - AIC_exponential (when has_delta_aic)
    std::string decision;    // the reason for `preferred`, in words
};

// D (m), rate (1/s, > 0) and sigma_log_rate (> 0), one entry per outlet size. The exponential is
// a linear WLS fit with covariance (X^T W X)^-1. The power law is fitted by profiling: for each
// trial Dc the model is linear in (ln A, gamma), solved by WLS; chi^2_min(Dc) is minimized over
// ln(Dc - max D) by a grid scan over 12 decades of (Dc - max D)/(max D - min D) followed by
// golden-section search. Its covariance is (J^T W J)^-1 with the Jacobian columns
// (1, ln(Dc - D_i), gamma / (Dc - D_i)) at the minimum. When the best Dc runs to the end of the
// scan, the power law has degenerated into the exponential (ln(Dc - D) -> const - D/Dc) and is
// reported invalid with that reason, the exponential being preferred.
// Mismatched sizes or non-finite input throw std::invalid_argument.
JamRateFits fit_jam_rate(std::span<const double> D, std::span<const double> rate,
                         std::span<const double> sigma_log_rate);

}  // namespace hopper::stats
