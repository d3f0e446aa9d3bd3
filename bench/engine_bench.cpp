// Engine speed benchmark (issue 2): ns per particle-step on the two standard full-size scenes,
// per-phase breakdown, peak memory, and what each thing the engine skips is worth.
//
//   bench_engine [--repeats R] [--steps K] [--particles N] [--full] [--skips] [--fields]
//                [--csv FILE] [--scheme gear4|verlet] [--delta D] [--kernel PATH]
//                [--corrections] [--paths] [--fusion F] [--lammps RUN_SH [--core C]]
//
//   --corrections  integrator.contact_corrections on (docs/accuracy.md)
//   --skin S  integrator.skin (Verlet skin in units of d_small; default 0.4)
//   --kernel  force path: auto (default), reference, baseline, avx2, avx512, avx512-gather (same
//   bits)
//   --paths   every force path this CPU has, compared on one trajectory (CPU time per step)
//   --fusion  none (default), corrector or step: the integrator's passes around the force pass
//             (system.hpp, StepFusion; same bits)
//   --lammps  side by side with LAMMPS: ../shared/reference/lammps-hopper/run.sh and this
//             engine alternate on core C (default 0), R pairs per scene; prints the ratio table
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
#include <sched.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
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

// Set from the command line (--scheme, --delta, --corrections, --kernel).
Scheme g_scheme = Scheme::gear4;
double g_delta = 50.0;
double g_skin = -1.0;  // --skin: integrator.skin (units of d_small); < 0: the default
bool g_corrections = false;
StepFusion g_fusion = StepFusion::none;
KernelPath g_kernel = KernelPath::automatic;

SceneParams full_scene(int particles) {
    SceneParams p;
    p.particles.count = particles;
    p.hopper.outlet = 4.5 * cm;
    p.hopper.theta = 60.0 * deg;
    p.material.collision_time = 8.0e-4;
    p.integrator.steps_per_collision = g_delta;
    p.integrator.scheme = g_scheme;
    p.integrator.contact_corrections = g_corrections;
    if (g_skin >= 0.0) p.integrator.skin = g_skin;
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

double thread_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// --paths: the force paths compared on one trajectory (they give the same bits, so the scene is
// the same for all): blocks of `steps` steps per path, taken in turn, `repeats` rounds; per path
// the median over blocks of the per-step CPU time of the force phase... measured as whole steps
// (thread CPU time, so that time the process waits for the core does not count).
int compare_paths(Realization& run, int repeats, int steps, bool discharge) {
    System& sys = run.system();
    std::vector<KernelPath> paths{KernelPath::reference, KernelPath::baseline};
    for (KernelPath p : {KernelPath::avx2, KernelPath::avx512, KernelPath::avx512_gather}) {
        try {
            sys.set_kernel(p);
            paths.push_back(p);
        } catch (const std::exception&) {
        }
    }
    std::vector<std::vector<double>> ns(paths.size());
    if (discharge) run.open();
    for (int r = 0; r < repeats; ++r)
        for (std::size_t k = 0; k < paths.size(); ++k) {
            sys.set_kernel(paths[k]);
            const double n = sys.mobile_count();
            const double t0 = thread_cpu_seconds();
            if (discharge)
                run.advance(steps * sys.dt());
            else
                sys.run(steps);
            ns[k].push_back((thread_cpu_seconds() - t0) / (n * steps) * 1e9);
        }
    std::printf("%s: CPU ns per particle-step, median of %d blocks of %d steps per path\n",
                discharge ? "discharge" : "settled column", repeats, steps);
    const double np = std::max(1, sys.mobile_count());
    std::printf("  (per particle: %.2f list entries (mobile %.2f, wall %.2f), %.2f touching)\n",
                double(sys.pair_count() + sys.wall_pair_count()) / np, sys.pair_count() / np,
                sys.wall_pair_count() / np, sys.contact_count() / np);
    for (std::size_t k = 0; k < paths.size(); ++k)
        std::printf("  %-10s %7.1f  (x %.2f of reference)\n", to_string(paths[k]).c_str(),
                    median(ns[k]), median(ns[k]) / median(ns[0]));
    return 0;
}

// Runs LAMMPS's reference script (`run.sh SCENE STEPS`, CORE pinned) and returns its last line:
// ns per mobile particle-step of its loop; NaN (with the reason on stderr) if it failed.
double run_lammps(const std::string& script, const char* scene, int steps, int core) {
    const std::string cmd = "CORE=" + std::to_string(core) + " bash '" + script + "' " + scene +
                            " " + std::to_string(steps) + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return std::nan("");
    std::string last, all;
    char buf[512];
    while (std::fgets(buf, sizeof buf, pipe)) {
        all += buf;
        last = buf;
    }
    const int rc = pclose(pipe);
    char* end = nullptr;
    const double ns = std::strtod(last.c_str(), &end);
    if (rc != 0 || end == last.c_str()) {
        std::fprintf(stderr, "bench_engine: %s failed (exit %d):\n%s", cmd.c_str(), rc,
                     all.c_str());
        return std::nan("");
    }
    return ns;
}

// --lammps SCRIPT: hopper and LAMMPS side by side on one core (issue 12). The process pins itself
// to CORE (--core, default 0) and passes the same core to run.sh; the runs alternate LAMMPS,
// hopper, LAMMPS, hopper ... per scene, `repeats` pairs each, and the ratio is taken pair by pair
// (wall clock for both: LAMMPS reports its loop's wall time). Scenes: the settled column (LAMMPS
// `packed`, hopper `steps` steps with the gate closed) and the steady discharge (LAMMPS
// `discharge` from its opened state, hopper 0.5 s windows from the opening).
int side_by_side(const std::string& script, int particles, int repeats, int steps, int core,
                 const RunHooks& hooks) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(core, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0)
        std::fprintf(stderr, "bench_engine: could not pin to core %d; running unpinned\n", core);
    Realization run(full_scene(particles), 1, hooks);
    System& sys = run.system();
    std::printf("hopper: %s, delta %g, force path %s; LAMMPS: %s; core %d\n",
                to_string(g_scheme).c_str(), g_delta, to_string(sys.kernel_path()).c_str(),
                script.c_str(), core);
    run.settle();
    if (run.finished()) {
        std::fprintf(stderr, "settling failed: %s\n", run.result().message.c_str());
        return 1;
    }
    struct Scene {
        const char* name;
        const char* lammps;
        int lammps_steps;
        std::vector<double> lmp, ours, ratio;
    };
    Scene scenes[2] = {{"settled column", "packed", 5000, {}, {}, {}},
                       {"steady discharge", "discharge", 15000, {}, {}, {}}};
    for (int k = 0; k < 2; ++k) {
        Scene& sc = scenes[k];
        if (k == 1) run.open();
        for (int r = 0; r < repeats; ++r) {
            const double l = run_lammps(script, sc.lammps, sc.lammps_steps, core);
            if (std::isnan(l)) return 1;
            double ns;
            if (k == 0) {
                const double n = sys.mobile_count();
                const auto t0 = Clock::now();
                sys.run(steps);
                ns = std::chrono::duration<double>(Clock::now() - t0).count() / (n * steps) * 1e9;
            } else {
                const double ps0 = run.result().diagnostics.particle_steps;
                const auto t0 = Clock::now();
                run.advance(0.5);
                const double ps = run.result().diagnostics.particle_steps - ps0;
                ns = std::chrono::duration<double>(Clock::now() - t0).count() / ps * 1e9;
            }
            sc.lmp.push_back(l);
            sc.ours.push_back(ns);
            sc.ratio.push_back(l / ns);
            std::printf("  %-17s pair %d: LAMMPS %6.1f ns, hopper %6.1f ns, ratio %.2f\n", sc.name,
                        r + 1, l, ns, l / ns);
            std::fflush(stdout);
        }
    }
    std::printf(
        "\n| scene | LAMMPS (ns/particle-step) | hopper (%s, delta %g) | LAMMPS / hopper |\n",
        to_string(g_scheme).c_str(), g_delta);
    std::printf("|---|---|---|---|\n");
    for (const Scene& sc : scenes)
        std::printf("| %s | %.1f | %.1f | %.2fx |\n", sc.name, median(sc.lmp), median(sc.ours),
                    median(sc.ratio));
    std::printf("(medians of %d interleaved pairs; the ratio is the median of the pairs' ratios)\n",
                repeats);
    return 0;
}

