#pragma once
// Contact laws (spec/physics.md, "Contact forces"). Each law is a small value type whose
// evaluate() is pure and inline; the pair loops in system.cpp are templates over the law, so the
// choice of law (frictionless / viscous friction / Cundall-Strack spring) is made once at setup
// and never per contact.

#include <algorithm>
#include <cmath>

#include "hopper/core/vec.hpp"

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
};

// Force on particle i from one contact, split into normal and tangential parts.
struct ContactForce {
    Vec2 normal;
    Vec2 tangential;
};

// Signed magnitude of F_n = (k_n x - gamma_n mbar v_n) n   (spec/physics.md, normal force)
HOPPER_HOT_INLINE double normal_magnitude(const ContactParams& p, double mbar, double overlap,
                                          double v_n) {
    return p.k_n * overlap - p.gamma_n * mbar * v_n;
}

// F_n = (k_n x - gamma_n mbar v_n) n
HOPPER_HOT_INLINE Vec2 normal_force(const ContactParams& p, double mbar, const Vec2& n,
                                    double overlap, double v_n) {
    return normal_magnitude(p, mbar, overlap, v_n) * n;
}

// Frictionless contacts (mu = 0 everywhere): no tangential force, hence no torque and no
// rotation to integrate.
struct FrictionlessLaw {
    static constexpr bool has_tangential = false;
    static constexpr bool has_history = false;
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& /*xi*/, double /*dt*/) {
        return {normal_force(p, mbar, n, overlap, v_ij.dot(n)), Vec2::Zero()};
    }
};

// k_t = 0: viscous ("kinetic") friction only, F_t* = -gamma_t mbar v_t, capped at mu |F_n|.
// No spring, so no contact history is kept at all.
struct ViscousFrictionLaw {
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = false;
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& /*xi*/, double /*dt*/) {
        const double v_n = v_ij.dot(n);
        const double fn = normal_magnitude(p, mbar, overlap, v_n);
        const Vec2 v_t = v_ij - v_n * n;
        Vec2 F_t = -p.gamma_t * mbar * v_t;
        const double cap = p.mu * std::abs(fn);  // mu |F_n|
        const double ft2 = F_t.squaredNorm();
        if (ft2 > cap * cap) F_t *= cap / std::sqrt(ft2);  // ft2 > cap^2 >= 0, so ft2 > 0
        return {fn * n, F_t};
    }
};

// Cundall-Strack static friction: a tangential spring xi that starts at zero length when the
// contact forms, is projected onto the current tangent line, grows by v_t dt per step, and is
// shortened when the Coulomb cap is active (spec/physics.md, tangential force).
struct SpringFrictionLaw {
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = true;
    HOPPER_HOT_INLINE static ContactForce evaluate(const ContactParams& p, double mbar,
                                                   const Vec2& n, double overlap, const Vec2& v_ij,
                                                   Vec2& xi, double dt) {
        const double v_n = v_ij.dot(n);
        const double fn = normal_magnitude(p, mbar, overlap, v_n);
        const Vec2 v_t = v_ij - v_n * n;
        // xi' = xi - n (n . xi), then grow by v_t dt
        xi = xi - n * n.dot(xi) + v_t * dt;
        // F_t* = -k_t xi' - gamma_t mbar v_t
        const Vec2 damping = p.gamma_t * mbar * v_t;
        Vec2 F_t = -p.k_t * xi - damping;
        const double cap = p.mu * std::abs(fn);  // mu |F_n|
        const double ft2 = F_t.squaredNorm();
        if (ft2 > cap * cap) {
            // F_t = mu |F_n| F_t*/|F_t*|, and the spring shortened to match:
            // xi' = -(F_t + gamma_t mbar v_t) / k_t (spring_only: xi' = -F_t / k_t)
            F_t *= cap / std::sqrt(ft2);
            xi = p.slip_spring_only ? Vec2(-F_t / p.k_t) : Vec2(-(F_t + damping) / p.k_t);
        }
        return {fn * n, F_t};
    }
};

// Relative velocity of the contact points of i and j (n points from j to i):
// v_ij = v_i - v_j - (R_i w_i + R_j w_j) (z x n)   (spec/physics.md)
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
