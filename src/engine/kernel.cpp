// The System's kernel: the integrators, and the force pass of the chosen path (kernel.hpp).
#include "kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "force_batch.hpp"
#include "hopper/core/error.hpp"
#include "integrate.hpp"
#include "laws.hpp"

namespace hopper::engine {

namespace {

using detail::gear_c0;
using detail::gear_c1;
using detail::gear_c3;
using detail::gear_c4;

// The integrator's loops are element by element (no sums across particles), so a vector
// instruction gives each particle exactly the bits of the scalar code: each loop is compiled for
// AVX-512, AVX2 and the baseline and the CPU's best is picked when the program starts (GCC
// function multi-versioning; FMA contraction stays off, see CMakeLists.txt). They stream the
// System's columns, so the wider loads matter more than the arithmetic.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HOPPER_ISA_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define HOPPER_ISA_CLONES
#endif

// Calls f with two std::bool_constant arguments equal to a and b: one loop compiled per case,
// the choice made once, outside the loop. Always inlined, like the loop bodies it calls
// (HOPPER_LOOP_BODY), so that each multi-versioned caller compiles them for its own
// instruction set.
#define HOPPER_LOOP_BODY __attribute__((always_inline))
template <class F>
[[gnu::always_inline]] inline void with_flags(bool a, bool b, F&& f) {
    using T = std::true_type;
    using N = std::false_type;
    if (a && b)
        f(T{}, T{});
    else if (a)
        f(T{}, N{});
    else if (b)
        f(N{}, T{});
    else
        f(N{}, N{});
}

// Gear predictor on one coordinate (Pascal triangle on the scaled derivatives
// r_k = dt^k/k! d^k r/dt^k; velocity kept unscaled). Free functions over raw columns so that
// the compiler sees no aliasing and vectorizes them. x may be null (rotation: the angle itself
// is not tracked); mean, when given, gets 0.5 (predicted v + last v) (the springs' velocity
// with the contact corrections), in the same pass.
template <bool X, bool Mean>
[[gnu::always_inline]] inline void gear_predict_loop(std::size_t n, double dt, double* __restrict x,
                                                     double* __restrict v, double* __restrict x2,
                                                     double* __restrict x3,
                                                     const double* __restrict x4,
                                                     double* __restrict mean) {
    const double inv_dt = 1.0 / dt;
    for (std::size_t i = 0; i < n; ++i) {
        const double v0 = v[i];
        if constexpr (X) x[i] += dt * v[i] + x2[i] + x3[i] + x4[i];
        v[i] += (2.0 * x2[i] + 3.0 * x3[i] + 4.0 * x4[i]) * inv_dt;
        x2[i] += 3.0 * x3[i] + 6.0 * x4[i];
        x3[i] += 4.0 * x4[i];
        if constexpr (Mean) mean[i] = 0.5 * (v[i] + v0);
    }
}

HOPPER_ISA_CLONES
void gear_predict_axis(std::size_t n, double dt, double* __restrict x, double* __restrict v,
                       double* __restrict x2, double* __restrict x3, const double* __restrict x4,
                       double* __restrict mean) {
    with_flags(x != nullptr, mean != nullptr, [&](auto X, auto M) HOPPER_LOOP_BODY {
        gear_predict_loop<X(), M()>(n, dt, x, v, x2, x3, x4, mean);
    });
}

// Gear corrector on one coordinate: e = dt^2/2 a(t+dt) - predicted r_2, with
// a = force * inv_mass + g. x may be null (rotation). One pass over the columns.
template <bool X>
[[gnu::always_inline]] inline void gear_correct_loop(std::size_t n, double dt, double g,
                                                     const double* __restrict force,
                                                     const double* __restrict inv_mass,
                                                     double* __restrict x, double* __restrict v,
                                                     double* __restrict x2, double* __restrict x3,
                                                     double* __restrict x4) {
    const double h = 0.5 * dt * dt, inv_dt = 1.0 / dt;
    for (std::size_t i = 0; i < n; ++i)
        detail::gear_correct_element<X>(i, h, inv_dt, g, force, inv_mass, x, v, x2, x3, x4);
}

HOPPER_ISA_CLONES
void gear_correct_axis(std::size_t n, double dt, double g, const double* __restrict force,
                       const double* __restrict inv_mass, double* __restrict x,
                       double* __restrict v, double* __restrict x2, double* __restrict x3,
                       double* __restrict x4) {
    if (x)
        gear_correct_loop<true>(n, dt, g, force, inv_mass, x, v, x2, x3, x4);
    else
        gear_correct_loop<false>(n, dt, g, force, inv_mass, x, v, x2, x3, x4);
}

// Velocity Verlet on one coordinate: the half kick v += dt/2 (force inv_mass + g), then, when
// x is given, the drift x += dt v (x is null for the closing half kick and for rotation); out,
// when given, gets the kicked v extrapolated by another half kick, v + dt/2 (force inv_mass + g)
// (the dashpots' velocity with the contact corrections), in the same pass.
template <bool X, bool Out>
[[gnu::always_inline]] inline void verlet_loop(std::size_t n, double dt, double g,
                                               const double* __restrict force,
                                               const double* __restrict inv_mass,
                                               double* __restrict v, double* __restrict x,
                                               double* __restrict out) {
    const double hdt = 0.5 * dt;
    for (std::size_t i = 0; i < n; ++i) {
        const double kick = hdt * (force[i] * inv_mass[i] + g);
        v[i] += kick;
        if constexpr (X) x[i] += dt * v[i];
        if constexpr (Out) out[i] = v[i] + kick;
    }
}

HOPPER_ISA_CLONES
void verlet_axis(std::size_t n, double dt, double g, const double* __restrict force,
                 const double* __restrict inv_mass, double* __restrict v, double* __restrict x,
                 double* __restrict out = nullptr) {
    with_flags(x != nullptr, out != nullptr, [&](auto X, auto O) HOPPER_LOOP_BODY {
        verlet_loop<X(), O()>(n, dt, g, force, inv_mass, v, x, out);
    });
}

// Largest squared displacement since the last rebuild; NaN if any position is not finite.
// (A maximum is exact, so its vector reduction gives the scalar loop's value.)
HOPPER_ISA_CLONES
double max_displacement2(std::size_t n, const double* __restrict x, const double* __restrict y,
                         const double* __restrict xr, const double* __restrict yr) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    double maxd2 = 0.0;
    int bad = 0;
#pragma omp simd reduction(max : maxd2) reduction(| : bad)
    for (std::size_t i = 0; i < n; ++i) {
        const double dx = x[i] - xr[i], dy = y[i] - yr[i];
        const double d2 = dx * dx + dy * dy;
        maxd2 = d2 > maxd2 ? d2 : maxd2;
        bad |= d2 < inf ? 0 : 1;  // NaN or inf
    }
    return bad ? std::numeric_limits<double>::quiet_NaN() : maxd2;
}

// The corrector on x and y at once, and the largest squared displacement from (xr, yr) of the
// positions that the next step's predictor will give (the fused step, integrate.hpp): per
// element the expressions of gear_correct_loop (twice), gear_predict_loop and
// max_displacement2, so the same bits as those passes, in one pass and without storing the
// prediction. NaN if a position is not finite.
HOPPER_ISA_CLONES
double gear_correct_xy_next(std::size_t n, double dt, double gx, double gy,
                            const double* __restrict fx, const double* __restrict fy,
                            const double* __restrict inv_m, double* __restrict x,
                            double* __restrict vx, double* __restrict x2, double* __restrict x3,
                            double* __restrict x4, double* __restrict y, double* __restrict vy,
                            double* __restrict y2, double* __restrict y3, double* __restrict y4,
                            const double* __restrict xr, const double* __restrict yr) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double h = 0.5 * dt * dt, inv_dt = 1.0 / dt;
    double maxd2 = 0.0;
    int bad = 0;
#pragma omp simd reduction(max : maxd2) reduction(| : bad)
    for (std::size_t i = 0; i < n; ++i) {
        detail::gear_correct_element<true>(i, h, inv_dt, gx, fx, inv_m, x, vx, x2, x3, x4);
        detail::gear_correct_element<true>(i, h, inv_dt, gy, fy, inv_m, y, vy, y2, y3, y4);
        const double px = x[i] + (dt * vx[i] + x2[i] + x3[i] + x4[i]);
        const double py = y[i] + (dt * vy[i] + y2[i] + y3[i] + y4[i]);
        const double dx = px - xr[i], dy = py - yr[i];
        const double d2 = dx * dx + dy * dy;
        maxd2 = d2 > maxd2 ? d2 : maxd2;
        bad |= d2 < inf ? 0 : 1;
    }
    return bad ? std::numeric_limits<double>::quiet_NaN() : maxd2;
}

