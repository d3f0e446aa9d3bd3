#pragma once
// The integrators' corrector fused into every force pass (private to the engine; round 3,
// issue 25; docs/performance.md, "The formulation of round 3"): the half list names
// every partner later in cell order (j > i), so once the force pass has finished particle i's
// row its force and torque are final and nothing later reads its state; correcting it there, or
// its block in the batched passes, gives exactly the bits of a separate pass: the same element-
// by-element loops (kernel.cpp) run on a block of particles instead of all of them.

#include <cstddef>

#include "hopper/engine/contact.hpp"

namespace hopper::engine::detail {

// Gear 5-value predictor-corrector for second-order equations (Allen & Tildesley, appendix E):
// corrector coefficients for r, dt v, dt^2/2 a, dt^3/6 b, dt^4/24 c.
inline constexpr double gear_c0 = 19.0 / 120.0;
inline constexpr double gear_c1 = 3.0 / 4.0;
inline constexpr double gear_c3 = 1.0 / 2.0;
inline constexpr double gear_c4 = 1.0 / 12.0;

// Gear corrector of element i on one coordinate: e = dt^2/2 a(t+dt) - predicted r_2, with
// a = force * inv_mass + g (h = dt^2/2). x may be null (rotation: the angle is not tracked).
template <bool X>
HOPPER_HOT_INLINE void gear_correct_element(std::size_t i, double h, double inv_dt, double g,
                                            const double* force, const double* inv_mass,
                                            double* x, double* v, double* x2, double* x3,
                                            double* x4) {
    const double e = h * (force[i] * inv_mass[i] + g) - x2[i];
    if constexpr (X) x[i] += gear_c0 * e;
    v[i] += gear_c1 * e * inv_dt;
    x2[i] += e;
    x3[i] += gear_c3 * e;
    x4[i] += gear_c4 * e;
}

// What the fused corrector needs: the scheme (none: forces only, e.g. the priming evaluation)
// and the System's columns.
struct CorrectArgs {
    enum Scheme { none, gear4, verlet } scheme = none;
    double dt = 0.0, gx = 0.0, gy = 0.0;
    const double *inv_m = nullptr, *inv_I = nullptr;
    double *x = nullptr, *y = nullptr, *vx = nullptr, *vy = nullptr, *w = nullptr;
    double *x2 = nullptr, *x3 = nullptr, *x4 = nullptr, *y2 = nullptr, *y3 = nullptr,
           *y4 = nullptr, *w2 = nullptr, *w3 = nullptr, *w4 = nullptr;
};

// The corrector over the particles [i0, i1), whose forces (and torques when rot) are final:
// the integrator's own multi-versioned loops (kernel.cpp: AVX-512, AVX2 or the baseline, picked
// when the program starts) on that range, so the fused corrector is vectorized on every path
// and gives the separate loops' bits. Called once per block of particles (the reference loop
// every 256 rows, the batched passes after each block). Defined in kernel.cpp, not inline.
void correct_block(const CorrectArgs& c, const double* fx, const double* fy, const double* tq,
                   bool rot, int i0, int i1);

}  // namespace hopper::engine::detail
