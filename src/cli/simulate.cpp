#include "cli/simulate.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/result_output.hpp"
#include "cli/scene_run.hpp"
#include "cli/snapshot_writer.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/store/store.hpp"
#include "hopper_version.h"  // HOPPER_VERSION, generated at build time (version.cmake)

namespace hopper::cli {

StoredTask stored_task(const std::filesystem::path& store_path, const std::string& label,
                       int realization) {
    const store::StoreStatus st = store::read_status(store_path);
    const store::PointPlan* p = st.plan.find(label);
    if (!p) {
        std::string labels;
        for (const auto& q : st.plan.points)
            labels += "\n  '" + q.label + "'";
        throw core::ConfigError("--point: no point '" + label + "' in " + store_path.string() +
                                "; its points are:" + labels);
    }
    if (realization < 0 || realization >= p->max_realizations())
        throw core::ConfigError("--realization " + std::to_string(realization) + ": point '" +
                                label + "' has realizations 0.." +
                                std::to_string(p->max_realizations() - 1));
    // A target campaign's plan lists the seeds of its rounds so far; later ones are derived
    // (the plan's typed settings are recorded with every plan that has a limit).
    const std::uint64_t seed = realization < p->realizations()
                                   ? p->seeds[static_cast<std::size_t>(realization)]
                                   : config::derive_seed(st.plan.seed, p->settings, realization);
    // The scene: rebuilt from the point's typed parameters, or for a store older than them from
    // the sweep texts the store recorded (campaign::point_scenes); either way its fingerprint is
    // the stored one, so the physics is the stored one.
    const std::size_t i = static_cast<std::size_t>(p - st.plan.points.data());
    std::optional<engine::SceneParams> scene = campaign::typed_scene(*p);
    std::string sweep_path = st.runs.empty() ? std::string() : st.runs.back().info.sweep_path;
    std::vector<core::Setting> written = p->parameters;
    if (!scene) {
        const auto recorded = campaign::recorded_points(
            st.plan, st.runs, [p](const store::PointPlan& q) { return &q == p; });
        if (recorded[i]) {
            scene = recorded[i]->point.scene;
            sweep_path = recorded[i]->sweep_path;
            written = recorded[i]->point.parameters;
        }
    }
    if (!scene)
        throw core::ConfigError("--point '" + label + "': neither its stored parameters nor the " +
                                std::to_string(st.runs.size()) +
                                " sweep file(s) recorded in the store give its stored physics with "
                                "this version of hopper");
    // The outlet and angle as the sweep file wrote them (typed parameters).
    const auto as_written = [&written](const char* name, double fallback) {
        for (const auto& s : written)
            if (s.name == name && std::holds_alternative<double>(s.value))
                return std::get<double>(s.value);
        return fallback;
    };
    std::vector<std::string> versions;
    for (const auto& r : st.runs)
        if (std::find(versions.begin(), versions.end(), r.info.code_version) == versions.end())
            versions.push_back(r.info.code_version);
    return {*scene,
            seed,
            as_written("D_cm", p->D_cm),
            as_written("theta_deg", p->theta_deg),
            sweep_path,
            std::move(versions)};
}

int run_simulate(const SimulateOptions& opt, std::ostream& out, std::ostream& err) {
    std::optional<StoredTask> stored;
    // The stored outcome the rerun is compared with, read before anything runs: a realization
    // not stored yet has nothing to compare with (issue 29, item 8).
    std::optional<engine::RealizationResult> before;
    if (opt.point) {
        stored = stored_task(*opt.store, *opt.point, opt.realization);
        for (auto& r : store::read_journal_realizations(*opt.store))
            if (r.label == *opt.point && r.record.realization == opt.realization)
                before = std::move(r.result);
        if (!before)
            throw core::ConfigError("--realization " + std::to_string(opt.realization) +
                                    ": realization " + std::to_string(opt.realization) + " of '" +
                                    *opt.point + "' is not stored yet in " + opt.store->string() +
                                    ", so there is nothing to rerun and compare with (`campaign "
                                    "status` lists what is done; `campaign run` stores it)");
    }
    // The scene and seed, and what the output echoes: a stored realization's, or the sweep's base
    // scene at --D and --theta as the Python module runs it too (scene_run.hpp).
    const SceneRun run = stored
                             ? SceneRun{stored->scene, RunRequest{stored->sweep_path, stored->D_cm,
                                                                  stored->theta_deg, stored->seed}}
                             : base_scene_run(config::load_sweep(opt.sweep), opt.sweep.string(),
                                              opt.D_cm, opt.theta_deg, opt.seed);
    const engine::SceneParams& scene = run.scene;

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
        // Wall-clock rate (simulated seconds per wall second) and, once particles leave, the
        // time left: the particles still in the hopper at the discharge rate seen so far in wall
        // time, at most what max_time leaves at the current rate.
        const auto wall_start = std::chrono::steady_clock::now();
        struct Since {
            double wall = -1.0, sim = 0.0;
            int in_hopper = 0;
        };
        auto opened = std::make_shared<Since>();
        const double max_time = scene.protocol.max_time;
        hooks.progress_interval = opt.progress_interval;
        hooks.on_progress = [&err, wall_start, opened, max_time](const engine::Progress& p) {
            const double wall =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start)
                    .count();
            const bool discharging = p.phase != engine::Phase::settle;
            if (discharging && opened->wall < 0) *opened = {wall, p.sim_time, p.in_hopper};
            std::string eta = "?";
            if (discharging && wall > opened->wall) {
                const double dw = wall - opened->wall;
                const int gone = opened->in_hopper - p.in_hopper;
                const double sim_rate = (p.sim_time - opened->sim) / dw;
                double left = sim_rate > 0 ? (max_time - p.discharge_time) / sim_rate : -1.0;
                if (gone > 0) {
                    const double by_flow = p.in_hopper * dw / gone;
                    left = left < 0 ? by_flow : std::min(left, by_flow);
                }
                if (left >= 0) eta = campaign::format_duration(left);
            }
            char line[200];
            std::snprintf(line, sizeof line,
                          "campaign: %-9s t_sim = %8.3f s  t_discharge = %8.3f s  in hopper = %d"
                          "  jams = %d  %.3g sim-s/s  elapsed %s  ETA %s\n",
                          std::string(engine::to_string(p.phase)).c_str(), p.sim_time,
                          p.discharge_time, p.in_hopper, p.n_jams,
                          wall > 0 ? p.sim_time / wall : 0.0,
                          campaign::format_duration(wall).c_str(), eta.c_str());
            err << line << std::flush;
        };
    }

    const engine::RealizationResult result = run_scene(run, hooks);
    if (!snapshot_error.empty())
        throw std::runtime_error("snapshots stopped the run: " + snapshot_error);

    const RunRequest& req = run.request;
    if (opt.json) {
        out << result_json(req, result) << '\n';
    } else {
        write_summary(out, req, result);
        if (snapshots)
            out << "  snapshots             " << snapshots->frames_written() << " frames in "
                << snapshots->directory().string() << '\n';
    }
    out << std::flush;
    if (stored) {
        // Bit for bit: the stored realization's outcomes must come out exactly.
        {
            const auto same_events = [](const auto& a, const auto& b) {
                if (a.size() != b.size()) return false;
                for (std::size_t i = 0; i < a.size(); ++i)
                    if (a[i].kind != b[i].kind || a[i].time != b[i].time ||
                        a[i].sim_time != b[i].sim_time || a[i].in_hopper != b[i].in_hopper)
                        return false;
                return true;
            };
            const bool same = before->status == result.status &&
                              before->survival_times == result.survival_times &&
                              before->censored == result.censored &&
                              before->jam_onsets == result.jam_onsets &&
                              before->exit_times == result.exit_times &&
                              before->curve_count == result.curve_count &&
                              same_events(before->events, result.events);
            if (!same) {
                err << "campaign: error: the run differs from the stored realization "
                    << opt.realization << " of '" << *opt.point << "'";
                std::string others;
                for (const auto& v : stored->code_versions)
                    if (v != HOPPER_VERSION) others += (others.empty() ? "" : ", ") + v;
                if (others.empty())
                    err << " (this version of hopper wrote the store: another machine's "
                           "arithmetic, or a fault; please report it)\n";
                else
                    err << ": the store was written by hopper " << others << ", this is "
                        << HOPPER_VERSION
                        << ". A version whose engine arithmetic differs (CHANGELOG names the "
                           "releases that changed it) reproduces a stored realization in "
                           "distribution, not bit for bit\n";
                return exit_error;
            }
            err << "campaign: identical to the stored realization (status, survival times, jam "
                   "onsets, exit times, discharge curve and events bit for bit)\n";
        }
    }
    return result.status == engine::Status::failed ? exit_realization_failed : exit_ok;
}

}  // namespace hopper::cli
