#pragma once
// The end of `campaign run`: what the sweep still lacks, the run's verdict, the store's end
// record, the summary table and the closing lines (what happened, how to go on).

#include <filesystem>
#include <ostream>
#include <string>

#include "hopper/campaign/master.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

// The sweep's realizations (those allotted so far, for a target campaign) after a run.
struct Outcome {
    int left = 0;    // still pending
    int failed = 0;  // stored as failed, or left in error
};

Outcome count_outcome(const store::Store& st, const config::CampaignSpec& spec,
                      const config::TaskList& tasks);

enum class Ending {
    complete,       // nothing left to run (failed realizations aside)
    interrupted,    // stopped by a signal, a deadline or a lost worker: resume
    stopped_early,  // identical early failures: the scene fails, not a seed
    with_failures,  // complete, with failed realizations
};

// The verdict. A stop that stopped nothing is no stop: a drain signal (SIGUSR1) that came after
// the last realization was handed out, which then finished, leaves a complete run. A stop sent to
// running realizations (SIGTERM, the end of a drain's grace, the deadline) stays a stop even when
// they ended first, and so does any stop of a campaign with a target (its rounds decide what is
// due).
Ending ending_of(const MasterReport& rep, const Outcome& o, bool has_target);

struct RunEndContext {
    std::filesystem::path store_path;
    std::string resume_command;  // printed when the run was interrupted
    int total = 0;               // realizations of the sweep (allotted so far with a target)
    bool has_target = false;
};

// Records the run's end in the store, writes the summary table on `out` and the closing lines on
// `err`; returns the exit code (run.hpp: run_ok, run_with_failures, run_stopped).
int finish_run(store::Store& st, const config::CampaignSpec& spec, const config::TaskList& tasks,
               const MasterReport& rep, const RunEndContext& ctx, std::ostream& out,
               std::ostream& err);

}  // namespace hopper::campaign
