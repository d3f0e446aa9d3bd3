#pragma once
// Contact laws (docs/model.md, "Contact forces"). Each law is a small value type whose
// evaluate() is pure and inline; the force pass (force_batch_impl.hpp) is a template over the
// law, so the choice of law is made once at setup and never per contact. Each names its normal
// and tangential parts (`normal`, `tangential`): a scene's material.normal_law and
// material.tangential_law pick the registered law (laws.hpp) that has both.

#include <algorithm>
#include <cmath>

#include "hopper/core/vec.hpp"
#include "hopper/engine/params.hpp"

// The laws are tiny and called once per contact per step: force inlining into the pair loops.
#if defined(__GNUC__)
#define HOPPER_HOT_INLINE [[gnu::always_inline]] inline
#else
#define HOPPER_HOT_INLINE inline
#endif

namespace hopper::engine {

using core::Vec2;

// Coefficients of one kind of contact (particle-particle or particle-wall).
struct ContactParams {
    double k_n = 0.0;      // N/m
    double gamma_n = 0.0;  // 1/s; damping force = gamma_n * mbar * v_n
    double k_t = 0.0;      // N/m
    double gamma_t = 0.0;  // 1/s
    double mu = 0.0;
    // While sliding, set the spring alone to the Coulomb limit (xi = -F_t / k_t) instead of
    // spring + dashpot (SlipRule in params.hpp).
    bool slip_spring_only = false;
    // The Hertz law (HertzSpringLaw; docs/model.md, "The Hertz law"): K = hertz_k sqrt(R*)
    // (N/m^1.5) for a pair of effective radius R*; the damping's alpha; k_t / (dF_n/dx) and the
    // tangential damping's share of the normal one.
    double hertz_k = 0.0;  // N/m^2: (5/3) E, E = Y / (3 (1 - sigma^2))
    double hertz_alpha = 0.0;
    double hertz_kt_ratio = 0.0;
    double hertz_gt_ratio = 0.0;
    // Rolling resistance (WithRolling; docs/model.md, "Rolling resistance"): the coefficient
    // mu_r of the constant resisting torque mu_r R* |F_n|.
    double mu_r = 0.0;
};

// Force on particle i from one contact, split into normal and tangential parts.
struct ContactForce {
    Vec2 normal;
    Vec2 tangential;
};

// Signed magnitude of F_n = (k_n x - gamma_n mbar v_n) n   (docs/model.md, normal force)
HOPPER_HOT_INLINE double normal_magnitude(const ContactParams& p, double mbar, double overlap,
                                          double v_n) {
    return p.k_n * overlap - p.gamma_n * mbar * v_n;
}

// F_n = (k_n x - gamma_n mbar v_n) n
HOPPER_HOT_INLINE Vec2 normal_force(const ContactParams& p, double mbar, const Vec2& n,
                                    double overlap, double v_n) {
    return normal_magnitude(p, mbar, overlap, v_n) * n;
}

// One contact in components, for the force pass (force_batch_impl.hpp). The laws are
// written once, here, on plain doubles: every path (the reference loop and the batched scalar,
// AVX2 and AVX-512 ones) evaluates the same operations in the same order, so all give the same
// bits. Select = true evaluates both sides of the Coulomb cap and picks (no branch: SIMD
// batches); false branches (scalar loops, where sliding contacts are few). The Vec2 form below
// wraps it.
struct ContactInput {
    double nx, ny;     // unit normal, from j to i
    double overlap;    // x > 0
    double mbar;       // m_i m_j / (m_i + m_j)
    double vx, vy;     // relative contact velocity for the dashpots and the Coulomb cap
    double sx, sy;     // relative contact velocity that grows the spring (= v unless corrected)
    double dt_spring;  // time over which the spring grows this step (dt, or less at onset)
    double rstar = 0;  // R_i R_j / (R_i + R_j): set only for laws with needs_rstar
    // Constants of the pair, computed at each neighbour rebuild by the law's pair_constants():
    // set only for laws with needs_pair_constants (the Hertz law: K and alpha sqrt(mbar K)).
    double hertz_K = 0, hertz_eta = 0;
};
struct ContactOutput {
    double fn;        // signed normal magnitude: the normal force is fn n
    double ftx, fty;  // tangential force
};

// Viscous ("kinetic") friction of a contact whose normal force is fn, shared by the laws without
// a spring: F_t* = -gm v_t with gm the tangential dashpot's coefficient (kg/s), capped at
// mu |F_n|. No contact history.
template <bool Select>
HOPPER_HOT_INLINE ContactOutput viscous_tangential(const ContactParams& p, const ContactInput& c,
                                                   double v_n, double fn, double gm) {
    const double vtx = c.vx - v_n * c.nx, vty = c.vy - v_n * c.ny;
    const double g = -gm;
    double ftx = g * vtx, fty = g * vty;
    const double cap = p.mu * std::abs(fn);  // mu |F_n|
    const double ft2 = ftx * ftx + fty * fty;
    const bool slip = ft2 > cap * cap;
    if (Select || slip) {  // Select: branch-free, both sides evaluated (SIMD batches)
        const double scale = cap / std::sqrt(ft2);  // used only where ft2 > cap^2 >= 0
        ftx = slip ? ftx * scale : ftx;
        fty = slip ? fty * scale : fty;
    }
    return {fn, ftx, fty};
}

// Frictionless contacts (mu = 0 everywhere): no tangential force, hence no torque and no
// rotation to integrate.
struct FrictionlessLaw {
    static constexpr NormalLaw normal = NormalLaw::linear;
    static constexpr TangentialLaw tangential = TangentialLaw::frictionless;
    static constexpr bool has_tangential = false;
    static constexpr bool has_history = false;
    template <bool Select = false>
    HOPPER_HOT_INLINE static ContactOutput evaluate(const ContactParams& p, const ContactInput& c,
                                                    double& /*hx*/, double& /*hy*/) {
        const double v_n = c.vx * c.nx + c.vy * c.ny;
        return {normal_magnitude(p, c.mbar, c.overlap, v_n), 0.0, 0.0};
    }
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& /*xi*/, double /*dt*/) {
        return {normal_force(p, mbar, n, overlap, v_ij.dot(n)), Vec2::Zero()};
    }
};

