// Derived constants and scene validation (docs/model.md, "Particles" and "Material and
// stiffness"). Every expected value is computed here independently of src/engine/params.cpp:
// the Hertz integral by quadrature instead of the Beta-function closed form, the masses and k_n
// straight from their defining formulas.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "hopper/core/error.hpp"
#include "hopper/engine/params.hpp"

namespace {

using hopper::core::ConfigError;
using hopper::core::pi;
using namespace hopper::engine;

// Composite Simpson rule on [a, b] with n (even) panels.
double simpson(const std::function<double(double)>& f, double a, double b, int n) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int k = 1; k < n; ++k)
        s += (k % 2 ? 4.0 : 2.0) * f(a + k * h);
    return s * h / 3.0;
}

// I(b) = 2 int_0^1 dy / sqrt(1 - y^(2+b)). The integrand blows up like (p (1-y))^(-1/2) at y = 1
// (p = 2 + b). With y = 1 - u^2, dy = -2u du:
//     I(b) = 2 int_0^1 2u du / sqrt(1 - (1 - u^2)^p),
// whose integrand tends to 2/sqrt(p) at u = 0 and is smooth there (a series in u^2). The only
// remaining non-smoothness is (1-u^2)^p at u = 1, whose p = 2.5 power makes the fourth derivative
// blow up like (1-u)^(-3/2): still integrable, so Simpson converges at least like h^3.5; with
// 2e5 panels the error is far below the 1e-6 we ask for (checked below by halving n).
double hertz_integral(double b, int panels) {
    const double p = 2.0 + b;
    auto f = [p](double u) {
        if (u == 0.0) return 2.0 / std::sqrt(p);  // limit u -> 0
        return 2.0 * u / std::sqrt(1.0 - std::pow(1.0 - u * u, p));
    };
    return 2.0 * simpson(f, 0.0, 1.0, panels);
}

// The spec's parameters for the "default material": large disk d = 0.770 cm, h = 0.32 cm,
// rho = 1000 kg/m^3, Y = 4.8e6 Pa, sigma = 0.5, v0 = sqrt(2 g d).
constexpr double d_large = 0.770e-2, d_small = 0.602e-2, h = 0.32e-2, rho = 1000.0;
constexpr double Y = 4.8e6, sigma = 0.5, g = 9.81;

TEST(Params, HertzIntegralQuadratureConverged) {
    // Halving the step must not change I(1/2) beyond 1e-9 relative (Simpson at h^3.5 or better).
    const double I1 = hertz_integral(0.5, 100000);
    const double I2 = hertz_integral(0.5, 200000);
    EXPECT_NEAR(I1, I2, 1e-9 * I2);
    // Sanity: I(b) > 2 (the integrand is >= 1) and < 2 * int dy/sqrt(1-y) = 4.
    EXPECT_GT(I2, 2.0);
    EXPECT_LT(I2, 4.0);
}

TEST(Params, HertzCollisionTimeOfTheDefaultMaterial) {
    const double m = rho * pi * d_large * d_large / 4.0 * h;
    const double v0 = std::sqrt(2.0 * g * d_large);
    const double b = 0.5, p = 2.0 + b;
    const double E = Y / (3.0 * (1.0 - sigma * sigma));
    // t_col = I(b) ((1+b)/2)^(1/(2+b)) (m / (E d^(1-b)))^(1/(2+b)) v0^(-b/(2+b))
    const double expected = hertz_integral(b, 200000) * std::pow((1.0 + b) / 2.0, 1.0 / p) *
                            std::pow(m / (E * std::pow(d_large, 1.0 - b)), 1.0 / p) *
                            std::pow(v0, -b / p);
    const double t = hertz_collision_time(m, d_large, Y, sigma, v0);
    // 1e-6: both sides evaluate the same formula; only the quadrature (< 1e-9) differs.
    EXPECT_NEAR(t, expected, 1e-6 * expected);
    // The spec quotes "~7.3e-4 s" for the formula (7.266e-4 s).
    EXPECT_NEAR(t, 7.3e-4, 0.05e-4);

    // derive_constants() uses the same number when no collision_time is given.
    SceneParams sp;
    const DerivedConstants c = derive_constants(sp);
    EXPECT_NEAR(c.hertz_time, expected, 1e-6 * expected);
    EXPECT_NEAR(c.tau_c, expected, 1e-6 * expected);
    // tau_c = pi sqrt(m_large / (2 k_n))  =>  k_n = pi^2 m / (2 tau_c^2) = 1393 N/m here.
    EXPECT_NEAR(c.k_n, pi * pi * m / (2.0 * expected * expected), 1e-5 * c.k_n);
}

