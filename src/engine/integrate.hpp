#pragma once
// The integrators' per-particle updates after the force pass (private to the engine), written
// once for the separate loops of kernel.cpp and for the corrector fused into every force pass
// (round 3, issue 25; docs/performance.md, "The formulation of round 3"): the half list names
// every partner later in cell order (j > i), so once the force pass has finished particle i's
// row its force and torque are final and nothing later reads its state; correcting it there, or
// its block in the batched passes, gives exactly the bits of a separate pass. Element by
// element, always inlined, FMA contraction off (CMakeLists.txt): the same bits on every
// instruction set.

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

// Velocity Verlet's closing half kick of element i: v += dt/2 (force inv_mass + g).
HOPPER_HOT_INLINE void verlet_kick_element(std::size_t i, double hdt, double g,
                                           const double* force, const double* inv_mass,
                                           double* v) {
    const double kick = hdt * (force[i] * inv_mass[i] + g);
    v[i] += kick;
}

// What the fused corrector needs: the scheme (none: forces only, e.g. the priming evaluation)
// and the System's columns.
struct CorrectArgs {
    enum Scheme { none, gear4, verlet } scheme = none;
    double h = 0.0, inv_dt = 0.0, hdt = 0.0, gx = 0.0, gy = 0.0;
    const double *inv_m = nullptr, *inv_I = nullptr;
    double *x = nullptr, *y = nullptr, *vx = nullptr, *vy = nullptr, *w = nullptr;
    double *x2 = nullptr, *x3 = nullptr, *x4 = nullptr, *y2 = nullptr, *y3 = nullptr,
           *y4 = nullptr, *w2 = nullptr, *w3 = nullptr, *w4 = nullptr;
};

// The corrector over the particles [i0, i1), whose forces (and torques when Rot) are final.
template <bool Rot>
HOPPER_HOT_INLINE void correct_range(const CorrectArgs& c, const double* fx, const double* fy,
                                     const double* tq, int i0, int i1) {
    if (c.scheme == CorrectArgs::gear4) {
        for (int i = i0; i < i1; ++i)
            gear_correct_element<true>(std::size_t(i), c.h, c.inv_dt, c.gx, fx, c.inv_m, c.x,
                                       c.vx, c.x2, c.x3, c.x4);
        for (int i = i0; i < i1; ++i)
            gear_correct_element<true>(std::size_t(i), c.h, c.inv_dt, c.gy, fy, c.inv_m, c.y,
                                       c.vy, c.y2, c.y3, c.y4);
        if constexpr (Rot)
            for (int i = i0; i < i1; ++i)
                gear_correct_element<false>(std::size_t(i), c.h, c.inv_dt, 0.0, tq, c.inv_I,
                                            nullptr, c.w, c.w2, c.w3, c.w4);
    } else if (c.scheme == CorrectArgs::verlet) {
        for (int i = i0; i < i1; ++i)
            verlet_kick_element(std::size_t(i), c.hdt, c.gx, fx, c.inv_m, c.vx);
        for (int i = i0; i < i1; ++i)
            verlet_kick_element(std::size_t(i), c.hdt, c.gy, fy, c.inv_m, c.vy);
        if constexpr (Rot)
            for (int i = i0; i < i1; ++i)
                verlet_kick_element(std::size_t(i), c.hdt, 0.0, tq, c.inv_I, c.w);
    }
}

}  // namespace hopper::engine::detail
