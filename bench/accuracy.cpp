// Accuracy against cost (issue 6, items 1 and 2): for each integrator and each delta = tau_c / dt,
// the error of the engine on observables with a known (or reference) answer, the run time per
// simulated second, the smallest safe delta, and the cheapest setting that keeps every error
// under 1 %. Method and results: bench/results/ACCURACY.md.
//
//   bench_accuracy [--quick] [--csv FILE] [--cases-csv FILE] [--replica-csv FILE] [--md FILE]
//                  [--parts LIST] [--schemes LIST] [--deltas LIST] [--seeds N] [--ref-seeds N]
//                  [--more-seeds DELTAS:N] [--scan-gear4 LIST] [--scan-verlet LIST]
//                  [--phases K] [--replica-mu MU] [--no-extra] [--corrections]
//
//   --parts       comma list of binary,replica,energy,column,hopper (default all). column and
//                 hopper share their realizations (settle, measure the column, open, discharge);
//                 replica (engine-side proposals, see below) needs binary.
//   --csv         the table (one row per scheme/delta); --cases-csv: every collision case;
//                 --replica-csv: the proposals; --md: the table in markdown
//   --seeds       realizations per scheme/delta of the hopper scene (default 8)
//   --ref-seeds   realizations of the delta = 400 reference (default: --seeds)
//   --more-seeds  e.g. 30,50,75:24 gives those deltas 24 realizations (more precise rates)
//   --scan-*      deltas below the grid, run for the smallest safe delta (scene and all parts)
//   --phases      onset phases per collision case (default 16)
//   --replica-mu  also run the replica with this mu everywhere (1e9: the Coulomb cap never acts)
//   --no-extra    never add delta 300 and 400 for the stricter rule
//   --corrections every engine run uses the contact corrections (integrator.contact_corrections)
//   --quick       e_n = 0.5 only, head-on and 60 deg, 4 phases, energy over 0.2 s,
//                 deltas {20, 50, 200}, 2 seeds
//
// Observables (tau_c = 8e-4 s, the published material; k_t = 0.8 k_n, gamma_t = gamma_n / 2):
//   binary   two disks, no gravity, relative speed sqrt(2 g d_large) along x, mu = 0.8,
//            e_n in {0.3, 0.5, 0.8}; pairs: large-large, small-large (d 0.602 / 0.770 cm),
//            large disk on a large wall disk; impact angle 0 (head-on), 30, 60 deg from the
//            normal. The contact begins at a fraction `phase` of a step; every case is run at K
//            evenly spaced phases (k + 1/2) / K. Per observable: bias = |phase mean - ref| / |ref|
//            and phase scatter = rms over phases of (value - phase mean) / |ref|.
//            Observables: restitution of the normal relative velocity, contact duration (zero
//            crossings of the overlap, interpolated), rebound angular velocity (oblique only).
//            ref: head-on restitution and duration: the exact damped linear oscillator with the
//            pair's mbar; oblique ones (the line of centres turns during the contact, so the 1D
//            answer does not apply exactly) and every rebound spin: the same scheme at
//            delta = 4000, phase-averaged. The two schemes' delta = 4000 references are
//            compared with each other (the reference's own uncertainty).
//   energy   40 bidisperse disks in a closed 10 x 10 cm box of wall disks, gravity, e_n = 1,
//            mu = 0, random speeds up to 0.5 m/s: max_t<=T |E(t) - E(0)| / E(0) with
//            E = kinetic + elastic + potential, T = 1 s.
//   column   400 disks in a hopper W = 12 cm, D = 4.5 cm, theta = 60 deg, default material
//            (e_n = 0.5, mu = 0.8), gate closed: settle(), then over 0.05 s the mean vertical
//            wall force against the weight (worst seed), and the bottom profile: the normal
//            forces on the funnel and gate wall disks (System::normal_force_sums) binned by x
//            in bins of d_large, time-averaged, in units of the column's weight, averaged over
//            the seeds and compared with delta = 400 of the same scheme as a relative L2
//            difference, with its noise (L2 norm of the per-bin standard errors).
//   hopper   the same realizations then open the gate and discharge to the end: mean rate over
//            the seeds against delta = 400 of the same scheme, with the standard error of the
//            ratio. Cost: CPU seconds per simulated second of the discharge.
// A run that throws core::SimulationError or ends with status failed marks its scheme/delta
// unstable. Costs are CPU time of this process (the machine is shared: wall time would count the
// other jobs), compared within one run.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper;
using namespace hopper::engine;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kTauC = 8.0e-4;
constexpr double kDL = 0.770e-2, kDS = 0.602e-2, kH = 0.32e-2, kRho = 1000.0, kG = 9.81;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRefDelta = 400.0;       // reference of the scene observables
constexpr double kCollisionRef = 4000.0;  // reference of the oblique collision observables
constexpr double kDefaultEn = 0.5;        // default material: e_n = 0.5, mu = 0.8
constexpr double kTolerance = 0.01;       // the 1 % criterion

double disk_mass(double d) {
    return kRho * core::pi * d * d / 4.0 * kH;
}
double disk_inertia(double d) {
    return disk_mass(d) * d * d / 8.0;
}
const double kKn = core::pi * core::pi * disk_mass(kDL) / (2.0 * kTauC * kTauC);

ContactParams contact(double e_n, double mu) {
    ContactParams p;
    p.k_n = kKn;
    p.gamma_n = e_n >= 1.0 ? 0.0 : -2.0 * std::log(e_n) / kTauC;
    p.k_t = 0.8 * kKn;
    p.gamma_t = 0.5 * p.gamma_n;
    p.mu = mu;
    return p;
}

// --corrections: every engine run of this bench (collisions, energy, scenes, references) uses the
// contact corrections (SystemConfig::contact_corrections, issue 12).
bool g_corrections = false;

SystemConfig config(Scheme scheme, double delta, const ContactParams& cp, Vec2 gravity) {
    SystemConfig c;
    c.contact_corrections = g_corrections;
    c.dt = kTauC / delta;
    c.scheme = scheme;
    c.particle = cp;
    c.wall = cp;
    c.gravity = gravity;
    c.skin = 0.25 * kDS;
    c.max_overlap = 0.25 * kDS;  // the realization's default guard
    return c;
}

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU time of this (single-threaded) process: the costs. Unlike wall time it does not grow when
// other jobs share the cores (the machine is shared).
double cpu_now() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::string fmt(double x, const char* f = "%.2e") {
    if (std::isnan(x)) return "";
    char b[64];
    std::snprintf(b, sizeof b, f, x);
    return b;
}

std::string pct(double x) {
    if (std::isnan(x)) return "-";
    char b[64];
    std::snprintf(b, sizeof b, x < 1e-3 ? "%.1g" : x < 0.1 ? "%.2f" : "%.1f", 100.0 * x);
    return b;
}

struct MeanSe {
    double mean = kNaN, sd = kNaN, se = kNaN;
    int n = 0;
};
MeanSe mean_se(const std::vector<double>& xs) {
    MeanSe out;
    out.n = int(xs.size());
    if (xs.empty()) return out;
    double m = 0.0;
    for (double x : xs)
        m += x;
    m /= double(xs.size());
    out.mean = m;
    if (xs.size() < 2) return out;
    double v = 0.0;
    for (double x : xs)
        v += (x - m) * (x - m);
    out.sd = std::sqrt(v / double(xs.size() - 1));
    out.se = out.sd / std::sqrt(double(xs.size()));
    return out;
}

// ----- binary collisions -----------------------------------------------------------------------

enum class Pair { large_large, small_large, large_wall };
const char* to_cstr(Pair p) {
    switch (p) {
        case Pair::large_large:
            return "LL";
        case Pair::small_large:
            return "SL";
        case Pair::large_wall:
            return "LW";
    }
    return "?";
}

struct Case {
    double e_n;
    double angle_deg;  // between the relative velocity and the line of centres at contact
    Pair pair;
    double mu = 0.8;  // friction (the replica's side experiment varies it)
};

struct Collision {
    double e = kNaN, t_contact = kNaN, omega = kNaN;
    double wall = 0.0, sim = 0.0;  // cost: CPU s, simulated s
};

