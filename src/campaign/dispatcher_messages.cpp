// What each kind of worker message does to the master's run (dispatcher.hpp): results,
// failures, checkpoints and heartbeats, and the bookkeeping of results and failures.
#include "dispatcher.hpp"

namespace hopper::campaign::detail {

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
    running_changed_ = true;  // the running file is rewritten once per pass of the loop
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
            stored_in_batch_.push_back(item);  // once its result is durable
        else
            restart_without_checkpoint(item, std::string(what.substr(checkpoint_refused.size())) +
                                                 ": the checkpoint of '" +
                                                 todo_[item.index].label() + "' #" +
                                                 std::to_string(todo_[item.index].realization));
        return;
    }
    // The other copy of a reassigned realization was stored already.
    if (!finished_[item.index]) record_error(worker, item, what);
    // A state that made its realization raise must not be tried again.
    if (ckpt_ && was.resumed && !finished_[item.index]) {
        ckpt_->remove(key_of(item));
        saved_before_[item.index] = 0.0;
        log_ << "campaign: the checkpoint of '" << todo_[item.index].label() << "' #"
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
        log_ << "campaign: '" << todo_[item.index].label() << "' #" << todo_[item.index].realization
             << " stopped after " << format_duration(m.seconds) << " on worker " << worker
             << "; its state is saved and continues on resume" << std::endl;
    } else {
        const double thrown = std::max(0.0, m.seconds - was.saved_seconds);
        report_.lost_worker_seconds += thrown;
        report_.saved_worker_seconds += m.seconds - thrown;
        log_ << "campaign: '" << todo_[item.index].label() << "' #" << todo_[item.index].realization
             << " stopped after " << format_duration(m.seconds) << " on worker " << worker << "; "
             << format_duration(thrown) << " of its worker time is thrown away ("
             << (ckpt_ ? "its state at the stop was not saved" : "checkpoints are off") << "); "
             << (was.saved_seconds > 0 ? "it continues from its last checkpoint on resume"
                                       : "it starts from the beginning on resume")
             << std::endl;
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
        restart_without_checkpoint(item, "'" + t.label() + "' #" + std::to_string(t.realization) +
                                             " failed after continuing from its checkpoint (" +
                                             r.message + "); the checkpoint");
        return;
    }
    if (finished_[item.index]) {
        const bool same = store::physics_digest(r) == digest_[item.index];
        ++(same ? report_.late_identical : report_.late_different);
        log_ << "campaign: " << (same ? "" : "warning: ") << "the second result of '" << t.label()
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
    store_.append(store::ResultRecord{t.label(), t.realization, t.seed, worker, item.attempt,
                                      seconds, store::unix_now(), m.payload});
    finished_[item.index] = 1;
    if (ckpt_) stored_in_batch_.push_back(item);  // its file goes once the result is durable
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
    if (++early_failures_[{t.label(), shape}] < options_.fail_fast_after) return;
    report_.fail_fast = std::to_string(options_.fail_fast_after) + " realizations of '" +
                        t.label() + "' failed the same way before the outlet opened (the last: #" +
                        std::to_string(t.realization) + ", " + r.message + ")";
    log_ << "campaign: failing fast: " << report_.fail_fast << "; handing out no more tasks"
         << (busy_.empty() ? "" : " (running ones finish)") << std::endl;
}

// An attempt that raised: logged in the store, retried once more unless draining or out of
// attempts.
void Dispatcher::record_error(int worker, const Item& item, const std::string& reason) {
    const TaskRef& t = todo_[item.index];
    store_.append(store::ErrorRecord{t.label(), t.realization, t.seed, worker, item.attempt,
                                     store::unix_now(), reason});
    ++report_.errors;
    ++errors_[item.index];
    if (errors_[item.index] < options_.max_attempts && !draining_) {
        log_ << "campaign: '" << t.label() << "' #" << t.realization << " raised an error on "
             << "worker " << worker << " (" << reason << "); trying once more" << std::endl;
        queue_.push_front({item.index, item.attempt + 1});
    } else {
        ++report_.gave_up;
        ++failed_now_;
        log_ << "campaign: '" << t.label() << "' #" << t.realization << " failed "
             << errors_[item.index] << " time(s) (" << reason << "); left for the next run"
             << std::endl;
    }
}

CheckpointKey Dispatcher::key_of(const Item& item) const {
    const TaskRef& t = todo_[item.index];
    return CheckpointKey{t.label(), t.realization, t.seed, t.physics};
}

bool Dispatcher::save_state(int worker, const Item& item, double seconds,
                            std::span<const std::uint8_t> state) {
    try {
        ckpt_->write(key_of(item), seconds, state);
        ++report_.checkpoints_written;
        return true;
    } catch (const core::StoreError& e) {
        log_ << "campaign: warning: the state of '" << todo_[item.index].label() << "' #"
             << todo_[item.index].realization << " from worker " << worker
             << " could not be saved (" << e.what() << "); it will start over" << std::endl;
        return false;
    }
}

}  // namespace hopper::campaign::detail
