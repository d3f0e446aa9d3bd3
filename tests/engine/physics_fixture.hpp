#pragma once
// Shared constants and builders for the System-level physics tests. The material is the one of
// the published study (docs/model.md): tau_c = 8.0e-4 s for two large disks, so
// k_n = pi^2 m_large / (2 tau_c^2) = 1149 N/m, gamma_n = -2 ln(e_n) / tau_c, k_t = 0.8 k_n,
// gamma_t = gamma_n / 2. Everything is recomputed here from the definitions, not taken from
// derive_constants(), so that these tests do not inherit its mistakes.

#include <cmath>
#include <ostream>

#include "hopper/core/units.hpp"
#include "hopper/core/vec.hpp"
#include "hopper/engine/contact.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine {
// GoogleTest prints parameters with this (found by ADL) instead of as raw bytes.
inline void PrintTo(Scheme s, std::ostream* os) {
    *os << to_string(s);
}
}  // namespace hopper::engine

namespace hopper::engine::testing {

using core::pi;

inline constexpr double d_large = 0.770e-2;   // m
inline constexpr double d_small = 0.602e-2;   // m
inline constexpr double thickness = 0.32e-2;  // m
inline constexpr double rho = 1000.0;         // kg/m^3
inline constexpr double g = 9.81;             // m/s^2
inline constexpr double tau_c = 8.0e-4;       // s

inline double disk_mass(double d) {
    return rho * pi * d * d / 4.0 * thickness;
}
inline double disk_inertia(double d) {
    return disk_mass(d) * d * d / 8.0;
}  // I = m d^2 / 8

inline const double m_large = disk_mass(d_large);
inline const double m_small = disk_mass(d_small);
// tau_c = pi sqrt(m_large / (2 k_n))
inline const double k_n = pi * pi * m_large / (2.0 * tau_c * tau_c);

inline double gamma_for(double e_n) {
    return e_n >= 1.0 ? 0.0 : -2.0 * std::log(e_n) / tau_c;
}

inline ContactParams contact_params(double e_n, double mu, double kt_over_kn = 0.8) {
    ContactParams p;
    p.k_n = k_n;
    p.gamma_n = gamma_for(e_n);
    p.k_t = kt_over_kn * k_n;
    p.gamma_t = 0.5 * p.gamma_n;
    p.mu = mu;
    return p;
}

// A configuration with the same contact law for particles and walls; dt = tau_c / delta.
inline SystemConfig system_config(Scheme scheme, double delta, const ContactParams& particle,
                                  const ContactParams& wall, Vec2 gravity = Vec2(0.0, -g)) {
    SystemConfig c;
    c.dt = tau_c / delta;
    c.scheme = scheme;
    c.particle = particle;
    c.wall = wall;
    c.gravity = gravity;
    c.skin = 0.25 * d_small;
    c.max_overlap = 0.0;
    return c;
}

inline int add_disk(System& s, const Vec2& pos, double d, const Vec2& vel = Vec2::Zero(),
                    double omega = 0.0) {
    return s.add_particle(pos, d, disk_mass(d), disk_inertia(d), vel, omega);
}

// A pile of 30 large disks with sideways speeds dropped into a box of wall disks (a floor at
// y = -5 mm, x within 10 cm), run for 8000 steps: the scene of the body forces' same-bits tests.
// Returns the number of contacts at the end (the pile must have landed).
inline std::size_t drop_pile(System& s) {
    for (double x = -0.1; x <= 0.1; x += 0.005)
        s.add_wall(Vec2(x, -0.005), 0.01);
    for (int k = 0; k < 30; ++k)
        add_disk(s, Vec2(-0.04 + 0.0081 * (k % 10), 0.01 + 0.0081 * (k / 10)), d_large,
                 Vec2(0.1 * ((k * 7) % 5 - 2), 0.0));
    for (int step = 0; step < 8000; ++step)
        s.step();
    return s.contacts_from_list().size();
}

// The exact damped linear oscillator of one contact (docs/model.md, normal force):
// mbar x'' = -k_n x - gamma_n mbar x', x(0) = 0, x'(0) = v0 > 0. With omega0^2 = k_n/mbar,
// beta = gamma_n/2, omega = sqrt(omega0^2 - beta^2): x(t) = v0/omega e^{-beta t} sin(omega t),
// so the overlap returns to zero at t_contact = pi/omega with x' = -v0 e^{-beta pi/omega}.
struct Oscillator {
    double omega0, beta, omega, t_contact, e;
};
inline Oscillator contact_oscillator(double kn, double gamma_n, double mbar) {
    Oscillator o;
    o.omega0 = std::sqrt(kn / mbar);
    o.beta = 0.5 * gamma_n;
    o.omega = std::sqrt(o.omega0 * o.omega0 - o.beta * o.beta);
    o.t_contact = pi / o.omega;
    o.e = std::exp(-o.beta * o.t_contact);
    return o;
}

}  // namespace hopper::engine::testing