// Verlet's closing half kick on x and y, and the next step's largest squared displacement (its
// opening kick with the same forces, then the drift): the expressions of verlet_loop and
// max_displacement2.
HOPPER_ISA_CLONES
double verlet_close_xy_next(std::size_t n, double dt, double gx, double gy,
                            const double* __restrict fx, const double* __restrict fy,
                            const double* __restrict inv_m, double* __restrict vx,
                            double* __restrict vy, const double* __restrict x,
                            const double* __restrict y, const double* __restrict xr,
                            const double* __restrict yr) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double hdt = 0.5 * dt;
    double maxd2 = 0.0;
    int bad = 0;
#pragma omp simd reduction(max : maxd2) reduction(| : bad)
    for (std::size_t i = 0; i < n; ++i) {
        const double kx = hdt * (fx[i] * inv_m[i] + gx);
        const double ky = hdt * (fy[i] * inv_m[i] + gy);
        vx[i] += kx;
        vy[i] += ky;
        const double dx = (x[i] + dt * (vx[i] + kx)) - xr[i];
        const double dy = (y[i] + dt * (vy[i] + ky)) - yr[i];
        const double d2 = dx * dx + dy * dy;
        maxd2 = d2 > maxd2 ? d2 : maxd2;
        bad |= d2 < inf ? 0 : 1;
    }
    return bad ? std::numeric_limits<double>::quiet_NaN() : maxd2;
}

}  // namespace

