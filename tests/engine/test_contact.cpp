// Pure checks of the contact laws in include/hopper/engine/contact.hpp against the formulas of
// docs/model.md ("Contact forces"), each written out again here from the spec. Everything is
// exact arithmetic on a few numbers, so tolerances are a few ulp (1e-12 relative) unless noted.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "hopper/engine/contact.hpp"

namespace {

using namespace hopper::engine;
using Vec3 = Eigen::Vector3d;
using hopper::core::perp;

constexpr double kRel = 1e-12;

// Parameters of the published model: k_n = 1149 N/m (tau_c = 8e-4 s), e_n = 0.5,
// gamma_n = -2 ln(e_n)/tau_c, k_t = 0.8 k_n, gamma_t = gamma_n / 2.
ContactParams default_params(double mu = 0.5) {
    ContactParams p;
    p.k_n = 1149.0;
    p.gamma_n = -2.0 * std::log(0.5) / 8.0e-4;
    p.k_t = 0.8 * p.k_n;
    p.gamma_t = 0.5 * p.gamma_n;
    p.mu = mu;
    return p;
}

constexpr double mbar = 0.5 * 1.490e-4;  // two large disks
constexpr double dt = 1.6e-5;

Vec2 unit(double angle) {
    return {std::cos(angle), std::sin(angle)};
}

void expect_vec_near(const Vec2& a, const Vec2& b, double tol, const char* what) {
    EXPECT_NEAR(a.x(), b.x(), tol) << what;
    EXPECT_NEAR(a.y(), b.y(), tol) << what;
}

TEST(ContactLaw, NormalForceIsSpringPlusDashpotAlongN) {
    const ContactParams p = default_params();
    const Vec2 n = unit(0.3);
    const double x = 2.0e-5;  // m
    const Vec2 t = perp(n);
    // Approaching (v_n < 0) at 0.2 m/s with some tangential motion that must not enter F_n.
    const Vec2 v = -0.2 * n + 0.05 * t;
    Vec2 xi = Vec2::Zero();
    const ContactForce f = SpringFrictionLaw::evaluate(p, mbar, n, x, v, xi, dt);
    // F_n = (k_n x - gamma_n mbar v_n) n with v_n = -0.2 m/s:
    // 1149 * 2e-5 + 1732.87 * 7.45e-5 * 0.2 = 0.02298 + 0.02582 N.
    const double Fn = p.k_n * x + p.gamma_n * mbar * 0.2;
    expect_vec_near(f.normal, Fn * n, kRel * Fn, "spring law");
    for (auto g : {FrictionlessLaw::evaluate(p, mbar, n, x, v, xi, dt),
                   ViscousFrictionLaw::evaluate(p, mbar, n, x, v, xi, dt)})
        expect_vec_near(g.normal, Fn * n, kRel * Fn, "other laws");
}

TEST(ContactLaw, NormalForceIsNotClampedWhenSeparatingFast) {
    // Near the end of a damped contact the dashpot outweighs the spring and the force pulls
    // (spec: no clamping). x = 1e-6, v_n = +0.3: 1149e-6 - 1732.87 * 7.45e-5 * 0.3 < 0.
    const ContactParams p = default_params();
    const Vec2 n = unit(-1.1);
    Vec2 xi = Vec2::Zero();
    const ContactForce f = FrictionlessLaw::evaluate(p, mbar, n, 1e-6, 0.3 * n, xi, dt);
    const double Fn = p.k_n * 1e-6 - p.gamma_n * mbar * 0.3;
    ASSERT_LT(Fn, 0.0);
    expect_vec_near(f.normal, Fn * n, kRel * std::abs(Fn), "attractive");
}

TEST(ContactLaw, FrictionlessHasNoTangentialForceAndKeepsNoHistory) {
    const ContactParams p = default_params(0.8);
    const Vec2 n = unit(2.0);
    Vec2 xi(3e-6, -1e-6);
    const Vec2 xi0 = xi;
    const ContactForce f =
        FrictionlessLaw::evaluate(p, mbar, n, 1e-5, -0.1 * n + 0.7 * perp(n), xi, dt);
    EXPECT_EQ(f.tangential, Vec2::Zero());
    EXPECT_EQ(xi, xi0);
    static_assert(!FrictionlessLaw::has_tangential && !FrictionlessLaw::has_history);
    static_assert(ViscousFrictionLaw::has_tangential && !ViscousFrictionLaw::has_history);
    static_assert(SpringFrictionLaw::has_tangential && SpringFrictionLaw::has_history);
}

TEST(ContactLaw, SpringGrowsByTangentialVelocityTimesDt) {
    const ContactParams p = default_params(100.0);  // cap far away
    const Vec2 n = unit(0.7);
    const Vec2 v_t = 0.03 * perp(n);
    const Vec2 v = -0.1 * n + v_t;
    Vec2 xi = Vec2::Zero();  // a new contact
    for (int k = 1; k <= 3; ++k) {
        const ContactForce f = SpringFrictionLaw::evaluate(p, mbar, n, 1e-5, v, xi, dt);
        // xi = k v_t dt after k steps; F_t = -k_t xi - gamma_t mbar v_t (below the cap).
        expect_vec_near(xi, k * dt * v_t, kRel * k * dt * 0.03, "xi");
        const Vec2 Ft = -p.k_t * (k * dt * v_t) - p.gamma_t * mbar * v_t;
        expect_vec_near(f.tangential, Ft, kRel * Ft.norm(), "F_t");
        // F_t is tangential.
        EXPECT_NEAR(f.tangential.dot(n), 0.0, kRel * Ft.norm());
    }
}

TEST(ContactLaw, StoredSpringIsProjectedOntoTheRotatedTangentBeforeGrowing) {
    const ContactParams p = default_params(100.0);
    // The spring was built up while the normal was along 0.4 rad; the contact has since turned
    // by 0.25 rad, so the stored xi has a component along the new n.
    const Vec2 n_old = unit(0.4);
    const Vec2 xi_old = 2.0e-6 * perp(n_old);
    const Vec2 n = unit(0.65);
    ASSERT_GT(std::abs(n.dot(xi_old)), 0.2 * xi_old.norm());  // 2e-6 sin 0.25 = 4.9e-7
    const Vec2 v_t = -0.01 * perp(n);
    const Vec2 v = 0.02 * n + v_t;
    Vec2 xi = xi_old;
    const ContactForce f = SpringFrictionLaw::evaluate(p, mbar, n, 1e-5, v, xi, dt);
    // xi' = xi - n (n . xi), then + v_t dt.
    const Vec2 expected = xi_old - n * n.dot(xi_old) + v_t * dt;
    expect_vec_near(xi, expected, 1e-12 * xi_old.norm(), "projected xi");
    EXPECT_NEAR(xi.dot(n), 0.0, 1e-12 * xi_old.norm());
    // Projection, not rotation: |xi'| = |xi| cos(0.25) before the growth.
    EXPECT_NEAR((xi - v_t * dt).norm(), xi_old.norm() * std::cos(0.25), 1e-12 * xi_old.norm());
    const Vec2 Ft = -p.k_t * expected - p.gamma_t * mbar * v_t;
    expect_vec_near(f.tangential, Ft, kRel * Ft.norm(), "F_t");
}

TEST(ContactLaw, CoulombCapAndSpringShortening) {
    const ContactParams p = default_params(0.5);
    const Vec2 n = unit(-0.9);
    const Vec2 t = perp(n);
    const double x = 1e-5;
    const Vec2 v = -0.01 * n + 0.2 * t;
    // A long stored spring: |k_t xi| = 919 * 1e-4 = 0.092 N >> mu F_n ~ 0.006 N.
    Vec2 xi = -1e-4 * t;
    const Vec2 xi_old = xi;
    const ContactForce f = SpringFrictionLaw::evaluate(p, mbar, n, x, v, xi, dt);
    const double Fn = p.k_n * x + p.gamma_n * mbar * 0.01;
    const Vec2 v_t = 0.2 * t;
    const Vec2 Ft_star = -p.k_t * (xi_old + v_t * dt) - p.gamma_t * mbar * v_t;
    ASSERT_GT(Ft_star.norm(), p.mu * Fn);
    // |F_t| = mu |F_n|, along F_t*.
    EXPECT_NEAR(f.tangential.norm(), p.mu * Fn, kRel * Fn);
    expect_vec_near(f.tangential, p.mu * Fn * Ft_star.normalized(), kRel * Fn, "direction");
    // Spring shortened: xi = -(F_t + gamma_t mbar v_t) / k_t.
    const Vec2 xi_expected = -(f.tangential + p.gamma_t * mbar * v_t) / p.k_t;
    expect_vec_near(xi, xi_expected, 1e-12 * xi_old.norm(), "shortened xi");
    EXPECT_LT(xi.norm(), xi_old.norm());

    // With no tangential motion the shortened spring now holds exactly the capped force:
    // F_t* = -k_t xi = F_t, |F_t*| = mu F_n, so the cap neither changes it nor shortens xi.
    const Vec2 v2 = Vec2::Zero();
    const double Fn2 = p.k_n * x;
    Vec2 xi2 = -(p.mu * Fn2) * t / p.k_t;  // a spring exactly at the cap for F_n = k_n x
    const Vec2 xi2_old = xi2;
    const ContactForce f2 = SpringFrictionLaw::evaluate(p, mbar, n, x, v2, xi2, dt);
    expect_vec_near(f2.tangential, p.mu * Fn2 * t, 1e-12 * Fn2, "at the cap");
    expect_vec_near(xi2, xi2_old, 1e-12 * xi2_old.norm(), "xi at the cap");
}

TEST(ContactLaw, CapUsesTheMagnitudeOfAnAttractiveNormalForce) {
    // F_n < 0 near the end of a damped contact: the cap is mu |F_n|, not mu F_n (< 0).
    const ContactParams p = default_params(0.5);
    const Vec2 n = unit(1.0);
    const Vec2 t = perp(n);
    const Vec2 v = 0.3 * n + 0.5 * t;
    Vec2 xi = Vec2::Zero();
    const ContactForce f = SpringFrictionLaw::evaluate(p, mbar, n, 1e-6, v, xi, dt);
    const double Fn = p.k_n * 1e-6 - p.gamma_n * mbar * 0.3;
    ASSERT_LT(Fn, 0.0);
    EXPECT_NEAR(f.tangential.norm(), p.mu * std::abs(Fn), kRel * std::abs(Fn));
    EXPECT_LT(f.tangential.dot(t), 0.0);  // opposes the slip
}

TEST(ContactLaw, ViscousLawOpposesSlipIsCappedAndNeverTouchesXi) {
    ContactParams p = default_params(0.5);
    p.k_t = 0.0;
    const Vec2 n = unit(2.5);
    const Vec2 t = perp(n);
    const double x = 2e-5;
    const Vec2 sentinel(123.0, -456.0);
    // Slow slip: below the cap, F_t = -gamma_t mbar v_t exactly.
    {
        const Vec2 v = -0.01 * n + 1e-3 * t;
        Vec2 xi = sentinel;
        const ContactForce f = ViscousFrictionLaw::evaluate(p, mbar, n, x, v, xi, dt);
        const Vec2 Ft = -p.gamma_t * mbar * 1e-3 * t;
        const double Fn = p.k_n * x + p.gamma_n * mbar * 0.01;
        ASSERT_LT(Ft.norm(), p.mu * Fn);
        expect_vec_near(f.tangential, Ft, kRel * Ft.norm(), "below cap");
        EXPECT_EQ(xi, sentinel);
    }
    // Fast slip: |F_t| = mu |F_n|, antiparallel to v_t.
    {
        const Vec2 v = -0.01 * n - 2.0 * t;
        Vec2 xi = sentinel;
        const ContactForce f = ViscousFrictionLaw::evaluate(p, mbar, n, x, v, xi, dt);
        const double Fn = p.k_n * x + p.gamma_n * mbar * 0.01;
        ASSERT_GT(p.gamma_t * mbar * 2.0, p.mu * Fn);
        expect_vec_near(f.tangential, p.mu * Fn * t, kRel * Fn, "capped");
        EXPECT_EQ(xi, sentinel);
    }
}

TEST(ContactLaw, ZeroFrictionCoefficientGivesNoTangentialForce) {
    const ContactParams p = default_params(0.0);
    const Vec2 n = unit(0.1);
    Vec2 xi = Vec2::Zero();
    const Vec2 v = -0.1 * n + 0.4 * perp(n);
    EXPECT_EQ(SpringFrictionLaw::evaluate(p, mbar, n, 1e-5, v, xi, dt).tangential.norm(), 0.0);
    EXPECT_EQ(ViscousFrictionLaw::evaluate(p, mbar, n, 1e-5, v, xi, dt).tangential.norm(), 0.0);
}

// Velocity of the material point p of a rigid body b (3D, z out of the plane):
// v_p = v_b + w_b z x (p - r_b).
Vec2 point_velocity(const Vec2& v_b, double w_b, const Vec2& r_b, const Vec2& p) {
    const Vec3 w(0.0, 0.0, w_b);
    const Vec3 arm(p.x() - r_b.x(), p.y() - r_b.y(), 0.0);
    const Vec3 u = w.cross(arm);
    return v_b + Vec2(u.x(), u.y());
}

TEST(ContactKinematics, ContactVelocityIsTheRelativeVelocityOfTheTouchingPoints) {
    // n = (r_i - r_j)/|r_i - r_j|; the contact point on i is r_i - R_i n, on j it is r_j + R_j n.
    // v_ij = v_i(p_i) - v_j(p_j) = v_i - v_j - (R_i w_i + R_j w_j) (z x n).
    std::mt19937_64 gen(20240611);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec2 r_i(U(gen), U(gen)), r_j(U(gen), U(gen));
        const double R_i = 0.2 + 0.1 * U(gen), R_j = 0.2 + 0.1 * U(gen);
        const Vec2 v_i(U(gen), U(gen)), v_j(U(gen), U(gen));
        const double w_i = 30.0 * U(gen), w_j = 30.0 * U(gen);
        const Vec2 n = (r_i - r_j).normalized();
        const Vec2 expected = point_velocity(v_i, w_i, r_i, r_i - R_i * n) -
                              point_velocity(v_j, w_j, r_j, r_j + R_j * n);
        const Vec2 got = contact_velocity(v_i, v_j, R_i, w_i, R_j, w_j, n);
        ASSERT_NEAR(got.x(), expected.x(), 1e-12 * (1.0 + expected.norm())) << trial;
        ASSERT_NEAR(got.y(), expected.y(), 1e-12 * (1.0 + expected.norm())) << trial;
    }
}

