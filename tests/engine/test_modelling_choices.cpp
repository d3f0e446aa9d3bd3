// The modelling choices the published study does not state (issue 11, docs/model.md "Modelling
// choices"): each setting must change the geometry or the force exactly as documented, and at
// its default must leave everything as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/engine/contact.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/scene.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper::engine;
using hopper::core::pi;
using hopper::core::Rng;

namespace {

SceneParams scene(double theta_deg) {
    SceneParams p;
    p.hopper.width = 15.0 * cm;
    p.hopper.outlet = 3.0 * cm;
    p.hopper.theta = theta_deg * deg;
    p.particles.count = 400;
    return p;
}

SceneLayout build(const SceneParams& p) {
    Rng rng(7);
    return build_scene(p, rng);
}

// The right-hand wall particle with the smallest y among those with x > 0 (the edge disk).
WallParticle right_edge(const SceneLayout& s) {
    WallParticle best{{0, 1e9}, 0};
    for (const auto& w : s.walls)
        if (w.pos.x() > 0 &&
            (w.pos.y() < best.pos.y() || (w.pos.y() == best.pos.y() && w.pos.x() < best.pos.x())))
            best = w;
    return best;
}

// Second disk of the right funnel wall: nearest right wall particle to the edge disk.
WallParticle right_second(const SceneLayout& s) {
    const WallParticle e = right_edge(s);
    WallParticle best{{0, 0}, 0};
    double dmin = 1e9;
    for (const auto& w : s.walls) {
        const double d = (w.pos - e.pos).norm();
        if (w.pos.x() > 0 && d > 0 && d < dmin) {
            dmin = d;
            best = w;
        }
    }
    return best;
}

double free_gap(const SceneLayout& s) {
    const WallParticle e = right_edge(s);
    return 2 * e.pos.x() - e.diameter;
}

}  // namespace

class ChoiceAngles : public ::testing::TestWithParam<double> {};

TEST_P(ChoiceAngles, DefaultGeometryIsUnchanged) {
    const SceneParams p = scene(GetParam());
    const SceneLayout s = build(p);
    // Edge disk centre at (D/2 + d_w/2, 0) exactly, and the free gap helper gives D exactly.
    EXPECT_EQ(right_edge(s).pos.x(), p.hopper.outlet / 2 + p.hopper.wall_diameter / 2);
    EXPECT_EQ(right_edge(s).pos.y(), 0.0);
    EXPECT_EQ(outlet_free_gap(p.hopper), p.hopper.outlet);
    EXPECT_EQ(edge_disk_centre(p.hopper).y(), 0.0);
}

TEST_P(ChoiceAngles, CentreGapPutsTheEdgeDiskCentresAtPlusMinusHalfD) {
    SceneParams p = scene(GetParam());
    p.hopper.outlet_measure = OutletMeasure::centre_gap;
    const SceneLayout s = build(p);
    EXPECT_NEAR(right_edge(s).pos.x(), p.hopper.outlet / 2, 1e-15);
    EXPECT_NEAR(free_gap(s), p.hopper.outlet - p.hopper.wall_diameter, 1e-15);
    EXPECT_NEAR(outlet_free_gap(p.hopper), p.hopper.outlet - p.hopper.wall_diameter, 1e-15);
}

TEST_P(ChoiceAngles, InnerEnvelopeCrossesTheOutletPlaneAtPlusMinusHalfD) {
    const double theta = GetParam() * deg;
    SceneParams p = scene(GetParam());
    p.hopper.outlet_measure = OutletMeasure::inner_envelope;
    const SceneLayout s = build(p);
    // The inner envelope: the line through the wall disks' centres moved d_w/2 towards the
    // material. From the two lowest disks: direction u, inner normal n_in = (-u_y, u_x).
    const Vec2 a = right_edge(s).pos, b = right_second(s).pos;
    const Vec2 u = (b - a).normalized();
    EXPECT_NEAR(std::atan2(u.y(), u.x()), theta, 1e-12);
    const Vec2 n_in(-u.y(), u.x());
    const Vec2 on_envelope = a + 0.5 * p.hopper.wall_diameter * n_in;
    // Where that line crosses y = 0:
    const double x_cross = on_envelope.x() - on_envelope.y() * u.x() / u.y();
    EXPECT_NEAR(x_cross, p.hopper.outlet / 2, 1e-14);
    // The free gap is D + d_w (1/sin(theta) - 1).
    const double expected = p.hopper.outlet + p.hopper.wall_diameter * (1 / std::sin(theta) - 1);
    EXPECT_NEAR(free_gap(s), expected, 1e-14);
    EXPECT_NEAR(outlet_free_gap(p.hopper), expected, 1e-14);
}

