#include "hopper/stats/jam_rate_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hopper::stats {

namespace {

struct Data {
    Eigen::VectorXd D, y, w;  // outlet, ln rate, weights 1/sigma^2
    double dmin = 0.0, dmax = 0.0;
};

// Weighted linear least squares y ~ X beta: beta = (X^T W X)^-1 X^T W y, returns chi^2.
double wls(const Eigen::MatrixXd& X, const Data& d, Eigen::VectorXd& beta, Eigen::MatrixXd* cov) {
    const Eigen::MatrixXd XtW = X.transpose() * d.w.asDiagonal();
    const Eigen::MatrixXd F = XtW * X;  // Fisher matrix
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(F);
    beta = ldlt.solve(XtW * d.y);
    if (cov) *cov = ldlt.solve(Eigen::MatrixXd::Identity(F.rows(), F.cols()));
    const Eigen::VectorXd res = d.y - X * beta;
    return res.dot(d.w.asDiagonal() * res);
}

ExponentialRateFit fit_exponential(const Data& d) {
    ExponentialRateFit f;
    const int n = static_cast<int>(d.D.size());
    if (n < kMinPointsExponential) {
        f.reason = "too few points for the exponential fit (" + std::to_string(n) + " < " +
                   std::to_string(kMinPointsExponential) + ")";
        return f;
    }
    // ln rate = ln A - B D: columns (1, -D).
    Eigen::MatrixXd X(n, 2);
    X.col(0).setOnes();
    X.col(1) = -d.D;
    Eigen::VectorXd beta;
    Eigen::MatrixXd cov;
    f.chi2 = wls(X, d, beta, &cov);
    f.ln_A = beta(0);
    f.B = beta(1);
    f.ln_A_err = std::sqrt(cov(0, 0));
    f.B_err = std::sqrt(cov(1, 1));
    f.corr = cov(0, 1) / (f.ln_A_err * f.B_err);
    f.dof = n - 2;
    f.aic = f.chi2 + 2.0 * 2;
    f.valid = true;
    return f;
}

// Profile chi^2 of the power law at Dc = dmax + s. Uses the column
//   u_i = ln(Dc - D_i) - ln(Dc - dmin) = log1p(-(D_i - dmin) / (Dc - dmin))
// (the constant goes into the intercept) so that large Dc keeps full precision.
double profile_chi2(const Data& d, double s, Eigen::VectorXd* beta) {
    const double Dc = d.dmax + s;
    const int n = static_cast<int>(d.D.size());
    Eigen::MatrixXd X(n, 2);
    X.col(0).setOnes();
    for (int i = 0; i < n; ++i)
        X(i, 1) = std::log1p(-(d.D(i) - d.dmin) / (Dc - d.dmin));
    Eigen::VectorXd b;
    const double chi2 = wls(X, d, b, nullptr);
    if (beta) *beta = b;
    return chi2;
}

PowerLawRateFit fit_power_law(const Data& d) {
    PowerLawRateFit f;
    const int n = static_cast<int>(d.D.size());
    if (n < kMinPointsPowerLaw) {
        f.reason = "too few points for the power-law fit (" + std::to_string(n) + " < " +
                   std::to_string(kMinPointsPowerLaw) + ")";
        return f;
    }
    // Scan ln s, s = Dc - dmax, over [1e-6, 1e6] x (dmax - dmin).
    const double span = d.dmax - d.dmin;
    const double lo = std::log(1e-6 * span), hi = std::log(1e6 * span);
    constexpr int kGrid = 241;
    int best = 0;
    double best_chi2 = 0.0;
    for (int i = 0; i < kGrid; ++i) {
        const double c = profile_chi2(d, std::exp(lo + (hi - lo) * i / (kGrid - 1)), nullptr);
        if (i == 0 || c < best_chi2) {
            best = i;
            best_chi2 = c;
        }
    }
    if (best == kGrid - 1) {
        f.reason =
            "the best critical outlet runs off to infinity: the power law degenerates into "
            "the exponential decay";
        return f;
    }
    if (best == 0) {
        f.reason =
            "the best critical outlet collapses onto the largest measured outlet: "
            "ill-determined";
        return f;
    }
    // Golden-section search for the minimum of chi^2 in ln s on the bracketing grid cells.
    const double step = (hi - lo) / (kGrid - 1);
    double a = lo + (best - 1) * step, b = lo + (best + 1) * step;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = profile_chi2(d, std::exp(x1), nullptr), f2 = profile_chi2(d, std::exp(x2), nullptr);
    while (b - a > 1e-10) {
        if (f1 < f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = profile_chi2(d, std::exp(x1), nullptr);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = profile_chi2(d, std::exp(x2), nullptr);
        }
    }
    const double s = std::exp(0.5 * (a + b));
    Eigen::VectorXd beta;
    f.chi2 = profile_chi2(d, s, &beta);
    f.Dc = d.dmax + s;
    f.gamma = beta(1);
    f.ln_A = beta(0) - f.gamma * std::log(f.Dc - d.dmin);  // undo the centring of the column

    // Covariance of (ln A, gamma, Dc) from the Jacobian of ln A + gamma ln(Dc - D).
    Eigen::MatrixXd J(n, 3);
    for (int i = 0; i < n; ++i) {
        J(i, 0) = 1.0;
        J(i, 1) = std::log(f.Dc - d.D(i));
        J(i, 2) = f.gamma / (f.Dc - d.D(i));
    }
    const Eigen::MatrixXd F = J.transpose() * d.w.asDiagonal() * J;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(F);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
        f.reason =
            "the power-law parameters are not separately determined (singular Fisher matrix)";
        return f;
    }
    const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(3, 3));
    f.ln_A_err = std::sqrt(cov(0, 0));
    f.gamma_err = std::sqrt(cov(1, 1));
    f.Dc_err = std::sqrt(cov(2, 2));
    f.dof = n - 3;
    f.aic = f.chi2 + 2.0 * 3;
    f.valid = true;
    return f;
}

}  // namespace