TEST(ContactKinematics, ContactTorqueIsLeverArmCrossForce) {
    // Torque about the centre of i of a force F acting at r_c = r_i - R_i n:
    // tau = (r_c - r_i) x F = -R_i n x F. For j the force is -F at r_j + R_j n:
    // tau_j = (R_j n) x (-F) = -R_j n x F: the same expression with R_j and the force on i.
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec2 n = unit(3.2 * U(gen));
        const Vec2 F = U(gen) * perp(n);  // tangential
        const double R_i = 0.1 + 0.05 * U(gen), R_j = 0.1 + 0.05 * U(gen);
        const Vec3 arm_i(-R_i * n.x(), -R_i * n.y(), 0.0), arm_j(R_j * n.x(), R_j * n.y(), 0.0);
        const Vec3 F3(F.x(), F.y(), 0.0);
        ASSERT_NEAR(contact_torque(R_i, n, F), arm_i.cross(F3).z(), 1e-14) << trial;
        ASSERT_NEAR(contact_torque(R_j, n, F), arm_j.cross(-F3).z(), 1e-14) << trial;
    }
    // Concrete sign: a disk resting on a floor (n = +y) pushed at its bottom point towards +x
    // spins counter-clockwise (tau > 0).
    EXPECT_GT(contact_torque(0.01, Vec2(0.0, 1.0), Vec2(1.0, 0.0)), 0.0);
}

