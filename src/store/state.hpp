#pragma once
// The store's state as the journal describes it (private to the store layer): the union plan,
// where every task stands, the runs and the failures. Built by replaying journal records; the
// HDF5 layout (layout.hpp) is written from it.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "hopper/store/journal.hpp"
#include "hopper/store/records.hpp"
#include "hopper/store/store.hpp"

namespace hopper::store {

struct State {
    CampaignPlan plan;  // union of every run's plan; points in order of first appearance
    std::map<std::string, int> point_index;
    std::vector<std::vector<TaskEntry>> tasks;  // [point][realization], at least planned long
    // The words of the few tasks that have them, by (point, realization): the message of a
    // failed result and the reason of the last exception (TaskEntry holds numbers only).
    struct Messages {
        std::string result;      // the failed result's message
        std::string last_error;  // the last exception's reason
    };
    std::map<std::pair<int, int>, Messages> messages;
    std::int64_t rows = 0;  // stored results
    std::vector<RunSummary> runs;
    std::vector<Failure> failures;  // every error record, in order
    int duplicates = 0;             // results for a task that already had one (ignored)
    // The last record (to decide whether the HDF5 file is in step).
    std::optional<RecordType> last_type;
    std::uint64_t last_offset = 0;
    std::optional<SyncRecord> last_sync;
    // The realizations (point, realization) handed out by the latest run and not answered yet
    // (DispatchRecord): when the next run starts and that run has no end record, each of them
    // gets a death (TaskEntry::deaths).
    std::set<std::pair<int, int>> in_flight;

    // Each returns what changed, for the HDF5 writer.
    // True when the union plan changed (new points or realizations).
    // Takes the record's points and run (a plan of 10^5 points is large: no copy).
    bool apply(RunStartRecord&& r);
    // True when an allotment grew (a target campaign's next round).
    bool apply(const AllotmentRecord& r);
    // The row of the new result, or -1 for a duplicate (ignored). Throws for an unknown point.
    std::int64_t apply(const ResultRecord& r, const engine::RealizationResult& result);
    // The point index (throws for an unknown point).
    int apply(const ErrorRecord& r);
    void apply(const RunEndRecord& r);
    void apply(const DispatchRecord& r);
    // The entry of realization `realization` of point `label` (the tasks grown to hold it), for
    // a record of `what` kind; throws for an unknown point or a negative index.
    std::pair<int, TaskEntry*> entry_for(const std::string& label, int realization,
                                         const char* what);

    // Whether the HDF5 file was closed in step with the journal, judged from the journal alone:
    // the last record is a sync record written right after the file was closed at that length.
    bool closed_in_step() const;
    int find_point(const std::string& label) const;
    // Lists the seeds of realizations [first, first + seeds.size()) of a point; true when its
    // allotment grew. Throws when `first` leaves a gap.
    bool extend_seeds(int point, int first, std::span<const std::uint64_t> seeds);
    std::uint64_t seed_of(int point, int realization) const;
    // The task's words (empty when it has none).
    const Messages& message_of(int point, int realization) const;
    // `counts`: read_status's caps (store.hpp).
    StoreStatus status(const std::map<std::string, int>& counts = {}) const;
};

// fsync of a file or directory, best effort (some file systems refuse it for directories).
void fsync_path(const std::filesystem::path& p, bool directory = false);

// The HDF5 file at `path` against the checksum in the state's last sync record (read without
// HDF5). unrecorded: not closed in step, or a sync record from before checksums; changed: bytes
// differ at the recorded size (damage in place since the close); other: another size or
// unreadable (opening it tells what it is: a foreign file put there is refused, not
// overwritten).
enum class FileCheck { unrecorded, intact, changed, other };
FileCheck check_closed_file(const State& state, const std::filesystem::path& path);

ResultSummary summarize(const engine::RealizationResult& r, const ResultRecord& rec);

// Replays the journal's records into `state`; `on_record` (optional) sees each decoded record
// after it was applied (for rebuilding the HDF5 file).
struct ReplaySink {
    virtual ~ReplaySink() = default;
    // The record itself is in the state (State::apply takes it).
    virtual void run_start(const State&, bool /*plan_changed*/) {}
    virtual void result(const State&, int /*point*/, std::int64_t /*row*/, const ResultRecord&,
                        const engine::RealizationResult&) {}
    virtual void error(const State&, int /*point*/, const ErrorRecord&) {}
    virtual void run_end(const State&, const RunEndRecord&) {}
    virtual void allotment(const State&, bool /*plan_changed*/) {}
};
void apply_record(State& state, RecordType type, std::uint64_t offset,
                  std::span<const std::uint8_t> payload, ReplaySink* sink);

// The HDF5 file `target` written from the journal's records before `limit` (truncates it), then
// closed as in step with `token` and `journal_bytes` (the rebuild, the snapshot and the merge).
// The state the replay builds is left in `into` when given (it must be empty): the store's
// rebuild keeps it as its own instead of holding two (at 10^6 tasks each is 150 MB: issue 44).
void write_from_journal(const std::filesystem::path& jpath, std::uint64_t limit,
                        const std::filesystem::path& target, const std::string& journal_name,
                        std::uint64_t token, std::uint64_t journal_bytes,
                        const PointParameters& parameters, State* into = nullptr);
// A random nonzero token naming an HDF5 file closed in step (its sync record holds it).
std::uint64_t random_token();

}  // namespace hopper::store