// k_t = 0: viscous ("kinetic") friction only, F_t* = -gamma_t mbar v_t, capped at mu |F_n|.
// No spring, so no contact history is kept at all.
struct ViscousFrictionLaw {
    static constexpr NormalLaw normal = NormalLaw::linear;
    static constexpr TangentialLaw tangential = TangentialLaw::viscous;
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = false;
    template <bool Select = false>
    HOPPER_HOT_INLINE static ContactOutput evaluate(const ContactParams& p, const ContactInput& c,
                                                    double& /*hx*/, double& /*hy*/) {
        const double v_n = c.vx * c.nx + c.vy * c.ny;
        const double fn = normal_magnitude(p, c.mbar, c.overlap, v_n);
        return viscous_tangential<Select>(p, c, v_n, fn, p.gamma_t * c.mbar);
    }
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& /*xi*/, double dt);
};

// The Cundall-Strack tangential spring of a contact whose normal force is fn (docs/model.md,
// tangential force), shared by the spring laws: a spring xi that starts at zero length when the
// contact forms, is projected onto the current tangent line, grows by v_t dt per step, and is
// shortened when the Coulomb cap is active. k_t: its stiffness; gm: the tangential dashpot's
// coefficient (gamma_t mbar, N s/m).
template <bool Select>
HOPPER_HOT_INLINE ContactOutput tangential_spring(const ContactParams& p, const ContactInput& c,
                                                  double v_n, double fn, double k_t, double gm,
                                                  double& hx, double& hy) {
    const double vtx = c.vx - v_n * c.nx, vty = c.vy - v_n * c.ny;
    // The spring's own tangential velocity (equal to v_t unless corrected).
    const double s_n = c.sx * c.nx + c.sy * c.ny;
    const double stx = c.sx - s_n * c.nx, sty = c.sy - s_n * c.ny;
    // xi' = xi - n (n . xi), then grow by v_t dt
    const double n_xi = c.nx * hx + c.ny * hy;
    double xx = (hx - c.nx * n_xi) + stx * c.dt_spring;
    double xy = (hy - c.ny * n_xi) + sty * c.dt_spring;
    // F_t* = -k_t xi' - gamma_t mbar v_t
    const double dx = gm * vtx, dy = gm * vty;
    const double mk = -k_t;
    double ftx = mk * xx - dx, fty = mk * xy - dy;
    const double cap = p.mu * std::abs(fn);  // mu |F_n|
    const double ft2 = ftx * ftx + fty * fty;
    // Sliding: F_t = mu |F_n| F_t*/|F_t*|, and the spring shortened to match:
    // xi' = -(F_t + gamma_t mbar v_t) / k_t (spring_only: xi' = -F_t / k_t).
    const bool slip = ft2 > cap * cap;
    if (Select || slip) {  // Select: branch-free, both sides evaluated (SIMD batches)
        const double scale = cap / std::sqrt(ft2);
        const double sfx = ftx * scale, sfy = fty * scale;
        // spring_only as a factor on the dashpot: an invariant select on a bool keeps GCC
        // from vectorizing the loops over pairs. 0 * d changes at most the sign of a zero.
        const double keep = p.slip_spring_only ? 0.0 : 1.0;
        const double rx = -(sfx + keep * dx);
        const double ry = -(sfy + keep * dy);
        // Round 3 (docs/performance.md): one reciprocal, two products (loop-invariant for the
        // linear law, where the compiler hoists it), instead of two divisions.
        const double inv_kt = 1.0 / k_t;
        xx = slip ? rx * inv_kt : xx;
        xy = slip ? ry * inv_kt : xy;
        ftx = slip ? sfx : ftx;
        fty = slip ? sfy : fty;
    }
    hx = xx;
    hy = xy;
    return {fn, ftx, fty};
}