TEST(Params, MassesAndMomentsOfInertia) {
    SceneParams sp;
    const DerivedConstants c = derive_constants(sp);
    // m = rho pi d^2/4 h; the spec quotes 4 significant digits (1.490e-4, 9.108e-5), i.e. a
    // rounding error of at most half a unit in the last digit: 3.4e-4 and 5.5e-5 relative.
    EXPECT_NEAR(c.m_large, 1.490e-4, 0.0005e-4);
    EXPECT_NEAR(c.m_small, 9.108e-5, 0.0005e-5);
    const double m_l = rho * pi * d_large * d_large / 4.0 * h;
    const double m_s = rho * pi * d_small * d_small / 4.0 * h;
    EXPECT_NEAR(c.m_large, m_l, 1e-12 * m_l);
    EXPECT_NEAR(c.m_small, m_s, 1e-12 * m_s);
    // I = m d^2 / 8 (uniform disk about its axis).
    EXPECT_NEAR(c.I_large, m_l * d_large * d_large / 8.0, 1e-12 * c.I_large);
    EXPECT_NEAR(c.I_small, m_s * d_small * d_small / 8.0, 1e-12 * c.I_small);
}

TEST(Params, GivenCollisionTimeSetsStiffnessDampingAndStep) {
    SceneParams sp;
    sp.material.collision_time = 8.0e-4;
    sp.material.system.e_n = 0.5;
    sp.material.wall.e_n = 0.3;
    sp.integrator.steps_per_collision = 50.0;
    const DerivedConstants c = derive_constants(sp);
    EXPECT_DOUBLE_EQ(c.tau_c, 8.0e-4);
    // k_n = pi^2 m_large / (2 tau_c^2) = pi^2 * 1.4901e-4 / (2 * 6.4e-7) = 1149.0 N/m; the spec
    // quotes "k_n = 1149 N/m": 0.1 % covers its rounding and the mass's.
    EXPECT_NEAR(c.k_n, 1149.0, 1.149);
    // k_t = 0.8 k_n (default kt_over_kn).
    EXPECT_NEAR(c.k_t, 0.8 * c.k_n, 1e-12 * c.k_n);
    // gamma_n = -2 ln(e_n) / tau_c: 1732.9 1/s (e_n = 0.5), 3010.0 1/s (e_n = 0.3).
    EXPECT_NEAR(c.gamma_n_system, -2.0 * std::log(0.5) / 8.0e-4, 1e-9 * c.gamma_n_system);
    EXPECT_NEAR(c.gamma_n_wall, -2.0 * std::log(0.3) / 8.0e-4, 1e-9 * c.gamma_n_wall);
    // dt = tau_c / delta = 1.6e-5 s (spec: "dt = 1.6e-5 s with tau_c = 8e-4 s").
    EXPECT_NEAR(c.dt, 1.6e-5, 1e-12 * 1.6e-5);
    sp.integrator.steps_per_collision = 200.0;
    EXPECT_NEAR(derive_constants(sp).dt, 4.0e-6, 1e-12 * 4.0e-6);
    // t_check = 2 sqrt(d_large / g) = 0.0560 s.
    EXPECT_NEAR(c.t_check, 2.0 * std::sqrt(d_large / g), 1e-12);
    EXPECT_NEAR(c.t_check, 0.056, 0.0005);
    // e_n = 1: no damping at all.
    sp.material.system.e_n = 1.0;
    EXPECT_EQ(derive_constants(sp).gamma_n_system, 0.0);
}

// Expects validate_scene to throw ConfigError whose message contains every string in `names`.
void expect_rejected(const SceneParams& sp, std::initializer_list<std::string> names) {
    try {
        validate_scene(sp);
        ADD_FAILURE() << "validate_scene accepted an invalid scene (expected a message naming "
                      << *names.begin() << ")";
    } catch (const ConfigError& e) {
        const std::string what = e.what();
        for (const auto& s : names)
            EXPECT_NE(what.find(s), std::string::npos)
                << "message '" << what << "' lacks '" << s << "'";
    }
}

TEST(Params, DefaultsAreValid) {
    EXPECT_NO_THROW(validate_scene(SceneParams{}));
}

