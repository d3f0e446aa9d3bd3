#include "config/key_table.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <sstream>

#include "hopper/core/units.hpp"

namespace hopper::config::detail {

namespace {

using engine::SceneParams;

double num(const Value& v) {
    return std::get<double>(v);
}

// The option of a choice key whose engine name (to_string) the file gave. The parser has checked
// the string against the key's list already, so the fallback is never taken.
template <class E>
E choice_of(const Value& v, std::initializer_list<E> options) {
    for (const E e : options)
        if (engine::to_string(e) == std::get<std::string>(v)) return e;
    return *options.begin();
}

// An SI value in file units: the shortest decimal x with x * unit == si (so that applying it
// gives the same scene bit for bit), else the plain quotient.
double in_unit(double si, double unit) {
    const double q = si / unit;
    char buf[64];
    for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, q);
        const double x = std::strtod(buf, nullptr);
        if (x * unit == si) return x;
    }
    return q;
}

Read in_unit(const std::optional<double>& si, double unit) {
    if (!si) return std::nullopt;
    return in_unit(*si, unit);
}

std::string flag(bool b) {
    return b ? "true" : "false";
}

using core::cm;
using core::deg;
using P = SceneParams;
using V = const Value&;
using FP = FingerprintLine;

constexpr bool open = true;
constexpr bool closed = false;

