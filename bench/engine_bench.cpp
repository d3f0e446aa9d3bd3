// Engine speed benchmark (issue 2): ns per particle-step on the two standard full-size scenes,
// per-phase breakdown, peak memory, and what each thing the engine skips is worth.
//
//   bench_engine [--repeats R] [--steps K] [--particles N] [--full] [--skips] [--fields]
//                [--csv FILE]
//
//   --full    also run the discharge to the end (the wall time of one whole realization)
//   --skips   what each thing the engine skips is worth (whole mid-size realizations)
//   --fields  the cost of the coarse-grained field observer (issue 7), whole mid-size
//             realizations with fields off and on (cell and Gaussian kernels, sampled every
//             1 ms and every step), run interleaved seed by seed; only this part runs
//
// Scenes (published values: 8750 particles, W = 43 cm, tau_c = 8e-4 s, delta = 50, Gear):
//   column     the settled packing before the outlet opens (gate closed), K steps per repeat;
//   discharge  D = 4.5 cm, theta = 60 deg, from the opening, 0.5 s of discharge per repeat.
// Each figure is the median of R repeats; the machine is shared, so compare ratios measured in
// the same run rather than absolute numbers across runs.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper::engine;
using Clock = std::chrono::steady_clock;

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double peak_rss_mib() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss / 1024.0;  // Linux: kilobytes
}

SceneParams full_scene(int particles) {
    SceneParams p;
    p.particles.count = particles;
    p.hopper.outlet = 4.5 * cm;
    p.hopper.theta = 60.0 * deg;
    p.material.collision_time = 8.0e-4;
    p.integrator.steps_per_collision = 50;
    p.integrator.scheme = Scheme::gear4;
    return p;
}

struct Sample {
    double ns_per_ps, forces, integration, neighbors, other;  // ns per particle-step
};

struct Row {
    std::string scene;
    std::vector<Sample> samples;
};

Sample median_sample(const std::vector<Sample>& s) {
    auto col = [&](double Sample::*f) {
        std::vector<double> v;
        for (const auto& x : s)
            v.push_back(x.*f);
        return median(v);
    };
    return {col(&Sample::ns_per_ps), col(&Sample::forces), col(&Sample::integration),
            col(&Sample::neighbors), col(&Sample::other)};
}

// Times `run` and splits its wall time by the System's phase timers.
template <class F>
Sample timed(System& s, double particle_steps_before, F&& run, double& particle_steps_after) {
    const PhaseSeconds p0 = s.phase_seconds();
    const auto t0 = Clock::now();
    run();
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const PhaseSeconds p1 = s.phase_seconds();
    const double ps = particle_steps_after - particle_steps_before;
    const double k = 1e9 / ps;
    const double f = (p1.forces - p0.forces) * k, i = (p1.integration - p0.integration) * k,
                 n = (p1.neighbors - p0.neighbors) * k;
    return {wall * k, f, i, n, wall * k - f - i - n};
}

void print(const Row& r) {
    const Sample m = median_sample(r.samples);
    std::printf("%-34s %8.1f %8.1f %8.1f %8.1f %8.1f   (median of %zu)\n", r.scene.c_str(),
                m.ns_per_ps, m.forces, m.integration, m.neighbors, m.other, r.samples.size());
}

// Whole realizations of a mid-size hopper with one setting changed: ns per particle-step.
double realization_ns(const SceneParams& p, std::uint64_t seed, double* wall = nullptr) {
    const RealizationResult r = run_realization(p, seed);
    if (r.status == Status::failed) std::fprintf(stderr, "  (failed: %s)\n", r.message.c_str());
    if (wall) *wall = r.diagnostics.wall_seconds;
    return r.diagnostics.ns_per_particle_step;
}

SceneParams mid_scene() {
    SceneParams p = full_scene(2000);
    p.hopper.width = 25.0 * cm;
    return p;
}