template <class Law, Scheme S>
struct KernelImpl final : System::Kernel {
    static constexpr bool rot = Law::has_tangential;
    static constexpr bool hist = Law::has_history;

    double predict(System& s) override {
        const std::size_t n = s.x_.size();
        const double dt = s.config_.dt;
        const bool corr = s.config_.contact_corrections;
        // The contact corrections' second velocity set (see velocity_sets), written by the
        // integrator's own pass: verlet's dashpots see the velocity extrapolated to the end of
        // the step with the last forces, v + dt/2 (F/m + g); gear4's springs grow with the mean
        // of the last corrected and the predicted velocity (only where there are springs).
        const bool second = corr && (S == Scheme::verlet || hist);
        if (second) {
            s.avx_.resize(n);
            s.avy_.resize(n);
            s.aw_.resize(n);
        }
        double* const avx = second ? s.avx_.data() : nullptr;
        double* const avy = second ? s.avy_.data() : nullptr;
        double* const aw = second ? s.aw_.data() : nullptr;
        if constexpr (S == Scheme::gear4) {
            gear_predict_axis(n, dt, s.x_.data(), s.vx_.data(), s.x2_.data(), s.x3_.data(),
                              s.x4_.data(), avx);
            gear_predict_axis(n, dt, s.y_.data(), s.vy_.data(), s.y2_.data(), s.y3_.data(),
                              s.y4_.data(), avy);
            if constexpr (rot)  // the angle is not tracked: omega and its derivatives only
                gear_predict_axis(n, dt, nullptr, s.w_.data(), s.w2_.data(), s.w3_.data(),
                                  s.w4_.data(), aw);
        } else {
            // Velocity Verlet: half kick with the last forces, then drift.
            const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
            verlet_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.vx_.data(), s.x_.data(), avx);
            verlet_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.vy_.data(), s.y_.data(), avy);
            if constexpr (rot)
                verlet_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), s.w_.data(), nullptr, aw);
        }
        return max_displacement2(n, s.x_.data(), s.y_.data(), s.xref_.data(), s.yref_.data());
    }

    void correct(System& s) override {
        const std::size_t n = s.x_.size();
        const double dt = s.config_.dt;
        const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
        if (s.config_.plate_decel > 0.0 || s.config_.load_accel > 0.0) {
            detail::CorrectArgs c;
            correct_args(s, c, false);
            detail::add_body_forces(c, s.fx_.data(), s.fy_.data(), 0, int(n));
        }
        if constexpr (S == Scheme::gear4) {
            gear_correct_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.x_.data(), s.vx_.data(),
                              s.x2_.data(), s.x3_.data(), s.x4_.data());
            gear_correct_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.y_.data(), s.vy_.data(),
                              s.y2_.data(), s.y3_.data(), s.y4_.data());
            if constexpr (rot)
                gear_correct_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), nullptr, s.w_.data(),
                                  s.w2_.data(), s.w3_.data(), s.w4_.data());
        } else {
            // Velocity Verlet: the closing half kick with the new forces.
            verlet_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.vx_.data(), nullptr);
            verlet_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.vy_.data(), nullptr);
            if constexpr (rot)
                verlet_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), s.w_.data(), nullptr);
        }
    }

    void prime(System& s) override {
        if constexpr (S == Scheme::gear4) {
            const std::size_t n = s.x_.size();
            const double h = 0.5 * s.config_.dt * s.config_.dt;
            const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
            for (auto* col : System::history_columns(s))
                col->assign(n, 0.0);
            for (std::size_t i = 0; i < n; ++i) {
                s.x2_[i] = h * (s.fx_[i] * s.inv_m_[i] + gx);
                s.y2_[i] = h * (s.fy_[i] * s.inv_m_[i] + gy);
                if constexpr (rot) s.w2_[i] = h * s.tq_[i] * s.inv_I_[i];
            }
        }
    }

    // The velocity sets of the force pass: without corrections the particles' velocities for
    // both; with them, verlet's dashpots use the extrapolated set and gear4's springs the mean.
    void velocity_sets(System& s, detail::ForceArgs& a, bool& two) const {
        const bool corr = s.config_.contact_corrections;
        const bool verlet_corr = corr && S == Scheme::verlet;
        a.vx = verlet_corr ? s.avx_.data() : s.vx_.data();
        a.vy = verlet_corr ? s.avy_.data() : s.vy_.data();
        a.w = verlet_corr ? s.aw_.data() : s.w_.data();
        two = corr && hist;
        const bool gear_corr = two && S == Scheme::gear4;
        a.svx = two ? (gear_corr ? s.avx_.data() : s.vx_.data()) : a.vx;
        a.svy = two ? (gear_corr ? s.avy_.data() : s.vy_.data()) : a.vy;
        a.sw = two ? (gear_corr ? s.aw_.data() : s.w_.data()) : a.w;
    }

    // The corrector, fused into the force pass (integrate.hpp) when `correct`; the predictor
    // too when `predict` (the fused step: System::step).
    void correct_args(System& s, detail::CorrectArgs& c, bool predict) const {
        const double dt = s.config_.dt;
        c.scheme = S == Scheme::gear4 ? detail::CorrectArgs::gear4 : detail::CorrectArgs::verlet;
        c.dt = dt;
        c.gx = s.config_.gravity.x();
        c.gy = s.config_.gravity.y();
        c.inv_m = s.inv_m_.data();
        c.inv_I = s.inv_I_.data();
        c.x = s.x_.data();
        c.y = s.y_.data();
        c.vx = s.vx_.data();
        c.vy = s.vy_.data();
        c.w = s.w_.data();
        if constexpr (S == Scheme::gear4) {
            c.x2 = s.x2_.data();
            c.x3 = s.x3_.data();
            c.x4 = s.x4_.data();
            c.y2 = s.y2_.data();
            c.y3 = s.y3_.data();
            c.y4 = s.y4_.data();
            c.w2 = s.w2_.data();
            c.w3 = s.w3_.data();
            c.w4 = s.w4_.data();
        }
        // The next step's displacement, for StepFusion::step's rebuild test.
        c.next_displacement = s.fusion_ == StepFusion::step;
        c.plate_decel = s.config_.plate_decel;
        c.plate_speed = s.config_.plate_speed;
        c.load_accel = s.config_.load_accel;
        c.load_y_lo = s.config_.load_y_lo;
        c.load_y_hi = s.config_.load_y_hi;
        c.xref = s.xref_.data();
        c.yref = s.yref_.data();
        if (predict) {
            const std::size_t n = s.x_.size();
            const bool second = s.config_.contact_corrections && (S == Scheme::verlet || hist);
            if (second) {  // as in predict()
                s.avx_.resize(n);
                s.avy_.resize(n);
                s.aw_.resize(n);
            }
            c.mx = second ? s.avx_.data() : nullptr;
            c.my = second ? s.avy_.data() : nullptr;
            c.mw = second && rot ? s.aw_.data() : nullptr;
            c.predict = true;
            c.reach = s.block_reach_.data();
        }
    }

    detail::ForceSums forces(System& s, bool correct, bool predict) override {
        detail::ForceArgs a = s.force_args();
        if (correct) correct_args(s, a.correct, predict);
        bool two = false;
        velocity_sets(s, a, two);
        // The force pass of the chosen path (force_batch.hpp: the reference is its scalar
        // build), for this law, with or without the springs' own velocity set.
        const detail::ForceSums sums =
            detail::force_table(s.kernel_path_).fn[detail::law_id<Law>][two ? 1 : 0](a);
        s.wall_force_ = Vec2(sums.wall_fx, sums.wall_fy);
        s.contacts_ = sums.contacts;
        return sums;
    }
};

