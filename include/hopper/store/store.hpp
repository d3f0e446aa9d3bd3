#pragma once
// The campaign store: one HDF5 file (STORE.h5) and its journal (STORE.h5.journal).
//
// The journal (journal.hpp) is the source of truth: every record is fsync'd before the master
// counts its realization as done. The HDF5 file is a self-describing view of the journal
// (layout in the README, "Campaigns and the store"), updated as realizations arrive and closed in
// step with the journal at the end of every run (a sync record names it). At the next open, a file
// that is not in step
// -- the writer was killed, the file is damaged or missing -- is rebuilt from the journal into a
// temporary file and renamed into place, so a kill -9 at any moment loses nothing that was
// counted as done and never leaves a corrupt store behind once `campaign run` has run again.
//
// Only the master writes (Store). Readers use read_status() (the journal, without locks: it works
// while a run is writing), write_snapshot() (a closed copy of the store as it stands, also while
// a run writes it) or read_realizations() (the HDF5 file, for analysis).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hopper/engine/result.hpp"
#include "hopper/store/analysis.hpp"
#include "hopper/store/records.hpp"

namespace hopper::store {

// The journal beside a store file: "<store>.journal".
std::filesystem::path journal_path(const std::filesystem::path& store);

// Where a task stands.
//   done:    a result whose status is complete, arrested or time_limit
//   failed:  a result whose status is failed (the engine is deterministic, so running it again
//            gives the same failure: it is final and shown, not retried)
//   error:   attempts ended in an exception and no result exists; the next run retries it
//   pending: nothing yet
enum class TaskState : std::uint8_t { pending = 0, done = 1, failed = 2, error = 3 };
std::string to_string(TaskState s);

// What the summary tables need from a stored result. One per realization of the campaign, held
// for the whole run (10^6 of them at scale: issue 44), so it holds numbers only; the message of
// a failed result and the reason of the last exception are kept beside the tasks, in the
// store's state, since few tasks have one (State::messages).
struct ResultSummary {
    double survival_sum = 0.0;  // s, all intervals, censored included
    double task_seconds = 0.0;
    std::optional<double> empty_time;
    int n_jams = 0;
    int n_intervals = 0;
    int n_uncensored = 0;
    int rank = 0;
    engine::Status status = engine::Status::failed;
};

struct TaskEntry {
    std::int64_t row = -1;  // row in /realizations
    std::optional<ResultSummary> result;
    int errors = 0;  // attempts that ended in an exception
    TaskState state = TaskState::pending;
    // Runs that died (no run-end record: their processes were killed) while this realization
    // was running on a worker (DispatchRecord), saturating at 255. A realization that kills its
    // worker (the kernel's OOM killer under a memory limit) dies with every run that hands it
    // out; `campaign run --max-deaths` sets such a one aside (issue 44).
    std::uint8_t deaths = 0;
};

struct PointStatus {
    std::string label;
    int planned = 0;  // allotted so far (a target campaign: to the end of its current round)
    int limit = 0;    // the most it may have (max_realizations with a target, else planned)
    int done = 0;
    int failed = 0;  // failed results plus tasks in error
    int errors = 0;  // of which in error (retried by the next run)
    int pending = 0;
    int extra = 0;  // stored realizations beyond the plan: those beyond read_status's counts
                    // (a lowered sweep); otherwise none from a journal the master wrote,
                    // counted rather than dropped
    // Planned by an earlier run but beyond the count of the last run's sweep, which lowered it:
    // neither planned nor pending here (read_status's counts; the plan itself only grows).
    int beyond_sweep = 0;
    // Over the planned realizations with a result whose status is not failed:
    int jams = 0;
    int intervals = 0;          // survival intervals
    int uncensored = 0;         // of which ended by a jam
    double survival_sum = 0.0;  // s, all intervals
    int emptied = 0;            // realizations with an empty time
    double empty_sum = 0.0;     // s
    int timed = 0;              // planned realizations with a result (failed included) ...
    double task_seconds = 0.0;  // ... and their wall-clock seconds on the workers
};

struct RunSummary {
    RunInfo info;
    std::optional<RunEndRecord> end;  // absent: still running, or killed
    int stored = 0;                   // results recorded by this run
    // A run without a run-end record: the realizations it was running when it died (from the
    // dispatch records; for the last run, what it runs now if it still runs).
    int died_running = 0;
    // Each worker's (rank's) latest result in this run, s since 1970 (finished_unix).
    std::map<int, double> last_result_unix;
};

struct Failure {
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0;
    int rank = 0;
    int attempt = 0;
    bool exception = false;  // true: an error record; false: a result with status failed
    std::string reason;
};

struct StoreStatus {
    std::filesystem::path store;
    bool has_plan = false;
    std::string campaign_name;
    std::uint64_t physics_hash = 0;
    int total = 0, done = 0, failed = 0, errors = 0, pending = 0;
    int died = 0;  // of the tasks in error, those that were running when a run died
    std::vector<PointStatus> points;
    std::vector<RunSummary> runs;
    std::vector<Failure> failures;  // one per failed task (its latest failure)
    bool writer_active = false;     // a `campaign run` holds the journal's lock
    bool hdf5_in_step = false;      // the HDF5 file was closed in step with the journal
    std::uint64_t journal_bytes = 0;
    std::uint64_t torn_bytes = 0;  // an incomplete last record (in progress or torn)
    CampaignPlan plan;             // the union of every run's plan (labels, scene texts, seeds)
};

// Progress and failures from the journal. Never blocks or disturbs a writer. `counts` (label ->
// realizations) caps the points a sweep lowered below the plan, which only grows: the tasks
// beyond the cap count as beyond_sweep, their stored results as extra (campaign status, from
// the last run's sweep).
StoreStatus read_status(const std::filesystem::path& store,
                        const std::map<std::string, int>& counts = {});

// Every stored realization, read back.
struct StoredRealization {
    std::string label;
    int point = 0;        // index in /points
    ResultRecord record;  // record.result left empty
    engine::RealizationResult result;
};
// From the HDF5 file (rows in the order they were stored).
std::vector<StoredRealization> read_realizations(const std::filesystem::path& store);
// From the journal (same order).
std::vector<StoredRealization> read_journal_realizations(const std::filesystem::path& store);
// The same realizations handed to `visit` one at a time as the journal is read (same order,
// same content), so that a reader that reduces each one as it comes (campaign analyze) holds
// one decoded result at a time instead of the whole campaign's (issue 44).
void for_each_journal_realization(const std::filesystem::path& store,
                                  const std::function<void(StoredRealization&&)>& visit);

// A reader's view of a store as it stands (docs/store.md, "Reading a store during a run"): the
// journal's complete records copied to `out`'s journal and the HDF5 file `out` written from them
// and closed in step, a store of its own that `campaign export`, `plot`, `analyze` and
// hopper_store.py open like any other. Reads the store without locks and writes nothing beside
// it, so a `campaign run` writing it is not disturbed. `out` and its journal must not exist.
struct Snapshot {
    std::int64_t realizations = 0;    // stored realizations the view holds
    std::uint64_t journal_bytes = 0;  // the journal's length it was taken at
    bool writer_active = false;       // a `campaign run` held the store when it was taken
};
// The typed columns of /points/parameters (docs/store.md): one dataset per scene parameter, one
// value per point of the plan, with its units. The store does not know the scene's parameters:
// the layer that does gives them (campaign::point_parameter_columns, from the scene schema);
// the runs are there for points recorded before typed parameters. Empty: no such group.
using PointParameters = std::function<std::vector<DerivedDataset>(
    const CampaignPlan& plan, const std::vector<RunSummary>& runs)>;

Snapshot write_snapshot(const std::filesystem::path& store, const std::filesystem::path& out,
                        const PointParameters& point_parameters = {});

// `campaign merge` (docs/store.md, "Merging stores"): the stores of one campaign joined into a new
// store `out` with its journal. Inputs are read only (their journals, as a snapshot does) and
// refused (core::ConfigError, naming the store and the problem; nothing is written) when a
// `campaign run` holds one, when an input's HDF5 file disagrees with its journal, when campaign
// names or seeds differ, when a point present in two inputs has other physics or seeds, and when
// two copies of a realization differ (physics digest, seed or status). `out` and its journal must
// not exist. The journal of `out` holds every run of the inputs once (a run shared by two inputs,
// as in a copy resumed elsewhere, is the same run-start record), each with its records, each
// realization once (the first input's copy, byte for byte), then a run of its own (`merge_run`,
// no points, reason "merged ..."); its HDF5 file is written from it and closed in step.
struct MergeInputSummary {
    std::filesystem::path store;
    std::int64_t realizations = 0;  // stored in that input
    int runs = 0;
    std::uint64_t torn_bytes = 0;  // an incomplete last record, left out (a killed run's)
};
struct MergeReport {
    std::vector<MergeInputSummary> inputs;
    std::int64_t realizations = 0;      // in the merged store
    std::int64_t identical_copies = 0;  // copies of a realization found in another input too
    int points = 0;
    int runs = 0;         // input runs copied (shared ones once), the merge's own not counted
    int shared_runs = 0;  // runs found in more than one input
};
MergeReport merge_stores(const std::vector<std::filesystem::path>& inputs,
                         const std::filesystem::path& out, RunInfo merge_run,
                         const PointParameters& point_parameters = {});

struct StoreOptions {
    // Seconds between HDF5 flushes while running (0: after every result). The journal is
    // always synced per record; this only bounds how stale an interrupted HDF5 file may be.
    double flush_interval = 1.0;
    // Test hook (fault injection): raise SIGKILL at a named point the n-th time it is passed:
    // "journal" (mid-record), "hdf5" (after a partial HDF5 update), "rebuild" (before the
    // rebuilt file is renamed into place), "close" (HDF5 closed, sync record not yet written).
    std::string crash_point;
    int crash_after = 0;
    // False: a file system without locks is accepted (with a note) instead of refused; nothing
    // then keeps two runs from writing the store at once (`campaign run --no-file-locking`).
    bool require_lock = true;
    // Test hook: called when a new journal is complete under its private name, before it is
    // linked into place (tests pause here to make two runs race for a new store).
    std::function<void()> before_journal_link;
    // The typed /points/parameters columns (see PointParameters); empty: not written.
    PointParameters point_parameters;
    // Test hook: raise SIGSTOP once this many results of this process's runs are durable (the
    // journal synced and the HDF5 view updated); 0: never. A test then acts on a run frozen in
    // a known state (so many stored, the rest not yet handed out) instead of racing it.
    int stop_after_results = 0;  // last: positional initializers of the above stay valid
};

// The master's handle. Opening takes the journal's lock (one writer at a time), scans the
// journal and drops a torn last record. Nothing is written to the HDF5 file until begin_run().
class Store {
  public:
    explicit Store(const std::filesystem::path& path, StoreOptions options = {});
    ~Store();
    Store(const Store&) = delete;
    Store& operator=(const Store&) = delete;