// clang-format off
const std::vector<KeyDef> table = {
    // [hopper]: geometry and particles
    KeyDef{"hopper", "D_cm", "D_cm", Kind::real, 0, 1e4, open, closed, "cm",
           [](P& p, V v) { p.hopper.outlet = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.hopper.outlet, cm); },
           FP{"hopper.outlet_m", 1, Enters::always}, [](const P& p) -> Read { return p.hopper.outlet; }},
    KeyDef{"hopper", "theta_deg", "theta_deg", Kind::real, 0, 90, closed, closed, "deg",
           [](P& p, V v) { p.hopper.theta = num(v) * deg; },
           [](const P& p) -> Read { return in_unit(p.hopper.theta, deg); },
           FP{"hopper.theta_rad", 2, Enters::always}, [](const P& p) -> Read { return p.hopper.theta; }},
    KeyDef{"hopper", "width_cm", "hopper.width_cm", Kind::real, 0, 1e4, open, closed, "cm",
           [](P& p, V v) { p.hopper.width = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.hopper.width, cm); },
           FP{"hopper.width_m", 0, Enters::always}, [](const P& p) -> Read { return p.hopper.width; }},
    KeyDef{"hopper", "particles", "hopper.particles", Kind::integer, 1, 1e7, closed, closed, "",
           [](P& p, V v) { p.particles.count = static_cast<int>(num(v)); },
           [](const P& p) -> Read { return static_cast<double>(p.particles.count); },
           FP{"particles.count", 5, Enters::always}},
    KeyDef{"hopper", "small_fraction", "hopper.small_fraction", Kind::real, 0, 1, closed, closed, "",
           [](P& p, V v) { p.particles.small_fraction = num(v); },
           [](const P& p) -> Read { return p.particles.small_fraction; },
           FP{"particles.small_fraction", 6, Enters::always}},
    KeyDef{"hopper", "size_spread", "hopper.size_spread", Kind::real, 0, 0.3, closed, closed, "",
           [](P& p, V v) { p.particles.size_spread = num(v); },
           [](const P& p) -> Read { return p.particles.size_spread; },
           FP{"particles.size_spread", 64, Enters::unless_default}},
    KeyDef{"hopper", "d_small_cm", "hopper.d_small_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.d_small = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.particles.d_small, cm); },
           FP{"particles.d_small_m", 7, Enters::always}, [](const P& p) -> Read { return p.particles.d_small; }},
    KeyDef{"hopper", "d_large_cm", "hopper.d_large_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.d_large = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.particles.d_large, cm); },
           FP{"particles.d_large_m", 8, Enters::always}, [](const P& p) -> Read { return p.particles.d_large; }},
    KeyDef{"hopper", "thickness_cm", "hopper.thickness_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.thickness = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.particles.thickness, cm); },
           FP{"particles.thickness_m", 9, Enters::always}, [](const P& p) -> Read { return p.particles.thickness; }},
    KeyDef{"hopper", "density_kg_m3", "hopper.density_kg_m3", Kind::real, 0, 1e5, open, closed, "kg/m^3",
           [](P& p, V v) { p.particles.density = num(v); },
           [](const P& p) -> Read { return p.particles.density; },
           FP{"particles.density_kg_m3", 10, Enters::always}},
    KeyDef{"hopper", "outlet_measure", "hopper.outlet_measure", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using M = engine::OutletMeasure;
               p.hopper.outlet_measure = choice_of(v, {M::surface_gap, M::centre_gap, M::inner_envelope});
           },
           [](const P& p) -> Read { return engine::to_string(p.hopper.outlet_measure); },
           FP{"hopper.outlet_measure", 40, Enters::unless_default}, nullptr, "surface_gap,centre_gap,inner_envelope"},
    // [material]: particle-particle contacts and stiffness
    KeyDef{"material", "e_n", "material.e_n", Kind::real, 0, 1, open, closed, "",
           [](P& p, V v) { p.material.system.e_n = num(v); },
           [](const P& p) -> Read { return p.material.system.e_n; },
           FP{"material.e_n", 11, Enters::always}},
    KeyDef{"material", "mu", "material.mu", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.system.mu = num(v); },
           [](const P& p) -> Read { return p.material.system.mu; },
           FP{"material.mu", 12, Enters::always}},
    KeyDef{"material", "kt_over_kn", "material.kt_over_kn", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.kt_over_kn = num(v); },
           [](const P& p) -> Read { return p.material.kt_over_kn; },
           FP{"material.kt_over_kn", 15, Enters::always}},
    KeyDef{"material", "youngs_modulus_pa", "material.youngs_modulus_pa", Kind::real, 1, 1e13, closed, closed, "Pa",
           [](P& p, V v) { p.material.youngs_modulus = num(v); },
           [](const P& p) -> Read { return p.material.youngs_modulus; },
           FP{"material.youngs_modulus_pa", 16, Enters::always}},
    KeyDef{"material", "poisson_ratio", "material.poisson_ratio", Kind::real, -1, 0.5, open, closed, "",
           [](P& p, V v) { p.material.poisson_ratio = num(v); },
           [](const P& p) -> Read { return p.material.poisson_ratio; },
           FP{"material.poisson_ratio", 17, Enters::always}},
    KeyDef{"material", "collision_time_s", "material.collision_time_s", Kind::real, 1e-9, 1, closed, closed, "s",
           [](P& p, V v) { p.material.collision_time = num(v); },
           [](const P& p) -> Read { return p.material.collision_time; },
           FP{"material.collision_time_s", 18, Enters::always}},
    KeyDef{"material", "gamma_t_over_gamma_n", "material.gamma_t_over_gamma_n", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.gamma_t_over_gamma_n = num(v); },
           [](const P& p) -> Read { return p.material.gamma_t_over_gamma_n; },
           FP{"material.gamma_t_over_gamma_n", 43, Enters::unless_default}},
    KeyDef{"material", "slip_rule", "material.slip_rule", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using R = engine::SlipRule;
               p.material.slip_rule = choice_of(v, {R::spring_and_dashpot, R::spring_only});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.slip_rule); },
           FP{"material.slip_rule", 44, Enters::unless_default}, nullptr, "spring_and_dashpot,spring_only"},
    KeyDef{"material", "lever_arm", "material.lever_arm", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.material.lever_arm = choice_of(v, {engine::LeverArm::radius, engine::LeverArm::contact});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.lever_arm); },
           FP{"material.lever_arm", 45, Enters::unless_default}, nullptr, "radius,contact"},
    KeyDef{"material", "normal_law", "material.normal_law", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using L = engine::NormalLaw;
               p.material.normal_law = choice_of(v, {L::linear, L::hertz});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.normal_law); },
           FP{"material.normal_law", 46, Enters::unless_default}, nullptr, "linear,hertz"},
    KeyDef{"material", "tangential_law", "material.tangential_law", Kind::choice, 0, 0, closed,
           closed, "",
           [](P& p, V v) {
               using T = engine::TangentialLaw;
               p.material.tangential_law =
                   choice_of(v, {T::automatic, T::frictionless, T::viscous, T::spring});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.tangential_law); },
           FP{"material.tangential_law", 67, Enters::unless_default}, nullptr,
           "auto,frictionless,viscous,spring"},
    KeyDef{"material", "mu_r", "material.mu_r", Kind::real, 0, 1, closed, closed, "",
           [](P& p, V v) { p.material.mu_r = num(v); },
           [](const P& p) -> Read { return p.material.mu_r; },
           FP{"material.mu_r", 47, Enters::unless_default}},
    KeyDef{"material", "rolling_law", "material.rolling_law", Kind::choice, 0, 0, closed, closed,
           "",
           [](P& p, V v) {
               using L = engine::RollingLaw;
               p.material.rolling_law = choice_of(v, {L::constant, L::spring});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.rolling_law); },
           FP{"material.rolling_law", 68, Enters::unless_default}, nullptr, "constant,spring"},
    KeyDef{"material", "plate_friction", "material.plate_friction", Kind::real, 0, 1, closed, closed, "",
           [](P& p, V v) { p.material.plate_friction = num(v); },
           [](const P& p) -> Read { return p.material.plate_friction; },
           FP{"material.plate_friction", 65, Enters::unless_default}},
    KeyDef{"material", "plate_speed_m_s", "material.plate_speed_m_s", Kind::real, 0, 10, open, closed, "m/s",
           [](P& p, V v) { p.material.plate_speed = num(v); },
           [](const P& p) -> Read { return p.material.plate_speed; },
           FP{"material.plate_speed_m_s", 66, Enters::unless_default}},
    KeyDef{"material", "normal_damping", "material.normal_damping", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using N = engine::NormalDamping;
               p.material.normal_damping = choice_of(v, {N::nominal, N::exact_restitution});
           },
           [](const P& p) -> Read { return engine::to_string(p.material.normal_damping); },
           FP{"material.normal_damping", 48, Enters::unless_default}, nullptr, "nominal,exact_restitution"},
    // [walls]: particle-wall contacts and wall roughness
    KeyDef{"walls", "e_n", "walls.e_n", Kind::real, 0, 1, open, closed, "",
           [](P& p, V v) { p.material.wall.e_n = num(v); },
           [](const P& p) -> Read { return p.material.wall.e_n; },
           FP{"walls.e_n", 13, Enters::always}},
    KeyDef{"walls", "mu", "walls.mu", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.wall.mu = num(v); },
           [](const P& p) -> Read { return p.material.wall.mu; },
           FP{"walls.mu", 14, Enters::always}},
    KeyDef{"walls", "particle_diameter_cm", "walls.particle_diameter_cm", Kind::real, 0.01, 100, closed, closed, "cm",
           [](P& p, V v) { p.hopper.wall_diameter = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.hopper.wall_diameter, cm); },
           FP{"hopper.wall_diameter_m", 3, Enters::always}, [](const P& p) -> Read { return p.hopper.wall_diameter; }},
    KeyDef{"walls", "spacing", "walls.spacing", Kind::real, 0.1, 100, closed, closed, "wall diameters",
           [](P& p, V v) { p.hopper.wall_spacing = num(v); },
           [](const P& p) -> Read { return p.hopper.wall_spacing; },
           FP{"hopper.wall_spacing", 4, Enters::always}},
    KeyDef{"walls", "edge_diameter_cm", "walls.edge_diameter_cm", Kind::real, 0.01, 100, closed, closed, "cm",
           [](P& p, V v) { p.hopper.edge_diameter = num(v) * cm; },
           [](const P& p) -> Read { return in_unit(p.hopper.edge_diameter, cm); },
           FP{"hopper.edge_diameter_m", 41, Enters::when_set}, [](const P& p) -> Read { return p.hopper.edge_diameter; }},
    KeyDef{"walls", "edge_offset", "walls.edge_offset", Kind::real, 0, 10, closed, closed, "wall diameters",
           [](P& p, V v) { p.hopper.edge_offset = num(v); },
           [](const P& p) -> Read { return p.hopper.edge_offset; },
           FP{"hopper.edge_offset", 42, Enters::unless_default}},
    // [integrator]
    KeyDef{"integrator", "scheme", "integrator.scheme", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.integrator.scheme = std::get<std::string>(v) == "verlet" ? engine::Scheme::verlet
                                                                         : engine::Scheme::gear4;
           },
           [](const P& p) -> Read { return engine::to_string(p.integrator.scheme); },
           FP{"integrator.scheme", 19, Enters::always}, nullptr, "gear4,verlet"},
    KeyDef{"integrator", "steps_per_collision", "integrator.steps_per_collision", Kind::real, 2, 1e5, closed, closed, "",
           [](P& p, V v) { p.integrator.steps_per_collision = num(v); },
           [](const P& p) -> Read { return p.integrator.steps_per_collision; },
           FP{"integrator.steps_per_collision", 20, Enters::always}},
    KeyDef{"integrator", "settle_steps_per_collision", "integrator.settle_steps_per_collision", Kind::real, 0, 1e5, closed, closed, "",
           [](P& p, V v) { p.integrator.settle_steps_per_collision = num(v); },
           [](const P& p) -> Read { return p.integrator.settle_steps_per_collision; },
           FP{"integrator.settle_steps_per_collision", 72, Enters::unless_default}},
    KeyDef{"integrator", "contact_corrections", "integrator.contact_corrections", Kind::boolean, 0, 0, closed, closed, "",
           [](P& p, V v) { p.integrator.contact_corrections = std::get<std::string>(v) == "true"; },
           [](const P& p) -> Read { return flag(p.integrator.contact_corrections); },
           FP{"integrator.contact_corrections", 50, Enters::unless_default, "", "false"}},
    KeyDef{"integrator", "skin", "integrator.skin", Kind::real, 0, 10, open, closed, "d_small",
           [](P& p, V v) { p.integrator.skin = num(v); },
           [](const P& p) -> Read { return p.integrator.skin; },
           FP{"integrator.skin", 21, Enters::always}},
    // [protocol]: fill, settle, jam detection, shaking, limits, sampling, guards
    KeyDef{"protocol", "fill_gap", "protocol.fill_gap", Kind::real, 0, 10, closed, closed, "d_large",
           [](P& p, V v) { p.protocol.fill_gap = num(v); },
           [](const P& p) -> Read { return p.protocol.fill_gap; },
           FP{"protocol.fill_gap", 22, Enters::always}},
    KeyDef{"protocol", "fill_speed_m_s", "protocol.fill_speed_m_s", Kind::real, 0, 10, closed, closed, "m/s",
           [](P& p, V v) { p.protocol.fill_speed = num(v); },
           [](const P& p) -> Read { return p.protocol.fill_speed; },
           FP{"protocol.fill_speed_m_s", 23, Enters::always}},
    KeyDef{"protocol", "fill_base", "protocol.fill_base", Kind::real, 0, 1000, closed, closed, "d_large",
           [](P& p, V v) { p.protocol.fill_base = num(v); },
           [](const P& p) -> Read { return p.protocol.fill_base; },
           FP{"protocol.fill_base", 49, Enters::unless_default}},
    KeyDef{"protocol", "settle_ke", "protocol.settle_ke", Kind::real, 0, 1, open, closed, "m_large g d_large",
           [](P& p, V v) { p.protocol.settle_ke = num(v); },
           [](const P& p) -> Read { return p.protocol.settle_ke; },
           FP{"protocol.settle_ke", 24, Enters::always}},
    KeyDef{"protocol", "settle_hold_s", "protocol.settle_hold_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.settle_hold = num(v); },
           [](const P& p) -> Read { return p.protocol.settle_hold; },
           FP{"protocol.settle_hold_s", 25, Enters::always}},
    KeyDef{"protocol", "settle_max_time_s", "protocol.settle_max_time_s", Kind::real, 0, 1e5, open, closed, "s",
           [](P& p, V v) { p.protocol.settle_max_time = num(v); },
           [](const P& p) -> Read { return p.protocol.settle_max_time; },
           FP{"protocol.settle_max_time_s", 26, Enters::always}},
    KeyDef{"protocol", "jam_region_height", "protocol.jam_region_height", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.jam_region_height = num(v); },
           [](const P& p) -> Read { return p.protocol.jam_region_height; },
           FP{"protocol.jam_region_height", 27, Enters::always}},
    KeyDef{"protocol", "jam_min_speed", "protocol.jam_min_speed", Kind::real, 0, 10, closed, closed, "sqrt(g d_large)",
           [](P& p, V v) { p.protocol.jam_min_speed = num(v); },
           [](const P& p) -> Read { return p.protocol.jam_min_speed; },
           FP{"protocol.jam_min_speed", 69, Enters::unless_default}},
    KeyDef{"protocol", "lid_gravity", "protocol.lid_gravity", Kind::real, 0, 1000, closed, closed, "g",
           [](P& p, V v) { p.protocol.lid_gravity = num(v); },
           [](const P& p) -> Read { return p.protocol.lid_gravity; },
           FP{"protocol.lid_gravity", 70, Enters::unless_default}},
    KeyDef{"protocol", "lid_depth", "protocol.lid_depth", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.lid_depth = num(v); },
           [](const P& p) -> Read { return p.protocol.lid_depth; },
           FP{"protocol.lid_depth", 71, Enters::always, "protocol.lid_gravity"}},
    KeyDef{"protocol", "t_check_s", "protocol.t_check_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.t_check = num(v); },
           [](const P& p) -> Read { return p.protocol.t_check; },
           FP{"protocol.t_check_s", 28, Enters::always}},
    KeyDef{"protocol", "detector_interval_s", "protocol.detector_interval_s", Kind::real, 0, 1, open, closed, "s",
           [](P& p, V v) { p.protocol.detector_interval = num(v); },
           [](const P& p) -> Read { return p.protocol.detector_interval; },
           FP{"protocol.detector_interval_s", 29, Enters::always}},
    KeyDef{"protocol", "shake_amplitude", "protocol.shake_amplitude", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.shake_amplitude = num(v); },
           [](const P& p) -> Read { return p.protocol.shake_amplitude; },
           FP{"protocol.shake_amplitude", 30, Enters::always}},
    KeyDef{"protocol", "shake_period_s", "protocol.shake_period_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.shake_period = num(v); },
           [](const P& p) -> Read { return p.protocol.shake_period; },
           FP{"protocol.shake_period_s", 31, Enters::always}},
    KeyDef{"protocol", "shake_direction_deg", "protocol.shake_direction_deg", Kind::real, -180, 180, closed, closed, "deg",
           [](P& p, V v) { p.protocol.shake_direction = num(v) * deg; },
           [](const P& p) -> Read { return in_unit(p.protocol.shake_direction, deg); },
           FP{"protocol.shake_direction_rad", 32, Enters::always}, [](const P& p) -> Read { return p.protocol.shake_direction; }},
    KeyDef{"protocol", "max_shakes", "protocol.max_shakes", Kind::integer, 0, 1e5, closed, closed, "",
           [](P& p, V v) { p.protocol.max_shakes = static_cast<int>(num(v)); },
           [](const P& p) -> Read { return static_cast<double>(p.protocol.max_shakes); },
           FP{"protocol.max_shakes", 33, Enters::always}},
    KeyDef{"protocol", "shake_growth", "protocol.shake_growth", Kind::real, 1, 10, closed, closed, "",
           [](P& p, V v) { p.protocol.shake_growth = num(v); },
           [](const P& p) -> Read { return p.protocol.shake_growth; },
           FP{"protocol.shake_growth", 54, Enters::unless_default}},
    KeyDef{"protocol", "shake_amplitude_max", "protocol.shake_amplitude_max", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.shake_amplitude_max = num(v); },
           [](const P& p) -> Read { return p.protocol.shake_amplitude_max; },
           FP{"protocol.shake_amplitude_max", 55, Enters::always, "protocol.shake_growth"}},
    KeyDef{"protocol", "max_time_s", "protocol.max_time_s", Kind::real, 0, 1e7, open, closed, "s",
           [](P& p, V v) { p.protocol.max_time = num(v); },
           [](const P& p) -> Read { return p.protocol.max_time; },
           FP{"protocol.max_time_s", 34, Enters::always}},
    KeyDef{"protocol", "exit_depth", "protocol.exit_depth", Kind::real, 0, 1000, open, closed, "d_large",
           [](P& p, V v) { p.protocol.exit_depth = num(v); },
           [](const P& p) -> Read { return p.protocol.exit_depth; },
           FP{"protocol.exit_depth", 35, Enters::always}},
    KeyDef{"protocol", "empty_threshold", "protocol.empty_threshold", Kind::integer, 0, 1e7, closed, closed, "",
           [](P& p, V v) { p.protocol.empty_threshold = static_cast<int>(num(v)); },
           [](const P& p) -> Read { return static_cast<double>(p.protocol.empty_threshold); },
           FP{"protocol.empty_threshold", 36, Enters::always}},
    KeyDef{"protocol", "sample_interval_s", "protocol.sample_interval_s", Kind::real, 0, 1e3, open, closed, "s",
           [](P& p, V v) { p.protocol.sample_interval = num(v); },
           [](const P& p) -> Read { return p.protocol.sample_interval; },
           FP{"protocol.sample_interval_s", 37, Enters::always}},
    KeyDef{"protocol", "max_overlap", "protocol.max_overlap", Kind::real, 0, 1, open, closed, "d_small",
           [](P& p, V v) { p.protocol.max_overlap = num(v); },
           [](const P& p) -> Read { return p.protocol.max_overlap; },
           FP{"protocol.max_overlap", 38, Enters::always}},
    KeyDef{"protocol", "mode", "protocol.mode", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using M = engine::ProtocolMode;
               p.protocol.mode = choice_of(v, {M::published, M::steady_state});
           },
           [](const P& p) -> Read { return engine::to_string(p.protocol.mode); },
           FP{"protocol.mode", 51, Enters::unless_default}, nullptr, "published,steady_state"},
    KeyDef{"protocol", "unjam", "protocol.unjam", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using U = engine::UnjamMode;
               p.protocol.unjam = choice_of(v, {U::shake, U::remove_arch, U::refill});
           },
           [](const P& p) -> Read { return engine::to_string(p.protocol.unjam); },
           FP{"protocol.unjam", 53, Enters::unless_default}, nullptr, "shake,remove_arch,refill"},
    KeyDef{"protocol", "jams_per_realization", "protocol.jams_per_realization", Kind::integer, 0, 1e7, closed, closed, "",
           [](P& p, V v) { p.protocol.jams_per_realization = static_cast<int>(num(v)); },
           [](const P& p) -> Read { return static_cast<double>(p.protocol.jams_per_realization); },
           FP{"protocol.jams_per_realization", 52, Enters::unless_default}},
    // [fields]: coarse-grained velocity and pressure fields of the discharge (off by default)
    KeyDef{"fields", "enabled", "fields.enabled", Kind::boolean, 0, 0, closed, closed, "",
           [](P& p, V v) { p.fields.enabled = std::get<std::string>(v) == "true"; },
           [](const P& p) -> Read { return flag(p.fields.enabled); },
           FP{"", 0, Enters::never}},
    KeyDef{"fields", "window_s", "fields.window_s", Kind::real, 0, 1e4, open, closed, "s",
           [](P& p, V v) { p.fields.window = num(v); },
           [](const P& p) -> Read { return p.fields.window; },
           FP{"fields.window_s", 56, Enters::always, "fields.enabled"}},
    KeyDef{"fields", "cell_dlarge", "fields.cell_dlarge", Kind::real, 0.25, 1000, closed, closed, "d_large",
           [](P& p, V v) { p.fields.cell = num(v); },
           [](const P& p) -> Read { return p.fields.cell; },
           FP{"fields.cell_dlarge", 57, Enters::always, "fields.enabled"}},
    KeyDef{"fields", "sample_interval_s", "fields.sample_interval_s", Kind::real, 0, 1e4, closed, closed, "s",
           [](P& p, V v) { p.fields.sample_interval = num(v); },
           [](const P& p) -> Read { return p.fields.sample_interval; },
           FP{"fields.sample_interval_s", 58, Enters::always, "fields.enabled"}},
    KeyDef{"fields", "start_s", "fields.start_s", Kind::real, 0, 1e6, closed, closed, "s",
           [](P& p, V v) { p.fields.start = num(v); },
           [](const P& p) -> Read { return p.fields.start; },
           FP{"fields.start_s", 59, Enters::always, "fields.enabled"}},
    KeyDef{"fields", "end_s", "fields.end_s", Kind::real, 0, 1e6, open, closed, "s",
           [](P& p, V v) { p.fields.end = num(v); },
           [](const P& p) -> Read { return p.fields.end; },
           FP{"fields.end_s", 60, Enters::always, "fields.enabled"}},
    KeyDef{"fields", "kernel", "fields.kernel", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.fields.kernel = std::get<std::string>(v) == "gaussian" ? engine::FieldKernel::gaussian
                                                                       : engine::FieldKernel::cell;
           },
           [](const P& p) -> Read { return engine::to_string(p.fields.kernel); },
           FP{"fields.kernel", 61, Enters::always, "fields.enabled"}, nullptr, "cell,gaussian"},
    KeyDef{"fields", "kernel_width_dlarge", "fields.kernel_width_dlarge", Kind::real, 0.05, 100, closed, closed, "d_large",
           [](P& p, V v) { p.fields.kernel_width = num(v); },
           [](const P& p) -> Read { return p.fields.kernel_width; },
           FP{"fields.kernel_width_dlarge", 62, Enters::always, "fields.kernel"}},
    // Not a key of the sweep file: how a re-inserted particle meets the springs of the packing
    // (the steady state only). Before this line existed every re-insertion reset every
    // tangential spring (a fault, fixed in round 3); the line keeps stores written then from
    // being resumed with the fixed engine, which would mix the two in one point.
    KeyDef{"", "reinsertion", "protocol.reinsertion", Kind::choice, 0, 0, closed, closed, "",
           [](P&, V) {},
           [](const P&) -> Read { return std::string("keeps_springs"); },
           FP{"protocol.reinsertion", 63, Enters::always, "protocol.mode"}, nullptr, "keeps_springs",
           false},
    // Not a key of the sweep file: standard gravity, in every fingerprint.
    KeyDef{"", "gravity_m_s2", "gravity_m_s2", Kind::real, 0, 1e3, open, closed, "m/s^2",
           [](P& p, V v) { p.gravity = num(v); },
           [](const P& p) -> Read { return p.gravity; },
           FP{"gravity_m_s2", 39, Enters::always}, nullptr, {}, false},
};
// clang-format on

}  // namespace