TEST_P(ChoiceAngles, EdgeOffsetStartsTheWallUpTheLineAndMovesTheGateWithIt) {
    const double theta = GetParam() * deg;
    SceneParams p = scene(GetParam());
    p.hopper.edge_offset = 0.5;
    const SceneLayout s = build(p);
    const double dw = p.hopper.wall_diameter;
    const double x_c = p.hopper.outlet / 2 + dw / 2;
    const WallParticle e = right_edge(s);
    EXPECT_NEAR(e.pos.x(), x_c + 0.5 * dw * std::cos(theta), 1e-15);
    EXPECT_NEAR(e.pos.y(), 0.5 * dw * std::sin(theta), 1e-15);
    EXPECT_NEAR(outlet_free_gap(p.hopper), p.hopper.outlet + dw * std::cos(theta), 1e-15);
    // The gate spans the outlet at the edge disks' height; nothing of the fill is below it.
    ASSERT_FALSE(s.gate.empty());
    for (const auto& g : s.gate) {
        EXPECT_NEAR(g.pos.y(), e.pos.y(), 1e-15);
        EXPECT_LT(std::abs(g.pos.x()), e.pos.x());
    }
    for (const auto& f : s.fill)
        EXPECT_GT(f.pos.y(), e.pos.y() + (dw + f.diameter) / 2);
}

TEST_P(ChoiceAngles, EdgeDiameterChangesOnlyTheTwoEdgeDisks) {
    SceneParams p = scene(GetParam());
    p.hopper.edge_diameter = 0.602 * cm;
    const SceneLayout s = build(p);
    int edge = 0;
    for (const auto& w : s.walls) {
        if (w.diameter == 0.602 * cm) {
            ++edge;
            EXPECT_EQ(w.pos.y(), 0.0);
        } else {
            EXPECT_EQ(w.diameter, p.hopper.wall_diameter);
        }
    }
    EXPECT_EQ(edge, 2);
    // surface_gap: the free gap between the (smaller) edge disks is still D.
    EXPECT_NEAR(free_gap(s), p.hopper.outlet, 1e-15);
}

INSTANTIATE_TEST_SUITE_P(Theta, ChoiceAngles, ::testing::Values(15.0, 45.0, 60.0, 90.0));

TEST(Choices, FillBaseRaisesTheLowestRowByExactlyThatHeight) {
    SceneParams p = scene(45.0);
    const SceneLayout s0 = build(p);
    p.protocol.fill_base = 3.0;
    const SceneLayout s1 = build(p);
    auto lowest = [](const SceneLayout& s) {
        double y = 1e9;
        for (const auto& f : s.fill)
            y = std::min(y, f.pos.y());
        return y;
    };
    EXPECT_NEAR(lowest(s1) - lowest(s0), 3.0 * p.particles.d_large, 1e-15);
}

TEST(Choices, InnerEnvelopeOnAFlatBottomIsRefused) {
    SceneParams p = scene(0.0);
    p.hopper.outlet_measure = OutletMeasure::inner_envelope;
    EXPECT_THROW(validate_scene(p), hopper::core::ConfigError);
}