// Disk 1 hits disk 2 (or a wall disk) with relative velocity v along +x, centre of mass at rest;
// at the moment of contact the line of centres makes `angle_deg` with the velocity. The contact
// begins at t = (3 + phase) dt. Returns the restitution of the normal relative velocity, the
// contact duration and disk 1's rebound spin (disk 2's is -R2 c / I2 against -R1 c / I1 for
// the same integral c of n x F_t, so its relative error is the same).
Collision collide(Scheme scheme, double delta, const Case& cs, double phase) {
    const double t0 = cpu_now();
    System s(config(scheme, delta, contact(cs.e_n, cs.mu), Vec2::Zero()));
    const double dt = s.dt();
    const bool wall = cs.pair == Pair::large_wall;
    const double d1 = cs.pair == Pair::small_large ? kDS : kDL, d2 = kDL;
    const double m1 = disk_mass(d1), m2 = disk_mass(d2);
    const double v = std::sqrt(2.0 * kG * kDL);
    const double angle = cs.angle_deg * core::pi / 180.0;
    const double gap = (3.0 + phase) * v * dt;       // distance along x to the touching position
    const Vec2 n(std::cos(angle), std::sin(angle));  // from 1 to 2 at contact
    const Vec2 r1 = -0.5 * (d1 + d2) * n - Vec2(gap, 0.0);
    int id1, id2 = -1;
    if (wall) {
        id1 = s.add_particle(r1, d1, m1, disk_inertia(d1), Vec2(v, 0.0));
        s.add_wall(Vec2::Zero(), d2);
    } else {
        id1 = s.add_particle(r1, d1, m1, disk_inertia(d1), Vec2(v * m2 / (m1 + m2), 0.0));
        id2 =
            s.add_particle(Vec2::Zero(), d2, m2, disk_inertia(d2), Vec2(-v * m1 / (m1 + m2), 0.0));
    }
    auto pos = [&](int id) -> Vec2 { return s.position(s.index_of(id)); };
    auto vel = [&](int id) -> Vec2 { return s.velocity(s.index_of(id)); };
    auto rel = [&]() -> Vec2 { return wall ? Vec2(pos(id1)) : Vec2(pos(id1) - pos(id2)); };
    auto vrel = [&]() -> Vec2 { return wall ? Vec2(vel(id1)) : Vec2(vel(id1) - vel(id2)); };
    auto overlap = [&] { return 0.5 * (d1 + d2) - rel().norm(); };
    const double vn_in = vrel().dot(n);  // approaching: > 0

    double t_start = -1.0, t_end = -1.0, prev = overlap();
    const std::int64_t max_steps = std::int64_t(40 * delta) + 100;
    for (std::int64_t k = 0; k < max_steps && t_end < 0.0; ++k) {
        s.step();
        const double ov = overlap();
        if (t_start < 0.0 && ov > 0.0 && prev <= 0.0)
            t_start = s.time() - dt + dt * (-prev) / (ov - prev);
        if (t_start >= 0.0 && ov <= 0.0 && prev > 0.0)
            t_end = s.time() - dt + dt * prev / (prev - ov);
        prev = ov;
    }
    if (t_end < 0.0)
        throw core::SimulationError("the contact never ended (e_n " + std::to_string(cs.e_n) +
                                    ", angle " + std::to_string(cs.angle_deg) + ", " +
                                    to_cstr(cs.pair) + ")");
    s.run(3);  // free flight
    Collision c;
    // The line of centres at the end of the contact (from 1 to 2): the pair flies apart at
    // constant relative velocity, so step back from now to t_end. (The line of centres keeps
    // turning after the contact; taken a few steps later it would add an error of first order
    // in dt to the oblique restitution.)
    const Vec2 nf = -(rel() - vrel() * (s.time() - t_end)).normalized();
    c.e = -vrel().dot(nf) / vn_in;
    c.t_contact = t_end - t_start;
    c.omega = s.omega(s.index_of(id1));
    if (!std::isfinite(c.e) || !std::isfinite(c.omega))
        throw core::SimulationError("non-finite rebound");
    c.wall = cpu_now() - t0;
    c.sim = s.time();
    return c;
}

struct Exact {
    double e, t_contact;
};
// The damped linear oscillator mbar x'' = -k_n x - gamma_n mbar x' from x = 0 to x = 0.
Exact exact_oscillator(const Case& cs) {
    const ContactParams cp = contact(cs.e_n, 0.8);
    const double m1 = disk_mass(cs.pair == Pair::small_large ? kDS : kDL), m2 = disk_mass(kDL);
    const double mbar = cs.pair == Pair::large_wall ? m1 : m1 * m2 / (m1 + m2);
    const double w0 = std::sqrt(cp.k_n / mbar), beta = 0.5 * cp.gamma_n;
    const double w = std::sqrt(w0 * w0 - beta * beta);
    return {std::exp(-beta * core::pi / w), core::pi / w};
}

// Phase statistics of one observable of one case: values over the K phases.
struct PhaseStat {
    double mean = kNaN, rms = kNaN;  // mean over phases; rms of (value - mean)
};
PhaseStat phase_stat(const std::vector<double>& xs) {
    PhaseStat p;
    double m = 0.0;
    for (double x : xs)
        m += x;
    m /= double(xs.size());
    double v = 0.0;
    for (double x : xs)
        v += (x - m) * (x - m);
    p.mean = m;
    p.rms = std::sqrt(v / double(xs.size()));
    return p;
}

struct CaseResult {
    PhaseStat e, tc, w;
    double wall = 0.0, sim = 0.0;
};

// One case at `phases` evenly spaced onset phases (k + 1/2) / phases; `collide_at(phase)` runs
// one collision (the engine's, or the replica's).
template <class Collide>
CaseResult over_phases(int phases, Collide&& collide_at) {
    std::vector<double> e, tc, w;
    CaseResult out;
    for (int k = 0; k < phases; ++k) {
        const Collision c = collide_at((k + 0.5) / phases);
        e.push_back(c.e);
        tc.push_back(c.t_contact);
        w.push_back(c.omega);
        out.wall += c.wall;
        out.sim += c.sim;
    }
    out.e = phase_stat(e);
    out.tc = phase_stat(tc);
    out.w = phase_stat(w);
    return out;
}

CaseResult run_case(Scheme scheme, double delta, const Case& cs, int phases) {
    return over_phases(phases, [&](double phase) { return collide(scheme, delta, cs, phase); });
}

// Reference values of a case: exact for head-on e and t_c, else the scheme at delta = 4000.
struct CaseRef {
    double e = kNaN, tc = kNaN, w = kNaN;
};

// Bias and scatter of one observable, relative to |ref|.
struct Err {
    double bias = kNaN, scatter = kNaN;
};
Err rel_err(const PhaseStat& p, double ref) {
    if (!std::isfinite(ref) || ref == 0.0) return {};
    return {std::abs(p.mean - ref) / std::abs(ref), p.rms / std::abs(ref)};
}

// Worst over cases: the largest bias and the largest scatter (not necessarily the same case).
struct Worst {
    double bias = kNaN, scatter = kNaN;
    std::string where;  // case of the largest bias
    void add(const Err& e, const std::string& label) {
        if (std::isnan(e.bias)) return;
        if (std::isnan(bias) || e.bias > bias) {
            bias = e.bias;
            where = label;
        }
        if (std::isnan(scatter) || e.scatter > scatter) scatter = e.scatter;
    }
};

// ----- replica of the engine's two-body collision (engine-side proposals) ----------------------
//
// A copy of the engine's step for two bodies (velocity Verlet, or the Gear 5-value predictor-
// corrector, with the same contact law) that can be changed without changing the engine. With
// every option off it reproduces the engine (checked against collide()); the options measure
// proposals for the engine:
//   onset    the tangential spring of a new contact grows by v_t f dt instead of v_t dt, with
//            f = min(1, overlap / (|v_n| dt)) the fraction of the step spent in contact (the
//            engine starts every spring a whole step long, on average half a step too long)
//   vel      Verlet only: the dashpots (normal and tangential) and the Coulomb cap use the
//            velocity extrapolated to the end of the step, v(t + dt/2) + dt/2 a(t), instead of
//            the half-step velocity; the spring still grows by the half-step velocity
//   trap     Gear only: the spring grows by the mean of the last corrected and the predicted
//            relative tangential velocity (trapezoid) instead of the predicted one (rectangle)
struct Variant {
    bool onset = false, vel = false, trap = false;
    std::string name() const {
        std::string n;
        if (onset) n += "+onset";
        if (vel) n += "+vel";
        if (trap) n += "+trap";
        return n.empty() ? "engine" : n.substr(1);
    }
};

struct Body {
    Vec2 r = Vec2::Zero(), v = Vec2::Zero();
    double w = 0.0, m = 0.0, I = 0.0, R = 0.0;
    bool fixed = false;
    Vec2 F = Vec2::Zero(), x2 = Vec2::Zero(), x3 = Vec2::Zero(), x4 = Vec2::Zero();
    double T = 0.0, w2 = 0.0, w3 = 0.0, w4 = 0.0;
    Vec2 v_prev = Vec2::Zero();  // Gear: velocity at the end of the last step
    double w_prev = 0.0;
};

// The contact law of SpringFrictionLaw::evaluate with the dashpot velocity, the spring velocity
// and the spring's time increment given separately (all equal: the engine's law).
ContactForce replica_law(const ContactParams& p, double mbar, const Vec2& n, double overlap,
                         const Vec2& v_damp, const Vec2& v_spring, double dt_spring, Vec2& xi) {
    const double v_n = v_damp.dot(n);
    const double fn = p.k_n * overlap - p.gamma_n * mbar * v_n;
    const Vec2 v_t = v_damp - v_n * n;
    const Vec2 v_ts = v_spring - v_spring.dot(n) * n;
    xi = xi - n * n.dot(xi) + v_ts * dt_spring;
    const Vec2 damping = p.gamma_t * mbar * v_t;
    Vec2 F_t = -p.k_t * xi - damping;
    const double cap = p.mu * std::abs(fn);
    const double ft2 = F_t.squaredNorm();
    if (ft2 > cap * cap) {
        F_t *= cap / std::sqrt(ft2);
        xi = -(F_t + damping) / p.k_t;
    }
    return {fn * n, F_t};
}

