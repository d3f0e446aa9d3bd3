#include "hopper/campaign/master.hpp"

#include "dispatcher.hpp"

namespace hopper::campaign {

namespace detail {

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
        if (dispatch_tasks() || running_changed_) update_running();
        if (timed_ && !draining_ && report_.fail_fast.empty() && busy_.empty() && !queue_.empty())
            end_when_nothing_fits();
        if (timed_ && !draining_ && !busy_.empty() && seconds_to_deadline() <= options_.grace)
            stop_at_deadline();
        if (busy_.empty() && (queue_.empty() || draining_ || !report_.fail_fast.empty())) break;
        const std::chrono::milliseconds wait = wait_time();
        last_wait_ = wait;
        receive(wait);
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
    report_.stopped_running = true;
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
            log_ << "campaign: warning: '" << t.label() << "' #" << t.realization
                 << " is expected to need " << format_duration(need)
                 << ", more than this allocation's " << format_duration(allocation_)
                 << ", and checkpoints are off: it cannot finish in an allocation "
                    "this long (raise the time limit or drop --no-checkpoints)"
                 << std::endl;
        // Longer than a whole allocation like this one: it can only ever finish in pieces, so
        // with checkpoints it starts (its state is saved at the deadline) rather than never.
        if (ckpt_ && need > allocation_ && left > 0.25 * allocation_) {
            log_ << "campaign: '" << t.label() << "' #" << t.realization << " is expected to need "
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
    // Journaled before it is sent: a run that dies tells what was running (issue 44).
    const TaskRef& t = todo_[item.index];
    store_.dispatched(
        store::DispatchRecord{t.label(), t.realization, t.seed, w, item.attempt, b.started_unix});
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

// Handles the messages waiting, as one group commit of the store (issue 44): the results and
// errors of every message already waiting are journaled with one fdatasync between them
// (store::Store::commit), not one each, so that the sync no longer limits the results per
// second to one per sync latency whatever the number of workers. Checkpoint files of the
// realizations stored go once their results are durable.
void Dispatcher::receive(std::chrono::milliseconds wait) {
    if (auto msg = channel_.receive(wait)) {
        store_.begin_batch();
        handle(msg->first, msg->second);
        // Drain whatever else is already waiting before handing out more.
        while (auto more = channel_.receive(std::chrono::milliseconds(0)))
            handle(more->first, more->second);
        store_.commit();
        for (const Item& item : stored_in_batch_)
            ckpt_->remove(key_of(item));
        stored_in_batch_.clear();
    }
}

// Busy workers silent for longer than their realization's limit: reported, and the
// realization goes to the front of the queue for another worker.
//
// Silence is what the master heard while it listened. A pass of the loop that took longer than
// the wait it gave the receive, beyond a quarter of a second, is time the master itself did not
// run (SIGSTOP, a swapped or overloaded node, a store write stalled on the file system): the
// workers' messages of that time wait in the channel, some not yet matched when it looks again
// (MPI delivers a large message only as both sides make progress). That gap is credited to
// every busy worker, so that a stalled master does not hand realizations out again that run
// well (issue 44: a master stopped for 3 s with a limit of 1 s did so for both workers).
void Dispatcher::check_silence() {
    const auto now = Clock::now();
    const auto stalled = (now - last_check_) - last_wait_ - std::chrono::milliseconds(250);
    last_check_ = now;
    if (stalled > Clock::duration::zero())
        for (auto& [w, b] : busy_)
            b.heard += stalled;
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
             << ") running '" << t.label() << "' #" << t.realization << "; "
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

void Dispatcher::update_running() {
    running_changed_ = false;
    if (options_.running_file.empty()) return;
    RunningFile f;
    f.pid = static_cast<std::int64_t>(getpid());
    f.host = host_;
    f.updated_unix = store::unix_now();
    for (const auto& [w, b] : busy_) {
        const TaskRef& t = todo_[b.item.index];
        f.tasks.push_back(
            RunningTask{w, b.started_unix, b.item.attempt, b.resumed, t.realization, t.label()});
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

}  // namespace detail

Master::Master(MasterChannel& channel, store::Store& store, const StopRequests& stop,
               MasterOptions options, std::ostream& log)
    : channel_(channel), store_(store), stop_(stop), options_(options), log_(log) {}

void add_round(MasterReport& run, const MasterReport& round) {
    using R = MasterReport;
    // The counts and seconds: summed, every one in this list.
    const auto sum = [&](auto... member) { ((run.*member += round.*member), ...); };
    sum(&R::stored, &R::failed, &R::errors, &R::gave_up, &R::interrupted, &R::not_started,
        &R::reassigned, &R::late_identical, &R::late_different, &R::wall_seconds, &R::cpu_seconds,
        &R::lost_worker_seconds, &R::saved_worker_seconds, &R::checkpoints_written, &R::resumed,
        &R::deadline_skipped);
    // The state at the end: the last round's, where it has one.
    run.silent_at_end = round.silent_at_end;
    if (round.stopped) {
        run.stopped = true;
        run.stop_reason = round.stop_reason;
    }
    run.stopped_running = run.stopped_running || round.stopped_running;
    if (!round.fail_fast.empty()) run.fail_fast = round.fail_fast;
}

MasterReport Master::run(const std::vector<TaskRef>& todo, Totals totals) {
    return detail::Dispatcher(channel_, store_, stop_, options_, log_, todo, totals).run();
}

}  // namespace hopper::campaign
