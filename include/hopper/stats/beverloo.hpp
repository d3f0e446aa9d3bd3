#pragma once
// Beverloo's law for the mass flow rate of a 2D hopper (Beverloo, Leniger & van de Velde, Chem.
// Eng. Sci. 15, 260 (1961), in its two-dimensional form; e.g. Mankoc et al., Granular Matter 9,
// 407 (2007)):
//   W(D) = C rho_b sqrt(g) (D - k d)^(3/2)
// W: mass flow rate (kg/s); D: outlet width (m); d: particle diameter (m; for a bidisperse
// packing, the caller states which, e.g. the mean diameter); g: gravity (m/s^2);
// rho_b: 2D bulk density (kg/m^2) = mass per unit AREA of the settled packing in the plane of the
// simulation, i.e. (total particle mass)/(area they occupy) = packing fraction x rho x thickness.
// The caller measures it (and reports how); this layer only uses it. C (dimensionless) and k
// (dimensionless) are fitted.

#include <span>
#include <string>

#include "hopper/core/units.hpp"

namespace hopper::stats {

struct BeverlooOptions {
    double g = core::standard_gravity;  // m/s^2
    // false: sigma_W are relative weights; the covariance is scaled by the residual variance
    //        s^2 = chi^2 / (n - 2)   (the usual choice when the sigmas are rough).
    // true:  sigma_W are absolute standard errors; covariance = (J^T Wt J)^-1 unscaled.
    bool absolute_sigma = false;
};

struct BeverlooFit {
    bool valid = false;
    std::string reason;
    int n_points = 0;
    double C = 0.0, C_err = 0.0;
    double k = 0.0, k_err = 0.0;
    double corr_Ck = 0.0;  // correlation coefficient of the estimates of C and k
    double chi2 = 0.0;  // sum ((W_i - W(D_i)) / sigma_i)^2 at the minimum (sigma_i = 1 unweighted)
    int dof = 0;        // n_points - 2
    int iterations = 0;
    double rho_b = 0.0, d = 0.0;  // echoed inputs
};

// Minimum number of outlet sizes for a fit (two parameters plus one degree of freedom for the
// residual variance).
inline constexpr int kMinBeverlooPoints = 3;

// Weighted nonlinear least squares: minimize chi^2(C, k) = sum_i ((W_i - W(D_i; C, k)) / sigma_i)^2
// by Levenberg–Marquardt (Levenberg 1944; Marquardt 1963; Press et al., "Numerical Recipes",
// 3rd ed., sec. 15.5.2) with Eigen, started from the linearization W^(2/3) = a (D - k d),
// a = (C rho_b sqrt g)^(2/3) (an ordinary straight-line fit of W^(2/3) against D), keeping
// D_i - k d > 0 for every point. Jacobian of W(D) (exact):
//   dW/dC = rho_b sqrt(g) (D - k d)^(3/2),   dW/dk = -(3/2) C rho_b sqrt(g) d (D - k d)^(1/2).
// Covariance of (C, k): s^2 (J^T Wt J)^-1 with Wt = diag(1/sigma_i^2) and s^2 = chi^2 / (n - 2),
// or without the s^2 factor when absolute_sigma (see BeverlooOptions); errors are its diagonal's
// square roots (standard errors, ~68 % if the model is right; multiply by Student's t_{n-2} for
// other levels).
// sigma_W: empty for an unweighted fit, else one positive value per point. Fewer than
// kMinBeverlooPoints points, fewer than 2 distinct D, or a non-positive rate give valid = false
// with the reason. Mismatched sizes or non-finite input throw std::invalid_argument.
BeverlooFit fit_beverloo(std::span<const double> D, std::span<const double> W,
                         std::span<const double> sigma_W, double rho_b, double d,
                         const BeverlooOptions& opt = {});

}  // namespace hopper::stats