struct Replica {
    Scheme scheme;
    Variant var;
    ContactParams p;
    double dt;
    Body b[2];
    Vec2 xi = Vec2::Zero();
    bool touching = false;
    double time = 0.0;

    // Forces at the current state; v_damp: velocities for the dashpots (index: body).
    void forces(const Vec2 vd[2], const double wd[2], const Vec2 vs[2], const double ws[2]) {
        for (Body& q : b) {
            q.F = Vec2::Zero();
            q.T = 0.0;
        }
        const Vec2 rij = b[0].r - b[1].r;
        const double rs = b[0].R + b[1].R, d = rij.norm();
        if (d >= rs) {
            xi = Vec2::Zero();
            touching = false;
            return;
        }
        const Vec2 n = rij / d;
        const double overlap = rs - d;
        const double inv = 1.0 / b[0].m + (b[1].fixed ? 0.0 : 1.0 / b[1].m);
        const double mbar = 1.0 / inv;
        const double w1 = b[1].fixed ? 0.0 : 1.0;
        const Vec2 v_damp =
            contact_velocity(vd[0], w1 * vd[1], b[0].R, wd[0], b[1].R, w1 * wd[1], n);
        const Vec2 v_spring =
            contact_velocity(vs[0], w1 * vs[1], b[0].R, ws[0], b[1].R, w1 * ws[1], n);
        double dts = dt;
        if (var.onset && !touching) {
            const double vn = v_spring.dot(n);  // < 0 while approaching
            if (vn < 0.0) dts = dt * std::min(1.0, overlap / (-vn * dt));
        }
        ContactForce cf;
        if (!var.vel && !var.trap && !var.onset) {
            Vec2 s = xi;  // the engine's own law
            cf = SpringFrictionLaw::evaluate(p, mbar, n, overlap, v_damp, s, dt);
            xi = s;
        } else {
            cf = replica_law(p, mbar, n, overlap, v_damp, v_spring, dts, xi);
        }
        touching = true;
        const Vec2 F = cf.normal + cf.tangential;
        const double c = core::cross(n, cf.tangential);
        b[0].F += F;
        b[0].T -= b[0].R * c;
        b[1].F -= F;
        b[1].T -= b[1].R * c;
    }

    void prime() {
        const Vec2 v[2] = {b[0].v, b[1].v};
        const double w[2] = {b[0].w, b[1].w};
        forces(v, w, v, w);
        const double h = 0.5 * dt * dt;
        for (Body& q : b) {
            q.x2 = h * q.F / q.m;
            q.x3 = q.x4 = Vec2::Zero();
            q.w2 = h * q.T / q.I;
            q.w3 = q.w4 = 0.0;
        }
    }

    void step() {
        const double hdt = 0.5 * dt;
        if (scheme == Scheme::verlet) {
            Vec2 vd[2], vs[2];
            double wd[2], ws[2];
            for (int k = 0; k < 2; ++k) {
                Body& q = b[k];
                if (!q.fixed) {
                    q.v += hdt * (q.F / q.m);
                    q.r += dt * q.v;
                    q.w += hdt * (q.T / q.I);
                }
                vs[k] = q.v;
                ws[k] = q.w;
                // Extrapolated to the end of the step with the last forces.
                vd[k] = var.vel && !q.fixed ? Vec2(q.v + hdt * (q.F / q.m)) : q.v;
                wd[k] = var.vel && !q.fixed ? q.w + hdt * (q.T / q.I) : q.w;
            }
            forces(vd, wd, vs, ws);
            for (Body& q : b)
                if (!q.fixed) {
                    q.v += hdt * (q.F / q.m);
                    q.w += hdt * (q.T / q.I);
                }
        } else {
            Vec2 vd[2], vs[2];
            double wd[2], ws[2];
            for (int k = 0; k < 2; ++k) {
                Body& q = b[k];
                q.v_prev = q.v;
                q.w_prev = q.w;
                if (!q.fixed) {
                    q.r += dt * q.v + q.x2 + q.x3 + q.x4;
                    q.v += (2.0 * q.x2 + 3.0 * q.x3 + 4.0 * q.x4) / dt;
                    q.x2 += 3.0 * q.x3 + 6.0 * q.x4;
                    q.x3 += 4.0 * q.x4;
                    q.w += (2.0 * q.w2 + 3.0 * q.w3 + 4.0 * q.w4) / dt;
                    q.w2 += 3.0 * q.w3 + 6.0 * q.w4;
                    q.w3 += 4.0 * q.w4;
                }
                vd[k] = q.v;
                wd[k] = q.w;
                vs[k] = var.trap ? Vec2(0.5 * (q.v + q.v_prev)) : q.v;
                ws[k] = var.trap ? 0.5 * (q.w + q.w_prev) : q.w;
            }
            forces(vd, wd, vs, ws);
            const double h = 0.5 * dt * dt;
            for (Body& q : b) {
                if (q.fixed) continue;
                const Vec2 e = h * q.F / q.m - q.x2;
                q.r += (19.0 / 120.0) * e;
                q.v += 0.75 * e / dt;
                q.x2 += e;
                q.x3 += 0.5 * e;
                q.x4 += e / 12.0;
                const double ew = h * q.T / q.I - q.w2;
                q.w += 0.75 * ew / dt;
                q.w2 += ew;
                q.w3 += 0.5 * ew;
                q.w4 += ew / 12.0;
            }
        }
        time += dt;
    }
};

// The same collision as collide(), integrated by the replica.
Collision collide_replica(Scheme scheme, const Variant& var, double delta, const Case& cs,
                          double phase) {
    Replica s{scheme, var, contact(cs.e_n, cs.mu), kTauC / delta, {}, Vec2::Zero(), false, 0.0};
    const double dt = s.dt;
    const bool wall = cs.pair == Pair::large_wall;
    const double d1 = cs.pair == Pair::small_large ? kDS : kDL, d2 = kDL;
    const double m1 = disk_mass(d1), m2 = disk_mass(d2);
    const double v = std::sqrt(2.0 * kG * kDL);
    const double angle = cs.angle_deg * core::pi / 180.0;
    const double gap = (3.0 + phase) * v * dt;
    const Vec2 n(std::cos(angle), std::sin(angle));
    s.b[0] = Body{-0.5 * (d1 + d2) * n - Vec2(gap, 0.0),
                  Vec2(wall ? v : v * m2 / (m1 + m2), 0.0),
                  0.0,
                  m1,
                  disk_inertia(d1),
                  0.5 * d1};
    s.b[1] =
        Body{Vec2::Zero(), Vec2(wall ? 0.0 : -v * m1 / (m1 + m2), 0.0), 0.0, m2, disk_inertia(d2),
             0.5 * d2};
    s.b[1].fixed = wall;
    s.prime();
    auto overlap = [&] { return 0.5 * (d1 + d2) - (s.b[0].r - s.b[1].r).norm(); };
    const double vn_in = (s.b[0].v - s.b[1].v).dot(n);
    double t_start = -1.0, t_end = -1.0, prev = overlap();
    const std::int64_t max_steps = std::int64_t(40 * delta) + 100;
    for (std::int64_t k = 0; k < max_steps && t_end < 0.0; ++k) {
        s.step();
        const double ov = overlap();
        if (t_start < 0.0 && ov > 0.0 && prev <= 0.0)
            t_start = s.time - dt + dt * (-prev) / (ov - prev);
        if (t_start >= 0.0 && ov <= 0.0 && prev > 0.0)
            t_end = s.time - dt + dt * prev / (prev - ov);
        prev = ov;
    }
    if (t_end < 0.0) throw core::SimulationError("replica: the contact never ended");
    for (int k = 0; k < 3; ++k)
        s.step();
    Collision c;
    const Vec2 nf =
        -((s.b[0].r - s.b[1].r) - (s.b[0].v - s.b[1].v) * (s.time - t_end)).normalized();
    c.e = -(s.b[0].v - s.b[1].v).dot(nf) / vn_in;
    c.t_contact = t_end - t_start;
    c.omega = s.b[0].w;
    return c;
}

CaseResult run_case_replica(Scheme scheme, const Variant& var, double delta, const Case& cs,
                            int phases) {
    return over_phases(
        phases, [&](double phase) { return collide_replica(scheme, var, delta, cs, phase); });
}

// ----- energy drift ----------------------------------------------------------------------------

struct Drift {
    double drift = kNaN, max_dev = kNaN, cost = kNaN;
};