TEST(Choices, AnEdgeDiskThatLeavesAGapIsRefused) {
    SceneParams p = scene(45.0);
    p.hopper.edge_diameter = 0.05 * cm;  // gap 0.77 - 0.41 = 0.36 cm... < d_small: allowed
    EXPECT_NO_THROW(validate_scene(p));
    p.hopper.wall_spacing = 1.7;  // gap 1.31 - 0.41 = 0.90 cm > d_small
    try {
        validate_scene(p);
        ADD_FAILURE() << "accepted";
    } catch (const hopper::core::ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("edge_diameter"), std::string::npos) << e.what();
    }
}

TEST(Choices, CentreGapNarrowerThanTheEdgeDiskIsRefused) {
    SceneParams p = scene(45.0);
    p.hopper.outlet = 0.5 * cm;  // centre gap 0.5 cm < d_w: no opening
    p.hopper.outlet_measure = OutletMeasure::centre_gap;
    EXPECT_THROW(validate_scene(p), hopper::core::ConfigError);
}

// ----- contact law ---------------------------------------------------------------------------

TEST(Choices, SlipRuleSpringOnlyLeavesTheSpringAtTheCoulombLimit) {
    ContactParams p{1149.0, 1732.9, 919.2, 866.4, 0.5, false};
    const double mbar = 7.45e-5, x = 1e-5, dt = 1.6e-5;
    const Vec2 n(0.6, 0.8), t(-0.8, 0.6);
    const Vec2 v = -0.01 * n + 0.2 * t;
    const Vec2 v_t = 0.2 * t;
    const Vec2 xi0 = -1e-4 * t;  // long: the cap is active
    Vec2 xi_a = xi0, xi_b = xi0;
    const ContactForce fa = SpringFrictionLaw::evaluate(p, mbar, n, x, v, xi_a, dt);
    p.slip_spring_only = true;
    const ContactForce fb = SpringFrictionLaw::evaluate(p, mbar, n, x, v, xi_b, dt);
    // The force is the same capped force either way.
    EXPECT_EQ(fa.tangential, fb.tangential);
    EXPECT_EQ(fa.normal, fb.normal);
    const double Fn = p.k_n * x + p.gamma_n * mbar * 0.01;
    ASSERT_NEAR(fb.tangential.norm(), p.mu * Fn, 1e-12 * Fn);
    // Default: spring + dashpot = capped force. spring_only: k_t |xi| = mu |F_n|.
    const Vec2 xa = -(fa.tangential + p.gamma_t * mbar * v_t) / p.k_t;
    EXPECT_NEAR((xi_a - xa).norm(), 0.0, 1e-12 * xa.norm());
    EXPECT_NEAR((xi_b + fb.tangential / p.k_t).norm(), 0.0, 1e-12 * xi_b.norm());
    EXPECT_NEAR(p.k_t * xi_b.norm(), p.mu * Fn, 1e-12 * Fn);
    // Below the cap the rule plays no part.
    Vec2 xi_c = Vec2::Zero(), xi_d = Vec2::Zero();
    p.slip_spring_only = false;
    const Vec2 slow = 1e-6 * t;
    const ContactForce fc = SpringFrictionLaw::evaluate(p, mbar, n, x, slow, xi_c, dt);
    p.slip_spring_only = true;
    const ContactForce fd = SpringFrictionLaw::evaluate(p, mbar, n, x, slow, xi_d, dt);
    EXPECT_EQ(fc.tangential, fd.tangential);
    EXPECT_EQ(xi_c, xi_d);
}

namespace {

// Two disks overlapping by x along the x axis, i spinning at w, no translation; the tangential
// force and torques after one force evaluation (first step: xi = v_t dt).
struct LeverCase {
    double ft, tq_i, tq_j;
};

LeverCase lever_case(bool contact_lever, double x) {
    SystemConfig c;
    c.dt = 1e-6;
    c.scheme = Scheme::verlet;
    c.gravity = Vec2::Zero();
    c.skin = 1e-3;
    c.particle = {1149.0, 0.0, 919.2, 0.0, 10.0, false};  // mu large: never capped
    c.wall = c.particle;
    c.contact_lever = contact_lever;
    System s(c);
    const double d = 0.01, m = 1e-4, I = m * d * d / 8;
    s.add_particle(Vec2(0, 0), d, m, I, Vec2::Zero(), 10.0);
    s.add_particle(Vec2(d - x, 0), d, m, I, Vec2::Zero(), 0.0);
    s.step();
    // Quantities proportional to the tangential force and the torques of the step (its force
    // evaluations all see the same lever arm and spin to within dt; only ratios are compared).
    const int i = s.index_of(0), j = s.index_of(1);
    LeverCase r;
    r.tq_i = (s.omega(i) - 10.0) * I / (0.5 * c.dt);
    r.tq_j = s.omega(j) * I / (0.5 * c.dt);
    r.ft = s.velocity(j).y() * m / (0.5 * c.dt);
    return r;
}

}  // namespace

