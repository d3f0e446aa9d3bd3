// Dispatch capacity of the campaign master, and the synthetic campaigns of the scale benchmark
// (issue 44, bench/scale.sh): how many results per second one master receives, stores (journal
// record fsync'd, HDF5 file updated) and hands out when the realizations themselves cost
// nothing. Divided into the realistic task length it tells how many workers one master can keep
// busy.
//
//   bench_dispatch [--tasks N] [--points P] [--threads T] [--dir DIR] [--flush-interval S]
//                  [--progress-interval S] [--keep] [--crash-after K]
//   mpirun -np K --oversubscribe bench_dispatch [...]   (K-1 worker ranks; --threads T: hybrid)
//
// N realizations over P points (N/P each; the points differ in D_cm and theta_deg). Without
// --keep the store DIR/dispatch.h5 is removed first; with it the run resumes the store there
// (journal replay, the HDF5 file caught up or rebuilt, the missing realizations run).
// --crash-after K: the master is killed (SIGKILL) in the middle of its K-th journal record, as
// `kill -9` would: an interrupted store for the resume benchmark.
//
// Every task returns the same fabricated result (seed set to the task's), of the size of a
// campaigns/tiny.toml realization: 6 survival intervals, 5 jams, 250 exit times, 300 discharge
// curve samples, 24 events. Prints one line: results per second, the master's CPU share and the
// store's bytes per realization (HDF5 file and journal).

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "hopper/campaign/mpi.hpp"
#include "hopper/campaign/run.hpp"

namespace fs = std::filesystem;
using namespace hopper;

namespace {

engine::RealizationResult canned() {
    engine::RealizationResult r;
    r.status = engine::Status::complete;
    r.particles = 250;
    r.wall_particles = 120;
    for (int i = 0; i < 6; ++i) {
        r.survival_times.push_back(0.37 * (i + 1));
        r.censored.push_back(i == 5);
    }
    for (int i = 0; i < 5; ++i) {
        r.jam_onsets.push_back(0.41 * (i + 1));
        r.shakes_per_jam.push_back(1 + i % 2);
    }
    r.n_jams = 5;
    r.n_shakes = 7;
    r.n_jams_multi_shake = 2;
    r.empty_time = 3.1;
    r.discharge_rate = 80.5;
    r.discharge_rate_mass = 0.011;
    r.discharged = 250;
    for (int i = 0; i < 250; ++i)
        r.exit_times.push_back(0.0123 * i);
    for (int i = 0; i < 300; ++i) {
        r.curve_time.push_back(0.01 * i);
        r.curve_count.push_back(250 - (i * 250) / 300);
    }
    for (int i = 0; i < 24; ++i)
        r.events.push_back({static_cast<engine::Event::Kind>(i % 8), 0.1 * i, 0.12 * i, 250 - i});
    r.diagnostics.steps = 400000;
    return r;
}

// A TOML array of n values first, first + step, ...
std::string values(int n, double first, double step) {
    std::string s = "[";
    char buf[32];
    for (int i = 0; i < n; ++i) {
        std::snprintf(buf, sizeof buf, "%s%.4f", i ? ", " : "", first + step * i);
        s += buf;
    }
    return s + "]";
}

// P points: D_cm (up to 100 values) x theta_deg (P / 100 values).
std::string sweep_text(int tasks, int points) {
    const int n_d = points < 100 ? points : 100;
    const int n_theta = points / n_d;
    std::ostringstream s;
    s << "[hopper]\nparticles = 250\nwidth_cm = 12\nD_cm = 3\ntheta_deg = 60\n"
      << "[campaign]\nname = \"dispatch\"\nstore = \"dispatch.h5\"\nrealizations = "
      << tasks / points << "\n";
    if (points > 1) {
        s << "[sweep]\nD_cm = " << values(n_d, 3.0, 0.01) << "\n";
        if (n_theta > 1) s << "theta_deg = " << values(n_theta, 45.0, 0.01) << "\n";
    }
    return s.str();
}

}  // namespace