// Cundall-Strack static friction with the linear normal force (tangential_spring above).
struct SpringFrictionLaw {
    static constexpr NormalLaw normal = NormalLaw::linear;
    static constexpr TangentialLaw tangential = TangentialLaw::spring;
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = true;
    template <bool Select = false>
    HOPPER_HOT_INLINE static ContactOutput evaluate(const ContactParams& p, const ContactInput& c,
                                                    double& hx, double& hy) {
        const double v_n = c.vx * c.nx + c.vy * c.ny;
        const double fn = normal_magnitude(p, c.mbar, c.overlap, v_n);
        return tangential_spring<Select>(p, c, v_n, fn, p.k_t, p.gamma_t * c.mbar, hx, hy);
    }
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& xi, double dt);
};

// The Hertz law with a Mindlin-type (no-slip) tangential spring (issue 28; docs/model.md, "The
// Hertz law"): the elastic normal force K x^(3/2) with K = hertz_k sqrt(R*); the damping of
// Tsuji et al., -alpha sqrt(mbar K) x^(1/4) v_n, whose restitution depends on alpha only (not on
// the impact speed); a Cundall-Strack tangential spring whose stiffness follows the normal
// contact's, k_t = hertz_kt_ratio (3/2) K x^(1/2), with the damping hertz_gt_ratio times the
// normal one and the Coulomb cap and slip rule of SpringFrictionLaw.
struct HertzSpringLaw {
    static constexpr NormalLaw normal = NormalLaw::hertz;
    static constexpr TangentialLaw tangential = TangentialLaw::spring;
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = true;
    static constexpr bool needs_rstar = true;
    static constexpr bool needs_pair_constants = true;
    // The pair's constants (round 3: computed once per neighbour rebuild, not per step; the
    // same expressions, so the same bits): K = hertz_k sqrt(R*) and the damping's
    // alpha sqrt(mbar K), which evaluate() multiplies by x^(1/4).
    HOPPER_HOT_INLINE static void pair_constants(const ContactParams& p, double rstar, double mbar,
                                                 double& K, double& eta0) {
        K = p.hertz_k * std::sqrt(rstar);
        eta0 = p.hertz_alpha * std::sqrt(mbar * K);
    }
    // c.hertz_K and c.hertz_eta from pair_constants().
    template <bool Select = false>
    HOPPER_HOT_INLINE static ContactOutput evaluate(const ContactParams& p, const ContactInput& c,
                                                    double& hx, double& hy) {
        const double K = c.hertz_K;
        const double sx = std::sqrt(c.overlap);  // x^(1/2)
        const double qx = std::sqrt(sx);         // x^(1/4)
        const double eta = c.hertz_eta * qx;     // kg/s: alpha sqrt(mbar K) x^(1/4)
        const double v_n = c.vx * c.nx + c.vy * c.ny;
        const double fn = K * c.overlap * sx - eta * v_n;
        const double kt = p.hertz_kt_ratio * 1.5 * K * sx;
        return tangential_spring<Select>(p, c, v_n, fn, kt, p.hertz_gt_ratio * eta, hx, hy);
    }
};