TEST(Params, ValidateRejectsNonPositiveOrExcessiveRestitution) {
    SceneParams sp;
    sp.material.system.e_n = 0.0;  // gamma_n = -2 ln(0) / tau_c = infinity
    expect_rejected(sp, {"e_n", "material"});
    sp.material.system.e_n = 1.2;  // an energy source
    expect_rejected(sp, {"e_n", "material"});
    sp.material.system.e_n = 1.0;  // elastic is allowed (energy tests, non-jamming checks)
    EXPECT_NO_THROW(validate_scene(sp));
    sp = SceneParams{};
    sp.material.wall.e_n = 0.0;
    expect_rejected(sp, {"e_n", "wall"});
}

TEST(Params, ValidateRejectsOutletWiderThanTheHopper) {
    SceneParams sp;
    sp.hopper.outlet = sp.hopper.width + 1e-3;
    expect_rejected(sp, {"outlet"});
    sp.hopper.outlet = 0.0;
    expect_rejected(sp, {"outlet"});
}

TEST(Params, ValidateRejectsWallSpacingThatLetsParticlesThrough) {
    // Free gap between two wall disks = (spacing - 1) d_w; a small disk slips through when the
    // gap reaches d_small: spacing >= 1 + d_small / d_w = 1 + 0.602/0.770 = 1.7818.
    SceneParams sp;
    const double limit = 1.0 + sp.particles.d_small / sp.hopper.wall_diameter;
    sp.hopper.wall_spacing = limit + 0.01;
    expect_rejected(sp, {"spacing"});
    sp.hopper.wall_spacing = limit - 0.01;
    EXPECT_NO_THROW(validate_scene(sp));
}

TEST(Params, ValidateRejectsNonsense) {
    SceneParams sp;
    sp.material.system.mu = -0.1;
    expect_rejected(sp, {"mu"});
    sp = SceneParams{};
    sp.hopper.theta = 100.0 * hopper::core::deg;
    expect_rejected(sp, {"theta"});
    sp = SceneParams{};
    sp.particles.d_large = 0.5 * sp.particles.d_small;
    expect_rejected(sp, {"d_large"});
    sp = SceneParams{};
    sp.integrator.steps_per_collision = 1.0;
    expect_rejected(sp, {"steps_per_collision"});
    for (double bad : {1.0, -25.0, 2e5, std::nan("")}) {  // 0 (the default) or [2, 1e5]
        sp = SceneParams{};
        sp.integrator.settle_steps_per_collision = bad;
        expect_rejected(sp, {"settle_steps_per_collision", "0 (the settle at"});
    }
    sp = SceneParams{};
    sp.material.collision_time = -1e-4;
    expect_rejected(sp, {"collision_time"});
}

TEST(Params, ValidateRejectsShakesThatShrinkOrACapBelowTheFirstShake) {
    SceneParams sp;
    sp.protocol.shake_growth = 0.5;
    expect_rejected(sp, {"protocol.shake_growth", "[1, 10]"});
    sp = SceneParams{};
    sp.protocol.shake_growth = 1.5;
    sp.protocol.shake_amplitude_max = 0.1;  // below shake_amplitude = 0.25
    expect_rejected(sp, {"protocol.shake_amplitude_max", "protocol.shake_amplitude"});
    sp.protocol.shake_growth = 1.0;  // no growth: the cap plays no part
    EXPECT_NO_THROW(validate_scene(sp));
}

TEST(Params, ValidateRejectsMoreJamsThanARefillAllows) {
    SceneParams sp;
    sp.protocol.mode = ProtocolMode::steady_state;
    sp.protocol.unjam = UnjamMode::refill;
    sp.protocol.jams_per_realization = 2;
    expect_rejected(sp, {"protocol.jams_per_realization", "refill"});
    sp.protocol.jams_per_realization = 1;
    EXPECT_NO_THROW(validate_scene(sp));
}

// The lid (issue 40) rests on the steady state's constant head: the published protocol, which
// empties the hopper, refuses it by name; its load and depth have ranges of their own.
TEST(Params, ValidateRejectsALidOutsideTheSteadyStateOrOutOfRange) {
    SceneParams sp;
    sp.protocol.lid_gravity = 5.0;
    expect_rejected(sp, {"protocol.lid_gravity", "steady_state"});
    sp.protocol.mode = ProtocolMode::steady_state;
    EXPECT_NO_THROW(validate_scene(sp));
    sp.protocol.lid_gravity = -1.0;
    expect_rejected(sp, {"protocol.lid_gravity", "[0, 1000]"});
    sp.protocol.lid_gravity = 5.0;
    sp.protocol.lid_depth = 0.0;
    expect_rejected(sp, {"protocol.lid_depth", "(0, 100]"});
}

}  // namespace