int main(int argc, char** argv) {
    int tasks = 2000, points = 1, threads = 1, crash_after = 0;
    double progress_interval = 0.0;
    bool keep = false;
    fs::path dir = fs::temp_directory_path() / "hopper_bench_dispatch";
    double flush_interval = 1.0;
    const char* usage =
        "usage: bench_dispatch [--tasks N] [--points P] [--threads T] [--dir DIR] "
        "[--flush-interval S] [--progress-interval S] [--keep] [--crash-after K]\n";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--keep") {
            keep = true;
            continue;
        }
        if (i + 1 >= argc) {
            std::cerr << usage;
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--tasks")
            tasks = std::stoi(v);
        else if (a == "--points")
            points = std::stoi(v);
        else if (a == "--threads")
            threads = std::stoi(v);
        else if (a == "--dir")
            dir = v;
        else if (a == "--flush-interval")
            flush_interval = std::stod(v);
        else if (a == "--progress-interval")
            progress_interval = std::stod(v);
        else if (a == "--crash-after")
            crash_after = std::stoi(v);
        else {
            std::cerr << usage;
            return 2;
        }
    }
    if (points < 1 || tasks < points || tasks % points != 0 || (points > 100 && points % 100)) {
        std::cerr << "bench_dispatch: --tasks must be a multiple of --points, and --points at "
                     "most 100 or a multiple of 100\n";
        return 2;
    }
    // Rank 0 writes the sweep file (atomically, named by the task and point counts so that a
    // stale one is never read) and, unless resuming, removes the previous store; the other
    // ranks wait for the file.
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    const bool master = rank == nullptr || std::string(rank) == "0";
    const fs::path sweep =
        dir / ("dispatch-" + std::to_string(tasks) + "-" + std::to_string(points) + ".toml");
    const fs::path store = dir / "dispatch.h5";
    const fs::path journal = dir / "dispatch.h5.journal";
    if (master) {
        fs::create_directories(dir);
        if (!keep) {
            fs::remove(store);
            fs::remove(journal);
            fs::remove_all(dir / "dispatch.h5.checkpoints");
        }
        const fs::path tmp = dir / "dispatch.toml.tmp";
        std::ofstream(tmp) << sweep_text(tasks, points);
        fs::rename(tmp, sweep);
    }
    campaign::RunOptions opt;
    opt.sweep = sweep;
    opt.threads = threads;
    opt.threads_given = threads > 1;
    opt.master.progress_interval = progress_interval;
    opt.store_options.flush_interval = flush_interval;
    if (crash_after > 0) {
        opt.store_options.crash_point = "journal";
        opt.store_options.crash_after = crash_after + 1;  // the run-start record is the first
    }
    opt.code_version = "bench";
    const engine::RealizationResult result = canned();
    opt.runner = [&result](const config::Task& t, const engine::SceneParams&,
                           const engine::RunHooks&) {
        engine::RealizationResult r = result;
        r.seed = t.seed;
        return r;
    };
    if (!master) {
        // Wait for rank 0's sweep file (the same machine in practice).
        for (int i = 0; i < 200 && !fs::exists(sweep); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::ostringstream table, log;
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = campaign::run_campaign(opt, table, progress_interval > 0 ? std::cerr : log);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!master) return rc;
    if (rc != 0) {
        std::cerr << log.str();
        return rc;
    }
    // "N to run" from the run's first line: what this run stored.
    const std::string text = log.str();
    int ran = tasks;
    if (const auto at = text.find(" to run on "); at != std::string::npos) {
        const auto from = text.rfind(", ", at);
        ran = std::stoi(text.substr(from + 2, at - from - 2));
    }
    const auto h5 = fs::file_size(store);
    const auto jbytes = fs::file_size(journal);
    std::string share = "?";
    if (const auto at = text.find("master CPU "); at != std::string::npos)
        share = text.substr(at + 11, text.find(' ', at + 11) - at - 11);
    std::cout << "dispatch: " << ran << " of " << tasks << " results (" << points << " points) in "
              << wall << " s = " << (wall > 0 ? ran / wall : 0.0) << " results/s (master CPU "
              << share << " of wall time); store " << h5 / tasks << " B/realization in HDF5 + "
              << jbytes / tasks << " B in the journal\n";
    return 0;
}
