// The tangential law named (material.tangential_law; issue 42, docs/model.md "Contact forces"):
// a named law is the one the coefficients used to imply, bit for bit; contradictions are refused
// naming the setting; the Hertz law with viscous friction (law_hertz_viscous.hpp, a law in a file
// of its own) against a hand evaluation of its formula.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "hopper/core/error.hpp"
#include "hopper/engine/law_hertz_viscous.hpp"
#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

constexpr double Y = 4.8e6, sigma = 0.5;

ContactParams with_hertz(ContactParams p, double e_n) {
    p.hertz_k = 5.0 / 3.0 * Y / (3.0 * (1.0 - sigma * sigma));
    p.hertz_alpha = hertz_damping_alpha(e_n);
    p.hertz_kt_ratio = 0.8;
    p.hertz_gt_ratio = 0.5;
    return p;
}

// Positions, velocities and spins of six disks after 3000 steps of oblique, spinning collisions
// among themselves and with a wall disk, under gravity.
std::vector<double> run(SystemConfig c) {
    System s(c);
    s.add_wall(Vec2(0.0, -0.02), d_large);
    const Vec2 v[] = {{0.31, -0.4}, {-0.22, -0.35}, {0.05, 0.2},
                      {-0.4, 0.1},  {0.12, -0.5},   {0.0, 0.0}};
    for (int i = 0; i < 6; ++i) {
        const int id = add_disk(s, Vec2(0.011 * (i % 3) - 0.011, 0.009 * (i / 3)),
                                i % 2 ? d_small : d_large, v[i]);
        s.set_velocity(s.index_of(id), v[i], 30.0 * (i - 2.5));
    }
    for (int k = 0; k < 3000; ++k)
        s.step();
    std::vector<double> out;
    for (int i = 0; i < s.mobile_count(); ++i) {
        out.insert(out.end(), {s.position(i).x(), s.position(i).y(), s.velocity(i).x(),
                               s.velocity(i).y(), s.omega(i)});
    }
    return out;
}

SystemConfig config(const ContactParams& cp, NormalLaw n, TangentialLaw t) {
    SystemConfig c = system_config(Scheme::verlet, 50.0, cp, cp, Vec2(0.0, -g));
    c.normal_law = n;
    c.tangential_law = t;
    return c;
}

TEST(TangentialLaw, ANamedLawIsTheLawTheCoefficientsImplied) {
    using T = TangentialLaw;
    const ContactParams spring = contact_params(0.5, 0.5);
    const ContactParams no_spring = contact_params(0.5, 0.5, 0.0);
    const ContactParams no_friction = contact_params(0.5, 0.0);
    // The Cundall-Strack spring, by name and inferred.
    const auto ref_spring = run(config(spring, NormalLaw::linear, T::automatic));
    EXPECT_EQ(run(config(spring, NormalLaw::linear, T::spring)), ref_spring);
    // Viscous friction: inferred from k_t = 0, named with a k_t it does not use.
    const auto ref_viscous = run(config(no_spring, NormalLaw::linear, T::automatic));
    EXPECT_EQ(run(config(spring, NormalLaw::linear, T::viscous)), ref_viscous);
    EXPECT_NE(ref_viscous, ref_spring);  // the runs tell the laws apart
    // Frictionless: inferred from mu = 0, named with a mu it does not use.
    const auto ref_frictionless = run(config(no_friction, NormalLaw::linear, T::automatic));
    EXPECT_EQ(run(config(spring, NormalLaw::linear, T::frictionless)), ref_frictionless);
    EXPECT_NE(ref_frictionless, ref_viscous);
    // The Hertz law's spring, by name and inferred.
    const ContactParams hertz = with_hertz(spring, 0.5);
    const auto ref_hertz = run(config(hertz, NormalLaw::hertz, T::automatic));
    EXPECT_EQ(run(config(hertz, NormalLaw::hertz, T::spring)), ref_hertz);
    // The Hertz law with viscous friction is another law.
    EXPECT_NE(run(config(hertz, NormalLaw::hertz, T::viscous)), ref_hertz);
}

