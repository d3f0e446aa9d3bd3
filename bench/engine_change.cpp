// Statistics of one engine build, seed by seed, for validating a change of the engine's bits
// (issue 25, part 2): built from two commits, the same command gives two JSON-lines files that
// bench/engine_change/compare.py sets side by side (means, errors, z). Method and results:
// docs/performance.md, "Statistical validation of the new formulation".
//
//   bench_engine_change --scene discharge|jamming --setting published|calibrated|default
//                       [--seeds N] [--first S] [--D CM] [--theta DEG] [--width CM]
//                       [--particles N] [--max-time S] [--out FILE]
//                       [--scheme gear4|verlet] [--delta N] [--corrections 0|1] [--settle-only 1]
//                       [--settle-ke X] [--settle-hold S] [--settle-delta N]
//
// Scenes (the published bidisperse disks and material, tau_c = 8e-4 s):
//   discharge  W = 20 cm, 1200 disks, D = 4.5 cm, theta = 45 deg: fill, settle, then the settled
//              packing fraction phi in a window of the column (below), then the whole discharge:
//              its steady rate (RealizationResult::discharge_rate, disks/s).
//   jamming    W = 12 cm, 500 disks, D = 2.3 cm, theta = 45 deg, 30 s of discharge at most, the
//              published shakes: jams, flowing time (the sum of the survival intervals), and
//              the settled phi as above.
// Settings: published = gear4, delta 50, no contact corrections (campaigns/paper); calibrated =
// published with issue 39's calibrated walls and shakes (campaigns/paper-calibrated-2026-12:
// wall spacing 0.5, edge offset 0.15, shake growth 1.5 up to one d_large, 50 shakes); default =
// the engine's IntegratorParams as they stand (what a sweep file without [integrator] gets);
// --scheme, --delta and --corrections override the setting's integrator; --settle-only 1 stops
// after phi (no discharge: rate, jams and flow time are then those of no discharge);
// --settle-ke and --settle-hold override the settle's stopping rule (protocol.settle_ke,
// protocol.settle_hold_s; issue 41: one build against itself at two rules); --settle-delta the
// settle's time step (integrator.settle_steps_per_collision).
// phi: the area of the disks whose centres lie in the window over the window's area; the window
// spans the column's width less 2 d_large on each side, from 2 d_large above the funnel's top
// to 3 d_large below the packing's highest centre. The same estimator on both builds, so its
// small bias at the window's edges cancels in the comparison.
// One JSON object per seed and line on stdout (or --out): scene, setting, seed, status, phi,
// settle_time (simulated s to rest), rate, jams, shakes, multi_shake (jams that needed more
// than one shake), flow_time, discharged, settle_steps, settle_cpu_s (CPU s of fill and
// settle), cpu_s.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <string>

#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper;
using namespace hopper::engine;

