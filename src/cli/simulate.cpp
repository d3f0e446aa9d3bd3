#include "cli/simulate.hpp"

#include <atomic>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "cli/result_output.hpp"
#include "cli/snapshot_writer.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/engine/realization.hpp"

namespace hopper::cli {

int run_simulate(const SimulateOptions& opt, std::ostream& out, std::ostream& err) {
    const config::SweepFile sweep = config::load_sweep(opt.sweep);
    const engine::SceneParams scene = config::scene_at(sweep, opt.D_cm, opt.theta_deg);

    engine::RunHooks hooks;
    // A failing snapshot write must not throw through the engine: remember it and stop the run.
    std::atomic<bool> stop{false};
    std::string snapshot_error;
    std::optional<SnapshotWriter> snapshots;
    if (opt.snapshot_dir) {
        try {
            snapshots.emplace(*opt.snapshot_dir, engine::derive_constants(scene).dt,
                              opt.snapshot_formats);
        } catch (const std::exception& e) {
            throw core::ConfigError("--snapshots: cannot use directory '" +
                                    opt.snapshot_dir->string() + "': " + e.what());
        }
        hooks.snapshot_interval = opt.snapshot_interval;
        hooks.on_snapshot = [&](const engine::Snapshot& s) {
            if (!snapshot_error.empty()) return;
            try {
                snapshots->write(s);
            } catch (const std::exception& e) {
                snapshot_error = e.what();
                stop = true;
            }
        };
        hooks.stop = &stop;
    }
    if (opt.progress) {
        hooks.progress_interval = opt.progress_interval;
        hooks.on_progress = [&err](const engine::Progress& p) {
            char line[160];
            std::snprintf(line, sizeof line,
                          "campaign: %-9s t_sim = %8.3f s  t_discharge = %8.3f s  in hopper = %d"
                          "  jams = %d\n",
                          std::string(engine::to_string(p.phase)).c_str(), p.sim_time,
                          p.discharge_time, p.in_hopper, p.n_jams);
            err << line << std::flush;
        };
    }

    const engine::RealizationResult result = engine::run_realization(scene, opt.seed, hooks);
    if (!snapshot_error.empty())
        throw std::runtime_error("snapshots stopped the run: " + snapshot_error);

    const RunRequest req{opt.sweep.string(), opt.D_cm, opt.theta_deg, opt.seed};
    if (opt.json) {
        out << result_json(req, result) << '\n';
    } else {
        write_summary(out, req, result);
        if (snapshots)
            out << "  snapshots             " << snapshots->frames_written() << " frames in "
                << snapshots->directory().string() << '\n';
    }
    out << std::flush;
    return result.status == engine::Status::failed ? exit_realization_failed : exit_ok;
}

}  // namespace hopper::cli
