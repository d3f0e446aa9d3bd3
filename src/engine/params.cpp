#include "hopper/engine/params.hpp"

#include <cmath>
#include <sstream>
#include <string_view>
#include <utility>

#include "hopper/core/error.hpp"
#include "hopper/engine/scene.hpp"

namespace hopper::engine {

using core::ConfigError;
using core::pi;

std::string to_string(Scheme s) {
    return s == Scheme::gear4 ? "gear4" : "verlet";
}

std::string to_string(OutletMeasure m) {
    switch (m) {
        case OutletMeasure::surface_gap:
            return "surface_gap";
        case OutletMeasure::centre_gap:
            return "centre_gap";
        case OutletMeasure::inner_envelope:
            return "inner_envelope";
    }
    return "unknown";
}

std::string to_string(SlipRule r) {
    return r == SlipRule::spring_and_dashpot ? "spring_and_dashpot" : "spring_only";
}

std::string to_string(LeverArm a) {
    return a == LeverArm::radius ? "radius" : "contact";
}

std::string to_string(NormalLaw l) {
    return l == NormalLaw::linear ? "linear" : "hertz";
}

std::string to_string(TangentialLaw l) {
    switch (l) {
        case TangentialLaw::automatic:
            return "auto";
        case TangentialLaw::frictionless:
            return "frictionless";
        case TangentialLaw::viscous:
            return "viscous";
        case TangentialLaw::spring:
            return "spring";
    }
    return "?";
}

std::string to_string(RollingLaw l) {
    return l == RollingLaw::constant ? "constant" : "spring";
}

double hertz_restitution(double alpha) {
    // RK4 from first contact (xi = 0, xi' = 1) until xi is back at 0; the crossing is located by
    // linear interpolation between the two steps that bracket it. A collision so damped that it
    // has not ended within 200 time units (the undamped one lasts 3.2) counts as no rebound.
    const auto acc = [alpha](double x, double v) {
        const double xp = x > 0.0 ? x : 0.0;
        return -xp * std::sqrt(xp) - alpha * std::sqrt(std::sqrt(xp)) * v;
    };
    const double h = 2e-4;
    double x = 0.0, v = 1.0;
    for (int k = 0; k < 1000000; ++k) {
        const double k1x = v, k1v = acc(x, v);
        const double k2x = v + 0.5 * h * k1v, k2v = acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        const double k3x = v + 0.5 * h * k2v, k3v = acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        const double k4x = v + h * k3v, k4v = acc(x + h * k3x, v + h * k3v);
        const double xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        const double vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if (k > 0 && xn <= 0.0) {
            const double f = x / (x - xn);
            return -(v + f * (vn - v));
        }
        x = xn;
        v = vn;
    }
    return 0.0;
}

double hertz_damping_alpha(double e_n) {
    if (e_n >= 1.0) return 0.0;
    // e falls from 1 at alpha = 0; bracket, then bisect.
    double lo = 0.0, hi = 1.0;
    while (hertz_restitution(hi) > e_n && hi < 1e3)
        hi *= 2.0;
    for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (hertz_restitution(mid) > e_n ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

std::string to_string(NormalDamping d) {
    return d == NormalDamping::nominal ? "nominal" : "exact_restitution";
}

std::string to_string(ProtocolMode m) {
    return m == ProtocolMode::published ? "published" : "steady_state";
}

std::string to_string(UnjamMode m) {
    switch (m) {
        case UnjamMode::shake:
            return "shake";
        case UnjamMode::remove_arch:
            return "remove_arch";
        case UnjamMode::refill:
            return "refill";
    }
    return "shake";
}

namespace {

// Rejects value unless lo <= value <= hi (or lo < value when open_lo), naming the parameter.
void require_range(const char* name, double value, double lo, double hi, bool open_lo = false,
                   const char* unit = "") {
    const bool ok = std::isfinite(value) && (open_lo ? value > lo : value >= lo) && value <= hi;
    if (!ok) {
        std::ostringstream msg;
        msg << "parameter " << name << " = " << value << unit << " is out of range: allowed "
            << (open_lo ? "(" : "[") << lo << ", " << hi << "]" << unit;
        throw ConfigError(msg.str());
    }
}

// The hopper's walls and outlet: sizes, the wall's spacing (no particle slips between two wall
// disks, nor between the edge disk and its neighbour) and the outlet's free gap.
void validate_geometry(const SceneParams& p) {
    const auto& h = p.hopper;
    const auto& s = p.particles;
    require_range("particles.d_small", s.d_small, 0.0, 1.0, true, " m");
    require_range("particles.d_large", s.d_large, s.d_small, 1.0, false, " m");
    require_range("hopper.width", h.width, 2.0 * s.d_large, 100.0, true, " m");
    require_range("hopper.outlet", h.outlet, 0.0, h.width, true, " m");
    require_range("hopper.theta", h.theta, 0.0, pi / 2, false, " rad");
    require_range("walls.diameter", h.wall_diameter, 1e-4, 1.0, false, " m");
    if (h.edge_diameter)
        require_range("walls.edge_diameter", *h.edge_diameter, 1e-4, 1.0, false, " m");
    require_range("walls.edge_offset", h.edge_offset, 0.0, 10.0, false, " wall diameters");
    if (h.outlet_measure == OutletMeasure::inner_envelope && !(h.theta >= 1.0 * core::deg))
        throw ConfigError(
            "hopper.outlet_measure = inner_envelope needs theta_deg >= 1 (the inner envelope of a "
            "flat bottom never crosses the outlet plane); use surface_gap or centre_gap");
    // No system particle may slip between two wall particles: gap < d_small.
    const double max_spacing = 1.0 + s.d_small / h.wall_diameter;
    if (!(h.wall_spacing >= 0.1 && h.wall_spacing < max_spacing)) {
        std::ostringstream msg;
        msg << "parameter walls.spacing = " << h.wall_spacing
            << " (centre distance / wall diameter) is out of range: allowed [0.1, " << max_spacing
            << ") so that no particle of diameter " << s.d_small
            << " m slips between two wall particles";
        throw ConfigError(msg.str());
    }
    // Neither may a particle slip between the edge disk and its neighbour on the wall.
    const double d_edge = h.edge_diameter.value_or(h.wall_diameter);
    const double edge_gap = h.wall_spacing * h.wall_diameter - (d_edge + h.wall_diameter) / 2;
    if (!(edge_gap < s.d_small)) {
        std::ostringstream msg;
        msg << "parameter walls.edge_diameter = " << d_edge << " m leaves a gap of " << edge_gap
            << " m to the next wall particle, wider than a small particle (" << s.d_small
            << " m): use a larger edge disk or a smaller walls.spacing";
        throw ConfigError(msg.str());
    }
    {
        const double free_gap = outlet_free_gap(h);
        if (!(free_gap > 0.0 && free_gap < h.width)) {
            std::ostringstream msg;
            msg << "the outlet's free gap between the edge disks would be " << free_gap
                << " m (outlet " << h.outlet << " m measured as " << to_string(h.outlet_measure)
                << ", edge disk " << d_edge << " m, edge_offset " << h.edge_offset
                << "): allowed (0, width = " << h.width << " m); widen the outlet";
            throw ConfigError(msg.str());
        }
    }
}

// The particles, the contact coefficients, the integrator and gravity.
void validate_particles_and_material(const SceneParams& p) {
    const auto& s = p.particles;
    const auto& m = p.material;
    if (s.count < 1 || s.count > 10'000'000)
        throw ConfigError("parameter particles.count = " + std::to_string(s.count) +
                          " is out of range: allowed [1, 10000000]");
    require_range("particles.small_fraction", s.small_fraction, 0.0, 1.0);
    require_range("particles.size_spread", s.size_spread, 0.0, 0.3);
    require_range("particles.thickness", s.thickness, 0.0, 1.0, true, " m");
    require_range("particles.density", s.density, 0.0, 1e5, true, " kg/m^3");
    require_range("material.e_n", m.system.e_n, 0.0, 1.0, true);
    require_range("material.mu", m.system.mu, 0.0, 10.0);
    require_range("walls.e_n", m.wall.e_n, 0.0, 1.0, true);
    require_range("walls.mu", m.wall.mu, 0.0, 10.0);
    require_range("material.kt_over_kn", m.kt_over_kn, 0.0, 10.0);
    require_range("material.youngs_modulus", m.youngs_modulus, 1.0, 1e13, false, " Pa");
    require_range("material.poisson_ratio", m.poisson_ratio, -1.0, 0.5);
    require_range("material.gamma_t_over_gamma_n", m.gamma_t_over_gamma_n, 0.0, 10.0);
    if (m.collision_time)
        require_range("material.collision_time", *m.collision_time, 1e-9, 1.0, false, " s");
    require_range("integrator.steps_per_collision", p.integrator.steps_per_collision, 2.0, 1e5);
    if (const double sd = p.integrator.settle_steps_per_collision;
        sd != 0.0 && !(std::isfinite(sd) && sd >= 2.0 && sd <= 1e5)) {
        std::ostringstream msg;
        msg << "parameter integrator.settle_steps_per_collision = " << sd
            << " is out of range: allowed 0 (the settle at steps_per_collision) or [2, 1e5]";
        throw ConfigError(msg.str());
    }
    require_range("integrator.skin", p.integrator.skin, 0.0, 10.0, true);
    require_range("gravity", p.gravity, 0.0, 1e3, true, " m/s^2");
}

// The fill lattice's spacing, speeds and base, and the column it makes.
void validate_fill(const SceneParams& p) {
    const auto& h = p.hopper;
    const auto& s = p.particles;
    const auto& pr = p.protocol;
    const double d_edge = h.edge_diameter.value_or(h.wall_diameter);
    require_range("protocol.fill_gap", pr.fill_gap, 0.0, 10.0);
    require_range("protocol.fill_speed", pr.fill_speed, 0.0, 10.0, false, " m/s");
    require_range("protocol.fill_base", pr.fill_base, 0.0, 1000.0, false, " d_large");
    {
        // The fill's column (scene.cpp: a square lattice of pitch d_large + gap, rows as wide
        // as the side walls allow at most) must be a hopper's, not a chimney many hundred widths
        // tall: 10 million disks in a 10 cm hopper would stack 5 km high and fill gigabytes
        // before the first step (issue 29, item 7). A lower bound on its height: every row full.
        const double gap = pr.fill_gap * s.d_large;
        const double pitch = s.d_large + gap;
        const double clear = std::max(h.wall_diameter, d_edge) / 2 + s.d_large / 2 + gap;
        const double row_width = h.width + h.wall_diameter - 2.0 * clear;
        const double per_row = row_width < 0.0 ? 1.0 : std::floor(row_width / pitch + 1e-9) + 1.0;
        const double column = std::ceil(s.count / per_row) * pitch;
        constexpr double max_aspect = 1000.0;
        if (column > max_aspect * h.width) {
            std::ostringstream msg;
            msg << "particles.count (hopper.particles) = " << s.count << " does not fit a hopper "
                << h.width << " m wide: its particles would stand in a column at least " << column
                << " m tall (" << std::llround(column / h.width) << " widths; at most "
                << max_aspect << " allowed); lower the particle count or widen the hopper";
            throw ConfigError(msg.str());
        }
    }
}

// Settling, the jam detector, the coarse-grained fields.
void validate_detection_and_fields(const SceneParams& p) {
    const auto& pr = p.protocol;
    require_range("protocol.settle_ke", pr.settle_ke, 0.0, 1.0, true);
    require_range("protocol.settle_hold", pr.settle_hold, 0.0, 100.0, true, " s");
    require_range("protocol.settle_max_time", pr.settle_max_time, 0.0, 1e5, true, " s");
    require_range("protocol.jam_region_height", pr.jam_region_height, 0.0, 100.0, true);
    require_range("protocol.jam_min_speed", pr.jam_min_speed, 0.0, 10.0, false);
    require_range("protocol.lid_gravity", pr.lid_gravity, 0.0, 1000.0, false);
    require_range("protocol.lid_depth", pr.lid_depth, 0.0, 100.0, true);
    if (pr.t_check) require_range("protocol.t_check", *pr.t_check, 0.0, 100.0, true, " s");
    require_range("protocol.detector_interval", pr.detector_interval, 0.0, 1.0, true, " s");
    const auto& f = p.fields;
    if (f.enabled) {
        require_range("fields.window", f.window, 0.0, 1e4, true, " s");
        require_range("fields.cell", f.cell, 0.25, 1000.0, false, " d_large");
        require_range("fields.sample_interval", f.sample_interval, 0.0, f.window, false, " s");
        require_range("fields.start", f.start, 0.0, 1e6, false, " s");
        if (f.end) require_range("fields.end", *f.end, f.start, 1e6, true, " s");
        if (f.kernel == FieldKernel::gaussian)
            require_range("fields.kernel_width", f.kernel_width, 0.05, 100.0, false, " d_large");
    }
}

// Shakes, the run's limits, the jams per realization and what clears them.
void validate_unjam_and_limits(const SceneParams& p) {
    const auto& s = p.particles;
    const auto& pr = p.protocol;
    require_range("protocol.shake_amplitude", pr.shake_amplitude, 0.0, 100.0, true);
    require_range("protocol.shake_period", pr.shake_period, 0.0, 100.0, true, " s");
    require_range("protocol.shake_direction", pr.shake_direction, -pi, pi, false, " rad");
    if (pr.max_shakes < 0 || pr.max_shakes > 100000)
        throw ConfigError("parameter protocol.max_shakes = " + std::to_string(pr.max_shakes) +
                          " is out of range: allowed [0, 100000]");
    require_range("protocol.shake_growth", pr.shake_growth, 1.0, 10.0, false);
    require_range("protocol.shake_amplitude_max", pr.shake_amplitude_max, 0.0, 100.0, true);
    if (pr.shake_growth > 1.0 && pr.shake_amplitude_max < pr.shake_amplitude)
        throw ConfigError(
            "parameter protocol.shake_amplitude_max = " + std::to_string(pr.shake_amplitude_max) +
            " is below protocol.shake_amplitude = " + std::to_string(pr.shake_amplitude) +
            ": the cap of growing shakes must be at least the first shake's "
            "amplitude");
    require_range("protocol.max_time", pr.max_time, 0.0, 1e7, true, " s");
    require_range("protocol.exit_depth", pr.exit_depth, pr.jam_region_height, 1000.0, true);
    if (pr.empty_threshold < 0 || pr.empty_threshold >= s.count)
        throw ConfigError(
            "parameter protocol.empty_threshold = " + std::to_string(pr.empty_threshold) +
            " is out of range: allowed [0, " + std::to_string(s.count - 1) + "]");
    require_range("protocol.sample_interval", pr.sample_interval, 0.0, 1e3, true, " s");
    require_range("protocol.max_overlap", pr.max_overlap, 0.0, 1.0, true);
    if (pr.jams_per_realization < 0 || pr.jams_per_realization > 10000000)
        throw ConfigError(
            "parameter protocol.jams_per_realization = " + std::to_string(pr.jams_per_realization) +
            " is out of range: allowed [0, 10000000]");
    if (pr.unjam == UnjamMode::refill && pr.jams_per_realization > 1)
        throw ConfigError(
            "parameter protocol.jams_per_realization = " + std::to_string(pr.jams_per_realization) +
            " cannot be met with protocol.unjam = refill, which ends every realization at its "
            "first jam; allowed with refill: 0 or 1");
}

// Settings that only make sense together (the Hertz law, rolling resistance, the steady state).
void validate_law_choices(const SceneParams& p) {
    const auto& m = p.material;
    const auto& pr = p.protocol;
    if (m.normal_law == NormalLaw::hertz && m.collision_time)
        throw ConfigError(
            "parameter material.collision_time_s sets the linear law's stiffness; with "
            "material.normal_law = hertz the stiffness comes from material.youngs_modulus and "
            "material.poisson_ratio (leave collision_time_s out)");
    require_range("material.mu_r", m.mu_r, 0.0, 1.0);
    require_range("material.plate_friction", m.plate_friction, 0.0, 1.0);
    require_range("material.plate_speed", m.plate_speed, 0.0, 10.0, true, " m/s");
    if (m.mu_r > 0.0 && !(m.kt_over_kn > 0.0 && (m.system.mu > 0.0 || m.wall.mu > 0.0)))
        throw ConfigError("parameter material.mu_r = " + std::to_string(m.mu_r) +
                          " needs the tangential spring of friction (material.kt_over_kn > 0 "
                          "and material.mu or walls.mu > 0): rolling resistance acts on rolling");
    if (m.rolling_law == RollingLaw::spring && !(m.mu_r > 0.0))
        throw ConfigError(
            "parameter material.rolling_law = spring needs material.mu_r > 0 (the spring's cap "
            "is mu_r R* |F_n|; it is 0)");
    if (m.rolling_law == RollingLaw::spring && m.normal_law != NormalLaw::linear)
        throw ConfigError(
            "parameter material.rolling_law = spring needs material.normal_law = linear (the "
            "rolling stiffness k_t R*^2 takes the linear law's constant k_t)");
    const TangentialLaw t = m.tangential_law;
    const bool spring_law = t == TangentialLaw::automatic || t == TangentialLaw::spring;
    if (m.mu_r > 0.0 && !spring_law)
        throw ConfigError("parameter material.mu_r = " + std::to_string(m.mu_r) +
                          " needs material.tangential_law = spring or auto (rolling resistance "
                          "comes with the spring laws), not " +
                          to_string(t));
    if (t == TangentialLaw::spring && m.normal_law == NormalLaw::linear && !(m.kt_over_kn > 0.0))
        throw ConfigError("parameter material.kt_over_kn = " + std::to_string(m.kt_over_kn) +
                          " is out of range with material.tangential_law = spring: allowed (0, 10] "
                          "(the spring's stiffness; 0 is the viscous law)");
    if (m.normal_law == NormalLaw::hertz && spring_law && !(m.kt_over_kn > 0.0))
        throw ConfigError(
            "parameter material.kt_over_kn = " + std::to_string(m.kt_over_kn) +
            " is out of range with material.normal_law = hertz: allowed (0, 10] (the Hertz law's "
            "tangential spring)");
    if (pr.mode == ProtocolMode::published && pr.jams_per_realization != 0)
        throw ConfigError(
            "parameter protocol.jams_per_realization = " + std::to_string(pr.jams_per_realization) +
            " needs protocol.mode = steady_state (the published protocol runs "
            "until the hopper is empty); allowed with mode = published: 0");
    if (pr.mode == ProtocolMode::published && pr.lid_gravity != 0.0)
        throw ConfigError("parameter protocol.lid_gravity = " + std::to_string(pr.lid_gravity) +
                          " needs protocol.mode = steady_state (the lid rests on a head the "
                          "re-insertion keeps constant); allowed with mode = published: 0");
}

}  // namespace

// In this order, so that of several bad values the same one is named first as before.
void validate_scene(const SceneParams& p) {
    validate_geometry(p);
    validate_particles_and_material(p);
    validate_fill(p);
    validate_detection_and_fields(p);
    validate_unjam_and_limits(p);
    validate_law_choices(p);
}

double hertz_collision_time(double m, double d, double youngs_modulus, double poisson_ratio,
                            double v0) {
    // t_col = I(b) ((1+b)/2)^(1/(2+b)) (m / (E d^(1-b)))^(1/(2+b)) v0^(-b/(2+b)),  b = 1/2,
    // E = Y / (3 (1 - sigma^2)),  I(b) = 2 int_0^1 dy / sqrt(1 - y^(2+b))   (docs/model.md)
    // With p = 2 + b: int_0^1 (1 - y^p)^(-1/2) dy = B(1/p, 1/2) / p
    //                = Gamma(1/p) Gamma(1/2) / (p Gamma(1/p + 1/2)).
    const double b = 0.5;
    const double p = 2.0 + b;
    const double I_b =
        2.0 * std::tgamma(1.0 / p) * std::sqrt(pi) / (p * std::tgamma(1.0 / p + 0.5));
    const double E = youngs_modulus / (3.0 * (1.0 - poisson_ratio * poisson_ratio));
    return I_b * std::pow((1.0 + b) / 2.0, 1.0 / p) *
           std::pow(m / (E * std::pow(d, 1.0 - b)), 1.0 / p) * std::pow(v0, -b / p);
}

double normal_damping_rate(NormalDamping form, double e_n, double tau_c) {
    const double ln_e = std::log(e_n);
    if (form == NormalDamping::nominal) return -2.0 * ln_e / tau_c;  // gamma_n = -2 ln(e_n) / tau_c
    // Two large disks (mbar = m_large / 2) are an oscillator x'' + gamma_n x' + w0^2 x = 0 with
    // w0 = pi / tau_c. It rebounds after half a damped period, pi / w_d with
    // w_d = sqrt(w0^2 - gamma_n^2 / 4), with restitution exp(-gamma_n pi / (2 w_d)). Setting
    // that to e_n: gamma_n = -2 w0 ln(e_n) / sqrt(pi^2 + ln(e_n)^2).
    const double w0 = pi / tau_c;
    return -2.0 * w0 * ln_e / std::sqrt(pi * pi + ln_e * ln_e);
}

DerivedConstants derive_constants(const SceneParams& p) {
    const auto& s = p.particles;
    const auto& mat = p.material;
    DerivedConstants c{};
    // m = rho pi d^2/4 h,  I = m d^2 / 8   (docs/model.md, particles)
    auto mass = [&](double d) { return s.density * pi * d * d / 4.0 * s.thickness; };
    c.m_small = mass(s.d_small);
    c.m_large = mass(s.d_large);
    c.I_small = c.m_small * s.d_small * s.d_small / 8.0;
    c.I_large = c.m_large * s.d_large * s.d_large / 8.0;
    const double v0 = std::sqrt(2.0 * p.gravity * s.d_large);
    // For Poisson ratio 0.5 (incompressible) E = Y/(3 * 0.75) is finite; at sigma -> +-1 it is not.
    c.hertz_time =
        (std::abs(mat.poisson_ratio) < 1.0)
            ? hertz_collision_time(c.m_large, s.d_large, mat.youngs_modulus, mat.poisson_ratio, v0)
            : 0.0;
    c.tau_c = mat.collision_time.value_or(c.hertz_time);
    if (mat.normal_law == NormalLaw::hertz) {
        // K = (5/3) E sqrt(R*), E = Y / (3 (1 - sigma^2)): for two large disks (R* = d/4) the
        // undamped collision at v0 lasts exactly the Hertz time above (docs/model.md).
        c.hertz_k =
            5.0 / 3.0 * mat.youngs_modulus / (3.0 * (1.0 - mat.poisson_ratio * mat.poisson_ratio));
        c.hertz_alpha_system = hertz_damping_alpha(mat.system.e_n);
        c.hertz_alpha_wall = hertz_damping_alpha(mat.wall.e_n);
    }
    if (!(c.tau_c > 0.0))
        throw core::ConfigError(
            "the collision time could not be derived from the material "
            "(poisson_ratio must be in (-1, 0.5]); give material.collision_time_s");
    // tau_c = pi sqrt(m_large / (2 k_n))  =>  k_n = m_large pi^2 / (2 tau_c^2)
    c.k_n = c.m_large * pi * pi / (2.0 * c.tau_c * c.tau_c);
    c.k_t = mat.kt_over_kn * c.k_n;
    c.gamma_n_system = normal_damping_rate(mat.normal_damping, mat.system.e_n, c.tau_c);
    c.gamma_n_wall = normal_damping_rate(mat.normal_damping, mat.wall.e_n, c.tau_c);
    c.dt = c.tau_c / p.integrator.steps_per_collision;
    c.settle_dt = p.integrator.settle_steps_per_collision > 0.0
                      ? c.tau_c / p.integrator.settle_steps_per_collision
                      : c.dt;
    c.t_check = p.protocol.t_check.value_or(2.0 * std::sqrt(s.d_large / p.gravity));
    // Every value is in range on its own; their combination must still give usable numbers.
    const std::pair<const char*, double> derived[] = {
        {"m_small", c.m_small}, {"m_large", c.m_large},        {"tau_c", c.tau_c},
        {"k_n", c.k_n},         {"gamma_n", c.gamma_n_system}, {"gamma_n (walls)", c.gamma_n_wall},
        {"dt", c.dt},           {"t_check", c.t_check},        {"settle dt", c.settle_dt}};
    for (const auto& [name, v] : derived)
        if (!std::isfinite(v) || (v <= 0.0 && std::string_view(name).substr(0, 7) != "gamma_n")) {
            std::ostringstream msg;
            msg << "the parameters give an unusable derived constant " << name << " = " << v
                << " (masses from density, thickness and diameters; k_n from the collision "
                   "time; dt = tau_c / steps_per_collision): change the extreme value";
            throw ConfigError(msg.str());
        }
    return c;
}

}  // namespace hopper::engine