Drift energy_drift(Scheme scheme, double delta, double T) {
    const double t0 = cpu_now();
    System s(config(scheme, delta, contact(1.0, 0.0), Vec2(0.0, -kG)));
    const double L = 0.10;  // inner size of the box (between wall-disk surfaces)
    const double Rw = 0.5 * kDL;
    const int nw = int(std::ceil((L + 2.0 * Rw) / kDL));
    for (int k = 0; k <= nw; ++k) {
        const double u = -Rw + k * kDL;
        s.add_wall(Vec2(u, -Rw), kDL);     // floor
        s.add_wall(Vec2(u, L + Rw), kDL);  // lid
        s.add_wall(Vec2(-Rw, u), kDL);     // left
        s.add_wall(Vec2(L + Rw, u), kDL);  // right
    }
    core::Rng rng(42);
    int placed = 0;
    for (int row = 0; row < 8 && placed < 40; ++row)
        for (int col = 0; col < 8 && placed < 40; ++col, ++placed) {
            const double d = (placed % 8 < 5) ? kDS : kDL;
            const Vec2 r(0.012 + col * 0.011, 0.012 + row * 0.011);
            const Vec2 v(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5));
            s.add_particle(r, d, disk_mass(d), disk_inertia(d), v);
        }
    auto energy = [&] { return s.kinetic_energy() + s.elastic_energy() + s.potential_energy(); };
    s.step();  // builds the neighbour list (no contact at the start)
    const double E0 = energy();
    const std::int64_t steps = std::llround(T / s.dt());
    const std::int64_t every = std::max<std::int64_t>(1, std::llround(1e-3 / s.dt()));
    double dev = 0.0;
    for (std::int64_t k = 1; k <= steps; ++k) {
        s.step();
        if (k % every == 0) dev = std::max(dev, std::abs(energy() - E0));
    }
    const double E1 = energy();
    if (!std::isfinite(E1)) throw core::SimulationError("non-finite energy");
    return {std::abs(E1 - E0) / E0, std::max(dev, std::abs(E1 - E0)) / E0,
            (cpu_now() - t0) / s.time()};
}

// ----- hopper scene: settled column, then discharge --------------------------------------------

SceneParams small_hopper(Scheme scheme, double delta) {
    SceneParams p;  // default material: e_n = 0.5, mu = 0.8 (particles and walls)
    p.particles.count = 400;
    p.hopper.width = 12.0 * cm;
    p.hopper.outlet = 4.5 * cm;
    p.hopper.theta = 60.0 * deg;
    p.material.collision_time = kTauC;
    p.integrator.scheme = scheme;
    p.integrator.steps_per_collision = delta;
    p.integrator.contact_corrections = g_corrections;
    p.protocol.max_time = 30.0;
    return p;
}

constexpr double kColumnWindow = 0.05;  // s of the settled column that are averaged
constexpr double kProfileEvery = 1e-4;  // s between samples of the bottom profile

int profile_bins(const SceneParams& p) {
    return int(std::ceil(p.hopper.width / p.particles.d_large - 1e-9));
}

struct Scene {
    std::string failure;          // empty: ran cleanly
    double force_ratio = kNaN;    // mean vertical wall force / weight over the window
    std::vector<double> profile;  // bottom normal force per x bin / weight
    double rate = kNaN;           // particles/s
    double wall_column = 0.0, sim_column = 0.0;  // CPU s, simulated s: settle + window
    double wall_hopper = 0.0, sim_hopper = 0.0;  // CPU s, simulated s: discharge
    double max_overlap_ratio = 0.0;
};

Scene run_scene(Scheme scheme, double delta, int seed, bool discharge) {
    Scene out;
    const SceneParams p = small_hopper(scheme, delta);
    const double t0 = cpu_now();
    Realization r(p, std::uint64_t(seed));
    r.settle();
    if (r.finished()) {
        out.failure = r.result().message;
        return out;
    }
    System& s = r.system();
    double weight = 0.0;
    for (double m : s.m())
        weight += m * kG;
    // Bottom walls: funnel and gate (the side walls stand at |x| = W/2 + d_w/2).
    const int nb = profile_bins(p);
    const double half = 0.5 * p.hopper.width, bin = p.particles.d_large, x_lo = -0.5 * nb * bin;
    std::vector<int> bin_of(s.wall_count(), -1);
    for (int k = 0; k < s.wall_count(); ++k) {
        const double x = s.wall_x()[k] + s.wall_offset().x();
        if (std::abs(x) < half) bin_of[k] = std::clamp(int((x - x_lo) / bin), 0, nb - 1);
    }
    std::vector<double> wall_fn(s.wall_count()), acc(nb, 0.0);
    const std::int64_t steps = std::llround(kColumnWindow / s.dt());
    const std::int64_t every = std::max<std::int64_t>(1, std::llround(kProfileEvery / s.dt()));
    double fy = 0.0;
    int samples = 0;
    try {
        for (std::int64_t k = 1; k <= steps; ++k) {
            s.step();
            fy += s.wall_force().y();
            if (k % every == 0) {
                s.normal_force_sums({}, wall_fn);
                for (int w = 0; w < s.wall_count(); ++w)
                    if (bin_of[w] >= 0) acc[bin_of[w]] += wall_fn[w];
                ++samples;
            }
        }
    } catch (const core::SimulationError& e) {
        out.failure = std::string("settled column: ") + e.what();
        return out;
    }
    // The wall force is the force of the particles on the walls: -weight at rest.
    out.force_ratio = -fy / double(steps) / weight;
    out.profile.resize(nb);
    for (int b = 0; b < nb; ++b)
        out.profile[b] = acc[b] / samples / weight;
    out.wall_column = cpu_now() - t0;
    out.sim_column = s.time();
    if (!discharge) return out;
    const double t1 = cpu_now();
    const double sim1 = s.time();
    r.open();
    while (r.advance(std::numeric_limits<double>::infinity())) {
    }
    const RealizationResult res = r.result();
    out.wall_hopper = cpu_now() - t1;
    out.sim_hopper = s.time() - sim1;
    out.max_overlap_ratio = res.diagnostics.max_overlap_ratio;
    if (res.status == Status::failed) {
        out.failure = res.message;
        return out;
    }
    if (!res.discharge_rate) {
        out.failure = "no discharge rate (status " + to_string(res.status) + ")";
        return out;
    }
    out.rate = *res.discharge_rate;
    return out;
}

// All realizations of one scheme/delta. Stops at the first failure (the setting is unstable).
struct SceneSet {
    std::vector<Scene> runs;
    std::string failure;
    int failed_seed = 0;
};

SceneSet run_scenes(Scheme scheme, double delta, int seeds, bool discharge) {
    SceneSet set;
    for (int seed = 1; seed <= seeds; ++seed) {
        Scene sc = run_scene(scheme, delta, seed, discharge);
        if (!sc.failure.empty()) {
            set.failure = sc.failure;
            set.failed_seed = seed;
            break;
        }
        set.runs.push_back(std::move(sc));
    }
    return set;
}

struct ProfileStat {
    std::vector<double> mean, se;
};
ProfileStat profile_stat(const SceneSet& set) {
    ProfileStat out;
    if (set.runs.empty()) return out;
    const std::size_t nb = set.runs.front().profile.size();
    for (std::size_t b = 0; b < nb; ++b) {
        std::vector<double> xs;
        for (const Scene& sc : set.runs)
            xs.push_back(sc.profile[b]);
        const MeanSe m = mean_se(xs);
        out.mean.push_back(m.mean);
        out.se.push_back(std::isnan(m.se) ? 0.0 : m.se);
    }
    return out;
}

// ----- table -----------------------------------------------------------------------------------

struct Row {
    Scheme scheme;
    double delta;
    bool extra = false;  // added for the stricter rule (not part of the grid)
    // Collisions: worst over cases at the default e_n (0.5) and over all e_n.
    Worst e05, tc05, w05, e_all, tc_all, w_all;
    double cost_binary = kNaN;
    double err_energy = kNaN, drift_energy_end = kNaN, cost_energy = kNaN;
    // Column.
    int column_seeds = 0;
    double err_column = kNaN, err_column_mean = kNaN;
    double prof_l2 = kNaN, prof_noise = kNaN;
    double bottom = kNaN, err_bottom = kNaN, err_bottom_se = kNaN;  // total bottom force / weight
    double cost_column = kNaN;
    // Discharge.
    int rate_seeds = 0;
    double rate = kNaN, rate_se = kNaN, err_rate = kNaN, err_rate_se = kNaN;
    double rate_corr = kNaN;  // correlation of the rates with the reference's, same seeds
    double cost_hopper = kNaN;
    double max_overlap_ratio = kNaN;
    std::vector<std::string> failed;  // observables that failed, with the first message
    // Decision.
    bool pass_default = false, pass_all = false;
    std::string fail_default, fail_all;  // first reason
};

bool stable(const Row& r) {
    return r.failed.empty();
}

// Statistical comparison: consistent with zero within 2 standard errors, or below 1 %.
bool consistent(double err, double se) {
    if (std::isnan(err)) return false;
    return err < kTolerance || (std::isfinite(se) && err < 2.0 * se);
}

