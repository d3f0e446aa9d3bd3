#include "hopper/stats/beverloo.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hopper::stats {

namespace {

struct Problem {
    Eigen::ArrayXd D, W, inv_sigma;
    double pref = 0.0;  // rho_b sqrt(g)
    double d = 0.0;
};

// Weighted residuals r_i = (W_i - W(D_i)) / sigma_i and Jacobian J_ij = d(model_i / sigma_i)/dp_j.
// Returns false when some D_i - k d <= 0 (outside the model's domain).
bool evaluate(const Problem& p, double C, double k, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    const Eigen::ArrayXd h = p.D - k * p.d;  // effective outlet D - k d
    if ((h <= 0.0).any()) return false;
    const Eigen::ArrayXd h32 = h * h.sqrt();
    r = ((p.W - C * p.pref * h32) * p.inv_sigma).matrix();
    if (J) {
        J->resize(p.D.size(), 2);
        J->col(0) = (p.pref * h32 * p.inv_sigma).matrix();
        J->col(1) = (-1.5 * C * p.pref * p.d * h.sqrt() * p.inv_sigma).matrix();
    }
    return true;
}

}  // namespace

BeverlooFit fit_beverloo(std::span<const double> D, std::span<const double> W,
                         std::span<const double> sigma_W, double rho_b, double d,
                         const BeverlooOptions& opt) {
    const std::size_t n = D.size();
    if (W.size() != n || (!sigma_W.empty() && sigma_W.size() != n))
        throw std::invalid_argument("fit_beverloo: D, W and sigma_W must have the same length");
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(D[i]) || !std::isfinite(W[i]) ||
            (!sigma_W.empty() && !std::isfinite(sigma_W[i])))
            throw std::invalid_argument("fit_beverloo: non-finite input at point " +
                                        std::to_string(i));
    if (!(rho_b > 0.0) || !(d > 0.0) || !(opt.g > 0.0) || !std::isfinite(rho_b) ||
        !std::isfinite(d))
        throw std::invalid_argument("fit_beverloo: rho_b, d and g must be finite and > 0");

    BeverlooFit fit;
    fit.n_points = static_cast<int>(n);
    fit.rho_b = rho_b;
    fit.d = d;
    if (fit.n_points < kMinBeverlooPoints) {
        fit.reason = "too few outlet sizes for a Beverloo fit (" + std::to_string(n) + " < " +
                     std::to_string(kMinBeverlooPoints) + ")";
        return fit;
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (!(W[i] > 0.0) || !(D[i] > 0.0)) {
            fit.reason =
                "a flow rate or outlet size is not positive (point " + std::to_string(i) + ")";
            return fit;
        }
        if (!sigma_W.empty() && !(sigma_W[i] > 0.0)) {
            fit.reason =
                "a flow-rate uncertainty is not positive (point " + std::to_string(i) + ")";
            return fit;
        }
    }
    const auto [dmin, dmax] = std::minmax_element(D.begin(), D.end());
    if (*dmin == *dmax) {
        fit.reason = "all points have the same outlet size";
        return fit;
    }

    Problem p;
    p.D = Eigen::Map<const Eigen::ArrayXd>(D.data(), n);
    p.W = Eigen::Map<const Eigen::ArrayXd>(W.data(), n);
    if (sigma_W.empty())
        p.inv_sigma = Eigen::ArrayXd::Ones(n);
    else
        p.inv_sigma = Eigen::Map<const Eigen::ArrayXd>(sigma_W.data(), n).inverse();
    p.pref = rho_b * std::sqrt(opt.g);
    p.d = d;

    // Start: weighted straight line y = a D + b with y = W^(2/3) (weights 1/sigma_y^2, sigma_y =
    // (2/3) W^(-1/3) sigma_W by error propagation); then C = a^(3/2) / pref, k = -b / (a d).
    const Eigen::ArrayXd y = p.W.pow(2.0 / 3.0);
    const Eigen::ArrayXd wy = (p.inv_sigma * 1.5 * p.W.pow(1.0 / 3.0)).square();
    const double sw = wy.sum(), sx = (wy * p.D).sum(), sy = (wy * y).sum();
    const double sxx = (wy * p.D * p.D).sum(), sxy = (wy * p.D * y).sum();
    const double a = (sw * sxy - sx * sy) / (sw * sxx - sx * sx);
    const double b = (sy - a * sx) / sw;
    if (!(a > 0.0)) {
        fit.reason = "the flow rate does not grow with the outlet size";
        return fit;
    }
    double C = std::pow(a, 1.5) / p.pref;
    // Keep the start inside the domain D_i - k d > 0.
    double k = std::min(-b / (a * d), 0.99 * *dmin / d);

    Eigen::VectorXd r, r_try;
    Eigen::MatrixXd J;
    if (!evaluate(p, C, k, r, &J)) {
        fit.reason = "internal: starting point outside the model's domain";
        return fit;
    }
    double chi2 = r.squaredNorm();
    Eigen::Matrix2d JtJ = J.transpose() * J;
    double lambda = 1e-3 * JtJ.diagonal().maxCoeff();
    int it = 0;
    for (; it < 200; ++it) {
        // (J^T J + lambda diag(J^T J)) delta = J^T r   (Marquardt's scaling of the damping).
        Eigen::Matrix2d A = JtJ;
        A.diagonal() *= 1.0 + lambda;
        const Eigen::Vector2d delta = A.ldlt().solve(J.transpose() * r);
        const double C_try = C + delta(0), k_try = k + delta(1);
        double chi2_try = 0.0;
        const bool ok = evaluate(p, C_try, k_try, r_try, nullptr);
        if (ok) chi2_try = r_try.squaredNorm();
        if (ok && chi2_try <= chi2) {
            const bool converged = chi2 - chi2_try <= 1e-14 * chi2 + 1e-300 &&
                                   std::abs(delta(0)) <= 1e-10 * std::abs(C) &&
                                   std::abs(delta(1)) <= 1e-10 * std::max(std::abs(k), 1.0);
            C = C_try;
            k = k_try;
            chi2 = chi2_try;
            evaluate(p, C, k, r, &J);
            JtJ = J.transpose() * J;
            lambda = std::max(lambda * 0.1, 1e-15);
            if (converged) break;
        } else {
            lambda *= 10.0;
            if (lambda > 1e15) break;  // no downhill step left: at the minimum to machine precision
        }
    }
    fit.iterations = it;
    fit.C = C;
    fit.k = k;
    fit.chi2 = chi2;
    fit.dof = fit.n_points - 2;

    Eigen::LDLT<Eigen::Matrix2d> ldlt(JtJ);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
        fit.reason = "C and k are not separately determined by these points (singular J^T J)";
        return fit;
    }
    Eigen::Matrix2d cov = ldlt.solve(Eigen::Matrix2d::Identity());
    if (!opt.absolute_sigma) cov *= chi2 / fit.dof;
    fit.C_err = std::sqrt(cov(0, 0));
    fit.k_err = std::sqrt(cov(1, 1));
    fit.corr_Ck = (fit.C_err > 0.0 && fit.k_err > 0.0) ? cov(0, 1) / (fit.C_err * fit.k_err) : 0.0;
    fit.valid = true;
    return fit;
}

}  // namespace hopper::stats