const std::vector<KeyDef>& key_table() {
    static const std::vector<KeyDef> keys = [] {
        std::vector<KeyDef> out;
        for (const auto& d : table)
            if (d.in_sweep_file) out.push_back(d);
        return out;
    }();
    return keys;
}

}  // namespace hopper::config::detail

namespace hopper::config {

const std::vector<SchemaRow>& scene_schema() {
    return detail::table;
}

}  // namespace hopper::config

namespace hopper::config::detail {

bool is_scene_section(std::string_view s) {
    return std::find(scene_sections.begin(), scene_sections.end(), s) != scene_sections.end();
}

const KeyDef* find_key(std::string_view section, std::string_view key) {
    for (const auto& d : key_table())
        if (d.section == section && d.key == key) return &d;
    return nullptr;
}

const KeyDef* find_name(std::string_view name) {
    for (const auto& d : key_table())
        if (d.name == name) return &d;
    return nullptr;
}

const KeyDef* quoted_dotted_key(std::string_view name) {
    const auto dot = name.find('.');
    if (dot == std::string_view::npos || !is_scene_section(name.substr(0, dot))) return nullptr;
    return find_key(name.substr(0, dot), name.substr(dot + 1));
}

std::vector<std::string> keys_of(std::string_view section) {
    std::vector<std::string> out;
    for (const auto& d : key_table())
        if (d.section == section) out.emplace_back(d.key);
    return out;
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
    std::string out;
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (i) out += sep;
        out += items[i];
    }
    return out;
}