TEST(TangentialLaw, HertzWithViscousFrictionIsItsFormula) {
    const ContactParams p = with_hertz(contact_params(0.5, 0.4), 0.5);
    const double rstar = 0.25 * d_large, mbar = 0.5 * m_large;
    ContactInput c{};
    c.nx = 0.6;
    c.ny = 0.8;
    c.overlap = 2e-5;
    c.mbar = mbar;
    c.rstar = rstar;
    HertzViscousLaw::pair_constants(p, rstar, mbar, c.hertz_K, c.hertz_eta);
    const double K = p.hertz_k * std::sqrt(rstar);
    EXPECT_DOUBLE_EQ(c.hertz_K, K);
    EXPECT_DOUBLE_EQ(c.hertz_eta, p.hertz_alpha * std::sqrt(mbar * K));
    const double eta = p.hertz_alpha * std::sqrt(mbar * K) * std::pow(c.overlap, 0.25);
    const double v_n = -0.01;  // closing
    const double fn = K * std::pow(c.overlap, 1.5) - eta * v_n;
    // The tangential direction t = (-ny, nx); a slow slide (below the cap) and a fast one.
    for (double vt : {1e-4, 0.5}) {
        c.vx = c.sx = v_n * c.nx - vt * c.ny;
        c.vy = c.sy = v_n * c.ny + vt * c.nx;
        double hx = 0, hy = 0;
        const ContactOutput o = HertzViscousLaw::evaluate(p, c, hx, hy);
        const ContactOutput s = HertzViscousLaw::evaluate<true>(p, c, hx, hy);  // SIMD form
        EXPECT_NEAR(o.fn, fn, 1e-12 * fn);
        const double want = std::min(p.hertz_gt_ratio * eta * vt, p.mu * std::abs(fn));
        const double got = -(o.ftx * -c.ny + o.fty * c.nx);  // against the slide
        EXPECT_NEAR(got, want, 1e-9 * want) << "v_t = " << vt;
        EXPECT_NEAR(o.ftx * c.nx + o.fty * c.ny, 0.0, 1e-15);  // tangential
        EXPECT_EQ(o.ftx, s.ftx);
        EXPECT_EQ(o.fty, s.fty);
        EXPECT_EQ(hx, 0.0);  // no spring
    }
    EXPECT_FALSE(HertzViscousLaw::has_history);
}

TEST(TangentialLaw, ContradictionsAreRefusedNamingTheSetting) {
    auto message = [](const SceneParams& p) -> std::string {
        try {
            validate_scene(p);
        } catch (const hopper::core::ConfigError& e) {
            return e.what();
        }
        return "";
    };
    SceneParams p;
    p.material.tangential_law = TangentialLaw::viscous;
    EXPECT_EQ(message(p), "");
    p.material.mu_r = 0.05;  // rolling resistance comes with the spring laws
    EXPECT_NE(message(p).find("material.tangential_law = spring or auto"), std::string::npos)
        << message(p);
    p.material.mu_r = 0.0;
    p.material.tangential_law = TangentialLaw::spring;
    p.material.kt_over_kn = 0.0;  // a spring without stiffness
    EXPECT_NE(message(p).find("material.tangential_law = spring"), std::string::npos) << message(p);
    // The Hertz law with viscous friction needs no spring stiffness; with its spring it does.
    p.material.normal_law = NormalLaw::hertz;
    p.material.collision_time.reset();
    p.material.tangential_law = TangentialLaw::viscous;
    EXPECT_EQ(message(p), "");
    p.material.tangential_law = TangentialLaw::spring;
    EXPECT_NE(message(p), "");
    // A System asked for a law the registry does not have says which it has.
    SystemConfig c = config(contact_params(0.5, 0.5), NormalLaw::linear, TangentialLaw::viscous);
    c.rolling = true;
    try {
        System s(c);
        ADD_FAILURE() << "rolling resistance with viscous friction was accepted";
    } catch (const hopper::core::ConfigError& e) {
        const std::string w = e.what();
        EXPECT_NE(w.find("no contact law has the normal law 'linear' with the tangential law "
                         "'viscous' and rolling resistance"),
                  std::string::npos)
            << w;
        EXPECT_NE(w.find("hertz with viscous"), std::string::npos) << w;
    }
}

}  // namespace