// Rolling resistance on top of a law with tangential forces (issue 28; docs/model.md, "Rolling
// resistance"): a constant torque of magnitude mu_r R* |F_n| against the relative rolling
// w_i - w_j (the "type A" model of Ai et al., Powder Technol. 206, 269 (2011)), on i and the
// opposite on j; none when w_i = w_j exactly. pair_force adds it (rolling_torque below).
template <class Base>
struct WithRolling : Base {
    static_assert(Base::has_tangential, "rolling resistance needs a law with torques");
    static constexpr bool needs_rstar = true;
    static constexpr bool rolling = true;
};

// Rolling resistance as an elastic-plastic spring (issue 39; docs/model.md, "Rolling
// resistance"): the "type C" model of Ai et al., with the rolling stiffness of Iwashita & Oda
// (Soils Found. 38, 1998), k_r = k_t R*^2. Each contact carries the spring's torque M (a third
// history column beside the tangential spring), which grows by -k_r (w_i - w_j) dt per step and
// is capped at mu_r R* |F_n|: below the cap a contact resists a small rolling elastically and
// holds a static torque without creeping, which the constant torque above cannot (it acts only
// while the disks roll). Below the cap a dashpot damps the rolling velocity R* (w_i - w_j) as the
// tangential dashpot damps v_t (gamma_t mbar, at the lever R*); at the cap the torque is the cap
// alone (Ai et al.'s f = 0), so that rolling disks feel the constant torque's mu_r R* |F_n|.
// pair_force adds it (rolling_spring_torque below). The linear normal law only (k_t constant).
template <class Base>
struct WithRollingSpring : WithRolling<Base> {
    static constexpr bool rolling_spring = true;
};

// Whether a law reads ContactInput::rstar (pair_force computes it only then), and whether it
// resists rolling.
template <class Law>
inline constexpr bool law_needs_rstar = requires {
    Law::needs_rstar;
};
template <class Law>
inline constexpr bool law_resists_rolling = requires {
    Law::rolling;
};
// Whether a law's rolling resistance is the spring (a third history column per contact).
template <class Law>
inline constexpr bool law_has_rolling_spring = requires {
    Law::rolling_spring;
};
// Whether a law has constants per pair (pair_constants(), computed at each neighbour rebuild).
template <class Law>
inline constexpr bool law_needs_pair_constants = requires {
    Law::needs_pair_constants;
};

// R* = R_i R_j / (R_i + R_j), a constant of the pair (computed at each neighbour rebuild).
HOPPER_HOT_INLINE double reduced_radius(double ri, double rj) {
    return ri * rj / (ri + rj);
}