namespace {

struct Options {
    std::string scene = "discharge", setting = "published", out;
    int seeds = 32, first = 1, particles = -1;
    double D = -1, theta = 45.0, width = -1, max_time = -1;
    std::string scheme;        // --scheme: overrides the setting's integrator
    double delta = -1;         // --delta: steps per collision time
    int corrections = -1;      // --corrections 0|1
    bool settle_only = false;  // --settle-only 1: phi only, no discharge
    double settle_ke = -1;     // --settle-ke: protocol.settle_ke (m_large g d_large)
    double settle_hold = -1;   // --settle-hold: protocol.settle_hold_s (s)
    double settle_delta = -1;  // --settle-delta: integrator.settle_steps_per_collision
};

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(
        stderr,
        "bench_engine_change: %s\nusage: bench_engine_change --scene discharge|jamming "
        "--setting published|calibrated|default [--seeds N] [--first S] [--D CM] [--theta DEG] "
        "[--width CM] [--particles N] [--max-time S] [--out FILE] [--scheme gear4|verlet] "
        "[--delta N] [--corrections 0|1] [--settle-only 1] [--settle-ke X] [--settle-delta N] "
        "[--settle-hold S]\n",
        why.c_str());
    std::exit(2);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage("option " + a + " needs a value");
        const std::string v = argv[++i];
        try {
            if (a == "--scene")
                o.scene = v;
            else if (a == "--setting")
                o.setting = v;
            else if (a == "--out")
                o.out = v;
            else if (a == "--seeds")
                o.seeds = std::stoi(v);
            else if (a == "--first")
                o.first = std::stoi(v);
            else if (a == "--particles")
                o.particles = std::stoi(v);
            else if (a == "--D")
                o.D = std::stod(v);
            else if (a == "--theta")
                o.theta = std::stod(v);
            else if (a == "--width")
                o.width = std::stod(v);
            else if (a == "--max-time")
                o.max_time = std::stod(v);
            else if (a == "--scheme")
                o.scheme = v;
            else if (a == "--delta")
                o.delta = std::stod(v);
            else if (a == "--corrections")
                o.corrections = std::stoi(v);
            else if (a == "--settle-only")
                o.settle_only = std::stoi(v) != 0;
            else if (a == "--settle-delta")
                o.settle_delta = std::stod(v);
            else if (a == "--settle-ke")
                o.settle_ke = std::stod(v);
            else if (a == "--settle-hold")
                o.settle_hold = std::stod(v);
            else
                usage("unknown option " + a);
        } catch (const std::logic_error&) {
            usage("option " + a + ": '" + v + "' is not a number");
        }
    }
    if (o.scene != "discharge" && o.scene != "jamming")
        usage("--scene: '" + o.scene + "' (allowed: discharge, jamming)");
    if (o.setting != "published" && o.setting != "calibrated" && o.setting != "default")
        usage("--setting: '" + o.setting + "' (allowed: published, calibrated, default)");
    if (o.seeds < 1 || o.first < 0) usage("--seeds must be >= 1 and --first >= 0");
    if (o.settle_ke != -1 && !(o.settle_ke > 0 && o.settle_ke <= 1))
        usage("--settle-ke must lie in (0, 1]");
    if (o.settle_delta != -1 && !(o.settle_delta >= 2 && o.settle_delta <= 1e5))
        usage("--settle-delta must lie in [2, 1e5]");
    if (o.settle_hold != -1 && !(o.settle_hold > 0 && o.settle_hold <= 100))
        usage("--settle-hold must lie in (0, 100] s");
    if (!o.scheme.empty() && o.scheme != "gear4" && o.scheme != "verlet")
        usage("--scheme: '" + o.scheme + "' (allowed: gear4, verlet)");
    return o;
}

SceneParams scene(const Options& o) {
    const bool discharge = o.scene == "discharge";
    SceneParams p;
    p.hopper.width = (o.width > 0 ? o.width : discharge ? 20.0 : 12.0) * cm;
    p.hopper.outlet = (o.D > 0 ? o.D : discharge ? 4.5 : 2.3) * cm;
    p.hopper.theta = o.theta * deg;
    p.particles.count = o.particles > 0 ? o.particles : discharge ? 1200 : 500;
    p.material.collision_time = 8.0e-4;
    p.protocol.max_time = o.max_time > 0 ? o.max_time : discharge ? 600.0 : 30.0;
    if (o.setting == "published" || o.setting == "calibrated") {
        p.integrator.scheme = Scheme::gear4;
        p.integrator.steps_per_collision = 50.0;
        p.integrator.contact_corrections = false;
    }
    if (o.setting == "calibrated") {  // campaigns/paper-calibrated-2026-12 (issue 39)
        p.hopper.wall_spacing = 0.5;
        p.hopper.edge_offset = 0.15;
        p.protocol.shake_growth = 1.5;
        p.protocol.shake_amplitude_max = 1.0;
        p.protocol.max_shakes = 50;
    }
    if (!o.scheme.empty())
        p.integrator.scheme = o.scheme == "gear4" ? Scheme::gear4 : Scheme::verlet;
    if (o.delta > 0) p.integrator.steps_per_collision = o.delta;
    if (o.corrections >= 0) p.integrator.contact_corrections = o.corrections != 0;
    if (o.settle_ke > 0) p.protocol.settle_ke = o.settle_ke;
    if (o.settle_hold > 0) p.protocol.settle_hold = o.settle_hold;
    if (o.settle_delta > 0) p.integrator.settle_steps_per_collision = o.settle_delta;
    return p;
}