double detail::correct_block(const CorrectArgs& c, double* fx, double* fy, const double* tq,
                             bool rot, int i0, int i1) {
    const std::size_t n = i1 > i0 ? std::size_t(i1 - i0) : 0;
    if (n == 0 || c.scheme == CorrectArgs::none) return 0.0;
    if (c.body_forces()) add_body_forces(c, fx, fy, i0, i1);
    double next = 0.0;
    if (c.scheme == CorrectArgs::gear4) {
        if (c.next_displacement) {
            next = gear_correct_xy_next(n, c.dt, c.gx, c.gy, fx + i0, fy + i0, c.inv_m + i0,
                                        c.x + i0, c.vx + i0, c.x2 + i0, c.x3 + i0, c.x4 + i0,
                                        c.y + i0, c.vy + i0, c.y2 + i0, c.y3 + i0, c.y4 + i0,
                                        c.xref + i0, c.yref + i0);
        } else {
            gear_correct_axis(n, c.dt, c.gx, fx + i0, c.inv_m + i0, c.x + i0, c.vx + i0, c.x2 + i0,
                              c.x3 + i0, c.x4 + i0);
            gear_correct_axis(n, c.dt, c.gy, fy + i0, c.inv_m + i0, c.y + i0, c.vy + i0, c.y2 + i0,
                              c.y3 + i0, c.y4 + i0);
        }
        if (rot)
            gear_correct_axis(n, c.dt, 0.0, tq + i0, c.inv_I + i0, nullptr, c.w + i0, c.w2 + i0,
                              c.w3 + i0, c.w4 + i0);
    } else {
        // Velocity Verlet: the closing half kick with the new forces.
        if (c.next_displacement) {
            next =
                verlet_close_xy_next(n, c.dt, c.gx, c.gy, fx + i0, fy + i0, c.inv_m + i0, c.vx + i0,
                                     c.vy + i0, c.x + i0, c.y + i0, c.xref + i0, c.yref + i0);
        } else {
            verlet_axis(n, c.dt, c.gx, fx + i0, c.inv_m + i0, c.vx + i0, nullptr);
            verlet_axis(n, c.dt, c.gy, fy + i0, c.inv_m + i0, c.vy + i0, nullptr);
        }
        if (rot) verlet_axis(n, c.dt, 0.0, tq + i0, c.inv_I + i0, c.w + i0, nullptr);
    }
    return next;
}

