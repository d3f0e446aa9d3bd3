#pragma once
// The master: hands task ids to idle workers (dynamic dispatch, in the order given: longest
// expected first), stores every result as it arrives (the only writer of the store), retries
// failed attempts, reacts to stop requests, and prints a progress line at a steady interval.
//
// Silent workers: every busy worker sends a heartbeat while its realization advances. One silent
// for longer than the limit (a hung node, a stopped process) is reported and its realization is
// handed to another worker; the silent worker gets no new task until it speaks again. A late
// result of a reassigned realization is compared with the stored one (physics digest) and
// stored once: the first result to arrive is kept, a later one is only checked.
//
// Retry policy: an attempt that raises an exception (no result) is recorded in the store's
// failure log and handed out once more in the same run (max_attempts = 2 in all); if that fails
// too the task is left in state "error", shown by status, and retried by the next `campaign run`.
// A realization that ends with status failed is a result: the engine is deterministic, so the
// same seed would fail the same way again; it is stored with its reason and not retried.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "hopper/campaign/channel.hpp"
#include "hopper/campaign/checkpoints.hpp"
#include "hopper/campaign/signals.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

// One realization to run. The master holds one per task of the campaign (10^6 at scale: issue
// 44), so the point's label is shared by its tasks, not copied into each (48 instead of about
// 100 bytes with the label's own allocation).
struct TaskRef {
    TaskRef() = default;
    TaskRef(int id, std::shared_ptr<const std::string> point_label, int r, std::uint64_t s,
            double expected = 0.0, std::uint64_t physics_hash = 0)
        : task_id(id),
          realization(r),
          seed(s),
          expected_seconds(expected),
          physics(physics_hash),
          label_(std::move(point_label)) {}
    // A label of its own (tests).
    TaskRef(int id, const std::string& point_label, int r, std::uint64_t s, double expected = 0.0,
            std::uint64_t physics_hash = 0)
        : TaskRef(id, std::make_shared<const std::string>(point_label), r, s, expected,
                  physics_hash) {}

    const std::string& label() const { return *label_; }

    int task_id = 0;  // what travels to the worker
    int realization = 0;
    std::uint64_t seed = 0;
    double expected_seconds = 0.0;  // from the cost model (plan.hpp); 0: unknown
    std::uint64_t physics = 0;      // the point's physics hash (checkpoint files)

  private:
    std::shared_ptr<const std::string> label_ = std::make_shared<const std::string>();
};

struct MasterOptions {
    double progress_interval = 10.0;  // s of wall time between progress lines; 0 = none
    double grace = 60.0;              // s running tasks may take to finish after a drain request
    int max_attempts = 2;             // attempts per task and run when attempts raise exceptions
    // Fail fast: after this many realizations of one point failed the same way before their
    // outlet opened (the same message, numbers aside), no more tasks are handed out: the
    // scene itself fails (a setting in the wrong unit), not a seed. 0: never.
    int fail_fast_after = 3;
    std::chrono::milliseconds max_wait{250};  // longest sleep between looks at stop requests
    // Seconds a busy worker may stay silent (no heartbeat, no reply) before its realization is
    // handed to another worker. Unset: worker_timeout_factor times the realization's expected
    // duration, and at least min_worker_timeout.
    std::optional<double> worker_timeout;
    double worker_timeout_factor = 5.0;
    double min_worker_timeout = 300.0;
    // Checkpoint files (checkpoints.hpp; not owned): states of interrupted realizations are
    // written there, a task with a usable file resumes from it, the file of a stored result is
    // removed. Null: no checkpoints (an interrupted realization starts over).
    CheckpointFiles* checkpoints = nullptr;
    // Time-aware dispatch: seconds since 1970 by which the run must have ended. A task is handed
    // out only if its expected duration (the cost model times the measured correction below)
    // ends before deadline - grace; at deadline - grace running tasks are stopped (and
    // checkpointed). When nothing more fits, the run ends as stopped ("the deadline").
    std::optional<double> deadline;
    // Correction of the cost model: measured worker seconds per expected second of the
    // realizations stored so far in this campaign (updated with every result of this run).
    // Before anything is measured the cost model's own, pessimistic, seconds (factor 1).
    double measured_seconds = 0.0;
    double measured_expected = 0.0;
    // A small file beside the store naming the running realizations (running.hpp); empty: none.
    std::filesystem::path running_file;
};

struct MasterReport {
    int stored = 0;          // results stored by this run (any status)
    int failed = 0;          // of which with status failed
    int errors = 0;          // attempts that raised exceptions
    int gave_up = 0;         // tasks left in error after max_attempts
    int interrupted = 0;     // running tasks stopped early (they run again on resume)
    int not_started = 0;     // tasks never handed out because of a stop request
    int reassigned = 0;      // realizations handed to another worker after a silence
    int late_identical = 0;  // late results of reassigned realizations equal to the stored one
    int late_different = 0;  // ... that differ (the engine is deterministic: a bug or a bad node)
    int silent_at_end = 0;   // workers still silent when the run ended
    bool stopped = false;
    std::string stop_reason;
    // A stop was sent to running realizations (SIGTERM, a second signal, the end of a drain's
    // grace or the deadline), whether or not they ended before it reached them.
    bool stopped_running = false;
    // Set when the run stopped handing out tasks because of identical early failures
    // (MasterOptions::fail_fast_after): what failed, and how.
    std::string fail_fast;
    double wall_seconds = 0.0;
    double cpu_seconds = 0.0;  // CPU time of the master's thread
    // Worker seconds of interrupted realizations that no checkpoint keeps (they are computed
    // again), and those kept in checkpoints (continued later).
    double lost_worker_seconds = 0.0;
    double saved_worker_seconds = 0.0;
    int checkpoints_written = 0;
    int resumed = 0;           // tasks started from a checkpoint
    int deadline_skipped = 0;  // tasks not started because they would end after the deadline
};

// Adds one round's report to a run's (a target campaign runs Master::run once per round): the
// counts and seconds add up; the stop, its reason, the early failure and the workers silent at
// the end are the last round's, where it has them. Every field of MasterReport is handled here.
void add_round(MasterReport& run, const MasterReport& round);

// Counts of the sweep's tasks before this run, for the progress line.
struct Totals {
    int total = 0;     // tasks of the sweep
    int finished = 0;  // already stored (done or failed)
    int failed = 0;    // of which failed, plus tasks in error
};

class Master {
  public:
    Master(MasterChannel& channel, store::Store& store, const StopRequests& stop,
           MasterOptions options, std::ostream& log);
    // Runs `todo` to the end or until a stop request ends the run. Does not send quit.
    MasterReport run(const std::vector<TaskRef>& todo, Totals totals);

  private:
    MasterChannel& channel_;
    store::Store& store_;
    const StopRequests& stop_;
    MasterOptions options_;
    std::ostream& log_;
};

}  // namespace hopper::campaign
