#pragma once
// The parameters of one hopper scene, in SI units, with the published values as defaults
// (docs/model.md). The config layer fills these from a sweep file; the engine validates them
// again (it is usable on its own) with validate_scene().

#include <optional>
#include <string>

#include "hopper/core/units.hpp"
#include "hopper/engine/fields.hpp"

namespace hopper::engine {

using core::cm;
using core::deg;

enum class Scheme { gear4, verlet };

std::string to_string(Scheme s);

// How the outlet width D is measured (docs/model.md, "Modelling choices"). Every choice places
// the outlet edge disks at y = 0; they differ in which distance between the two sides is D.
enum class OutletMeasure {
    surface_gap,     // D = free gap between the edge disks' surfaces (the default)
    centre_gap,      // D = distance between the edge disks' centres (free gap D - d_edge)
    inner_envelope,  // D = distance between the inclined walls' inner envelopes at y = 0
};

// What happens to the tangential spring while a contact slides (|F_t*| > mu |F_n|).
enum class SlipRule {
    spring_and_dashpot,  // spring set so that spring + dashpot = the capped force (default;
                         // LAMMPS's gran/hooke/history does the same)
    spring_only,         // spring alone set to the Coulomb limit: xi = -F_t / k_t
};

// Lever arm of a contact: from a disk's centre to the contact point.
enum class LeverArm {
    radius,   // R_i (the specification's v_ij and torque; the default)
    contact,  // R_i - x/2: the distance to the middle of the overlap
};

// The normal force law (docs/model.md, "Contact forces"; issue 28).
enum class NormalLaw {
    linear,  // F_n = k_n x - gamma_n mbar v_n (the specification; the default)
    hertz,   // F_n = K x^(3/2) - alpha sqrt(mbar K) x^(1/4) v_n, K from Y and sigma
};

// The tangential force law (docs/model.md, "Contact forces"; issue 42): named by
// material.tangential_law, or inferred from the coefficients (automatic, the default).
enum class TangentialLaw {
    automatic,     // frictionless when mu = 0, viscous when k_t = 0, else spring (the Hertz law:
                   // spring); the choice before the setting existed
    frictionless,  // no tangential force (mu is not used)
    viscous,       // kinetic friction only: F_t = -gamma_t mbar v_t, capped at mu |F_n|; no spring
    spring,        // a Cundall-Strack spring and dashpot, capped at mu |F_n| (k_t constant with the
                   // linear normal law, following the normal stiffness with the Hertz law)
};

// What resists the relative rolling of two touching disks when material.mu_r > 0 (docs/model.md,
// "Rolling resistance"; issue 39).
enum class RollingLaw {
    constant,  // the torque mu_r R* |F_n| against w_i - w_j while they differ (issue 28; default)
    spring,    // an elastic-plastic spring per contact, k_r = k_t R*^2, capped at mu_r R* |F_n|:
               // holds a static torque (linear normal law only)
};

// How gamma_n follows from e_n.
enum class NormalDamping {
    nominal,            // gamma_n = -2 ln(e_n) / tau_c (the specification; the default)
    exact_restitution,  // gamma_n such that two large disks rebound with exactly e_n
};

// How a realization runs (docs/model.md, "Realization protocol").
enum class ProtocolMode {
    published,     // fill, settle, discharge until empty (the default)
    steady_state,  // particles that leave are re-inserted at the top of the packing: the head
                   // stays constant and the realization runs until jams_per_realization jams
};

// What clears a jam (docs/model.md, step 5; issue 26).
enum class UnjamMode {
    shake,        // shake the whole hopper (the published protocol; the default)
    remove_arch,  // remove the arch over the outlet and re-insert its disks at the top
    refill,       // end the realization at its first jam: the next avalanche is a new fill's
};

std::string to_string(OutletMeasure m);
std::string to_string(ProtocolMode m);
std::string to_string(UnjamMode m);
std::string to_string(SlipRule r);
std::string to_string(LeverArm a);
std::string to_string(NormalDamping d);
std::string to_string(NormalLaw l);
std::string to_string(TangentialLaw l);
std::string to_string(RollingLaw l);

struct HopperGeometry {
    double width = 43.0 * cm;           // W: total inner width between the side walls
    double outlet = 4.5 * cm;           // D: free gap between the innermost wall particles
    double theta = 60.0 * deg;          // wall angle to the horizontal, [0, 90] deg
    double wall_diameter = 0.770 * cm;  // diameter of wall particles (default d_large)
    double wall_spacing = 1.0;          // centre distance of wall particles / wall_diameter
    OutletMeasure outlet_measure = OutletMeasure::surface_gap;
    // Diameter of the lowest disk of each inclined wall (the outlet edge); unset = wall_diameter.
    std::optional<double> edge_diameter;
    // The inclined walls' disks start this far (in wall diameters, along the wall) above the
    // point where the wall's centre line crosses the outlet plane y = 0; D is measured at that
    // crossing. 0 = the edge disks sit on the outlet plane (the default).
    double edge_offset = 0.0;
};

struct ParticleSpec {
    int count = 8750;              // N
    double small_fraction = 0.62;  // number fraction of small disks
    // Polydispersity (issue 39): each disk's diameter uniform in [d (1 - w), d (1 + w)] about
    // its species' d_small or d_large, mass and moment of inertia scaled with it (m ~ d^2,
    // I ~ d^4 at fixed thickness and density). 0 = exactly two sizes (the default).
    double size_spread = 0.0;
    double d_small = 0.602 * cm;
    double d_large = 0.770 * cm;
    double thickness = 0.32 * cm;  // h: disk thickness (sets the mass)
    double density = 1000.0;       // rho, kg/m^3
};

struct SurfaceMaterial {
    double e_n = 0.5;  // nominal normal restitution
    double mu = 0.8;   // Coulomb friction coefficient
};

struct MaterialParams {
    SurfaceMaterial system;         // particle-particle contacts
    SurfaceMaterial wall;           // particle-wall contacts
    double kt_over_kn = 0.8;        // k_t / k_n; 0 = viscous (kinetic) friction only
    double youngs_modulus = 4.8e6;  // Y, Pa
    double poisson_ratio = 0.5;     // sigma
    // tau_c given directly (the published study: 8.0e-4 s); unset = from the Hertz formula.
    std::optional<double> collision_time;
    double gamma_t_over_gamma_n = 0.5;  // gamma_t / gamma_n (the specification: 1/2)
    SlipRule slip_rule = SlipRule::spring_and_dashpot;
    LeverArm lever_arm = LeverArm::radius;
    NormalDamping normal_damping = NormalDamping::nominal;
    NormalLaw normal_law = NormalLaw::linear;
    TangentialLaw tangential_law = TangentialLaw::automatic;
    // Rolling resistance (issue 28): the coefficient of the torque mu_r R* |F_n| against the
    // relative rolling of two touching disks (particles and walls); 0 = none.
    double mu_r = 0.0;
    RollingLaw rolling_law = RollingLaw::constant;  // the law of that resistance
    // Friction against the front and back plates of a quasi-2D cell (issue 39; docs/model.md,
    // "Plate friction"): every mobile disk feels a force of plate_friction m g against its
    // velocity, Coulomb's law with the plates' normal load a fixed fraction of the weight, made
    // viscous below plate_speed (v / plate_speed of it, so that a disk at rest feels none);
    // 0 = none (the published study's disks).
    double plate_friction = 0.0;
    double plate_speed = 0.01;  // m/s
};

// Default: velocity Verlet at delta = 200, the cheapest setting of bench/accuracy whose every
// error is below 1 % (README, "Accuracy"). The published study used gear4 at delta = 50 (the
// paper campaigns pin that); it is 3x cheaper but its rebound spin is 3 % off.
struct IntegratorParams {
    // The default is what bench_accuracy's rule chooses (docs/accuracy.md): the cheapest setting
    // whose every measured error is below 1 %, velocity Verlet at delta = 75 with the contact
    // corrections (until issue 12: verlet at delta = 200 without them).
    Scheme scheme = Scheme::verlet;
    double steps_per_collision = 75.0;  // delta: dt = tau_c / delta
    // The settle's own delta (protocol step 2; issue 41): 0, the default, settles at
    // steps_per_collision. The step returns to dt = tau_c / steps_per_collision at the opening.
    double settle_steps_per_collision = 0.0;
    double skin = 0.4;  // Verlet skin, in units of d_small (bench_engine)
    // The contact corrections of bench/results/ACCURACY.md (SystemConfig::contact_corrections):
    // smaller collision biases at a given delta, the same model.
    bool contact_corrections = true;
};

struct ProtocolParams {
    // Fill (lattice spacing d_large + fill_gap; random velocities up to fill_speed).
    double fill_gap = 0.05;    // in units of d_large
    double fill_speed = 0.05;  // m/s, max initial speed per component
    double fill_base = 0.0;    // extra height of the lowest fill row, in units of d_large
    // Settle with the outlet closed until the mean kinetic energy per particle stays below
    // settle_ke * m_large g d_large for settle_hold seconds; give up after settle_max_time.
    double settle_ke = 1e-4;
    double settle_hold = 0.05;      // s
    double settle_max_time = 20.0;  // s
    // Jam detection: region |x| < D/2, -jam_region_height < y < 0 (units of d_large).
    double jam_region_height = 2.0;
    // A disk in the region counts only while its speed is at least jam_min_speed sqrt(g d_large)
    // (issue 39: a disk lodged there at rest hid a stopped flow). 0: every disk counts, the
    // detector of 0.4.0 and earlier.
    double jam_min_speed = 0.01;
    std::optional<double> t_check;    // s; unset = 2 sqrt(d_large / g)
    double detector_interval = 1e-4;  // s between looks at the region
    // Unjamming: one sinusoidal oscillation of the whole hopper per shake.
    double shake_amplitude = 0.25;        // in units of d_large
    double shake_period = 0.05;           // s
    double shake_direction = 90.0 * deg;  // angle to the horizontal (90 deg = vertical)
    int max_shakes = 10;                  // shakes per jam before the realization is "arrested"
    // Escalation (issue 23): the k-th shake of one jam has the amplitude
    // min(shake_amplitude * shake_growth^(k-1), max(shake_amplitude, shake_amplitude_max)).
    // At shake_growth = 1 (the default) every shake is the same, as in the published protocol.
    double shake_growth = 1.0;
    double shake_amplitude_max = 1.0;  // in units of d_large
    double max_time = 600.0;           // s of discharge (shaking excluded) before "time_limit"
    // A particle this far below the outlet (units of d_large) has left and is removed.
    double exit_depth = 4.0;
    // The hopper counts as empty when at most this many particles are left in it.
    int empty_threshold = 0;
    double sample_interval = 0.01;  // s between samples of the discharge curve
    // Numerical guards.
    double max_overlap = 0.25;  // largest allowed overlap / d_small
    // Steady state (issue 13): re-insert what leaves; end after this many jams (0: only at
    // max_time). Ignored by the published protocol, which must leave it at 0.
    ProtocolMode mode = ProtocolMode::published;
    int jams_per_realization = 0;
    // What clears a jam (issue 26). With remove_arch, max_shakes bounds the arch removals of
    // one jam and the shake settings play no part.
    UnjamMode unjam = UnjamMode::shake;
    // The lid (issue 40; steady state only): while the hopper discharges, the disks whose centres
    // lie between 1 and 1 + lid_depth large diameters below the packing's top (the steady
    // state's insertion height) weigh 1 + lid_gravity times their weight: a weighted layer of
    // free disks that stands in for the column a small head lacks. 0: no lid.
    double lid_gravity = 0.0;
    double lid_depth = 3.0;  // in units of d_large
};

struct SceneParams {
    HopperGeometry hopper;
    ParticleSpec particles;
    MaterialParams material;
    IntegratorParams integrator;
    ProtocolParams protocol;
    FieldParams fields;  // coarse-grained fields (off by default; fields.hpp)
    double gravity = core::standard_gravity;
};

// Throws core::ConfigError naming the parameter, its value and the allowed range.
void validate_scene(const SceneParams& p);

// Quantities derived once from the parameters (docs/model.md, material and stiffness).
struct DerivedConstants {
    double m_small, m_large;  // kg
    double I_small, I_large;  // kg m^2, I = m d^2 / 8
    double hertz_time;        // s, t_col of the Hertz formula for two large disks
    double tau_c;             // s, the collision time used
    double k_n;               // N/m, tau_c = pi sqrt(m_large / (2 k_n))
    double k_t;               // N/m
    double gamma_n_system;    // 1/s, -2 ln(e_n) / tau_c
    double gamma_n_wall;
    // The Hertz law (normal_law = hertz): K = hertz_k sqrt(R*), and its damping constant for the
    // particles' and the walls' e_n (hertz_damping_alpha).
    double hertz_k = 0.0;  // N/m^2
    double hertz_alpha_system = 0.0, hertz_alpha_wall = 0.0;
    double dt;         // s, tau_c / delta
    double settle_dt;  // s, the settle's: tau_c / integrator.settle_steps_per_collision, or dt
    double t_check;    // s
};

DerivedConstants derive_constants(const SceneParams& p);

// The Hertz law's damping: the alpha for which two disks meeting head on rebound with e_n
// (xi'' = -xi^(3/2) - alpha xi^(1/4) xi', the collision in units where K, mbar and the impact
// speed are 1: e depends on alpha only), and the restitution of a given alpha.
double hertz_damping_alpha(double e_n);
double hertz_restitution(double alpha);

// gamma_n (1/s) for restitution e_n and collision time tau_c in the given damping form.
double normal_damping_rate(NormalDamping form, double e_n, double tau_c);

// The Hertz collision time t_col (docs/model.md) for disks of mass m, diameter d, material
// (Y, sigma), impact speed v0.
double hertz_collision_time(double m, double d, double youngs_modulus, double poisson_ratio,
                            double v0);

}  // namespace hopper::engine