int main(int argc, char** argv) {
    int repeats = 5, steps = 2000, particles = 8750;
    bool skips = false, full_run = false, fields = false, paths = false;
    std::string lammps;
    int core = 0;
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
        else if (arg == "--lammps")
            lammps = next();
        else if (arg == "--core")
            core = std::stoi(next());
        else if (arg == "--paths")
            paths = true;
        else if (arg == "--fusion")
            g_fusion = parse_step_fusion(next());
        else if (arg == "--kernel")
            g_kernel = parse_kernel_path(next());
        else if (arg == "--scheme")
            g_scheme = next() == "verlet" ? Scheme::verlet : Scheme::gear4;
        else if (arg == "--delta")
            g_delta = std::stod(next());
        else if (arg == "--skin")
            g_skin = std::stod(next());
        else if (arg == "--corrections")
            g_corrections = true;
        else {
            std::fprintf(
                stderr,
                "usage: bench_engine [--repeats R] [--steps K] [--particles N] [--full] "
                "[--skips] [--fields] [--csv FILE] [--scheme gear4|verlet] [--delta D] [--skin S] "
                "[--corrections] [--kernel auto|reference|baseline|avx2|avx512|avx512-gather] "
                "[--paths] "
                "[--fusion none|corrector|step] "
                "[--lammps RUN_SH [--core C]]\n");
            return 2;
        }
    }

    if (fields) return field_overhead(repeats);
    if (!lammps.empty()) {
        RunHooks hooks;
        hooks.kernel = g_kernel;
        return side_by_side(lammps, particles, repeats, steps, core, hooks);
    }

    std::printf(
        "hopper engine benchmark: %d particles, W = 43 cm, tau_c = 8e-4 s, delta = %g, "
        "%s%s; medians of %d repeats\n",
        particles, g_delta, to_string(g_scheme).c_str(),
        g_corrections ? " with the contact corrections" : "", repeats);
    const double rss0 = peak_rss_mib();
    RunHooks hooks;
    hooks.kernel = g_kernel;
    Realization run(full_scene(particles), 1, hooks);
    System& sys = run.system();
    sys.set_step_fusion(g_fusion);
    std::printf("force kernel: %s, step fusion: %s\n", to_string(sys.kernel_path()).c_str(),
                to_string(g_fusion).c_str());
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
    if (paths) {
        compare_paths(run, repeats, steps, false);
        return compare_paths(run, repeats, steps, true);
    }

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