// The decision rule. `all_en`: the collision biases over e_n in {0.3, 0.5, 0.8}.
bool passes(const Row& r, bool all_en, std::string& why) {
    if (!stable(r)) {
        why = "unstable";
        return false;
    }
    const std::pair<const char*, double> det[] = {
        {"restitution", all_en ? r.e_all.bias : r.e05.bias},
        {"contact time", all_en ? r.tc_all.bias : r.tc05.bias},
        {"rebound spin", all_en ? r.w_all.bias : r.w05.bias},
        {"energy", r.err_energy},
        {"column force", r.err_column}};
    for (const auto& [name, e] : det)
        if (!(e < kTolerance)) {
            why = std::string(name) + (std::isnan(e) ? " not measured" : " " + pct(e) + " %");
            return false;
        }
    if (!consistent(r.prof_l2, r.prof_noise)) {
        why = "bottom profile " + pct(r.prof_l2) + " % (noise " + pct(r.prof_noise) + " %)";
        return false;
    }
    if (!consistent(r.err_rate, r.err_rate_se)) {
        why = "rate " + pct(r.err_rate) + " % +- " + pct(r.err_rate_se) + " %";
        return false;
    }
    why.clear();
    return true;
}

std::vector<std::string> split(const std::string& s, char sep = ',') {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, sep);)
        if (!item.empty()) out.push_back(item);
    return out;
}

std::vector<double> parse_deltas(const std::string& s) {
    std::vector<double> out;
    for (const auto& d : split(s))
        out.push_back(std::stod(d));
    return out;
}

