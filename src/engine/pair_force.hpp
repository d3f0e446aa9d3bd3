#pragma once
// The force of one touching pair, written once for every build of the force pass
// (force_batch_impl.hpp: the reference with one lane, the batched baseline, AVX2 and AVX-512
// builds of the same source). Plain doubles, no branches that depend on the data (selects instead),
// and always inlined, so that a loop over pairs vectorizes and every path performs the same
// operations in the same order: the same bits on every instruction set (with FMA contraction
// off, see src/engine/CMakeLists.txt).

#include <cmath>

#include "hopper/engine/contact.hpp"

namespace hopper::engine::detail {

// One touching pair seen from i: separation r_i - r_j = (dx, dy) with d2 = dx^2 + dy^2 < rs^2,
// the reduced mass (a wall's inverse mass is 0), radii, and two velocity sets: `v*`/`w*` for the
// dashpots and the Coulomb cap, `s*`/`sw*` for the spring's growth (the same values unless the
// contact corrections are on, see SystemConfig::contact_corrections).
struct PairInput {
    double dx, dy, d2, rs, mbar, ri, rj;  // mbar = 1 / (1/m_i + 1/m_j)
    double vix, viy, wi, vjx, vjy, wj;
    double six, siy, swi, sjx, sjy, swj;
    // Constants of the pair from the rebuild, read only by the laws that need them:
    // R* (law_needs_rstar) and the law's pair_constants() (law_needs_pair_constants).
    double rstar, hertz_K, hertz_eta;
};

// The force on i (the partner gets -F), the torques' parts t_i = l_i (n x F_t) and
// t_j = l_j (n x F_t) (each particle's torque changes by -t), and the overlap.
struct PairOutput {
    double fx, fy, ti, tj, overlap;
};

// Contact velocity v_i - v_j - (l_i w_i + l_j w_j) (z x n) with z x n = (-n_y, n_x).
HOPPER_HOT_INLINE void relative_velocity(bool rot, double vix, double viy, double wi, double vjx,
                                         double vjy, double wj, double li, double lj, double nx,
                                         double ny, double& vx, double& vy) {
    if (rot) {
        const double sw = li * wi + lj * wj;
        vx = (vix - vjx) - sw * (-ny);
        vy = (viy - vjy) - sw * nx;
    } else {
        vx = vix - vjx;
        vy = viy - vjy;
    }
}

// Select: see contact.hpp (true in the batched passes, false in the reference pass).
// lever_half: 0 (lever arm R) or 0.5 (R - x/2). Corr (contact corrections): the spring grows
// with the second velocity set, and a new spring (exactly (0, 0)) only over the estimated part
// of the step spent in contact, min(1, x / (|s_n| dt)). hx, hy: the tangential spring; hr: the
// rolling spring's torque (law_has_rolling_spring; not read otherwise).
template <class Law, bool Corr, bool Select>
HOPPER_HOT_INLINE PairOutput pair_force(const ContactParams& p, double dt, double lever_half,
                                        const PairInput& q, double& hx, double& hy, double& hr) {
    constexpr bool rot = Law::has_tangential;
    const double d = std::sqrt(q.d2);
    const double inv_d = 1.0 / d;
    const double nx = q.dx * inv_d, ny = q.dy * inv_d;
    const double overlap = q.rs - d;
    const double li = q.ri - lever_half * overlap;
    const double lj = q.rj - lever_half * overlap;
    const double mbar = q.mbar;
    double vx, vy;
    relative_velocity(rot, q.vix, q.viy, q.wi, q.vjx, q.vjy, q.wj, li, lj, nx, ny, vx, vy);
    double sx = vx, sy = vy;
    if constexpr (Corr)
        relative_velocity(rot, q.six, q.siy, q.swi, q.sjx, q.sjy, q.swj, li, lj, nx, ny, sx, sy);
    double dts = dt;
    if constexpr (Corr && Law::has_history) {
        // A new spring grows over min(dt, x / |s_n|), the estimated time in contact (round 3:
        // one division, and in the scalar loop only for a new spring; the same value in every
        // path: the select below evaluates the same expression).
        // Bitwise &, not &&: no control flow, so that the loops over pairs vectorize.
        const double s_n = sx * nx + sy * ny;  // < 0 while approaching
        const bool fresh = (hx == 0.0) & (hy == 0.0) & (s_n < 0.0);
        if constexpr (Select) {
            const double t_in = overlap / -s_n;
            dts = fresh ? (t_in < dt ? t_in : dt) : dt;
        } else if (fresh) {
            const double t_in = overlap / -s_n;
            dts = t_in < dt ? t_in : dt;
        }
    }
    ContactInput c{nx, ny, overlap, mbar, vx, vy, sx, sy, dts};
    if constexpr (law_needs_rstar<Law>) c.rstar = q.rstar;  // reduced_radius, at the rebuild
    if constexpr (law_needs_pair_constants<Law>) {
        c.hertz_K = q.hertz_K;
        c.hertz_eta = q.hertz_eta;
    }
    const ContactOutput f = Law::template evaluate<Select>(p, c, hx, hy);
    PairOutput out;
    out.fx = f.fn * nx + f.ftx;
    out.fy = f.fn * ny + f.fty;
    const double cr = rot ? nx * f.fty - ny * f.ftx : 0.0;  // n x F_t
    out.ti = li * cr;
    out.tj = lj * cr;
    if constexpr (law_resists_rolling<Law>) {
        // Each particle's torque changes by -t: i gets +M, j gets -M.
        double M;
        if constexpr (law_has_rolling_spring<Law>) {
            // The spring grows with the springs' velocity set, over the tangential spring's time.
            const double w_s = Corr ? q.swi - q.swj : q.wi - q.wj;
            M = rolling_spring_torque(p.mu_r, p.k_t, p.gamma_t * mbar, c.rstar, f.fn, w_s,
                                      q.wi - q.wj, dts, hr);
        } else {
            M = rolling_torque(p.mu_r, c.rstar, f.fn, q.wi - q.wj);
        }
        out.ti -= M;
        out.tj += M;
    }
    out.overlap = overlap;
    return out;
}

}  // namespace hopper::engine::detail