// Canonical order of settings: D_cm, theta_deg, then by name.
bool canonical_less(std::string_view a, std::string_view b) {
    auto rank = [](std::string_view n) { return n == "D_cm" ? 0 : n == "theta_deg" ? 1 : 2; };
    const int ra = rank(a), rb = rank(b);
    return ra != rb ? ra < rb : a < b;
}

std::string range_text(const KeyDef& d) {
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on the one-expression form.
    std::string s(d.open_lo ? "(" : "[");
    s += message_number(d.lo);
    s += ", ";
    s += message_number(d.hi);
    s += d.open_hi ? ")" : "]";
    if (!d.unit.empty()) {
        s += ' ';
        s += d.unit;
    }
    return s;
}

// Empty when v is allowed for d, else the reason.
// `shown` is the value as the file wrote it (default: v formatted).
std::optional<std::string> range_error(const KeyDef& d, double v, const std::string& shown) {
    const bool ok = std::isfinite(v) && (d.open_lo ? v > d.lo : v >= d.lo) &&
                    (d.open_hi ? v < d.hi : v <= d.hi);
    if (ok) return std::nullopt;
    return std::string(d.name) + " = " + (shown.empty() ? message_number(v) : shown) +
           " is out of range: allowed " + range_text(d);
}

// A name from the file, shortened for messages (a 1 MB key must not make a 1 MB message).
std::string clip(std::string_view name, std::size_t limit) {
    if (name.size() <= limit) return std::string(name);
    return std::string(name.substr(0, limit)) + "... (" + std::to_string(name.size()) +
           " characters)";
}