void detail::predict_block(const CorrectArgs& c, double* fx, double* fy, double* tq, bool rot,
                           int j0, int j1) {
    const std::size_t n = j1 > j0 ? std::size_t(j1 - j0) : 0;
    if (n == 0) return;
    auto at = [&](double* p) { return p ? p + j0 : nullptr; };
    // The predict() pass's calls on [j0, j1).
    if (c.scheme == CorrectArgs::gear4) {
        gear_predict_axis(n, c.dt, c.x + j0, c.vx + j0, c.x2 + j0, c.x3 + j0, c.x4 + j0, at(c.mx));
        gear_predict_axis(n, c.dt, c.y + j0, c.vy + j0, c.y2 + j0, c.y3 + j0, c.y4 + j0, at(c.my));
        if (rot)
            gear_predict_axis(n, c.dt, nullptr, c.w + j0, c.w2 + j0, c.w3 + j0, c.w4 + j0,
                              at(c.mw));
    } else if (c.scheme == CorrectArgs::verlet) {
        verlet_axis(n, c.dt, c.gx, fx + j0, c.inv_m + j0, c.vx + j0, c.x + j0, at(c.mx));
        verlet_axis(n, c.dt, c.gy, fy + j0, c.inv_m + j0, c.vy + j0, c.y + j0, at(c.my));
        if (rot) verlet_axis(n, c.dt, 0.0, tq + j0, c.inv_I + j0, c.w + j0, nullptr, at(c.mw));
    }
    // Then the pass's forces start from zero (verlet's kick above read the last ones).
    std::fill(fx + j0, fx + j1, 0.0);
    std::fill(fy + j0, fy + j1, 0.0);
    if (rot) std::fill(tq + j0, tq + j1, 0.0);
}

namespace {

template <class Law>
std::unique_ptr<System::Kernel> make_kernel_for(Scheme scheme) {
    if (scheme == Scheme::gear4) return std::make_unique<KernelImpl<Law, Scheme::gear4>>();
    return std::make_unique<KernelImpl<Law, Scheme::verlet>>();
}

}  // namespace

std::unique_ptr<System::Kernel> detail::make_kernel(int law, Scheme scheme) {
    // One factory per registered law (laws.hpp), in the registry's order.
    using Factory = std::unique_ptr<System::Kernel> (*)(Scheme);
    static constexpr auto factories =
        for_each_law([]<class L>() -> Factory { return &make_kernel_for<L>; });
    if (law < 0 || law >= int(factories.size()))
        throw core::ConfigError("make_kernel: no contact law with id " + std::to_string(law));
    return factories[std::size_t(law)](scheme);
}

}  // namespace hopper::engine