// The field observer's cost: whole mid-size realizations, the variants interleaved seed by seed
// (so that load changes on the shared machine hit them alike); medians over seeds. Two
// measures: the total ns per particle-step (noisy on a shared machine), and the observers' own
// time (wall time minus the System's force, integration and neighbour timers; the field
// sampling runs there), whose difference to "off" is the overhead proper.
int field_overhead(int repeats) {
    struct Variant {
        const char* name;
        SceneParams p;
        std::vector<double> ns, obs;
    };
    std::vector<Variant> v;
    v.push_back({"fields off", mid_scene(), {}, {}});
    {
        SceneParams p = mid_scene();
        p.fields.enabled = true;
        v.push_back({"cells 2 d_large, every 1 ms", p, {}, {}});
        p.fields.kernel = FieldKernel::gaussian;
        v.push_back({"Gaussian w = d_large, every 1 ms", p, {}, {}});
        p.fields.kernel = FieldKernel::cell;
        p.fields.sample_interval = 0.0;
        v.push_back({"cells 2 d_large, every step", p, {}, {}});
    }
    std::printf(
        "field observer overhead: 2000 particles, W = 25 cm, D = 4.5 cm, theta = 60 deg, "
        "whole realizations, %d seeds, variants interleaved\n",
        repeats);
    for (int r = 0; r < repeats; ++r)
        for (auto& x : v) {
            const RealizationResult res = run_realization(x.p, 200 + r);
            const auto& d = res.diagnostics;
            x.ns.push_back(d.ns_per_particle_step);
            x.obs.push_back(d.seconds_observers * 1e9 / d.particle_steps);
        }
    std::printf("  %-36s %10s %8s %12s %10s\n", "variant", "total ns", "ratio", "observers ns",
                "overhead");
    const double off = median(v[0].ns);
    for (const auto& x : v) {
        std::vector<double> diff;
        for (int r = 0; r < repeats; ++r)
            diff.push_back(x.obs[r] - v[0].obs[r]);
        std::printf("  %-36s %10.2f %8.3f %12.2f %+10.2f\n", x.name, median(x.ns),
                    median(x.ns) / off, median(x.obs), median(diff));
    }
    std::printf(
        "  (overhead = median over seeds of the observers' ns per particle-step minus that of "
        "\"fields off\")\n");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 5, steps = 2000, particles = 8750;
    bool skips = false, full_run = false, fields = false;
    std::string csv;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        auto next = [&]() -> std::string {
            if (a + 1 >= argc) {
                std::fprintf(stderr, "bench_engine: %s needs a value\n", arg.c_str());
                std::exit(2);
            }
            return argv[++a];
        };
        if (arg == "--repeats")
            repeats = std::stoi(next());
        else if (arg == "--steps")
            steps = std::stoi(next());
        else if (arg == "--particles")
            particles = std::stoi(next());
        else if (arg == "--skips")
            skips = true;
        else if (arg == "--full")
            full_run = true;
        else if (arg == "--fields")
            fields = true;
        else if (arg == "--csv")
            csv = next();
        else {
            std::fprintf(stderr,
                         "usage: bench_engine [--repeats R] [--steps K] [--particles N] [--full] "
                         "[--skips] [--fields] [--csv FILE]\n");
            return 2;
        }
    }

    if (fields) return field_overhead(repeats);

    std::printf(
        "hopper engine benchmark: %d particles, W = 43 cm, tau_c = 8e-4 s, delta = 50, "
        "gear4; medians of %d repeats\n",
        particles, repeats);
    const double rss0 = peak_rss_mib();
    Realization run(full_scene(particles), 1);
    System& sys = run.system();
    auto t0 = Clock::now();
    run.settle();
    const double settle_wall = std::chrono::duration<double>(Clock::now() - t0).count();
    if (run.finished()) {
        std::fprintf(stderr, "settling failed: %s\n", run.result().message.c_str());
        return 1;
    }
    std::printf("fill + settle: %.2f s simulated, %.1f s wall, %lld steps\n",
                run.result().diagnostics.settle_time, settle_wall,
                (long long)run.result().diagnostics.settle_steps);

    std::printf("\n%-34s %8s %8s %8s %8s %8s\n", "scene (ns per particle-step)", "total", "forces",
                "integr.", "neighb.", "other");
    std::vector<Row> rows;
    Row column{"settled column (gate closed)", {}};
    for (int r = 0; r < repeats; ++r) {
        const double n = sys.mobile_count();
        double after = n * steps;
        column.samples.push_back(timed(
            sys, 0.0, [&] { sys.run(steps); }, after));
    }
    print(column);
    rows.push_back(column);

    run.open();
    Row discharge{"discharge D=4.5 cm theta=60 deg", {}};
    for (int r = 0; r < repeats && !run.finished(); ++r) {
        const double before = run.result().diagnostics.particle_steps;
        double after = 0.0;
        Sample s = timed(
            sys, before,
            [&] {
                run.advance(0.5);
                after = run.result().diagnostics.particle_steps;
            },
            after);
        discharge.samples.push_back(s);
    }
    print(discharge);
    rows.push_back(discharge);
    std::printf(
        "(discharge repeats are consecutive 0.5 s windows from the opening: %d -> %d "
        "particles in the hopper)\n",
        particles, sys.mobile_count());
    if (full_run) {
        while (run.advance(5.0)) {
        }
        const RealizationResult full = run.result();
        std::printf(
            "\nfull realization D=4.5 cm theta=60 deg: status %s, empty time %.2f s, %lld "
            "steps, wall %.1f s (settle included), %.1f ns per particle-step overall\n",
            to_string(full.status).c_str(), full.empty_time.value_or(-1.0),
            (long long)full.diagnostics.steps, full.diagnostics.wall_seconds,
            full.diagnostics.ns_per_particle_step);
    }
    std::printf("peak memory (max RSS) of the process: %.1f MiB (%.1f MiB before the scene)\n",
                peak_rss_mib(), rss0);

    if (skips) {
        // What skipping is worth: whole mid-size realizations (2000 particles, W = 25 cm,
        // D = 4.5 cm, theta = 60 deg), medians over seeds, as ratios within this run.
        std::printf(
            "\nwhat each skip is worth (2000 particles, whole realizations, median ns "
            "per particle-step over %d seeds):\n",
            repeats);
        auto mid = mid_scene;
        struct Variant {
            const char* name;
            SceneParams p;
        };
        std::vector<Variant> variants;
        variants.push_back({"reference (k_t = 0.8 k_n, mu = 0.8)", mid()});
        {
            SceneParams p = mid();
            p.material.kt_over_kn = 0.0;
            variants.push_back({"k_t = 0 (no spring history)", p});
        }
        {
            SceneParams p = mid();
            p.material.system.mu = p.material.wall.mu = 0.0;
            variants.push_back({"mu = 0 (no tangential, no rotation)", p});
        }
        {
            SceneParams p = mid();
            p.integrator.scheme = Scheme::verlet;
            variants.push_back({"velocity Verlet instead of Gear", p});
        }
        {
            SceneParams p = mid();
            p.protocol.exit_depth = 60.0;  // particles fall 46 cm before they are removed
            variants.push_back({"removal 60 d_large below (not 4)", p});
        }
        double ref_ns = 0.0, ref_wall = 0.0;
        for (auto& v : variants) {
            std::vector<double> ns, wall;
            for (int r = 0; r < repeats; ++r) {
                double w = 0.0;
                ns.push_back(realization_ns(v.p, 100 + r, &w));
                wall.push_back(w);
            }
            const double m = median(ns), mw = median(wall);
            if (ref_ns == 0.0) {
                ref_ns = m;
                ref_wall = mw;
            }
            // Per particle-step and per realization: removal changes how many particles are
            // integrated, so only the wall time shows its whole worth.
            std::printf("  %-40s %7.1f ns (x %.2f)   %6.2f s per realization (x %.2f)\n", v.name, m,
                        m / ref_ns, mw, mw / ref_wall);
        }
    }

    if (!csv.empty()) {
        std::ofstream out(csv);
        out << "scene,repeat,ns_per_particle_step,forces,integration,neighbors,other\n";
        for (const auto& r : rows)
            for (std::size_t k = 0; k < r.samples.size(); ++k) {
                const auto& s = r.samples[k];
                out << '"' << r.scene << "\"," << k << ',' << s.ns_per_ps << ',' << s.forces << ','
                    << s.integration << ',' << s.neighbors << ',' << s.other << '\n';
            }
    }
    return 0;
}
