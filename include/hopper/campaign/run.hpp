#pragma once
// `campaign run`: runs or resumes the campaign of a sweep file. Under an MPI launcher, rank 0 is
// the master and every other rank a worker; without one, a single process runs a master and
// worker threads (one by default). The master opens the store (creating it, or resuming it after
// checking that the physics agrees), hands out the missing realizations, stores each result as
// it arrives, and prints the summary table at the end.

#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>

#include "hopper/campaign/master.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

// Exit codes of `campaign run` beyond 0 (everything stored) and those of the cli.
enum RunExit : int {
    run_ok = 0,
    run_with_failures = 3,  // finished, but some realizations failed (see the table / status)
    run_stopped = 4,        // stopped by a signal; run the same command again to resume
};

struct RunOptions {
    std::filesystem::path sweep;
    std::optional<std::filesystem::path> store;  // default: the sweep's [campaign] store
    MasterOptions master;
    store::StoreOptions store_options;
    int threads = 1;  // worker threads in a single-process run (ignored under MPI)
    bool threads_given = false;
    // Accept new points whose unvaried settings differ from stored points' (mixing.hpp); by
    // default such a sweep is refused.
    bool allow_mixed = false;  // --threads was on the command line: say so when MPI ignores it
    // Checkpoints inside a realization (checkpoints.hpp): on by default; the running states are
    // also saved every checkpoint_interval seconds of wall time (0: only when stopped).
    bool checkpoints = true;
    double checkpoint_interval = 600.0;
    // A realization running each of the last max_deaths times the job died (killed: the OOM
    // killer, a crash, a lost node) is set aside instead of handed out again; 0: no limit.
    int max_deaths = 3;
    // --dry-run: list what would run and its estimated core-hours; touch nothing.
    bool dry_run = false;
    // Called on the master only: the deadline (s since 1970) by which the run must end, or
    // none (MasterOptions::deadline); it may write notes to the stream. Unset: no deadline.
    std::function<std::optional<double>(std::ostream& err)> deadline;
    std::string code_version = "unknown";
    std::string command_line;
    // The command that resumes this run, printed when a signal stops it: the same arguments,
    // shell-quoted. Empty: the sweep file and --store only.
    std::string resume_command;
    // One realization (default: engine::run_realization(scene, task.seed, hooks)). Benchmarks
    // and tests replace it.
    std::function<engine::RealizationResult(const config::Task&, const engine::SceneParams&,
                                            const engine::RunHooks&)>
        runner;
    // Called on the master only, after the run has ended and the store is closed and unlocked,
    // with the store's path and the exit code; returns the exit code. `campaign run` analyzes
    // the store here (the campaign layer knows nothing of the statistics).
    std::function<int(const std::filesystem::path& store, int code)> after_run;
};

// Returns the exit code (RunExit). The summary table goes to `out`, progress and notes to `err`.
// Throws core::ConfigError (bad sweep file, physics differing from the store's) and
// core::StoreError (store cannot be used); under MPI only rank 0 throws, other ranks return.
int run_campaign(const RunOptions& options, std::ostream& out, std::ostream& err);

// `campaign run --dry-run`: the realizations the sweep would run on its store (none is
// started, the store is not opened for writing) and their estimated cost per point and in all,
// from the cost model (expected_cost) at the worker seconds per particle-step measured on the
// store's stored realizations, or at the prior speed (plan.hpp) when nothing is measured yet.
// Throws like run_campaign when the sweep cannot run on the store. Returns 0.
// What a dry run estimated: the worker seconds of everything still to run, and of its longest
// realization.
struct DryRunTotals {
    double worker_seconds = 0.0;
    double longest_seconds = 0.0;
    int realizations = 0;
};
int dry_run(const RunOptions& options, std::ostream& out, std::ostream& err,
            DryRunTotals* totals = nullptr);

// The compiler that built this code ("gcc 12.2.0"), for provenance.
std::string compiler_id();

}  // namespace hopper::campaign