// Settled packing fraction in the window described at the top of the file.
double packing_fraction(System& s, const SceneParams& p) {
    const double dl = p.particles.d_large;
    const double funnel_top = 0.5 * (p.hopper.width - p.hopper.outlet) * std::tan(p.hopper.theta);
    double top = -1e9;
    for (int i = 0; i < s.mobile_count(); ++i)
        top = std::max(top, s.position(i).y());
    const double x0 = -0.5 * p.hopper.width + 2.0 * dl, x1 = -x0;
    const double y0 = funnel_top + 2.0 * dl, y1 = top - 3.0 * dl;
    if (y1 <= y0) return std::nan("");
    double area = 0.0;
    for (int i = 0; i < s.mobile_count(); ++i) {
        const Vec2 c = s.position(i);
        if (c.x() >= x0 && c.x() < x1 && c.y() >= y0 && c.y() < y1)
            area += M_PI * s.radius(i) * s.radius(i);
    }
    return area / ((x1 - x0) * (y1 - y0));
}

void number(std::FILE* f, const char* key, double v) {
    if (std::isfinite(v))
        std::fprintf(f, ", \"%s\": %.17g", key, v);
    else
        std::fprintf(f, ", \"%s\": null", key);
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    const SceneParams p = scene(o);
    std::FILE* f = o.out.empty() ? stdout : std::fopen(o.out.c_str(), "w");
    if (!f) usage("cannot write " + o.out);
    for (int k = 0; k < o.seeds; ++k) {
        const std::uint64_t seed = std::uint64_t(o.first + k);
        const std::clock_t c0 = std::clock();
        Realization r(p, seed);
        r.settle();
        const double settle_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
        const double phi = packing_fraction(r.system(), p);
        if (!o.settle_only) {
            r.open();
            while (r.advance(1.0)) {
            }
        }
        const RealizationResult res = r.result();
        const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
        const std::string status = o.settle_only ? "settled" : to_string(res.status);
        double flow = 0.0;
        for (double t : res.survival_times)
            flow += t;
        std::fprintf(f,
                     "{\"scene\": \"%s\", \"setting\": \"%s\", \"seed\": %llu, \"status\": \"%s\"",
                     o.scene.c_str(), o.setting.c_str(), (unsigned long long)seed, status.c_str());
        number(f, "phi", phi);
        number(f, "settle_time", res.diagnostics.settle_time);
        number(f, "rate", res.discharge_rate ? *res.discharge_rate : std::nan(""));
        std::fprintf(f, ", \"jams\": %d", res.n_jams);
        std::fprintf(f, ", \"shakes\": %d, \"multi_shake\": %d", res.n_shakes,
                     res.n_jams_multi_shake);
        number(f, "flow_time", flow);
        std::fprintf(f, ", \"discharged\": %d", res.discharged);
        std::fprintf(f, ", \"settle_steps\": %lld", (long long)res.diagnostics.settle_steps);
        number(f, "settle_cpu_s", settle_cpu);
        number(f, "cpu_s", cpu);
        std::fprintf(f, "}\n");
        std::fflush(f);
        std::fprintf(stderr, "  %s %s seed %llu: %s, %d jams, %.1f s cpu\n", o.scene.c_str(),
                     o.setting.c_str(), (unsigned long long)seed, status.c_str(), res.n_jams, cpu);
    }
    if (f != stdout) std::fclose(f);
    return 0;
}