TEST(Choices, ContactLeverArmScalesSlipVelocityAndTorqueByRMinusHalfTheOverlap) {
    const double x = 1e-3, R = 0.005;
    const LeverCase a = lever_case(false, x);
    const LeverCase b = lever_case(true, x);
    ASSERT_NE(a.ft, 0.0);
    // The spring grows by v_t dt with v_t = lever * omega: the force scales by (R - x/2)/R,
    // and each torque by that factor again (force times lever arm).
    // Tolerance: within the step the overlap and spin change by O(dt) (relative ~1e-6); the
    // effect tested is 10 % (k = 0.9).
    const double k = (R - x / 2) / R;
    EXPECT_NEAR(b.ft / a.ft, k, 1e-5);
    EXPECT_NEAR(b.tq_i / a.tq_i, k * k, 1e-5);
    EXPECT_NEAR(b.tq_j / a.tq_j, k * k, 1e-5);
    // Torque = -lever (n x F_t), the same sign on both disks (equal radii).
    EXPECT_NEAR(a.tq_i / a.tq_j, 1.0, 1e-9);
}

// ----- damping and derived constants ---------------------------------------------------------

TEST(Choices, ExactRestitutionDampingGivesExactlyENForTwoLargeDisks) {
    const double tau = 8e-4, w0 = pi / tau;
    for (double e : {0.3, 0.5, 0.8}) {
        const double g_nom = normal_damping_rate(NormalDamping::nominal, e, tau);
        const double g_ex = normal_damping_rate(NormalDamping::exact_restitution, e, tau);
        EXPECT_DOUBLE_EQ(g_nom, -2 * std::log(e) / tau);
        // The damped oscillator x'' + g x' + w0^2 x = 0 leaves contact after pi / w_d with
        // velocity ratio exp(-g pi / (2 w_d)).
        const double wd = std::sqrt(w0 * w0 - g_ex * g_ex / 4);
        EXPECT_NEAR(std::exp(-g_ex * pi / (2 * wd)), e, 1e-14);
        const double wd_nom = std::sqrt(w0 * w0 - g_nom * g_nom / 4);
        EXPECT_LT(std::exp(-g_nom * pi / (2 * wd_nom)), e - 1e-4);  // nominal: a bit below e_n
    }
}

TEST(Choices, RealizationPassesGammaTRatioSlipRuleAndLeverToTheSystem) {
    SceneParams p = scene(45.0);
    p.particles.count = 20;
    const DerivedConstants c = derive_constants(p);
    {
        Realization r(p, 1);
        const auto& cfg = r.system().config();
        EXPECT_EQ(cfg.particle.gamma_t, c.gamma_n_system / 2);
        EXPECT_FALSE(cfg.particle.slip_spring_only);
        EXPECT_FALSE(cfg.contact_lever);
    }
    p.material.gamma_t_over_gamma_n = 0.25;
    p.material.slip_rule = SlipRule::spring_only;
    p.material.lever_arm = LeverArm::contact;
    p.material.wall.e_n = 0.8;
    Realization r(p, 1);
    const auto& cfg = r.system().config();
    const DerivedConstants c2 = derive_constants(p);
    EXPECT_DOUBLE_EQ(cfg.particle.gamma_t, 0.25 * c2.gamma_n_system);
    EXPECT_DOUBLE_EQ(cfg.wall.gamma_t, 0.25 * c2.gamma_n_wall);
    EXPECT_TRUE(cfg.particle.slip_spring_only);
    EXPECT_TRUE(cfg.wall.slip_spring_only);
    EXPECT_TRUE(cfg.contact_lever);
}

