#include "hopper/campaign/master.hpp"

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

namespace hopper::campaign {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// CPU time of the calling thread (the master's), so that a worker thread in the same process
// is not counted.
double thread_cpu_seconds() {
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
Clock::duration to_duration(double seconds) {
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

Dispatcher::Dispatcher(MasterChannel& channel, store::Store& store, const StopRequests& stop,
                       const MasterOptions& options, std::ostream& log,
                       const std::vector<TaskRef>& todo, Totals totals)
    : channel_(channel),
      store_(store),
      stop_(stop),
      options_(options),
      log_(log),
      todo_(todo),
      totals_(totals),
      errors_(todo.size(), 0),
      finished_(todo.size(), 0),
      reassigned_(todo.size(), 0),
      progress_(options.progress_interval > 0),
      interval_(to_duration(progress_ ? options.progress_interval : 1e9)),
      next_progress_(start_ + interval_),
      failed_now_(totals.failed),
      eta_(channel.workers(), prior_seconds_per_particle_step / slow_seconds_per_particle_step),
      ckpt_(options.checkpoints),
      measured_seconds_(options.measured_seconds),
      measured_expected_(options.measured_expected),
      saved_before_(todo.size(), 0.0),
      timed_(options.deadline.has_value()) {
    for (std::size_t i = 0; i < todo_.size(); ++i)
        queue_.push_back({i, 1});
    for (int w = 1; w <= channel_.workers(); ++w)
        idle_.push_back(w);
    for (const auto& t : todo_) {
        eta_.add_pending(t.expected_seconds);
        costs_known_ = costs_known_ && t.expected_seconds > 0;
    }
    if (gethostname(host_, sizeof host_ - 1) != 0) std::snprintf(host_, sizeof host_, "unknown");
    if (ckpt_)
        for (std::size_t i = 0; i < todo_.size(); ++i)
            saved_before_[i] = ckpt_->peek_seconds(key_of(Item{i, 1})).value_or(0.0);
    if (timed_) allocation_ = *options_.deadline - store::unix_now() - options_.grace;
}

MasterReport Dispatcher::run() {
    for (;;) {
        const StopLevel level = stop_.level();
        if (level != StopLevel::none && !draining_) begin_drain(level);
        if (draining_ && !stop_sent_ && !busy_.empty() &&
            (stop_.level() == StopLevel::now || Clock::now() >= drain_deadline_))
            stop_running();
        if (dispatch_tasks()) update_running();
        if (timed_ && !draining_ && report_.fail_fast.empty() && busy_.empty() && !queue_.empty())
            end_when_nothing_fits();
        if (timed_ && !draining_ && !busy_.empty() && seconds_to_deadline() <= options_.grace)
            stop_at_deadline();
        if (busy_.empty() && (queue_.empty() || draining_ || !report_.fail_fast.empty())) break;
        receive(wait_time());
        check_silence();
        if (progress_ && Clock::now() >= next_progress_) {
            print_progress();
            next_progress_ += interval_;
        }
    }
    return finish();
}

// A stop request: no more tasks; running ones may finish within the grace (drain) or are
// stopped at once (now, by stop_running on the same pass).
void Dispatcher::begin_drain(StopLevel level) {
    draining_ = true;
    report_.stopped = true;
    report_.stop_reason = stop_.reason();
    // With a deadline the running realizations were started because they are expected to end
    // before deadline - grace: a drain (Slurm's warning signal comes with up to a minute's
    // jitter) lets them go on until then, at least the grace time.
    const double until =
        timed_ ? std::max(options_.grace, seconds_to_deadline() - options_.grace) : options_.grace;
    drain_deadline_ = Clock::now() + to_duration(until);
    if (ckpt_ && level == StopLevel::drain)
        for (const auto& [w, b] : busy_)
            channel_.send(w,
                          Message::make(MessageKind::checkpoint_now, todo_[b.item.index].task_id));
    log_ << "campaign: " << report_.stop_reason << ": handing out no more tasks";
    if (!busy_.empty()) {
        if (level == StopLevel::now) {
            log_ << "; stopping the " << busy_.size() << " running realization(s) now";
            stop_announced_ = true;
        } else
            log_ << "; the " << busy_.size() << " running realization(s) may finish within "
                 << format_duration(until) << " (signal again to stop them now)";
    }
    log_ << std::endl;
}

void Dispatcher::stop_running() {
    if (!stop_announced_)
        log_ << "campaign: stopping the " << busy_.size() << " running realization(s)" << std::endl;
    send_stop_now();
}

// Hands queued tasks to idle workers; returns whether any was handed out.
bool Dispatcher::dispatch_tasks() {
    bool dispatched = false;
    while (!draining_ && report_.fail_fast.empty() && !idle_.empty() && !queue_.empty()) {
        const auto pick = pick_task();
        if (pick == queue_.end()) break;
        const Item item = *pick;
        queue_.erase(pick);
        send_task(item);
        dispatched = true;
    }
    return dispatched;
}

// The next task: the first in the queue (most expensive first); with a deadline, the first
// expected to end in time, or end() when none is. Until something of this campaign is measured
// the cost model's seconds are a guess (off by 2x either way); skipping on a guess could start
// nothing, allocation after allocation. So the estimate filters only once a result has been
// measured.
std::deque<Item>::iterator Dispatcher::pick_task() {
    auto pick = queue_.begin();
    if (timed_ && !measured() && !told_unmeasured_) {
        told_unmeasured_ = true;
        log_ << "campaign: nothing of this campaign is measured yet: realizations are "
                "handed out until the deadline minus the grace, when running ones are "
                "stopped; the deadline's estimates start with the first result"
             << std::endl;
    }
    if (!timed_ || !measured()) return pick;
    const double left = seconds_to_deadline() - options_.grace;
    for (; pick != queue_.end(); ++pick) {
        const TaskRef& t = todo_[pick->index];
        const double need =
            std::max(0.0, t.expected_seconds * correction() - saved_before_[pick->index]);
        if (need <= left) break;
        if (!ckpt_ && need > allocation_ && hopeless_.insert(pick->index).second)
            log_ << "campaign: warning: '" << t.label << "' #" << t.realization
                 << " is expected to need " << format_duration(need)
                 << ", more than this allocation's " << format_duration(allocation_)
                 << ", and checkpoints are off: it cannot finish in an allocation "
                    "this long (raise the time limit or drop --no-checkpoints)"
                 << std::endl;
        // Longer than a whole allocation like this one: it can only ever finish in pieces, so
        // with checkpoints it starts (its state is saved at the deadline) rather than never.
        if (ckpt_ && need > allocation_ && left > 0.25 * allocation_) {
            log_ << "campaign: '" << t.label << "' #" << t.realization << " is expected to need "
                 << format_duration(need) << ", more than this allocation's "
                 << format_duration(allocation_)
                 << "; started anyway: its state is saved at the deadline" << std::endl;
            break;
        }
    }
    return pick;
}

// Sends item to the first idle worker, with its checkpoint's state when there is a usable one.
void Dispatcher::send_task(const Item& item) {
    const int w = idle_.front();
    idle_.pop_front();
    Message task = Message::make(MessageKind::task, todo_[item.index].task_id, item.attempt);
    Busy b{item, Clock::now(), store::unix_now()};
    if (ckpt_) {
        std::string refusal;
        if (auto loaded = ckpt_->read(key_of(item), &refusal)) {
            task.payload = std::move(loaded->state);
            b.resumed = true;
            b.base_seconds = loaded->worker_seconds;
            saved_before_[item.index] = loaded->worker_seconds;
            ++report_.resumed;
        } else {
            saved_before_[item.index] = 0.0;
            if (!refusal.empty()) log_ << "campaign: " << refusal << std::endl;
        }
    }
    channel_.send(w, task);
    busy_[w] = b;
}

// The deadline ends the run as stopped (resumable); the queued tasks were skipped for it.
void Dispatcher::stop_for_deadline() {
    draining_ = true;
    report_.stopped = true;
    report_.stop_reason = "the deadline";
    report_.deadline_skipped = static_cast<int>(queue_.size());
}

// Nothing left fits before the deadline: end the run as stopped (resumable).
void Dispatcher::end_when_nothing_fits() {
    stop_for_deadline();
    log_ << "campaign: the deadline is " << format_duration(std::max(0.0, seconds_to_deadline()))
         << " away (grace " << format_duration(options_.grace) << "): none of the " << queue_.size()
         << " realization(s) left is expected to finish before it "
         << "(the shortest needs about "
         << format_duration(todo_[queue_.back().index].expected_seconds * correction())
         << "); they run in the next allocation" << std::endl;
}

void Dispatcher::stop_at_deadline() {
    stop_for_deadline();
    log_ << "campaign: the deadline is " << format_duration(std::max(0.0, seconds_to_deadline()))
         << " away: stopping the " << busy_.size() << " running realization(s)"
         << (ckpt_ ? " (their states are saved)" : "") << std::endl;
    send_stop_now();
    stop_announced_ = true;
}

// How long to wait for a message: until the next thing that is due (progress line, end of the
// drain, deadline, a worker's silence limit), at most max_wait.
std::chrono::milliseconds Dispatcher::wait_time() const {
    auto wait = options_.max_wait;
    const auto now = Clock::now();
    auto bound = [&](Clock::time_point t) {
        if (t > now)
            wait = std::min(wait, std::chrono::ceil<std::chrono::milliseconds>(t - now));
        else
            wait = std::chrono::milliseconds(0);
    };
    if (progress_) bound(next_progress_);
    if (draining_ && !stop_sent_) bound(drain_deadline_);
    if (timed_ && !draining_)
        bound(now + to_duration(std::max(0.0, seconds_to_deadline() - options_.grace)));
    for (const auto& [w, b] : busy_)
        bound(b.heard + silence_limit(b.item) + std::chrono::milliseconds(1));
    return wait;
}

void Dispatcher::receive(std::chrono::milliseconds wait) {
    if (auto msg = channel_.receive(wait)) {
        handle(msg->first, msg->second);
        // Drain whatever else is already waiting before handing out more.
        while (auto more = channel_.receive(std::chrono::milliseconds(0)))
            handle(more->first, more->second);
    }
}

// Busy workers silent for longer than their realization's limit: reported, and the
// realization goes to the front of the queue for another worker.
void Dispatcher::check_silence() {
    const auto now = Clock::now();
    for (auto it = busy_.begin(); it != busy_.end();) {
        const Item item = it->second.item;
        const auto limit = silence_limit(item);
        if (now - it->second.heard <= limit) {
            ++it;
            continue;
        }
        const TaskRef& t = todo_[item.index];
        log_ << "campaign: worker " << it->first << " has been silent for "
             << format_duration(std::chrono::duration<double>(now - it->second.heard).count())
             << " (limit " << format_duration(std::chrono::duration<double>(limit).count())
             << ") running '" << t.label << "' #" << t.realization << "; "
             << (draining_ ? "it runs again on resume" : "handing it to another worker")
             << std::endl;
        lost_[it->first] = item;
        reassigned_[item.index] = 1;
        ++report_.reassigned;
        if (!draining_) queue_.push_front({item.index, item.attempt + 1});
        it = busy_.erase(it);
    }
}

MasterReport Dispatcher::finish() {
    report_.not_started = static_cast<int>(queue_.size());
    if (ckpt_) ckpt_->remove_dir_if_empty();
    if (!options_.running_file.empty()) {
        std::error_code ec;
        std::filesystem::remove(options_.running_file, ec);
    }
    report_.silent_at_end = static_cast<int>(lost_.size());
    report_.wall_seconds = seconds_since(start_);
    report_.cpu_seconds = thread_cpu_seconds() - cpu0_;
    if (progress_) print_progress();
    return report_;
}

void Dispatcher::handle(int worker, const Message& m) {
    if (m.kind == MessageKind::checkpoint)
        on_checkpoint(worker, m);
    else if (m.kind == MessageKind::heartbeat)
        on_heartbeat(worker);
    else if (lost_.count(worker))
        on_late_reply(worker, m);
    else
        on_reply(worker, m);
}

void Dispatcher::on_checkpoint(int worker, const Message& m) {
    const auto it = busy_.find(worker);
    if (!ckpt_ || it == busy_.end() || todo_[it->second.item.index].task_id != m.task) return;
    it->second.heard = Clock::now();
    if (save_state(worker, it->second.item, it->second.base_seconds + m.seconds, m.payload))
        it->second.saved_seconds = m.seconds;
}

void Dispatcher::on_heartbeat(int worker) {
    if (const auto it = busy_.find(worker); it != busy_.end())
        it->second.heard = Clock::now();
    else if (lost_.count(worker) && revived_.insert(worker).second)
        log_ << "campaign: worker " << worker << " is heard from again; its realization "
             << "runs elsewhere too (the first result is stored, the other compared)" << std::endl;
}

// The late reply of a realization that was handed to another worker.
void Dispatcher::on_late_reply(int worker, const Message& m) {
    const auto lt = lost_.find(worker);
    const Item item = lt->second;
    lost_.erase(lt);
    revived_.erase(worker);
    idle_.push_back(worker);
    if (todo_[item.index].task_id == m.task && m.kind == MessageKind::result)
        accept_result(worker, item, m, false);
}

// The reply of a busy worker: a result, an error or an interruption; the worker is idle again.
void Dispatcher::on_reply(int worker, const Message& m) {
    const auto it = busy_.find(worker);
    if (it == busy_.end() || todo_[it->second.item.index].task_id != m.task) {
        log_ << "campaign: warning: unexpected message from worker " << worker << " (task "
             << m.task << "); ignored" << std::endl;
        return;
    }
    const Item item = it->second.item;
    const Busy was = it->second;
    busy_.erase(it);
    idle_.push_back(worker);
    update_running();
    switch (m.kind) {
        case MessageKind::result:
            accept_result(worker, item, m, was.resumed);
            break;
        case MessageKind::error:
            on_error(worker, item, was, m);
            break;
        case MessageKind::interrupted:
            on_interrupted(worker, item, was, m);
            break;
        default:
            log_ << "campaign: warning: worker " << worker << " sent message kind "
                 << static_cast<int>(m.kind) << "; ignored" << std::endl;
    }
}

void Dispatcher::on_error(int worker, const Item& item, const Busy& was, const Message& m) {
    const std::string what(m.payload.begin(), m.payload.end());
    // The engine refused the checkpoint's state (issue 29, item 1): not an error of the
    // realization, which starts again from its beginning.
    if (ckpt_ && was.resumed && what.starts_with(checkpoint_refused)) {
        --report_.resumed;
        if (finished_[item.index])
            ckpt_->remove(key_of(item));
        else
            restart_without_checkpoint(item, std::string(what.substr(checkpoint_refused.size())) +
                                                 ": the checkpoint of '" + todo_[item.index].label +
                                                 "' #" +
                                                 std::to_string(todo_[item.index].realization));
        return;
    }
    // The other copy of a reassigned realization was stored already.
    if (!finished_[item.index]) record_error(worker, item, what);
    // A state that made its realization raise must not be tried again.
    if (ckpt_ && was.resumed && !finished_[item.index]) {
        ckpt_->remove(key_of(item));
        saved_before_[item.index] = 0.0;
        log_ << "campaign: the checkpoint of '" << todo_[item.index].label << "' #"
             << todo_[item.index].realization
             << " is removed: the next attempt starts from the beginning" << std::endl;
    }
}

void Dispatcher::on_interrupted(int worker, const Item& item, const Busy& was, const Message& m) {
    if (finished_[item.index]) return;
    ++report_.interrupted;
    if (ckpt_ && !m.payload.empty() &&
        save_state(worker, item, was.base_seconds + m.seconds, m.payload)) {
        report_.saved_worker_seconds += m.seconds;
        saved_before_[item.index] = was.base_seconds + m.seconds;
        log_ << "campaign: '" << todo_[item.index].label << "' #" << todo_[item.index].realization
             << " stopped after " << format_duration(m.seconds) << " on worker " << worker
             << "; its state is saved and continues on resume" << std::endl;
    } else {
        const double thrown = std::max(0.0, m.seconds - was.saved_seconds);
        report_.lost_worker_seconds += thrown;
        report_.saved_worker_seconds += m.seconds - thrown;
    }
}

// A result for item from worker: checked, then stored unless this run stored one already (a
// reassigned realization), in which case it is compared with it.
void Dispatcher::accept_result(int worker, const Item& item, const Message& m, bool resumed) {
    const TaskRef& t = todo_[item.index];
    engine::RealizationResult r;
    try {
        r = store::decode_result(m.payload, "result from worker " + std::to_string(worker));
        if (r.seed != t.seed)
            throw core::StoreError("result from worker " + std::to_string(worker) + " has seed " +
                                   std::to_string(r.seed) + ", expected " + std::to_string(t.seed));
    } catch (const core::StoreError& e) {
        if (!finished_[item.index]) record_error(worker, item, e.what());
        return;
    }
    // A realization that failed after continuing from its checkpoint: the state may be what
    // failed (a valid checksum over a wrong state). Its file goes and the realization starts
    // over from its beginning; the fresh attempt's outcome is what is stored.
    if (resumed && ckpt_ && r.status == engine::Status::failed && !finished_[item.index]) {
        report_.lost_worker_seconds += m.seconds;
        restart_without_checkpoint(item, "'" + t.label + "' #" + std::to_string(t.realization) +
                                             " failed after continuing from its checkpoint (" +
                                             r.message + "); the checkpoint");
        return;
    }
    if (finished_[item.index]) {
        const bool same = store::physics_digest(r) == digest_[item.index];
        ++(same ? report_.late_identical : report_.late_different);
        log_ << "campaign: " << (same ? "" : "warning: ") << "the second result of '" << t.label
             << "' #" << t.realization << " (worker " << worker << ") is "
             << (same ? "identical to the stored one; stored once"
                      : "DIFFERENT from the stored one (the engine is deterministic: a bad "
                        "node or a bug); the first is kept")
             << std::endl;
        return;
    }
    // The worker time of a realization continued from a checkpoint includes the time its
    // checkpoint holds.
    const double seconds = m.seconds + saved_before_[item.index];
    store_.append(store::ResultRecord{t.label, t.realization, t.seed, worker, item.attempt, seconds,
                                      store::unix_now(), m.payload});
    finished_[item.index] = 1;
    if (ckpt_) ckpt_->remove(key_of(item));
    if (t.expected_seconds > 0 && seconds > 0) {
        measured_seconds_ += seconds;
        measured_expected_ += t.expected_seconds;
    }
    if (reassigned_[item.index]) digest_[item.index] = store::physics_digest(r);
    ++report_.stored;
    // What it computed: the engine's particle-steps (the stored result carries them as its wall
    // time over its ns per particle-step), in the cost units of expected_seconds.
    const auto& dg = r.diagnostics;
    const double particle_steps = dg.particle_steps > 0 ? dg.particle_steps
                                  : dg.ns_per_particle_step > 0
                                      ? dg.wall_seconds * 1e9 / dg.ns_per_particle_step
                                      : -1.0;
    eta_.finished(t.expected_seconds, seconds, 1, true,
                  particle_steps > 0 ? particle_steps * slow_seconds_per_particle_step : -1.0);
    if (r.status == engine::Status::failed) {
        ++report_.failed;
        ++failed_now_;
        check_fail_fast(t, r);
    }
}

// A checkpoint that must not be continued from (`what` names it and why): its file goes and the
// realization starts again from its beginning, now or (draining) in the next run.
void Dispatcher::restart_without_checkpoint(const Item& item, const std::string& what) {
    ckpt_->remove(key_of(item));
    saved_before_[item.index] = 0.0;
    log_ << "campaign: " << what << " is removed and the realization "
         << (draining_ ? "starts from its beginning on resume" : "starts again from its beginning")
         << std::endl;
    if (!draining_) queue_.push_front({item.index, item.attempt + 1});
}

// A failure before the outlet opened (while filling or settling) that repeats, numbers aside,
// in fail_fast_after realizations of one point comes from the scene, not from a seed: running
// the rest of the campaign would only repeat it. No more tasks are handed out; running ones
// finish.
void Dispatcher::check_fail_fast(const TaskRef& t, const engine::RealizationResult& r) {
    if (options_.fail_fast_after <= 0 || !report_.fail_fast.empty()) return;
    if (r.diagnostics.steps > r.diagnostics.settle_steps) return;  // the outlet had opened
    std::string shape;  // the message with every number replaced by '#'
    for (std::size_t i = 0; i < r.message.size(); ++i) {
        const char ch = r.message[i];
        if (std::isdigit(static_cast<unsigned char>(ch))) {
            while (i + 1 < r.message.size() &&
                   (std::isdigit(static_cast<unsigned char>(r.message[i + 1])) ||
                    std::strchr(".e-+", r.message[i + 1])))
                ++i;
            shape += '#';
        } else {
            shape += ch;
        }
    }
    if (++early_failures_[{t.label, shape}] < options_.fail_fast_after) return;
    report_.fail_fast = std::to_string(options_.fail_fast_after) + " realizations of '" + t.label +
                        "' failed the same way before the outlet opened (the last: #" +
                        std::to_string(t.realization) + ", " + r.message + ")";
    log_ << "campaign: failing fast: " << report_.fail_fast << "; handing out no more tasks"
         << (busy_.empty() ? "" : " (running ones finish)") << std::endl;
}

// An attempt that raised: logged in the store, retried once more unless draining or out of
// attempts.
void Dispatcher::record_error(int worker, const Item& item, const std::string& reason) {
    const TaskRef& t = todo_[item.index];
    store_.append(store::ErrorRecord{t.label, t.realization, t.seed, worker, item.attempt,
                                     store::unix_now(), reason});
    ++report_.errors;
    ++errors_[item.index];
    if (errors_[item.index] < options_.max_attempts && !draining_) {
        log_ << "campaign: '" << t.label << "' #" << t.realization << " raised an error on "
             << "worker " << worker << " (" << reason << "); trying once more" << std::endl;
        queue_.push_front({item.index, item.attempt + 1});
    } else {
        ++report_.gave_up;
        ++failed_now_;
        log_ << "campaign: '" << t.label << "' #" << t.realization << " failed "
             << errors_[item.index] << " time(s) (" << reason << "); left for the next run"
             << std::endl;
    }
}

CheckpointKey Dispatcher::key_of(const Item& item) const {
    const TaskRef& t = todo_[item.index];
    return CheckpointKey{t.label, t.realization, t.seed, t.physics};
}

bool Dispatcher::save_state(int worker, const Item& item, double seconds,
                            std::span<const std::uint8_t> state) {
    try {
        ckpt_->write(key_of(item), seconds, state);
        ++report_.checkpoints_written;
        return true;
    } catch (const core::StoreError& e) {
        log_ << "campaign: warning: the state of '" << todo_[item.index].label << "' #"
             << todo_[item.index].realization << " from worker " << worker
             << " could not be saved (" << e.what() << "); it will start over" << std::endl;
        return false;
    }
}

void Dispatcher::update_running() {
    if (options_.running_file.empty()) return;
    RunningFile f;
    f.pid = static_cast<std::int64_t>(getpid());
    f.host = host_;
    f.updated_unix = store::unix_now();
    for (const auto& [w, b] : busy_) {
        const TaskRef& t = todo_[b.item.index];
        f.tasks.push_back(
            RunningTask{w, b.started_unix, b.item.attempt, b.resumed, t.realization, t.label});
    }
    write_running(options_.running_file, f);
}

void Dispatcher::print_progress() {
    const double elapsed = seconds_since(start_);
    const double rate = elapsed > 0 ? report_.stored / elapsed : 0.0;
    std::vector<RunningCost> running;
    const double now = store::unix_now();
    for (const auto& [w, b] : busy_)
        running.push_back({todo_[b.item.index].expected_seconds,
                           b.base_seconds + std::max(0.0, now - b.started_unix)});
    log_ << progress_line(totals_.finished + report_.stored, totals_.total,
                          static_cast<int>(busy_.size()), failed_now_, rate, elapsed,
                          costs_known_ ? eta_.seconds_left(running) : -1.0)
         << std::endl;
}

void Dispatcher::send_stop_now() {
    for (const auto& [w, b] : busy_)
        channel_.send(w, Message::make(MessageKind::stop_now, todo_[b.item.index].task_id));
    stop_sent_ = true;
}

Clock::duration Dispatcher::silence_limit(const Item& item) const {
    const double s =
        options_.worker_timeout
            ? *options_.worker_timeout
            : std::max(options_.min_worker_timeout,
                       options_.worker_timeout_factor * todo_[item.index].expected_seconds);
    return to_duration(s);
}

bool Dispatcher::measured() const {
    return measured_expected_ > 0 && measured_seconds_ > 0;
}

double Dispatcher::correction() const {
    return measured() ? measured_seconds_ / measured_expected_ : 1.0;
}

double Dispatcher::seconds_to_deadline() const {
    return timed_ ? *options_.deadline - store::unix_now() : 1e300;
}

}  // namespace

Master::Master(MasterChannel& channel, store::Store& store, const StopRequests& stop,
               MasterOptions options, std::ostream& log)
    : channel_(channel), store_(store), stop_(stop), options_(options), log_(log) {}

MasterReport Master::run(const std::vector<TaskRef>& todo, Totals totals) {
    return Dispatcher(channel_, store_, stop_, options_, log_, todo, totals).run();
}

}  // namespace hopper::campaign
