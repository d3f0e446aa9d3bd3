// Where a realization's wall time goes (issue 41, part 1; docs/performance.md, "A published
// realization, phase by phase"):
//
//   bench_phases SWEEP.toml --D CM --theta DEG --seed N [--kernel PATH] [--interval S]
//
// Runs one realization of the sweep file's scene at (D, theta) with the engine alone (no store,
// no MPI) and splits its wall time by phase of the protocol: the fill (building the scene), the
// settling, the opening, the discharge while it flows, the shakes, and the result's assembly.
// Each phase's time is split again into the System's parts of a step (forces, integration,
// neighbour rebuilds: System::phase_seconds) and the rest (the protocol's observers: the jam
// detector, the removals, the discharge curve, re-insertion, the hook itself). The phases of
// the discharge are told apart by the progress hook, called every --interval seconds of
// simulated time (default 0.001 s: the discharge/shake boundary is placed within one interval).
// One JSON object on stdout.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "bench_args.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper;
using namespace hopper::engine;
using Clock = std::chrono::steady_clock;

namespace {

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(stderr,
                 "bench_phases: %s\nusage: bench_phases SWEEP.toml --D CM --theta DEG --seed N "
                 "[--kernel auto|reference|baseline|avx2|avx512|avx512-gather] [--interval S]\n",
                 why.c_str());
    std::exit(2);
}

double number(const std::string& opt, const char* text, double lo, double hi) {
    return bench::number(opt, text, lo, hi, usage);
}

struct Tally {
    double wall = 0, forces = 0, integration = 0, neighbors = 0;
    long steps = 0;
};

// The clocks now: wall time and the System's parts, and the step count.
struct Reading {
    Clock::time_point t;
    PhaseSeconds parts;
    double sim_time = 0;
};

Reading read(const System& s) {
    return {Clock::now(), s.phase_seconds(), s.time()};
}

void add(Tally& t, const Reading& a, const Reading& b, double dt) {
    t.wall += std::chrono::duration<double>(b.t - a.t).count();
    t.forces += b.parts.forces - a.parts.forces;
    t.integration += b.parts.integration - a.parts.integration;
    t.neighbors += b.parts.neighbors - a.parts.neighbors;
    t.steps += std::lround((b.sim_time - a.sim_time) / dt);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) usage("no sweep file");
    const std::string sweep = argv[1];
    double D = -1, theta = -1, interval = 1e-3;
    long long seed = -1;
    KernelPath kernel = KernelPath::automatic;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage(a + " needs a value");
        const char* v = argv[++i];
        if (a == "--D") {
            D = number("--D", v, 0.1, 100);
        } else if (a == "--theta") {
            theta = number("--theta", v, 0, 90);
        } else if (a == "--seed") {
            seed = static_cast<long long>(number("--seed", v, 0, 9e15));
        } else if (a == "--interval") {
            interval = number("--interval", v, 1e-6, 1);
        } else if (a == "--kernel") {
            try {
                kernel = parse_kernel_path(v);
            } catch (const std::exception& e) {
                usage(e.what());
            }
        } else {
            usage("unknown option " + a);
        }
    }
    if (D < 0 || theta < 0 || seed < 0) usage("--D, --theta and --seed are required");
    const SceneParams p = config::scene_at(config::load_sweep(sweep), D, theta);

    std::map<std::string, Tally> tally;
    RunHooks hooks;
    hooks.kernel = kernel;
    Realization* self = nullptr;
    Reading last{};
    Phase last_phase = Phase::settle;
    double dt = 0;
    hooks.progress_interval = interval;
    hooks.on_progress = [&](const Progress& pr) {
        if (!self) return;
        const Reading now = read(self->system());
        // The time since the last call belongs to the phase the last call saw (a change of
        // phase is placed at the call that first sees it).
        if (last_phase != Phase::settle)
            add(tally[std::string(to_string(last_phase))], last, now, dt);
        last = now;
        last_phase = pr.phase;
    };
    const auto t0 = Clock::now();
    Realization r(p, static_cast<std::uint64_t>(seed), hooks);
    self = &r;
    dt = r.system().dt();
    tally["fill"].wall = std::chrono::duration<double>(Clock::now() - t0).count();
    Reading a = read(r.system());
    r.settle();
    Reading b = read(r.system());
    add(tally["settle"], a, b, dt);
    r.open();
    Reading c = read(r.system());
    add(tally["open"], b, c, dt);
    last = c;
    last_phase = Phase::discharge;
    while (r.advance(1e9)) {
    }
    const Reading d = read(r.system());
    add(tally[std::string(to_string(last_phase))], last, d, dt);
    const RealizationResult res = r.result();
    tally["result"].wall = std::chrono::duration<double>(Clock::now() - d.t).count();
    const double total = std::chrono::duration<double>(Clock::now() - t0).count();

    const std::string empty = res.empty_time ? std::to_string(*res.empty_time) : "null";
    std::printf(
        "{\"sweep\": \"%s\", \"D_cm\": %g, \"theta_deg\": %g, \"seed\": %lld, "
        "\"force_path\": \"%s\", \"status\": \"%s\", \"particles\": %d, \"jams\": %d, "
        "\"shakes\": %d, \"empty_time_s\": %s, \"wall_s\": %.3f, \"phases\": {",
        sweep.c_str(), D, theta, seed, res.diagnostics.force_path.c_str(),
        to_string(res.status).c_str(), res.particles, res.n_jams, res.n_shakes, empty.c_str(),
        total);
    bool first = true;
    for (const char* name : {"fill", "settle", "open", "discharge", "shake", "result"}) {
        const Tally& t = tally[name];
        const double rest = t.wall - t.forces - t.integration - t.neighbors;
        std::printf(
            "%s\"%s\": {\"wall_s\": %.3f, \"share\": %.4f, \"steps\": %ld, "
            "\"forces_s\": %.3f, \"integration_s\": %.3f, \"neighbors_s\": %.3f, "
            "\"rest_s\": %.3f}",
            first ? "" : ", ", name, t.wall, t.wall / total, t.steps, t.forces, t.integration,
            t.neighbors, rest);
        first = false;
    }
    std::printf("}}\n");
    return res.status == Status::failed ? 1 : 0;
}
