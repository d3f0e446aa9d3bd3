#pragma once
// The master's run (private to the campaign layer): the Dispatcher holds the queue, the
// workers' states, the checkpoint bookkeeping and the report. master.cpp has the loop and its
// steps; dispatcher_messages.cpp what each kind of worker message does (results, failures,
// checkpoints, heartbeats) and the bookkeeping of results and failures.

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <deque>
#include <map>
#include <set>

#include <unistd.h>

#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/running.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/codec.hpp"

#include "hopper/campaign/master.hpp"

namespace hopper::campaign::detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// CPU time of the calling thread (the master's), so that a worker thread in the same process
// is not counted.
inline double thread_cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_THREAD, &u);
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Item {
    std::size_t index;  // in todo
    int attempt;
};

struct Busy {
    Item item;
    Clock::time_point heard;  // the last message from the worker (or when the task was sent)
    double started_unix = 0.0;
    bool resumed = false;        // continued from a checkpoint file
    double base_seconds = 0.0;   // worker seconds in the checkpoint it continued from
    double saved_seconds = 0.0;  // seconds of this attempt kept in its latest checkpoint
};

// Clamped to +-30 years: a deadline far ahead (9999-12-31) would overflow the clock's 64-bit
// nanoseconds and come out negative, a wait of zero (busy polling) and a drain ending at once.
inline Clock::duration to_duration(double seconds) {
    constexpr double limit = 1e9;
    const double s = std::isnan(seconds) ? 0.0 : std::clamp(seconds, -limit, limit);
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// One run of the master: the queue, the workers' states, the checkpoint bookkeeping and the
// report, with one method per step of the loop in run() and one per kind of message.
class Dispatcher {
  public:
    Dispatcher(MasterChannel& channel, store::Store& store, const StopRequests& stop,
               const MasterOptions& options, std::ostream& log, const std::vector<TaskRef>& todo,
               Totals totals);
    MasterReport run();

  private:
    // The loop's steps, in their order.
    void begin_drain(StopLevel level);
    void stop_running();
    bool dispatch_tasks();
    std::deque<Item>::iterator pick_task();
    void send_task(const Item& item);
    void end_when_nothing_fits();
    void stop_at_deadline();
    void stop_for_deadline();
    std::chrono::milliseconds wait_time() const;
    void receive(std::chrono::milliseconds wait);
    void check_silence();
    MasterReport finish();

    // Messages from workers.
    void handle(int worker, const Message& m);
    void on_checkpoint(int worker, const Message& m);
    void on_heartbeat(int worker);
    void on_late_reply(int worker, const Message& m);
    void on_reply(int worker, const Message& m);
    void on_error(int worker, const Item& item, const Busy& was, const Message& m);
    void on_interrupted(int worker, const Item& item, const Busy& was, const Message& m);
    void accept_result(int worker, const Item& item, const Message& m, bool resumed);
    void record_error(int worker, const Item& item, const std::string& reason);
    void restart_without_checkpoint(const Item& item, const std::string& what);

    // Helpers.
    CheckpointKey key_of(const Item& item) const;
    bool save_state(int worker, const Item& item, double seconds,
                    std::span<const std::uint8_t> state);
    void update_running();
    void print_progress();
    void check_fail_fast(const TaskRef& t, const engine::RealizationResult& r);
    void send_stop_now();
    Clock::duration silence_limit(const Item& item) const;
    double correction() const;
    bool measured() const;
    double seconds_to_deadline() const;

    MasterChannel& channel_;
    store::Store& store_;
    const StopRequests& stop_;
    const MasterOptions& options_;
    std::ostream& log_;
    const std::vector<TaskRef>& todo_;
    const Totals totals_;

    const Clock::time_point start_ = Clock::now();
    const double cpu0_ = thread_cpu_seconds();
    MasterReport report_;
    std::deque<Item> queue_;
    std::vector<int> errors_;
    std::deque<int> idle_;
    std::map<int, Busy> busy_;
    std::map<int, Item> lost_;      // silent workers and the realization they were running
    std::set<int> revived_;         // lost workers heard from again (reported once)
    std::vector<char> finished_;    // a result was stored by this run
    std::vector<char> reassigned_;  // handed to another worker after a silence
    std::map<std::size_t, std::uint64_t> digest_;  // reassigned and stored: physics digest
    std::vector<Item> stored_in_batch_;  // stored since the store's last commit (checkpoints on)
    bool running_changed_ = false;       // a worker became idle since the running file was written

    // Silence is counted only while the master listens: the end of the last silence check and
    // the wait the receive after it was given (check_silence credits a longer gap, a master
    // that was stopped or stalled, to every busy worker).
    Clock::time_point last_check_ = Clock::now();
    Clock::duration last_wait_{};

    bool draining_ = false, stop_sent_ = false, stop_announced_ = false;
    Clock::time_point drain_deadline_{};
    const bool progress_;
    Clock::duration interval_;
    Clock::time_point next_progress_;
    int failed_now_;
    // ETA weighted by the cost model (TaskRef::expected_seconds: particle-steps at the slow
    // speed of plan.hpp), at the speed measured on what finished realizations computed; the
    // prior speed until one has finished. Running realizations count with what they have left.
    CostEta eta_;
    bool costs_known_ = true;

    CheckpointFiles* const ckpt_;  // checkpoint files, or null
    char host_[256] = {};          // for the running file
    // Expected seconds of a task: the cost model corrected by the measured durations.
    double measured_seconds_;
    double measured_expected_;
    std::vector<double> saved_before_;  // seconds in a checkpoint file
    const bool timed_;
    bool told_unmeasured_ = false;
    std::set<std::size_t> hopeless_;  // tasks warned about: longer than the allocation
    // Failures before the outlet opened, per point label and message shape (fail fast).
    std::map<std::pair<std::string, std::string>, int> early_failures_;
    // Seconds this run may compute: from its start to the deadline minus the grace.
    double allocation_ = 1e300;
};

}  // namespace hopper::campaign::detail