TEST(ContactKinematics, FrictionDrivesASlidingDiskTowardsRolling) {
    // Disk i on a floor disk j (n = +y), sliding to +x without spin: the contact point slips to
    // +x, friction on i points to -x and its torque makes w negative, which is the sense of
    // rolling to +x (v = -w R). Both effects reduce the slip v_x + w R.
    const ContactParams p = default_params(0.5);
    const Vec2 n(0.0, 1.0);
    const double R = 0.00385;
    const Vec2 v_ij = contact_velocity(Vec2(0.3, 0.0), Vec2::Zero(), R, 0.0, 1.0, 0.0, n);
    Vec2 xi = Vec2::Zero();
    const ContactForce f = SpringFrictionLaw::evaluate(p, 1.49e-4, n, 2e-6, v_ij, xi, dt);
    EXPECT_LT(f.tangential.x(), 0.0);
    EXPECT_LT(contact_torque(R, n, f.tangential), 0.0);
    // A disk spinning with w < 0 (the rolling sense for +x) but not translating: its bottom
    // point moves at w z x (-R n) = (R w, 0), i.e. to -x; friction pushes it to +x (dragging
    // the disk along) and its torque (> 0) spins w back towards zero.
    const Vec2 v2 = contact_velocity(Vec2::Zero(), Vec2::Zero(), R, -50.0, 1.0, 0.0, n);
    EXPECT_NEAR(v2.x(), R * -50.0, 1e-15);
    Vec2 xi2 = Vec2::Zero();
    const ContactForce f2 = SpringFrictionLaw::evaluate(p, 1.49e-4, n, 2e-6, v2, xi2, dt);
    EXPECT_GT(f2.tangential.x(), 0.0);
    EXPECT_GT(contact_torque(R, n, f2.tangential), 0.0);
}

}  // namespace
