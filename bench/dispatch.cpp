// Dispatch capacity of the campaign master: how many tasks per second one master can hand out
// and store (journal record fsync'd, HDF5 file updated) when the tasks themselves cost nothing.
// Divided into the realistic task length it tells how many workers one master can keep busy.
//
//   bench_dispatch [--tasks N] [--dir DIR] [--flush-interval S]            (worker threads: 1)
//   mpirun -np K --oversubscribe bench_dispatch [--tasks N] [--dir DIR]    (K-1 worker ranks)
//
// Every task returns the same fabricated result (seed set to the task's), of the size of a
// campaigns/tiny.toml realization: 6 survival intervals, 5 jams, 250 exit times, 300 discharge
// curve samples, 24 events. Prints tasks/s, the master's CPU share and the store's bytes per
// realization (HDF5 file and journal).

#include <chrono>
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

}  // namespace

int main(int argc, char** argv) {
    int tasks = 2000;
    fs::path dir = fs::temp_directory_path() / "hopper_bench_dispatch";
    double flush_interval = 1.0;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--tasks")
            tasks = std::stoi(argv[i + 1]);
        else if (a == "--dir")
            dir = argv[i + 1];
        else if (a == "--flush-interval")
            flush_interval = std::stod(argv[i + 1]);
        else {
            std::cerr << "usage: bench_dispatch [--tasks N] [--dir DIR] [--flush-interval S]\n";
            return 2;
        }
    }
    // Rank 0 writes the sweep file (atomically, named by the task count so that a stale one
    // is never read) and removes the previous store; the other ranks wait for the file.
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    const bool master = rank == nullptr || std::string(rank) == "0";
    const fs::path sweep = dir / ("dispatch-" + std::to_string(tasks) + ".toml");
    if (master) {
        fs::create_directories(dir);
        fs::remove(dir / "dispatch.h5");
        fs::remove(dir / "dispatch.h5.journal");
        const fs::path tmp = dir / "dispatch.toml.tmp";
        std::ofstream(tmp) << "[hopper]\nparticles = 250\nwidth_cm = 12\nD_cm = 3\ntheta_deg = "
                              "60\n[campaign]\nname = \"dispatch\"\nstore = \"dispatch.h5\"\n"
                              "realizations = "
                           << tasks << "\n";
        fs::rename(tmp, sweep);
    }
    campaign::RunOptions opt;
    opt.sweep = sweep;
    opt.master.progress_interval = 0;
    opt.store_options.flush_interval = flush_interval;
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
    const int rc = campaign::run_campaign(opt, table, log);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!master) return rc;
    if (rc != 0) {
        std::cerr << log.str();
        return rc;
    }
    const auto h5 = fs::file_size(dir / "dispatch.h5");
    const auto journal = fs::file_size(dir / "dispatch.h5.journal");
    std::string share = log.str();
    const auto at = share.find("master CPU ");
    share =
        at == std::string::npos ? "?" : share.substr(at + 11, share.find(' ', at + 11) - at - 11);
    std::cout << "dispatch: " << tasks << " trivial tasks in " << wall << " s = " << tasks / wall
              << " tasks/s (master CPU " << share << " of wall time); store " << h5 / tasks
              << " B/realization in HDF5 + " << journal / tasks << " B in the journal\n";
    return 0;
}