// Polydispersity (hopper.size_spread = w, issue 39; docs/model.md "Particles"): every disk's
// diameter lies within [d (1 - w), d (1 + w)] of its species, the sizes are spread over that
// range (not two values), and each mass is the nominal one times (d / d_nom)^2. At w = 0 the
// layout is the default's, bit for bit (the generator draws nothing more). A realization with a
// spread runs, and a checkpoint of its steady state (re-inserted disks of 400 sizes) continues
// to the same result.
namespace {
TEST(Choices, SizeSpreadDrawsEachDiameterAboutItsSpeciesAndScalesTheMass) {
    SceneParams p = scene(45.0);
    const SceneLayout two = build(p);
    p.particles.size_spread = 0.0;
    const SceneLayout zero = build(p);
    ASSERT_EQ(two.fill.size(), zero.fill.size());
    for (std::size_t i = 0; i < two.fill.size(); ++i)
        ASSERT_EQ(two.fill[i].diameter, zero.fill[i].diameter);
    const double w = 0.1;
    p.particles.size_spread = w;
    const SceneLayout poly = build(p);
    double lo_s = 9, hi_s = 0, lo_l = 9, hi_l = 0;
    for (const auto& f : poly.fill) {
        const double s = f.diameter / (f.large ? p.particles.d_large : p.particles.d_small);
        EXPECT_GE(s, 1 - w);
        EXPECT_LE(s, 1 + w);
        (f.large ? lo_l : lo_s) = std::min(f.large ? lo_l : lo_s, s);
        (f.large ? hi_l : hi_s) = std::max(f.large ? hi_l : hi_s, s);
    }
    // 400 draws: the extremes within 2 % of the range's ends for both species.
    EXPECT_LT(lo_s, 1 - 0.9 * w);
    EXPECT_GT(hi_s, 1 + 0.9 * w);
    EXPECT_LT(lo_l, 1 - 0.9 * w);
    EXPECT_GT(hi_l, 1 + 0.9 * w);
    // Masses in a realization: m = rho pi d^2 / 4 h for every disk.
    Realization r(p, 11);
    auto& sys = r.system();
    const auto rad = sys.r();
    const auto m = sys.m();
    ASSERT_EQ(int(rad.size()), p.particles.count);
    for (std::size_t i = 0; i < rad.size(); ++i) {
        const double d = 2 * rad[i];
        EXPECT_NEAR(m[i], p.particles.density * pi * d * d / 4 * p.particles.thickness,
                    1e-12 * m[i]);
    }
    EXPECT_THROW(
        {
            SceneParams q = p;
            q.particles.size_spread = 0.31;
            validate_scene(q);
        },
        hopper::core::ConfigError);
}

TEST(Choices, ASteadyStateWithASizeSpreadContinuesFromItsCheckpoint) {
    SceneParams p = scene(45.0);
    p.particles.size_spread = 0.1;
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.jams_per_realization = 3;
    p.protocol.max_time = 3.0;
    const RealizationResult whole = run_realization(p, 5);
    Realization part(p, 5);
    part.settle();
    part.open();
    part.advance(1.0);
    int reinserted = 0;
    for (int i = 0; i < part.system().mobile_count(); ++i)
        reinserted += part.system().id(i) >= p.particles.count;
    ASSERT_GT(reinserted, 0) << "no disk re-inserted before the checkpoint: nothing tested";
    const auto state = part.save_state();
    const RealizationResult resumed = resume_realization(p, 5, state);
    EXPECT_EQ(resumed.status, whole.status);
    EXPECT_EQ(resumed.survival_times, whole.survival_times);
    EXPECT_EQ(resumed.n_jams, whole.n_jams);
    EXPECT_GT(whole.discharged, 0);
}
}  // namespace