JamRateFits fit_jam_rate(std::span<const double> D, std::span<const double> rate,
                         std::span<const double> sigma_log_rate) {
    const std::size_t n = D.size();
    if (rate.size() != n || sigma_log_rate.size() != n)
        throw std::invalid_argument(
            "fit_jam_rate: D, rate and sigma_log_rate must have the same length");
    JamRateFits out;
    out.n_points = static_cast<int>(n);
    out.preferred = "undecided";
    Data d;
    d.D.resize(n);
    d.y.resize(n);
    d.w.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(D[i]) || !std::isfinite(rate[i]) || !std::isfinite(sigma_log_rate[i]))
            throw std::invalid_argument("fit_jam_rate: non-finite input at point " +
                                        std::to_string(i));
        if (!(rate[i] > 0.0) || !(sigma_log_rate[i] > 0.0)) {
            const std::string why =
                "point " + std::to_string(i) +
                " has no positive rate or uncertainty (points without jams must "
                "be left out by the caller and reported)";
            out.exponential.reason = out.power_law.reason = out.decision = why;
            return out;
        }
        d.D(i) = D[i];
        d.y(i) = std::log(rate[i]);
        d.w(i) = 1.0 / (sigma_log_rate[i] * sigma_log_rate[i]);
    }
    if (n > 0) {
        d.dmin = d.D.minCoeff();
        d.dmax = d.D.maxCoeff();
    }
    if (n >= 2 && d.dmin == d.dmax) {
        out.exponential.reason = out.power_law.reason = out.decision =
            "all points have the same outlet size";
        return out;
    }

    out.exponential = fit_exponential(d);
    out.power_law = fit_power_law(d);

    if (out.n_points < kMinPointsDecision) {
        out.decision = "too few points to decide (" + std::to_string(n) + " < " +
                       std::to_string(kMinPointsDecision) + ")";
        return out;
    }
    if (!out.exponential.valid) {
        out.decision = "exponential fit failed: " + out.exponential.reason;
        return out;
    }
    if (!out.power_law.valid) {
        if (out.power_law.reason.find("degenerates into the exponential") != std::string::npos) {
            out.preferred = "exponential";
            out.decision = "the power law's best fit is the exponential limit (Dc -> infinity)";
        } else {
            out.decision = "power-law fit failed: " + out.power_law.reason;
        }
        return out;
    }
    out.has_delta_aic = true;
    out.delta_aic = out.power_law.aic - out.exponential.aic;
    if (out.delta_aic > 2.0) {
        out.preferred = "exponential";
        out.decision = "AIC prefers the exponential decay (Delta AIC > 2)";
    } else if (out.delta_aic < -2.0) {
        out.preferred = "power_law";
        out.decision = "AIC prefers the power-law divergence (Delta AIC < -2)";
    } else {
        out.decision = "|Delta AIC| <= 2: the data do not distinguish the two laws";
    }
    return out;
}

}  // namespace hopper::stats
