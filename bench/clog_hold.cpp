// Does a real clog hold by itself? (issue 39, part 1; docs/validation.md, "Statics".)
//
//   bench_clog_hold [--D-over-d X] [--seeds N] [--first S] [--hold-windows K]
//                   [--collision-time S] [--max-time S] [--mu-r X] [--rolling-law L]
//
// The flat silo of campaigns/silo-validation (800 monodisperse disks of d = 0.77 cm, W = 25 d,
// theta = 0, e_n = 0.2, mu = 0.5, steady state) run to its first clog (the refill protocol ends
// a realization there: the region below the outlet has been empty for t_check). The packing is
// then left alone, no arch removed, no shake, for K clog windows (K t_check of simulated time,
// default 10), and watched: does any disk fall through the outlet (the clog breaks by itself),
// how far the disks move (all of them: the re-inserted ones may still be landing; and those
// within 3 d of the outlet's centre: the arch and what rests on it), how fast they are at the
// end. One line per seed (JSON) on stdout.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper;
using namespace hopper::engine;

namespace {

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(stderr,
                 "bench_clog_hold: %s\nusage: bench_clog_hold [--D-over-d X] [--seeds N] "
                 "[--first S] [--hold-windows K] [--collision-time S] [--max-time S] [--mu-r X] "
                 "[--rolling-law constant|spring]\n",
                 why.c_str());
    std::exit(2);
}

double number(const std::string& opt, const char* text, double lo, double hi) {
    return bench::number(opt, text, lo, hi, usage);
}

SceneParams silo(double D_over_d, double collision_time, double max_time, double mu_r,
                 RollingLaw rolling_law) {
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
    p.material.mu_r = mu_r;  // rolling resistance (docs/model.md): the silo of issue 39, part 4
    p.material.rolling_law = rolling_law;
    p.protocol.mode = ProtocolMode::steady_state;
    p.protocol.unjam = UnjamMode::refill;
    p.protocol.jams_per_realization = 1;
    p.protocol.max_time = max_time;
    return p;
}

}  // namespace

int main(int argc, char** argv) {
    double D_over_d = 3.5, collision_time = -1, max_time = 300, windows = 10, mu_r = 0;
    RollingLaw rolling_law = RollingLaw::constant;
    int seeds = 8, first = 1;
    for (int k = 1; k < argc; k += 2) {
        const std::string o = argv[k];
        if (k + 1 >= argc) usage(o + " needs a value");
        if (o == "--D-over-d")
            D_over_d = number("--D-over-d", argv[k + 1], 1.0, 20.0);
        else if (o == "--seeds")
            seeds = int(number("--seeds", argv[k + 1], 1, 1e6));
        else if (o == "--first")
            first = int(number("--first", argv[k + 1], 0, 1e9));
        else if (o == "--hold-windows")
            windows = number("--hold-windows", argv[k + 1], 0.1, 1e5);
        else if (o == "--collision-time")
            collision_time = number("--collision-time", argv[k + 1], 1e-9, 1.0);
        else if (o == "--max-time")
            max_time = number("--max-time", argv[k + 1], 0.1, 1e7);
        else if (o == "--mu-r")
            mu_r = number("--mu-r", argv[k + 1], 0.0, 1.0);
        else if (o == "--rolling-law") {
            const std::string l = argv[k + 1];
            if (l != "constant" && l != "spring")
                usage("--rolling-law '" + l + "': expected constant or spring");
            rolling_law = l == "spring" ? RollingLaw::spring : RollingLaw::constant;
        } else
            usage("unknown option " + o);
    }
    const SceneParams p = silo(D_over_d, collision_time, max_time, mu_r, rolling_law);
    validate_scene(p);
    const double d = p.particles.d_large, g = p.gravity;
    const double t_check = 2.0 * std::sqrt(d / g);
    const double half = 0.5 * p.hopper.outlet;
    for (int seed = first; seed < first + seeds; ++seed) {
        Realization r(p, std::uint64_t(seed));
        r.settle();
        r.open();
        while (r.advance(1.0)) {
        }
        const RealizationResult res = r.result();
        if (res.n_jams < 1) {
            std::printf("{\"seed\": %d, \"clogged\": false, \"status\": \"%s\"}\n", seed,
                        to_string(res.status).c_str());
            continue;
        }
        System& s = r.system();
        s.take_removals();
        const int n = s.mobile_count();
        std::vector<int> ids(static_cast<std::size_t>(n));
        std::vector<Vec2> p0(static_cast<std::size_t>(n));
        for (int i = 0; i < n; ++i) {
            ids[std::size_t(i)] = s.id(i);
            p0[std::size_t(i)] = s.position(i);
        }
        const auto steps = std::int64_t(std::llround(windows * t_check / s.dt()));
        int below = 0;  // disks seen in the outlet's mouth (below y = 0 within the outlet)
        double t_first_below = -1.0;
        const double t0 = s.time();
        for (std::int64_t k = 0; k < steps; ++k) {
            s.step();
            if (k % 20 == 0) {
                int now = 0;
                for (int i = 0; i < s.mobile_count(); ++i)
                    if (s.position(i).y() < 0.0 && std::abs(s.position(i).x()) < half) ++now;
                below = std::max(below, now);
                if (now > 0 && t_first_below < 0) t_first_below = s.time() - t0;
            }
        }
        const auto gone = s.take_removals();
        // The arch's neighbourhood: disks that started within 3 d of the outlet's centre.
        double creep = 0.0, creep_near = 0.0, v_end = 0.0, v_near = 0.0;
        for (int k = 0; k < n; ++k) {
            const int i = s.index_of(ids[std::size_t(k)]);
            if (i < 0) continue;
            const double moved = (s.position(i) - p0[std::size_t(k)]).norm();
            creep = std::max(creep, moved);
            v_end = std::max(v_end, s.velocity(i).norm());
            if (p0[std::size_t(k)].norm() < 3.0 * d) {
                creep_near = std::max(creep_near, moved);
                v_near = std::max(v_near, s.velocity(i).norm());
            }
        }
        std::printf(
            "{\"seed\": %d, \"clogged\": true, \"D_over_d\": %.4g, \"clog_at_s\": %.4f, "
            "\"hold_s\": %.4f, \"t_check_s\": %.4f, \"fell_through\": %zu, "
            "\"most_in_mouth\": %d, \"first_in_mouth_s\": %.4f, \"largest_move_d\": %.4g, "
            "\"largest_speed_end_m_s\": %.3g, \"near_outlet_largest_move_d\": %.4g, "
            "\"near_outlet_speed_end_m_s\": %.3g}\n",
            seed, D_over_d, res.survival_times.empty() ? 0.0 : res.survival_times.back(),
            windows * t_check, t_check, gone.size(), below, t_first_below, creep / d, v_end,
            creep_near / d, v_near);
        std::fflush(stdout);
    }
    return 0;
}