std::string csv_safe(std::string s) {
    for (char& ch : s)
        if (ch == ',' || ch == '\n' || ch == '"') ch = ';';
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    const auto t_run = Clock::now();
    bool quick = false, allow_extra = true;
    std::string csv, cases_csv, md, replica_csv, parts_arg = "binary,replica,energy,column,hopper";
    std::string schemes_arg = "gear4,verlet", deltas_arg, more_arg;
    std::string scan_arg[2] = {"", ""};  // gear4, verlet
    int seeds = -1, ref_seeds = -1, phases = -1;
    double replica_mu = -1.0;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        auto next = [&]() -> std::string {
            if (a + 1 >= argc) {
                std::fprintf(stderr, "bench_accuracy: %s needs a value\n", arg.c_str());
                std::exit(2);
            }
            return argv[++a];
        };
        if (arg == "--quick")
            quick = true;
        else if (arg == "--corrections")
            g_corrections = true;
        else if (arg == "--no-extra")
            allow_extra = false;
        else if (arg == "--csv")
            csv = next();
        else if (arg == "--cases-csv")
            cases_csv = next();
        else if (arg == "--md")
            md = next();
        else if (arg == "--replica-csv")
            replica_csv = next();
        else if (arg == "--replica-mu")
            replica_mu = std::stod(next());
        else if (arg == "--parts")
            parts_arg = next();
        else if (arg == "--schemes")
            schemes_arg = next();
        else if (arg == "--deltas")
            deltas_arg = next();
        else if (arg == "--seeds")
            seeds = std::stoi(next());
        else if (arg == "--ref-seeds")
            ref_seeds = std::stoi(next());
        else if (arg == "--more-seeds")
            more_arg = next();
        else if (arg == "--scan-gear4")
            scan_arg[0] = next();
        else if (arg == "--scan-verlet")
            scan_arg[1] = next();
        else if (arg == "--phases")
            phases = std::stoi(next());
        else {
            std::fprintf(stderr,
                         "usage: bench_accuracy [--quick] [--csv FILE] [--cases-csv FILE] "
                         "[--replica-csv FILE] [--md FILE] [--parts "
                         "binary,replica,energy,column,hopper] [--schemes gear4,verlet] "
                         "[--deltas LIST] [--seeds N] [--ref-seeds N] [--more-seeds DELTAS:N] "
                         "[--scan-gear4 LIST] [--scan-verlet LIST] [--phases K] [--replica-mu MU] "
                         "[--no-extra]\n");
            return 2;
        }
    }
    if (seeds < 0) seeds = quick ? 2 : 8;
    if (ref_seeds < 0) ref_seeds = seeds;
    if (phases < 0) phases = quick ? 4 : 16;
    std::map<double, int> seeds_of;  // --more-seeds
    if (!more_arg.empty()) {
        const auto colon = more_arg.find(':');
        if (colon == std::string::npos) {
            std::fprintf(stderr, "bench_accuracy: --more-seeds wants DELTAS:N\n");
            return 2;
        }
        const int n = std::stoi(more_arg.substr(colon + 1));
        for (double d : parse_deltas(more_arg.substr(0, colon)))
            seeds_of[d] = n;
    }
    const auto parts = split(parts_arg);
    auto want = [&](const char* p) {
        return std::find(parts.begin(), parts.end(), p) != parts.end();
    };
    const bool want_scene = want("column") || want("hopper");
    std::vector<Scheme> schemes;
    for (const auto& s : split(schemes_arg)) {
        if (s == "gear4")
            schemes.push_back(Scheme::gear4);
        else if (s == "verlet")
            schemes.push_back(Scheme::verlet);
        else {
            std::fprintf(stderr, "bench_accuracy: unknown scheme %s\n", s.c_str());
            return 2;
        }
    }
    std::vector<double> grid = quick ? std::vector<double>{20, 50, 200}
                                     : std::vector<double>{10, 15, 20, 30, 50, 75, 100, 200};
    if (!deltas_arg.empty()) grid = parse_deltas(deltas_arg);
    const std::vector<double> e_ns =
        quick ? std::vector<double>{0.5} : std::vector<double>{0.3, 0.5, 0.8};
    const std::vector<double> angles =
        quick ? std::vector<double>{0.0, 60.0} : std::vector<double>{0.0, 30.0, 60.0};
    const std::vector<Pair> pairs = {Pair::large_large, Pair::small_large, Pair::large_wall};
    std::vector<Case> cases;
    for (double e_n : e_ns)
        for (double ang : angles)
            for (Pair pr : pairs)
                cases.push_back({e_n, ang, pr});
    auto label = [](const Case& c) {
        char b[64];
        std::snprintf(b, sizeof b, "e_n=%.1f %s %g deg", c.e_n, to_cstr(c.pair), c.angle_deg);
        return std::string(b);
    };
    const double energy_T = quick ? 0.2 : 1.0;
    auto n_seeds = [&](double delta) {
        const auto it = seeds_of.find(delta);
        return it == seeds_of.end() ? seeds : std::max(seeds, it->second);
    };

    std::printf(
        "hopper accuracy benchmark (bench/accuracy.cpp): tau_c = 8e-4 s, phases %d, "
        "seeds %d (reference %d)%s\n",
        phases, seeds, ref_seeds, quick ? ", QUICK" : "");
    std::fflush(stdout);

    std::ofstream cases_out;
    if (!cases_csv.empty()) {
        cases_out.open(cases_csv);
        cases_out << "scheme,delta,e_n,pair,angle_deg,e_mean,e_rms,e_ref,tc_mean,tc_rms,tc_ref,"
                     "w_mean,w_rms,w_ref,bias_e,scatter_e,bias_tc,scatter_tc,bias_w,scatter_w\n";
    }

    // ---- collision references: delta = 4000 of each scheme ----------------------------------
    std::map<Scheme, std::vector<CaseResult>> ref4000;
    if (want("binary")) {
        for (Scheme scheme : schemes) {
            auto& v = ref4000[scheme];
            for (const Case& c : cases)
                v.push_back(run_case(scheme, kCollisionRef, c, phases));
        }
        std::printf("\ncollision references (delta = %g, phase-averaged):\n", kCollisionRef);
        for (Scheme scheme : schemes) {
            double he = 0, htc = 0;  // head-on against the exact oscillator
            double oe = 0, otc = 0;  // oblique against the 1D oscillator (not the reference)
            for (std::size_t k = 0; k < cases.size(); ++k) {
                const Exact x = exact_oscillator(cases[k]);
                const CaseResult& r = ref4000[scheme][k];
                const double de = std::abs(r.e.mean / x.e - 1.0);
                const double dtc = std::abs(r.tc.mean / x.t_contact - 1.0);
                if (cases[k].angle_deg == 0.0) {
                    he = std::max(he, de);
                    htc = std::max(htc, dtc);
                } else {
                    oe = std::max(oe, de);
                    otc = std::max(otc, dtc);
                }
            }
            std::printf(
                "  %-6s head-on vs exact: e %.1e, t_c %.1e; oblique vs the 1D oscillator "
                "(turning line of centres): e %.1e, t_c %.1e\n",
                to_string(scheme).c_str(), he, htc, oe, otc);
        }
        if (ref4000.size() == 2) {
            double de = 0, dtc = 0, dw = 0;
            std::string where;
            for (std::size_t k = 0; k < cases.size(); ++k) {
                const CaseResult& g = ref4000[Scheme::gear4][k];
                const CaseResult& v = ref4000[Scheme::verlet][k];
                de = std::max(de, std::abs(g.e.mean / v.e.mean - 1.0));
                dtc = std::max(dtc, std::abs(g.tc.mean / v.tc.mean - 1.0));
                if (cases[k].angle_deg != 0.0) {
                    const double d = std::abs(g.w.mean / v.w.mean - 1.0);
                    if (d > dw) where = label(cases[k]);
                    dw = std::max(dw, d);
                }
            }
            std::printf(
                "  gear4 vs verlet at delta = %g (the references' own uncertainty): "
                "e %.1e, t_c %.1e, rebound spin %.1e (worst: %s)\n",
                kCollisionRef, de, dtc, dw, where.c_str());
        }
        std::fflush(stdout);
    }

    // ---- replica: engine-side proposals, measured on the collisions ------------------------
    if (want("replica") && want("binary")) {
        std::printf(
            "\nreplica of the two-body step (proposals for the engine; bias of the phase "
            "mean in %%, worst case, e_n = 0.5 | all e_n):\n");
        // Check: with every option off the replica is the engine; with --corrections, the
        // engine is the replica's onset+vel (verlet) or onset+trap (gear4) variant.
        for (Scheme scheme : schemes) {
            double worst = 0.0;
            Variant engine_variant;
            if (g_corrections) {
                engine_variant.onset = true;
                engine_variant.vel = scheme == Scheme::verlet;
                engine_variant.trap = scheme == Scheme::gear4;
            }
            for (const Case& c : cases) {
                const CaseResult a = run_case(scheme, 50.0, c, phases);
                const CaseResult b = run_case_replica(scheme, engine_variant, 50.0, c, phases);
                for (auto [x, y] : {std::pair{a.e.mean, b.e.mean}, std::pair{a.tc.mean, b.tc.mean},
                                    std::pair{a.w.mean, b.w.mean}})
                    if (x != 0.0) worst = std::max(worst, std::abs(y / x - 1.0));
            }
            std::printf(
                "  %s: replica (%s) against the engine at delta 50: largest "
                "relative difference %.1e\n",
                to_string(scheme).c_str(), engine_variant.name().c_str(), worst);
        }
        std::ofstream rout;
        if (!replica_csv.empty()) {
            rout.open(replica_csv);
            rout << "mu,scheme,variant,delta,bias_e,bias_tc,bias_w,bias_e_all,bias_tc_all,"
                    "bias_w_all,scatter_e,scatter_w\n";
        }
        // mu = 0.8 against the engine's references; another mu (--replica-mu, e.g. 1e9: the
        // Coulomb cap never acts) against the engine's step at delta = 4000 with that mu.
        std::vector<double> mus{0.8};
        if (replica_mu > 0.0) mus.push_back(replica_mu);
        for (double mu : mus) {
            std::map<Scheme, std::vector<CaseResult>> refs_mu;
            if (mu != 0.8) {
                std::printf("  side experiment: mu = %g for every contact\n", mu);
                for (Scheme scheme : schemes)
                    for (Case c : cases) {
                        c.mu = mu;
                        refs_mu[scheme].push_back(
                            run_case_replica(scheme, Variant{}, kCollisionRef, c, phases));
                    }
            }
            std::printf("  %-6s %-10s %5s | %13s | %13s | %13s | worst spin case\n", "scheme",
                        "variant", "delta", "restitution", "duration", "spin");
            for (Scheme scheme : schemes) {
                std::vector<Variant> vars;
                vars.push_back({});
                vars.push_back({true, false, false});
                if (scheme == Scheme::verlet) {
                    vars.push_back({false, true, false});
                    vars.push_back({true, true, false});
                } else {
                    vars.push_back({false, false, true});
                    vars.push_back({true, false, true});
                }
                for (const Variant& var : vars)
                    for (double delta : grid) {
                        if (delta < 20.0) continue;
                        Worst e05, tc05, w05, ea, tca, wa;
                        for (std::size_t k = 0; k < cases.size(); ++k) {
                            Case c = cases[k];
                            c.mu = mu;
                            const CaseResult r = run_case_replica(scheme, var, delta, c, phases);
                            const CaseResult& ref =
                                mu == 0.8 ? ref4000[scheme][k] : refs_mu[scheme][k];
                            const Exact x = exact_oscillator(c);
                            const bool head = c.angle_deg == 0.0;
                            const Err ee = rel_err(r.e, head ? x.e : ref.e.mean);
                            const Err et = rel_err(r.tc, head ? x.t_contact : ref.tc.mean);
                            const Err ew = rel_err(r.w, head ? kNaN : ref.w.mean);
                            const std::string lb = label(c);
                            ea.add(ee, lb);
                            tca.add(et, lb);
                            wa.add(ew, lb);
                            if (c.e_n == kDefaultEn) {
                                e05.add(ee, lb);
                                tc05.add(et, lb);
                                w05.add(ew, lb);
                            }
                        }
                        std::printf("  %-6s %-10s %5g | %6s %6s | %6s %6s | %6s %6s | %s\n",
                                    to_string(scheme).c_str(), var.name().c_str(), delta,
                                    pct(e05.bias).c_str(), pct(ea.bias).c_str(),
                                    pct(tc05.bias).c_str(), pct(tca.bias).c_str(),
                                    pct(w05.bias).c_str(), pct(wa.bias).c_str(), wa.where.c_str());
                        if (rout.is_open())
                            rout << mu << ',' << to_string(scheme) << ',' << var.name() << ','
                                 << delta << ',' << fmt(e05.bias, "%.4g") << ','
                                 << fmt(tc05.bias, "%.4g") << ',' << fmt(w05.bias, "%.4g") << ','
                                 << fmt(ea.bias, "%.4g") << ',' << fmt(tca.bias, "%.4g") << ','
                                 << fmt(wa.bias, "%.4g") << ',' << fmt(ea.scatter, "%.4g") << ','
                                 << fmt(wa.scatter, "%.4g") << '\n';
                    }
            }
        }
        std::fflush(stdout);
    }

    // ---- scene references: delta = 400 of each scheme -----------------------------------------
    std::map<Scheme, SceneSet> ref_scene;
    std::map<Scheme, double> ref_cost_hopper;
    if (want_scene) {
        for (Scheme scheme : schemes) {
            const auto t0 = Clock::now();
            SceneSet set = run_scenes(scheme, kRefDelta, ref_seeds, want("hopper"));
            std::vector<double> rates;
            for (const Scene& sc : set.runs)
                rates.push_back(sc.rate);
            const MeanSe m = mean_se(rates);
            std::fprintf(stderr,
                         "%s reference delta=%g: %d seeds, rate %.2f +- %.2f /s (%.0f s) %s\n",
                         to_string(scheme).c_str(), kRefDelta, int(set.runs.size()), m.mean, m.se,
                         seconds_since(t0), set.failure.c_str());
            ref_scene[scheme] = std::move(set);
        }
    }

    // ---- one row
    // ---------------------------------------------------------------------------------
    auto measure = [&](Scheme scheme, double delta, bool extra) {
        Row row;
        row.scheme = scheme;
        row.delta = delta;
        row.extra = extra;
        const auto t0 = Clock::now();
        if (want("binary")) {
            try {
                double wall = 0, sim = 0;
                for (std::size_t k = 0; k < cases.size(); ++k) {
                    const Case& c = cases[k];
                    const CaseResult r = run_case(scheme, delta, c, phases);
                    wall += r.wall;
                    sim += r.sim;
                    const CaseResult& ref = ref4000[scheme][k];
                    CaseRef cr;
                    if (c.angle_deg == 0.0) {
                        const Exact x = exact_oscillator(c);
                        cr = {x.e, x.t_contact, kNaN};
                    } else {
                        cr = {ref.e.mean, ref.tc.mean, ref.w.mean};
                    }
                    const Err ee = rel_err(r.e, cr.e), et = rel_err(r.tc, cr.tc),
                              ew = rel_err(r.w, cr.w);
                    const std::string lb = label(c);
                    row.e_all.add(ee, lb);
                    row.tc_all.add(et, lb);
                    row.w_all.add(ew, lb);
                    if (c.e_n == kDefaultEn) {
                        row.e05.add(ee, lb);
                        row.tc05.add(et, lb);
                        row.w05.add(ew, lb);
                    }
                    if (cases_out.is_open())
                        cases_out << to_string(scheme) << ',' << delta << ',' << c.e_n << ','
                                  << to_cstr(c.pair) << ',' << c.angle_deg << ','
                                  << fmt(r.e.mean, "%.9g") << ',' << fmt(r.e.rms, "%.4g") << ','
                                  << fmt(cr.e, "%.9g") << ',' << fmt(r.tc.mean, "%.9g") << ','
                                  << fmt(r.tc.rms, "%.4g") << ',' << fmt(cr.tc, "%.9g") << ','
                                  << fmt(r.w.mean, "%.9g") << ',' << fmt(r.w.rms, "%.4g") << ','
                                  << fmt(cr.w, "%.9g") << ',' << fmt(ee.bias, "%.4g") << ','
                                  << fmt(ee.scatter, "%.4g") << ',' << fmt(et.bias, "%.4g") << ','
                                  << fmt(et.scatter, "%.4g") << ',' << fmt(ew.bias, "%.4g") << ','
                                  << fmt(ew.scatter, "%.4g") << '\n';
                }
                row.cost_binary = wall / sim;
            } catch (const core::SimulationError& ex) {
                row.failed.push_back(std::string("binary: ") + ex.what());
            }
        }
        if (want("energy")) {
            try {
                const Drift d = energy_drift(scheme, delta, energy_T);
                row.err_energy = d.max_dev;      // largest |E(t) - E(0)| / E(0), t <= T
                row.drift_energy_end = d.drift;  // at t = T
                row.cost_energy = d.cost;
            } catch (const core::SimulationError& ex) {
                row.failed.push_back(std::string("energy: ") + ex.what());
            }
        }
        if (want_scene) {
            const bool is_ref = delta == kRefDelta;
            SceneSet own;
            if (!is_ref) own = run_scenes(scheme, delta, n_seeds(delta), want("hopper"));
            const SceneSet& set = is_ref ? ref_scene[scheme] : own;
            const SceneSet& ref = ref_scene[scheme];
            if (!set.failure.empty()) {
                char b[64];
                std::snprintf(b, sizeof b, "scene (seed %d): ", set.failed_seed);
                row.failed.push_back(b + set.failure);
            }
            if (set.failure.empty() && !set.runs.empty()) {
                double worst = 0.0, sum = 0.0, wall_c = 0, sim_c = 0, wall_h = 0, sim_h = 0;
                double ov = 0.0;
                std::vector<double> rates;
                for (const Scene& sc : set.runs) {
                    const double e = std::abs(sc.force_ratio - 1.0);
                    worst = std::max(worst, e);
                    sum += sc.force_ratio;
                    wall_c += sc.wall_column;
                    sim_c += sc.sim_column;
                    wall_h += sc.wall_hopper;
                    sim_h += sc.sim_hopper;
                    ov = std::max(ov, sc.max_overlap_ratio);
                    rates.push_back(sc.rate);
                }
                row.column_seeds = int(set.runs.size());
                row.err_column = worst;
                row.err_column_mean = std::abs(sum / double(set.runs.size()) - 1.0);
                row.cost_column = wall_c / sim_c;
                // Bottom profile against the reference: relative L2 difference and its noise.
                const ProfileStat a = profile_stat(set), b = profile_stat(ref);
                if (!a.mean.empty() && a.mean.size() == b.mean.size() && ref.failure.empty()) {
                    double d2 = 0, n2 = 0, r2 = 0;
                    for (std::size_t k = 0; k < a.mean.size(); ++k) {
                        d2 += (a.mean[k] - b.mean[k]) * (a.mean[k] - b.mean[k]);
                        n2 += is_ref ? 0.0 : a.se[k] * a.se[k] + b.se[k] * b.se[k];
                        r2 += b.mean[k] * b.mean[k];
                    }
                    row.prof_l2 = std::sqrt(d2 / r2);
                    row.prof_noise = std::sqrt(n2 / r2);
                    // The whole bottom (sum of the bins): far less noisy than one bin.
                    std::vector<double> ta, tb;
                    for (const Scene& sc : set.runs)
                        ta.push_back(std::accumulate(sc.profile.begin(), sc.profile.end(), 0.0));
                    for (const Scene& sc : ref.runs)
                        tb.push_back(std::accumulate(sc.profile.begin(), sc.profile.end(), 0.0));
                    const MeanSe ma = mean_se(ta), mb = mean_se(tb);
                    const double q = ma.mean / mb.mean;
                    row.bottom = ma.mean;
                    row.err_bottom = std::abs(q - 1.0);
                    row.err_bottom_se =
                        is_ref ? 0.0 : q * std::hypot(ma.se / ma.mean, mb.se / mb.mean);
                }
                if (want("hopper")) {
                    row.rate_seeds = int(rates.size());
                    const MeanSe m = mean_se(rates);
                    row.rate = m.mean;
                    row.rate_se = m.se;
                    row.cost_hopper = wall_h / sim_h;
                    row.max_overlap_ratio = ov;
                    std::vector<double> rr;
                    for (const Scene& sc : ref.runs)
                        rr.push_back(sc.rate);
                    const MeanSe mr = mean_se(rr);
                    if (ref.failure.empty() && std::isfinite(mr.mean)) {
                        const double q = m.mean / mr.mean;
                        row.err_rate = std::abs(q - 1.0);
                        row.err_rate_se =
                            is_ref ? 0.0 : q * std::hypot(m.se / m.mean, mr.se / mr.mean);
                        // Same seeds, same fill: are the rates correlated? (then the unpaired
                        // standard error above is conservative)
                        const std::size_t nc = std::min(rates.size(), rr.size());
                        if (!is_ref && nc > 2) {
                            double ma = 0, mb = 0, sab = 0, saa = 0, sbb = 0;
                            for (std::size_t k = 0; k < nc; ++k) {
                                ma += rates[k];
                                mb += rr[k];
                            }
                            ma /= double(nc);
                            mb /= double(nc);
                            for (std::size_t k = 0; k < nc; ++k) {
                                sab += (rates[k] - ma) * (rr[k] - mb);
                                saa += (rates[k] - ma) * (rates[k] - ma);
                                sbb += (rr[k] - mb) * (rr[k] - mb);
                            }
                            row.rate_corr = sab / std::sqrt(saa * sbb);
                        }
                    }
                }
            }
        }
        for (const auto& f : row.failed)
            std::fprintf(stderr, "%s delta=%g unstable: %s\n", to_string(scheme).c_str(), delta,
                         f.substr(0, 200).c_str());
        std::fprintf(stderr, "done %s delta=%g (%.0f s)\n", to_string(scheme).c_str(), delta,
                     seconds_since(t0));
        row.pass_default = passes(row, false, row.fail_default);
        row.pass_all = passes(row, true, row.fail_all);
        return row;
    };

    std::vector<Row> rows;
    for (Scheme scheme : schemes) {
        std::vector<double> ds = grid;
        for (double d : parse_deltas(scan_arg[scheme == Scheme::gear4 ? 0 : 1]))
            if (std::find(ds.begin(), ds.end(), d) == ds.end()) ds.push_back(d);
        std::sort(ds.begin(), ds.end());
        for (double delta : ds)
            rows.push_back(measure(scheme, delta, false));
    }

    auto cheapest = [&](bool all_en) -> const Row* {
        const Row* best = nullptr;
        for (const Row& r : rows) {
            if (!(all_en ? r.pass_all : r.pass_default)) continue;
            if (!best || r.cost_hopper < best->cost_hopper) best = &r;
        }
        return best;
    };
    // Stricter rule: if no grid setting passes, add delta 300 and 400.
    bool added_extra = false;
    if (allow_extra && !cheapest(true) && want("binary") && want_scene) {
        added_extra = true;
        for (Scheme scheme : schemes)
            for (double delta : {300.0, 400.0})
                if (std::none_of(rows.begin(), rows.end(), [&](const Row& r) {
                        return r.scheme == scheme && r.delta == delta;
                    }))
                    rows.push_back(measure(scheme, delta, true));
    }
    std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
        return a.scheme != b.scheme ? a.scheme < b.scheme : a.delta < b.delta;
    });

    // ---- table -----------------------------------------------------------------------------
    std::printf(
        "\nrelative errors in %% at the default material (e_n = 0.5, mu = 0.8); collisions: "
        "bias of the phase mean [phase scatter], worst case; energy: e_n = 1, mu = 0; column "
        "force: worst seed; profile and rate: vs delta = %g of the same scheme, +- 1 standard "
        "error; cost: CPU s per simulated s of the discharging hopper\n",
        kRefDelta);
    std::printf("%-6s %5s | %13s %13s %13s | %6s | %6s %13s | %14s %5s | %7s | %s\n", "scheme",
                "delta", "restitution", "duration", "spin", "energy", "column", "profile", "rate",
                "seeds", "cost", "status");
    auto cell = [](const Worst& w) {
        if (std::isnan(w.bias)) return std::string("-");
        return pct(w.bias) + " [" + pct(w.scatter) + "]";
    };
    auto pm = [](double a, double b) {
        if (std::isnan(a)) return std::string("-");
        return pct(a) + "+-" + pct(b);
    };
    for (const Row& r : rows) {
        std::string status = !stable(r)       ? "UNSTABLE"
                             : r.pass_default ? (r.pass_all ? "PASS (all e_n)" : "PASS")
                                              : "fail: " + r.fail_default;
        std::printf("%-6s %5g | %13s %13s %13s | %6s | %6s %13s | %14s %5s | %7s | %s\n",
                    to_string(r.scheme).c_str(), r.delta, cell(r.e05).c_str(), cell(r.tc05).c_str(),
                    cell(r.w05).c_str(), pct(r.err_energy).c_str(), pct(r.err_column).c_str(),
                    pm(r.prof_l2, r.prof_noise).c_str(), pm(r.err_rate, r.err_rate_se).c_str(),
                    r.rate_seeds ? std::to_string(r.rate_seeds).c_str() : "-",
                    fmt(r.cost_hopper, "%.3g").c_str(), status.c_str());
    }
    std::printf(
        "\nover all e_n in {0.3, 0.5, 0.8} (collisions only; the scenes use the default "
        "material):\n%-6s %5s | %13s %13s %13s | %s\n",
        "scheme", "delta", "restitution", "duration", "spin", "stricter rule");
    for (const Row& r : rows)
        std::printf("%-6s %5g | %13s %13s %13s | %s   worst e: %s, spin: %s\n",
                    to_string(r.scheme).c_str(), r.delta, cell(r.e_all).c_str(),
                    cell(r.tc_all).c_str(), cell(r.w_all).c_str(),
                    r.pass_all ? "PASS" : ("fail: " + r.fail_all).c_str(), r.e_all.where.c_str(),
                    r.w_all.where.c_str());

    // Smallest safe delta: this delta and every larger one ran every seed of every part.
    std::map<Scheme, double> safe;
    std::printf("\n");
    for (Scheme scheme : schemes) {
        double s = kNaN;
        for (auto it = rows.rbegin(); it != rows.rend(); ++it) {
            if (it->scheme != scheme) continue;
            if (!stable(*it)) break;
            s = it->delta;
        }
        safe[scheme] = s;
        double ov = kNaN;
        for (const Row& r : rows)
            if (r.scheme == scheme && r.delta == s) ov = r.max_overlap_ratio;
        std::printf(
            "smallest safe delta, %s: %s (every delta >= it ran all seeds of the column "
            "and the discharge cleanly; max overlap there %s d_small)\n",
            to_string(scheme).c_str(), std::isnan(s) ? "none" : fmt(s, "%g").c_str(),
            fmt(ov, "%.3f").c_str());
        for (const Row& r : rows)
            if (r.scheme == scheme && !stable(r))
                std::printf("  unstable at delta %g: %s\n", r.delta,
                            r.failed.front().substr(0, 160).c_str());
    }
    for (Scheme scheme : schemes) {
        for (const Row& r : rows)
            if (r.scheme == scheme && std::isfinite(r.rate_corr)) {
                std::printf("correlation of seed-wise rates with the reference (%s): ",
                            to_string(scheme).c_str());
                for (const Row& q : rows)
                    if (q.scheme == scheme && std::isfinite(q.rate_corr))
                        std::printf(" %g:%.2f", q.delta, q.rate_corr);
                std::printf("\n");
                break;
            }
    }

    std::printf(
        "\ndecision rule: the cheapest setting (cost per simulated second of the discharging "
        "hopper, this run) with every deterministic error (phase-averaged restitution, contact "
        "duration and rebound-spin bias, energy drift, column force) < 1 %% and every "
        "statistical comparison (bottom profile, rate) within 2 standard errors of zero or "
        "< 1 %%\n");
    const Row* best = cheapest(false);
    const Row* strict = cheapest(true);
    const Row* g50 = nullptr;
    for (const Row& r : rows)
        if (r.scheme == Scheme::gear4 && r.delta == 50.0) g50 = &r;
    auto describe = [&](const Row* r) {
        if (!r) return std::string("none");
        char b[256];
        std::snprintf(
            b, sizeof b, "%s delta = %g (cost %.3g s/s%s)", to_string(r->scheme).c_str(), r->delta,
            r->cost_hopper,
            g50 && std::isfinite(g50->cost_hopper)
                ? (", " + fmt(r->cost_hopper / g50->cost_hopper, "%.2f") + " x gear4 delta = 50")
                      .c_str()
                : "");
        return std::string(b);
    };
    std::printf("  at the default material (e_n = 0.5): %s\n", describe(best).c_str());
    std::printf("  over all e_n in {0.3, 0.5, 0.8} (stricter): %s%s\n", describe(strict).c_str(),
                added_extra ? " (delta 300 and 400 added to the candidates: no grid setting "
                              "passed; at delta 400 the profile and rate are the reference "
                              "itself)"
                            : "");
    for (const Row& r : rows)
        if (&r == best || &r == strict) {
            std::printf(
                "  %s delta %g: restitution %s %%, duration %s %%, spin %s %% (e_n = "
                "0.5; all e_n: %s / %s / %s %%), energy %s %%, column force %s %%, "
                "profile %s %% +- %s %%, rate %s %% +- %s %%\n",
                to_string(r.scheme).c_str(), r.delta, pct(r.e05.bias).c_str(),
                pct(r.tc05.bias).c_str(), pct(r.w05.bias).c_str(), pct(r.e_all.bias).c_str(),
                pct(r.tc_all.bias).c_str(), pct(r.w_all.bias).c_str(), pct(r.err_energy).c_str(),
                pct(r.err_column).c_str(), pct(r.prof_l2).c_str(), pct(r.prof_noise).c_str(),
                pct(r.err_rate).c_str(), pct(r.err_rate_se).c_str());
        }
    std::printf("this run: %.0f s wall, %.0f s CPU\n", seconds_since(t_run), cpu_now());

    if (!csv.empty()) {
        std::ofstream f(csv);
        f << "scheme,delta,dt,extra,"
             "bias_e,scatter_e,bias_tc,scatter_tc,bias_w,scatter_w,"
             "bias_e_all,scatter_e_all,bias_tc_all,scatter_tc_all,bias_w_all,scatter_w_all,"
             "worst_case_e_all,worst_case_w_all,cost_binary,"
             "err_energy,drift_energy_end,cost_energy,"
             "column_seeds,err_column_force,err_column_force_mean,err_profile,err_profile_noise,"
             "bottom_over_weight,err_bottom,err_bottom_se,"
             "cost_column,rate_seeds,rate,rate_se,err_rate,err_rate_se,rate_corr,cost_hopper,"
             "max_overlap_ratio,status,pass_default,pass_all_en,chosen_default,chosen_all_en,"
             "fail_default,fail_all_en,failure\n";
        auto F = [](double x) { return fmt(x, "%.6g"); };
        for (const Row& r : rows) {
            const std::string why =
                r.failed.empty() ? "" : csv_safe(r.failed.front().substr(0, 160));
            f << to_string(r.scheme) << ',' << r.delta << ',' << F(kTauC / r.delta) << ','
              << (r.extra ? 1 : 0) << ',';
            for (const Worst* w : {&r.e05, &r.tc05, &r.w05, &r.e_all, &r.tc_all, &r.w_all})
                f << F(w->bias) << ',' << F(w->scatter) << ',';
            f << csv_safe(r.e_all.where) << ',' << csv_safe(r.w_all.where) << ','
              << F(r.cost_binary) << ',' << F(r.err_energy) << ',' << F(r.drift_energy_end) << ','
              << F(r.cost_energy) << ',' << r.column_seeds << ',' << F(r.err_column) << ','
              << F(r.err_column_mean) << ',' << F(r.prof_l2) << ',' << F(r.prof_noise) << ','
              << F(r.bottom) << ',' << F(r.err_bottom) << ',' << F(r.err_bottom_se) << ','
              << F(r.cost_column) << ',' << r.rate_seeds << ',' << F(r.rate) << ',' << F(r.rate_se)
              << ',' << F(r.err_rate) << ',' << F(r.err_rate_se) << ',' << F(r.rate_corr) << ','
              << F(r.cost_hopper) << ',' << F(r.max_overlap_ratio) << ','
              << (stable(r) ? "ok" : "unstable") << ',' << (r.pass_default ? 1 : 0) << ','
              << (r.pass_all ? 1 : 0) << ',' << (&r == best ? 1 : 0) << ','
              << (&r == strict ? 1 : 0) << ',' << csv_safe(r.fail_default) << ','
              << csv_safe(r.fail_all) << ',' << why << '\n';
        }
        std::printf("wrote %s\n", csv.c_str());
    }
    if (!md.empty()) {
        std::ofstream f(md);
        f << "| scheme | delta | restitution bias [scatter] | duration bias [scatter] | spin "
             "bias [scatter] | restitution, all e_n | spin, all e_n | energy | column force | "
             "bottom profile | rate | seeds | cost (s/s) | rule e_n = 0.5 | rule all e_n |\n"
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
        for (const Row& r : rows) {
            auto mark = [&](bool pass, const std::string& why) {
                return !stable(r) ? std::string("unstable") : pass ? std::string("**pass**") : why;
            };
            f << "| " << to_string(r.scheme) << " | " << r.delta << (r.extra ? "*" : "") << " | "
              << cell(r.e05) << " | " << cell(r.tc05) << " | " << cell(r.w05) << " | "
              << cell(r.e_all) << " | " << cell(r.w_all) << " | " << pct(r.err_energy) << " | "
              << pct(r.err_column) << " | " << pm(r.prof_l2, r.prof_noise) << " | "
              << pm(r.err_rate, r.err_rate_se) << " | "
              << (r.rate_seeds ? std::to_string(r.rate_seeds) : "-") << " | "
              << fmt(r.cost_hopper, "%.3g") << " | " << mark(r.pass_default, r.fail_default)
              << (&r == best ? " (chosen)" : "") << " | " << mark(r.pass_all, r.fail_all)
              << (&r == strict ? " (chosen)" : "") << " |\n";
        }
        std::printf("wrote %s\n", md.c_str());
    }
    return 0;
}
