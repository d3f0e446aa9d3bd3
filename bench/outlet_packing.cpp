// The packing over the outlet: settled fill against steady flow (issue 39, part 3: why does
// refilling the silo after every clog give the same avalanches as removing the arch?).
//
//   bench_outlet_packing [--D-over-d X] [--seeds N] [--first S] [--flow-s T] [--radius R]
//                        [--collision-time S] [--dump-opening FILE]
//
// The flat silo of campaigns/silo-validation (800 monodisperse disks, d = 0.77 cm, W = 25 d,
// e_n 0.2, mu 0.5, arch removal, steady state). Per seed: the area fraction phi of the disks
// whose centres lie within R d (default 2.5) of the outlet's centre above the outlet plane
// (a half disk; each disk counts whole: the same estimator everywhere, so its edge bias cancels
// in the comparison), and the mean speed there:
//   - at the opening (the settled fill, what a refill realization starts from),
//   - sampled every 1e-3 s while the silo flows (discharge phase, a sample counting while
//     the region below the outlet holds a disk) over T seconds of discharge (default 20):
//     the steady state's mean,
//   - in the last sample before each clog's onset is detected (the region empty: the arch
//     has formed; phi there is the arch's own packing), reported as a mean.
// One JSON line per seed on stdout.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_args.hpp"
#include "hopper/core/units.hpp"
#include "hopper/engine/realization.hpp"

using namespace hopper;
using namespace hopper::engine;

namespace {

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(stderr,
                 "bench_outlet_packing: %s\nusage: bench_outlet_packing [--D-over-d X] "
                 "[--seeds N] [--first S] [--flow-s T] [--radius R] [--collision-time S]\n",
                 why.c_str());
    std::exit(2);
}

double number(const std::string& opt, const char* text, double lo, double hi) {
    return bench::number(opt, text, lo, hi, usage);
}

struct Region {
    double R;  // m
    double phi = 0, speed = 0;
    int n = 0;
    void measure(const Snapshot& s) {
        double area = 0, v = 0;
        n = 0;
        for (std::size_t i = 0; i < s.x.size(); ++i) {
            if (s.y[i] < 0 || s.x[i] * s.x[i] + s.y[i] * s.y[i] > R * R) continue;
            area += core::pi * s.radius[i] * s.radius[i];
            v += std::hypot(s.vx[i], s.vy[i]);
            ++n;
        }
        phi = area / (0.5 * core::pi * R * R);
        speed = n ? v / n : 0.0;
    }
};

}  // namespace

int main(int argc, char** argv) {
    double D_over_d = 3.0, flow_s = 20.0, radius = 2.5, collision_time = -1;
    std::string dump;  // --dump-opening FILE: x y r of every disk at the opening (first seed)
    int seeds = 8, first = 1;
    for (int k = 1; k < argc; k += 2) {
        const std::string o = argv[k];
        if (k + 1 >= argc) usage(o + " needs a value");
        if (o == "--D-over-d")
            D_over_d = number(o, argv[k + 1], 1.0, 20.0);
        else if (o == "--seeds")
            seeds = int(number(o, argv[k + 1], 1, 1e6));
        else if (o == "--first")
            first = int(number(o, argv[k + 1], 0, 1e9));
        else if (o == "--flow-s")
            flow_s = number(o, argv[k + 1], 0.01, 1e6);
        else if (o == "--radius")
            radius = number(o, argv[k + 1], 0.5, 20);
        else if (o == "--collision-time")
            collision_time = number(o, argv[k + 1], 1e-9, 1.0);
        else if (o == "--dump-opening")
            dump = argv[k + 1];
        else
            usage("unknown option " + o);
    }
    SceneParams p;
    const double d = 0.770 * cm;
    p.hopper.width = 19.25 * cm;
    p.hopper.theta = 0.0;
    p.hopper.outlet = D_over_d * d;
    p.particles.count = 800;
    p.particles.small_fraction = 0.0;
    p.material.system = {0.2, 0.5};
    p.material.wall = {0.2, 0.5};
    if (collision_time > 0) p.material.collision_time = collision_time;
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.unjam = UnjamMode::remove_arch;
    p.protocol.jams_per_realization = 1000000;
    p.protocol.max_time = flow_s;
    for (int seed = first; seed < first + seeds; ++seed) {
        Region now{radius * d};
        double phi_open = -1, speed_open = 0, sum_phi = 0, sum_speed = 0;
        long samples = 0;
        int jams_seen = 0, before_n = 0;
        double before_phi = 0, last_flow_phi = 0;
        bool was_empty = false;
        RunHooks hooks;
        hooks.snapshot_interval = 1e-3;
        hooks.on_snapshot = [&](const Snapshot& s) {
            if (s.phase != Phase::discharge) return;
            now.measure(s);
            if (phi_open < 0) {
                if (!dump.empty() && seed == first) {
                    FILE* f = std::fopen(dump.c_str(), "w");
                    if (!f) usage("--dump-opening: cannot write " + dump);
                    for (std::size_t i = 0; i < s.x.size(); ++i)
                        std::fprintf(f, "%.6g %.6g %.6g\n", s.x[i], s.y[i], s.radius[i]);
                    for (std::size_t i = 0; i < s.wall_x.size(); ++i)
                        std::fprintf(f, "%.6g %.6g %.6g w\n", s.wall_x[i], s.wall_y[i],
                                     s.wall_radius[i]);
                    std::fclose(f);
                }
                phi_open = now.phi;
                speed_open = now.speed;
                return;
            }
            // the region just below the outlet: empty means the flow has stopped (an arch)
            bool empty = true;
            for (std::size_t i = 0; i < s.y.size() && empty; ++i)
                if (s.y[i] < 0 && s.y[i] > -2 * d && std::abs(s.x[i]) < 0.5 * p.hopper.outlet)
                    empty = false;
            if (!empty) {  // flowing
                sum_phi += now.phi;
                sum_speed += now.speed;
                ++samples;
            }
            if (empty && !was_empty) {
                before_phi += last_flow_phi;
                ++before_n;
            }
            was_empty = empty;
            if (!empty) last_flow_phi = now.phi;
        };
        const RealizationResult r = run_realization(p, std::uint64_t(seed), hooks);
        jams_seen = r.n_jams;
        std::printf(
            "{\"seed\": %d, \"D_over_d\": %.4g, \"radius_d\": %.3g, \"phi_at_opening\": %.4f, "
            "\"speed_at_opening_m_s\": %.3g, \"phi_flowing\": %.4f, \"speed_flowing_m_s\": %.4f, "
            "\"samples\": %ld, \"jams\": %d, \"phi_before_flow_stops\": %.4f, \"stops\": %d}\n",
            seed, D_over_d, radius, phi_open, speed_open, samples ? sum_phi / samples : 0.0,
            samples ? sum_speed / samples : 0.0, samples, jams_seen,
            before_n ? before_phi / before_n : 0.0, before_n);
        std::fflush(stdout);
    }
    return 0;
}