std::string suggestion(std::string_view word, const std::vector<std::string>& options) {
    if (word.size() > 64) return "";  // no real key is that long; and keep the work bounded
    auto distance = [](std::string_view a, std::string_view b) {
        std::vector<std::size_t> row(b.size() + 1);
        for (std::size_t j = 0; j <= b.size(); ++j)
            row[j] = j;
        for (std::size_t i = 1; i <= a.size(); ++i) {
            std::size_t diag = row[0];
            row[0] = i;
            for (std::size_t j = 1; j <= b.size(); ++j) {
                const std::size_t up = row[j];
                const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                                  std::tolower(static_cast<unsigned char>(b[j - 1]));
                row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (same ? 0 : 1)});
                diag = up;
            }
        }
        return row[b.size()];
    };
    std::string best;
    std::size_t best_d = std::max<std::size_t>(2, word.size() / 3) + 1;
    for (const auto& o : options) {
        const std::size_t dd = distance(word, o);
        if (dd < best_d) {
            best_d = dd;
            best = o;
        }
    }
    return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

// ---------------------------------------------------------------------------------------------
// Number text

// Shortest text that reads back as the same double (std::to_chars): labels and seeds use it.
std::string format_number(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// Text for messages: integral values without an exponent ("10000000", not "1e+07").
std::string message_number(double v) {
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15) {
        return std::to_string(static_cast<long long>(v));
    }
    return format_number(v);
}

// Text of a derived (converted-back) quantity for messages, e.g. 0.027 m / cm -> "2.7".
std::string approx_number(double v) {
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

std::string value_text(const Value& v) {
    return std::holds_alternative<double>(v) ? format_number(std::get<double>(v))
                                             : std::get<std::string>(v);
}

}  // namespace hopper::config::detail
