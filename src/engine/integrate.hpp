#pragma once
// The integrators' corrector fused into every force pass (private to the engine; round 3,
// issue 25; docs/performance.md, "The formulation of round 3"): the half list names
// every partner later in cell order (j > i), so once the force pass has finished particle i's
// row its force and torque are final and nothing later reads its state; correcting it there, or
// its block in the batched passes, gives exactly the bits of a separate pass: the same element-
// by-element loops (kernel.cpp) run on a block of particles instead of all of them.

#include <cmath>
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
                                            const double* force, const double* inv_mass, double* x,
                                            double* v, double* x2, double* x3, double* x4) {
    const double e = h * (force[i] * inv_mass[i] + g) - x2[i];
    if constexpr (X) x[i] += gear_c0 * e;
    v[i] += gear_c1 * e * inv_dt;
    x2[i] += e;
    x3[i] += gear_c3 * e;
    x4[i] += gear_c4 * e;
}

// The particles of one block of the force pass (force_batch_impl.hpp, every path): each block
// is corrected (and predicted ahead, below) once its rows are done.
inline constexpr int block_rows = 256;

// What the fused integrator needs: the scheme (none: forces only, e.g. the priming evaluation)
// and the System's columns. StepFusion::step (docs/performance.md, "Round 3, second session"):
// with `predict`, the force pass also runs the predictor, a block ahead of the rows that read
// the predicted state (`reach`), and zeroes the forces there; with `next_displacement` the
// corrector also returns the largest squared displacement from (xref, yref) that the next
// step's predictor will give, so that the next step knows without a pass of its own whether
// it must rebuild the neighbour list.
struct CorrectArgs {
    enum Scheme { none, gear4, verlet } scheme = none;
    double dt = 0.0, gx = 0.0, gy = 0.0;
    const double *inv_m = nullptr, *inv_I = nullptr;
    double *x = nullptr, *y = nullptr, *vx = nullptr, *vy = nullptr, *w = nullptr;
    double *x2 = nullptr, *x3 = nullptr, *x4 = nullptr, *y2 = nullptr, *y3 = nullptr, *y4 = nullptr,
           *w2 = nullptr, *w3 = nullptr, *w4 = nullptr;
    // The predictor's second velocity set (the contact corrections; null without them).
    double *mx = nullptr, *my = nullptr, *mw = nullptr;
    bool predict = false;
    // Block b (rows [b block_rows, (b + 1) block_rows)) reads the particles [0, reach[b]):
    // its own and its rows' partners (System::pair_constants).
    const int* reach = nullptr;
    bool next_displacement = false;
    const double *xref = nullptr, *yref = nullptr;
    // Plate friction (SystemConfig::plate_decel; 0: none): added to the forces of a block before
    // its correction, from the velocities it is corrected from.
    double plate_decel = 0.0, plate_speed = 0.0;
    // The load band (SystemConfig::load_accel; 0: none): likewise, from the positions the block
    // is corrected from.
    double load_accel = 0.0, load_y_lo = 0.0, load_y_hi = 0.0;
    bool body_forces() const { return plate_decel > 0.0 || load_accel > 0.0; }
};

// Adds the plate friction -m a v / max(|v|, v_c) to the forces of the particles [i0, i1)
// (docs/model.md, "Plate friction"). One loop for every path, so every path gives the same bits.
inline void add_plate_friction(const CorrectArgs& c, double* fx, double* fy, int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
        const double vx = c.vx[i], vy = c.vy[i];
        const double speed = std::sqrt(vx * vx + vy * vy);
        const double k =
            c.plate_decel / (c.inv_m[i] * (speed > c.plate_speed ? speed : c.plate_speed));
        fx[i] -= k * vx;
        fy[i] -= k * vy;
    }
}

// Adds the load band's m a_load downward to the forces of the particles [i0, i1) whose centres
// lie in [load_y_lo, load_y_hi] (docs/model.md, "The lid").
inline void add_load_band(const CorrectArgs& c, double* fy, int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
        const double y = c.y[i];
        if (y >= c.load_y_lo && y <= c.load_y_hi) fy[i] -= c.load_accel / c.inv_m[i];
    }
}

// The forces that are not contacts, in one order for every path: the plate friction, then the
// load band.
inline void add_body_forces(const CorrectArgs& c, double* fx, double* fy, int i0, int i1) {
    if (c.plate_decel > 0.0) add_plate_friction(c, fx, fy, i0, i1);
    if (c.load_accel > 0.0) add_load_band(c, fy, i0, i1);
}

// The corrector over the particles [i0, i1), whose forces (and torques when rot) are final:
// the integrator's own multi-versioned loops (kernel.cpp: AVX-512, AVX2 or the baseline, picked
// when the program starts) on that range, so the fused corrector is vectorized on every path
// and gives the separate loops' bits. Called once per block of particles, after its rows (the
// force pass of every path). Defined in kernel.cpp, not inline. Returns the block's largest
// squared next displacement when c.next_displacement (NaN if a position is not finite), else 0.
double correct_block(const CorrectArgs& c, double* fx, double* fy, const double* tq, bool rot,
                     int i0, int i1);

// The predictor over the particles [j0, j1) (the separate pass's loops on that range, so the
// same bits), then their forces (and torques when rot) set to zero: called by the fused passes
// before a block's rows read those particles (kernel.cpp).
void predict_block(const CorrectArgs& c, double* fx, double* fy, double* tq, bool rot, int j0,
                   int j1);

// The fused passes' combination of the blocks' next displacements: the maximum (exact in any
// order), NaN if either is NaN. (Always inlined, as everything the batched passes call.)
HOPPER_HOT_INLINE double max_or_nan(double a, double b) {
    return (a != a || b != b) ? a + b : (b > a ? b : a);
}

// Predicts ahead for block b when the pass predicts (see CorrectArgs): [predicted, reach[b]).
HOPPER_HOT_INLINE void predict_ahead(const CorrectArgs& c, double* fx, double* fy, double* tq,
                                     bool rot, int b, int& predicted) {
    if (!c.predict) return;
    const int want = c.reach[b];
    if (want <= predicted) return;
    predict_block(c, fx, fy, tq, rot, predicted, want);
    predicted = want;
}

}  // namespace hopper::engine::detail
