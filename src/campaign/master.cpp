#include "hopper/campaign/master.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <deque>
#include <map>
#include <set>

#include <unistd.h>

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

Clock::duration to_duration(double seconds) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace

Master::Master(MasterChannel& channel, store::Store& store, const StopRequests& stop,
               MasterOptions options, std::ostream& log)
    : channel_(channel), store_(store), stop_(stop), options_(options), log_(log) {}

MasterReport Master::run(const std::vector<TaskRef>& todo, Totals totals) {
    const auto start = Clock::now();
    const double cpu0 = thread_cpu_seconds();
    MasterReport report;
    std::deque<Item> queue;
    for (std::size_t i = 0; i < todo.size(); ++i)
        queue.push_back({i, 1});
    std::vector<int> errors(todo.size(), 0);
    std::deque<int> idle;
    for (int w = 1; w <= channel_.workers(); ++w)
        idle.push_back(w);
    std::map<int, Busy> busy;
    std::map<int, Item> lost;  // silent workers and the realization they were running
    std::set<int> revived;     // lost workers heard from again (reported once)
    std::vector<char> finished(todo.size(), 0);    // a result was stored by this run
    std::vector<char> reassigned(todo.size(), 0);  // handed to another worker after a silence
    std::map<std::size_t, std::uint64_t> digest;   // reassigned and stored: physics digest

    bool draining = false, stop_sent = false, stop_announced = false;
    Clock::time_point drain_deadline{};
    const bool progress = options_.progress_interval > 0;
    const auto interval = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(progress ? options_.progress_interval : 1e9));
    auto next_progress = start + interval;
    int failed_now = totals.failed;
    // ETA weighted by the cost model, corrected by the worker seconds measured so far. The cost
    // model's expected_seconds assume a pessimistic 100 ns per particle-step; 0.5 of that is the
    // prior until a realization has finished.
    CostEta eta(channel_.workers(), 0.5);
    bool costs_known = true;
    for (const auto& t : todo) {
        eta.add_pending(t.expected_seconds);
        costs_known = costs_known && t.expected_seconds > 0;
    }

    // Checkpoint files and the running file.
    CheckpointFiles* const ckpt = options_.checkpoints;
    auto key_of = [&](const Item& item) {
        const TaskRef& t = todo[item.index];
        return CheckpointKey{t.label, t.realization, t.seed, t.physics};
    };
    auto save_state = [&](int worker, const Item& item, double seconds,
                          std::span<const std::uint8_t> state) {
        try {
            ckpt->write(key_of(item), seconds, state);
            ++report.checkpoints_written;
            return true;
        } catch (const core::StoreError& e) {
            log_ << "campaign: warning: the state of '" << todo[item.index].label << "' #"
                 << todo[item.index].realization << " from worker " << worker
                 << " could not be saved (" << e.what() << "); it will start over" << std::endl;
            return false;
        }
    };
    char host[256] = {};
    if (gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "unknown");
    auto update_running = [&] {
        if (options_.running_file.empty()) return;
        RunningFile f;
        f.pid = static_cast<std::int64_t>(getpid());
        f.host = host;
        f.updated_unix = store::unix_now();
        for (const auto& [w, b] : busy) {
            const TaskRef& t = todo[b.item.index];
            f.tasks.push_back(
                RunningTask{w, b.started_unix, b.item.attempt, b.resumed, t.realization, t.label});
        }
        write_running(options_.running_file, f);
    };
    // Expected seconds of a task: the cost model corrected by the measured durations.
    double measured_seconds = options_.measured_seconds;
    double measured_expected = options_.measured_expected;
    auto correction = [&] {
        return measured_expected > 0 && measured_seconds > 0 ? measured_seconds / measured_expected
                                                             : 1.0;
    };
    std::vector<double> saved_before(todo.size(), 0.0);  // seconds in a checkpoint file
    if (ckpt)
        for (std::size_t i = 0; i < todo.size(); ++i)
            saved_before[i] = ckpt->peek_seconds(key_of(Item{i, 1})).value_or(0.0);
    const bool timed = options_.deadline.has_value();
    bool told_unmeasured = false;
    std::set<std::size_t> hopeless;  // tasks warned about: longer than the allocation
    // Seconds this run may compute: from its start to the deadline minus the grace.
    const double allocation =
        timed ? *options_.deadline - store::unix_now() - options_.grace : 1e300;
    auto seconds_to_deadline = [&] {
        return timed ? *options_.deadline - store::unix_now() : 1e300;
    };

    auto print_progress = [&] {
        const double elapsed = seconds_since(start);
        const double rate = elapsed > 0 ? report.stored / elapsed : 0.0;
        log_ << progress_line(totals.finished + report.stored, totals.total,
                              static_cast<int>(busy.size()), failed_now, rate, elapsed,
                              costs_known ? eta.seconds_left() : -1.0)
             << std::endl;
    };

    auto silence_limit = [&](const Item& item) {
        const double s =
            options_.worker_timeout
                ? *options_.worker_timeout
                : std::max(options_.min_worker_timeout,
                           options_.worker_timeout_factor * todo[item.index].expected_seconds);
        return to_duration(s);
    };

    auto record_error = [&](int worker, const Item& item, const std::string& reason) {
        const TaskRef& t = todo[item.index];
        store_.append(store::ErrorRecord{t.label, t.realization, t.seed, worker, item.attempt,
                                         store::unix_now(), reason});
        ++report.errors;
        ++errors[item.index];
        if (errors[item.index] < options_.max_attempts && !draining) {
            log_ << "campaign: '" << t.label << "' #" << t.realization << " raised an error on "
                 << "worker " << worker << " (" << reason << "); trying once more" << std::endl;
            queue.push_front({item.index, item.attempt + 1});
        } else {
            ++report.gave_up;
            ++failed_now;
            log_ << "campaign: '" << t.label << "' #" << t.realization << " failed "
                 << errors[item.index] << " time(s) (" << reason << "); left for the next run"
                 << std::endl;
        }
    };

    // A result for item from worker: checked, then stored unless this run stored one already
    // (a reassigned realization), in which case it is compared with it.
    auto accept_result = [&](int worker, const Item& item, const Message& m) {
        const TaskRef& t = todo[item.index];
        engine::RealizationResult r;
        try {
            r = store::decode_result(m.payload, "result from worker " + std::to_string(worker));
            if (r.seed != t.seed)
                throw core::StoreError("result from worker " + std::to_string(worker) +
                                       " has seed " + std::to_string(r.seed) + ", expected " +
                                       std::to_string(t.seed));
        } catch (const core::StoreError& e) {
            if (!finished[item.index]) record_error(worker, item, e.what());
            return;
        }
        if (finished[item.index]) {
            const bool same = store::physics_digest(r) == digest[item.index];
            ++(same ? report.late_identical : report.late_different);
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
        const double seconds = m.seconds + saved_before[item.index];
        store_.append(store::ResultRecord{t.label, t.realization, t.seed, worker, item.attempt,
                                          seconds, store::unix_now(), m.payload});
        finished[item.index] = 1;
        if (ckpt) ckpt->remove(key_of(item));
        if (t.expected_seconds > 0 && seconds > 0) {
            measured_seconds += seconds;
            measured_expected += t.expected_seconds;
        }
        if (reassigned[item.index]) digest[item.index] = store::physics_digest(r);
        ++report.stored;
        eta.finished(t.expected_seconds, seconds);
        if (r.status == engine::Status::failed) {
            ++report.failed;
            ++failed_now;
        }
    };

    auto handle = [&](int worker, const Message& m) {
        if (m.kind == MessageKind::checkpoint) {
            const auto it = busy.find(worker);
            if (!ckpt || it == busy.end() || todo[it->second.item.index].task_id != m.task) return;
            it->second.heard = Clock::now();
            if (save_state(worker, it->second.item, it->second.base_seconds + m.seconds, m.payload))
                it->second.saved_seconds = m.seconds;
            return;
        }
        if (m.kind == MessageKind::heartbeat) {
            if (const auto it = busy.find(worker); it != busy.end())
                it->second.heard = Clock::now();
            else if (lost.count(worker) && revived.insert(worker).second)
                log_ << "campaign: worker " << worker << " is heard from again; its realization "
                     << "runs elsewhere too (the first result is stored, the other compared)"
                     << std::endl;
            return;
        }
        if (const auto lt = lost.find(worker); lt != lost.end()) {
            // The late reply of a realization that was handed to another worker.
            const Item item = lt->second;
            lost.erase(lt);
            revived.erase(worker);
            idle.push_back(worker);
            if (todo[item.index].task_id == m.task && m.kind == MessageKind::result)
                accept_result(worker, item, m);
            return;
        }
        const auto it = busy.find(worker);
        if (it == busy.end() || todo[it->second.item.index].task_id != m.task) {
            log_ << "campaign: warning: unexpected message from worker " << worker << " (task "
                 << m.task << "); ignored" << std::endl;
            return;
        }
        const Item item = it->second.item;
        const Busy was = it->second;
        busy.erase(it);
        idle.push_back(worker);
        update_running();
        switch (m.kind) {
            case MessageKind::result:
                accept_result(worker, item, m);
                break;
            case MessageKind::error:
                // The other copy of a reassigned realization was stored already.
                if (!finished[item.index])
                    record_error(worker, item, std::string(m.payload.begin(), m.payload.end()));
                // A state that made its realization raise must not be tried again.
                if (ckpt && was.resumed && !finished[item.index]) {
                    ckpt->remove(key_of(item));
                    saved_before[item.index] = 0.0;
                    log_ << "campaign: the checkpoint of '" << todo[item.index].label << "' #"
                         << todo[item.index].realization
                         << " is removed: the next attempt starts from the beginning" << std::endl;
                }
                break;
            case MessageKind::interrupted:
                if (finished[item.index]) break;
                ++report.interrupted;
                if (ckpt && !m.payload.empty() &&
                    save_state(worker, item, was.base_seconds + m.seconds, m.payload)) {
                    report.saved_worker_seconds += m.seconds;
                    saved_before[item.index] = was.base_seconds + m.seconds;
                    log_ << "campaign: '" << todo[item.index].label << "' #"
                         << todo[item.index].realization << " stopped after "
                         << format_duration(m.seconds) << " on worker " << worker
                         << "; its state is saved and continues on resume" << std::endl;
                } else {
                    const double thrown = std::max(0.0, m.seconds - was.saved_seconds);
                    report.lost_worker_seconds += thrown;
                    report.saved_worker_seconds += m.seconds - thrown;
                }
                break;
            default:
                log_ << "campaign: warning: worker " << worker << " sent message kind "
                     << static_cast<int>(m.kind) << "; ignored" << std::endl;
        }
    };

    // Busy workers silent for longer than their realization's limit: reported, and the
    // realization goes to the front of the queue for another worker.
    auto check_silence = [&] {
        const auto now = Clock::now();
        for (auto it = busy.begin(); it != busy.end();) {
            const Item item = it->second.item;
            const auto limit = silence_limit(item);
            if (now - it->second.heard <= limit) {
                ++it;
                continue;
            }
            const TaskRef& t = todo[item.index];
            log_ << "campaign: worker " << it->first << " has been silent for "
                 << format_duration(std::chrono::duration<double>(now - it->second.heard).count())
                 << " (limit " << format_duration(std::chrono::duration<double>(limit).count())
                 << ") running '" << t.label << "' #" << t.realization << "; "
                 << (draining ? "it runs again on resume" : "handing it to another worker")
                 << std::endl;
            lost[it->first] = item;
            reassigned[item.index] = 1;
            ++report.reassigned;
            if (!draining) queue.push_front({item.index, item.attempt + 1});
            it = busy.erase(it);
        }
    };

    for (;;) {
        const StopLevel level = stop_.level();
        if (level != StopLevel::none && !draining) {
            draining = true;
            report.stopped = true;
            report.stop_reason = stop_.reason();
            // With a deadline the running realizations were started because they are expected
            // to end before deadline - grace: a drain (Slurm's warning signal comes with up to a
            // minute's jitter) lets them go on until then, at least the grace time.
            const double until =
                timed ? std::max(options_.grace, seconds_to_deadline() - options_.grace)
                      : options_.grace;
            drain_deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(until));
            if (ckpt && level == StopLevel::drain)
                for (const auto& [w, b] : busy)
                    channel_.send(
                        w, Message::make(MessageKind::checkpoint_now, todo[b.item.index].task_id));
            log_ << "campaign: " << report.stop_reason << ": handing out no more tasks";
            if (!busy.empty()) {
                if (level == StopLevel::now) {
                    log_ << "; stopping the " << busy.size() << " running realization(s) now";
                    stop_announced = true;
                } else
                    log_ << "; the " << busy.size() << " running realization(s) may finish within "
                         << format_duration(until) << " (signal again to stop them now)";
            }
            log_ << std::endl;
        }
        if (draining && !stop_sent && !busy.empty() &&
            (stop_.level() == StopLevel::now || Clock::now() >= drain_deadline)) {
            if (!stop_announced)
                log_ << "campaign: stopping the " << busy.size() << " running realization(s)"
                     << std::endl;
            for (const auto& [w, b] : busy)
                channel_.send(w, Message::make(MessageKind::stop_now, todo[b.item.index].task_id));
            stop_sent = true;
        }
        bool dispatched = false;
        while (!draining && !idle.empty() && !queue.empty()) {
            // With a deadline: the first task (most expensive first) expected to end in time.
            // Until something of this campaign is measured the cost model's seconds are a guess
            // (off by 2x either way); skipping on a guess could start nothing, allocation after
            // allocation. So the estimate filters only once a result has been measured.
            auto pick = queue.begin();
            const bool measured = measured_expected > 0 && measured_seconds > 0;
            if (timed && !measured && !told_unmeasured) {
                told_unmeasured = true;
                log_ << "campaign: nothing of this campaign is measured yet: realizations are "
                        "handed out until the deadline minus the grace, when running ones are "
                        "stopped; the deadline's estimates start with the first result"
                     << std::endl;
            }
            if (timed && measured) {
                const double left = seconds_to_deadline() - options_.grace;
                for (; pick != queue.end(); ++pick) {
                    const TaskRef& t = todo[pick->index];
                    const double need = std::max(
                        0.0, t.expected_seconds * correction() - saved_before[pick->index]);
                    if (need <= left) break;
                    if (!ckpt && need > allocation && hopeless.insert(pick->index).second)
                        log_ << "campaign: warning: '" << t.label << "' #" << t.realization
                             << " is expected to need " << format_duration(need)
                             << ", more than this allocation's " << format_duration(allocation)
                             << ", and checkpoints are off: it cannot finish in an allocation "
                                "this long (raise the time limit or drop --no-checkpoints)"
                             << std::endl;
                    // Longer than a whole allocation like this one: it can only ever finish in
                    // pieces, so with checkpoints it starts (its state is saved at the
                    // deadline) rather than never.
                    if (ckpt && need > allocation && left > 0.25 * allocation) {
                        log_ << "campaign: '" << t.label << "' #" << t.realization
                             << " is expected to need " << format_duration(need)
                             << ", more than this allocation's " << format_duration(allocation)
                             << "; started anyway: its state is saved at the deadline" << std::endl;
                        break;
                    }
                }
                if (pick == queue.end()) break;
            }
            const Item item = *pick;
            queue.erase(pick);
            const int w = idle.front();
            idle.pop_front();
            Message task = Message::make(MessageKind::task, todo[item.index].task_id, item.attempt);
            Busy b{item, Clock::now(), store::unix_now()};
            if (ckpt) {
                std::string refusal;
                if (auto loaded = ckpt->read(key_of(item), &refusal)) {
                    task.payload = std::move(loaded->state);
                    b.resumed = true;
                    b.base_seconds = loaded->worker_seconds;
                    saved_before[item.index] = loaded->worker_seconds;
                    ++report.resumed;
                } else {
                    saved_before[item.index] = 0.0;
                    if (!refusal.empty()) log_ << "campaign: " << refusal << std::endl;
                }
            }
            channel_.send(w, task);
            busy[w] = b;
            dispatched = true;
        }
        if (dispatched) update_running();
        if (timed && !draining && busy.empty() && !queue.empty()) {
            // Nothing left fits before the deadline: end the run as stopped (resumable).
            draining = true;
            report.stopped = true;
            report.stop_reason = "the deadline";
            report.deadline_skipped = static_cast<int>(queue.size());
            log_ << "campaign: the deadline is "
                 << format_duration(std::max(0.0, seconds_to_deadline())) << " away (grace "
                 << format_duration(options_.grace) << "): none of the " << queue.size()
                 << " realization(s) left is expected to finish before it "
                 << "(the shortest needs about "
                 << format_duration(todo[queue.back().index].expected_seconds * correction())
                 << "); they run in the next allocation" << std::endl;
        }
        if (timed && !draining && !busy.empty() && seconds_to_deadline() <= options_.grace) {
            draining = true;
            report.stopped = true;
            report.stop_reason = "the deadline";
            report.deadline_skipped = static_cast<int>(queue.size());
            log_ << "campaign: the deadline is "
                 << format_duration(std::max(0.0, seconds_to_deadline())) << " away: stopping the "
                 << busy.size() << " running realization(s)"
                 << (ckpt ? " (their states are saved)" : "") << std::endl;
            for (const auto& [w, b] : busy)
                channel_.send(w, Message::make(MessageKind::stop_now, todo[b.item.index].task_id));
            stop_sent = stop_announced = true;
        }
        if (busy.empty() && (queue.empty() || draining)) break;

        auto wait = options_.max_wait;
        const auto now = Clock::now();
        auto bound = [&](Clock::time_point t) {
            if (t > now)
                wait = std::min(wait, std::chrono::ceil<std::chrono::milliseconds>(t - now));
            else
                wait = std::chrono::milliseconds(0);
        };
        if (progress) bound(next_progress);
        if (draining && !stop_sent) bound(drain_deadline);
        if (timed && !draining)
            bound(now + to_duration(std::max(0.0, seconds_to_deadline() - options_.grace)));
        for (const auto& [w, b] : busy)
            bound(b.heard + silence_limit(b.item) + std::chrono::milliseconds(1));
        if (auto msg = channel_.receive(wait)) {
            handle(msg->first, msg->second);
            // Drain whatever else is already waiting before handing out more.
            while (auto more = channel_.receive(std::chrono::milliseconds(0)))
                handle(more->first, more->second);
        }
        check_silence();
        if (progress && Clock::now() >= next_progress) {
            print_progress();
            next_progress += interval;
        }
    }
    report.not_started = static_cast<int>(queue.size());
    if (ckpt) ckpt->remove_dir_if_empty();
    if (!options_.running_file.empty()) {
        std::error_code ec;
        std::filesystem::remove(options_.running_file, ec);
    }
    report.silent_at_end = static_cast<int>(lost.size());
    report.wall_seconds = seconds_since(start);
    report.cpu_seconds = thread_cpu_seconds() - cpu0;
    if (progress) print_progress();
    return report;
}

}  // namespace hopper::campaign