// The rolling resistance torque on i: -mu_r R* |F_n| sign(w_i - w_j) (0 at w_i = w_j). A select,
// not a branch, so that the batched passes vectorize.
HOPPER_HOT_INLINE double rolling_torque(double mu_r, double rstar, double fn, double w_rel) {
    const double m = mu_r * rstar * std::abs(fn);
    return w_rel > 0.0 ? -m : (w_rel < 0.0 ? m : 0.0);
}

// The rolling torque on i after one step (WithRollingSpring): the spring M' = M - k_r w_s dt
// with k_r = k_t R*^2, capped at mu_r R* |F_n| (the cap keeps M's sign: a contact rolled past
// it slips, and rolled back it unloads elastically from the cap), plus, below the cap, the
// dashpot -gm R*^2 w_d (gm = gamma_t mbar). w_s: the relative spin that grows the spring (the
// springs' velocity set), w_d: the dashpots'. M is updated in place. Selects, not branches, so
// that the batched passes vectorize.
HOPPER_HOT_INLINE double rolling_spring_torque(double mu_r, double k_t, double gm, double rstar,
                                               double fn, double w_s, double w_d, double dt,
                                               double& M) {
    const double cap = mu_r * rstar * std::abs(fn);
    const double r2 = rstar * rstar;
    const double m = M - k_t * r2 * w_s * dt;
    const bool above = m > cap, below = m < -cap;
    const double capped = above ? cap : (below ? -cap : m);
    M = capped;
    const double damp = above || below ? 0.0 : gm * r2 * w_d;
    return capped - damp;
}

// The Vec2 form of a law: damping and spring velocities equal, the spring grows over dt.
template <class Law>
HOPPER_HOT_INLINE ContactForce evaluate_vec(const ContactParams& p, double mbar, const Vec2& n,
                                            double overlap, const Vec2& v_ij, Vec2& xi, double dt) {
    const ContactInput c{n.x(), n.y(), overlap, mbar, v_ij.x(), v_ij.y(), v_ij.x(), v_ij.y(), dt};
    double hx = xi.x(), hy = xi.y();
    const ContactOutput o = Law::template evaluate<false>(p, c, hx, hy);
    if constexpr (Law::has_history) xi = Vec2(hx, hy);
    return {o.fn * n, Vec2(o.ftx, o.fty)};
}

HOPPER_HOT_INLINE ContactForce ViscousFrictionLaw::evaluate(const ContactParams& p, double mbar,
                                                            const Vec2& n, double overlap,
                                                            const Vec2& v_ij, Vec2& xi, double dt) {
    return evaluate_vec<ViscousFrictionLaw>(p, mbar, n, overlap, v_ij, xi, dt);
}

HOPPER_HOT_INLINE ContactForce SpringFrictionLaw::evaluate(const ContactParams& p, double mbar,
                                                           const Vec2& n, double overlap,
                                                           const Vec2& v_ij, Vec2& xi, double dt) {
    return evaluate_vec<SpringFrictionLaw>(p, mbar, n, overlap, v_ij, xi, dt);
}

// Relative velocity of the contact points of i and j (n points from j to i):
// v_ij = v_i - v_j - (R_i w_i + R_j w_j) (z x n)   (docs/model.md)
HOPPER_HOT_INLINE Vec2 contact_velocity(const Vec2& v_i, const Vec2& v_j, double R_i, double w_i,
                                        double R_j, double w_j, const Vec2& n) {
    return v_i - v_j - (R_i * w_i + R_j * w_j) * core::perp(n);
}

// Torque (z) on a particle of radius R touching at -R n with tangential force F_t:
// I dw/dt = -R (n x F_t). The same expression, with R_j, holds for the partner j.
HOPPER_HOT_INLINE double contact_torque(double R, const Vec2& n, const Vec2& F_t) {
    return -R * core::cross(n, F_t);
}

}  // namespace hopper::engine