    const std::filesystem::path& path() const;
    // The union of every plan recorded so far (empty for a new store).
    const CampaignPlan& plan() const;
    bool is_new() const;  // nothing recorded yet
    // What opening found or did ("dropped an incomplete last journal record of 123 bytes", ...).
    const std::vector<std::string>& notes() const;

    const TaskEntry* task(const std::string& label, int realization) const;
    StoreStatus status() const;

    // Records a run and its plan (the caller has checked that the plan's physics agrees with
    // plan()); extends the store's plan with new points and realizations. Brings the HDF5 file
    // in step (rebuilding it from the journal when needed) and opens it for writing.
    void begin_run(RunStartRecord run);
    // Records the realizations a target campaign's next round allots (only the points whose
    // allotment grows; nothing when none does), before they are handed out.
    void allot(const AllotmentRecord& r);
    // Durable (journal fsync) when it returns; the HDF5 file follows within flush_interval.
    // Inside a batch: written to the journal at once, durable when commit() returns.
    void append(const ResultRecord& r);
    void append(const ErrorRecord& r);
    // A realization handed to a worker: journaled without a sync (the page cache outlives a
    // killed process; a lost node may lose it, and with it only the count of one death).
    void dispatched(const DispatchRecord& r);
    // Group commit (issue 44): the results and errors appended between begin_batch() and
    // commit() are written to the journal one by one as they come but synced together, by one
    // fdatasync in commit(), which only then brings them into the HDF5 view (the view never
    // holds what the journal might lose). Their realizations count as done when commit()
    // returns. The records, their order and so the store's bytes are those of single appends;
    // a kill before commit() leaves at most a torn last record, as before, and a machine
    // crash loses at most the batch (its realizations run again). allot() and end_run() commit
    // an open batch first.
    void begin_batch();
    void commit();
    // Records the end of the run, closes the HDF5 file in step with the journal.
    void end_run(const RunEndRecord& r);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace hopper::store
