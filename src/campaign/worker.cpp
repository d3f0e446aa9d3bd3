#include "hopper/campaign/worker.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "hopper/store/codec.hpp"

namespace hopper::campaign {

namespace {

using Clock = std::chrono::steady_clock;

// Thrown by the progress hook when a stop was requested: it unwinds the realization at once
// (the engine itself looks at the stop flag only every few hundred steps, which on a scene of
// millions of particles is half a minute).
struct Interrupted {};

// A progress interval shorter than any time step: the engine calls the hook after every step.
constexpr double every_step = 1e-12;

Message error_reply(const Message& task, const std::string& what) {
    Message reply = Message::make(MessageKind::error, task.task, task.attempt);
    reply.payload.assign(what.begin(), what.end());
    return reply;
}

// Shared by the watching thread and the computing thread, which may outlive the watching loop
// when told to quit while its realization hangs (it is then left behind, detached).
struct Shared {
    std::atomic<bool> stop{false};
    std::atomic<std::uint64_t> steps{0};
    // Checkpoints: a request the engine looks at every step; with stop_after_checkpoint the
    // realization stops right after saving (a drain or a stop).
    std::atomic<bool> checkpoint_request{false};
    std::atomic<bool> stop_after_checkpoint{false};
    std::mutex mutex;
    std::condition_variable done_cv;
    bool done = false;
    Message reply;
    std::vector<std::uint8_t> state;  // the last state saved and not yet sent
    bool state_ready = false;
    double state_seconds = 0.0;  // wall seconds of the task when it was saved
};

// Runs one task on the calling thread; the reply to send (without its duration).
Message run_task(const Message& m, const ResumableTaskRunner& run, Shared& sh,
                 std::chrono::steady_clock::time_point t0, bool checkpoints) {
    engine::RunHooks hooks;
    hooks.stop = &sh.stop;
    hooks.progress_interval = every_step;
    hooks.on_progress = [&](const engine::Progress&) {
        sh.steps.fetch_add(1, std::memory_order_relaxed);
        if (sh.stop.load(std::memory_order_relaxed)) throw Interrupted{};
    };
    if (checkpoints) {
        hooks.checkpoint_request = &sh.checkpoint_request;
        hooks.on_checkpoint = [&](std::vector<std::uint8_t>&& bytes) {
            {
                std::lock_guard lock(sh.mutex);
                sh.state = std::move(bytes);
                sh.state_ready = true;
                sh.state_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
            }
            if (sh.stop_after_checkpoint.load()) throw Interrupted{};
        };
    }
    Message reply = Message::make(MessageKind::result, m.task, m.attempt);
    try {
        const engine::RealizationResult r = run(m.task, m.payload, hooks);
        // Stopped early: the engine ends it as failed ("interrupted"). A realization that
        // finished before it saw the request is a result like any other.
        if (sh.stop && r.status == engine::Status::failed)
            reply.kind = MessageKind::interrupted;
        else
            reply.payload = store::encode_result(r);
    } catch (const Interrupted&) {
        reply.kind = MessageKind::interrupted;
        if (sh.stop_after_checkpoint.load()) {
            std::lock_guard lock(sh.mutex);
            if (sh.state_ready) {
                reply.payload = std::move(sh.state);
                sh.state_ready = false;
            }
        }
    } catch (const std::bad_alloc& e) {
        // A memory limit (ulimit, a cgroup without the OOM killer, Slurm's --mem) below what the
        // scene needs: said as such, not as the bare "std::bad_alloc" (issue 44).
        reply = error_reply(m, std::string("out of memory (") + e.what() +
                                   "): the worker could not allocate what this realization "
                                   "needs; raise the memory limit of the worker processes "
                                   "(ulimit -d/-v, Slurm's --mem) or give them more memory each");
    } catch (const std::exception& e) {
        reply = error_reply(m, e.what());
    } catch (...) {
        reply = error_reply(m, "unknown exception");
    }
    return reply;
}

}  // namespace

double heartbeat_interval_for(double worker_timeout) {
    return std::clamp(worker_timeout / 4.0, 0.05, 10.0);
}

void run_worker(WorkerChannel& channel, const TaskRunner& run, WorkerOptions options) {
    const ResumableTaskRunner fresh = [&run](int task, std::span<const std::uint8_t>,
                                             const engine::RunHooks& hooks) {
        return run(task, hooks);
    };
    run_worker(channel, fresh, options);
}

void run_worker(WorkerChannel& channel, const ResumableTaskRunner& run, WorkerOptions options) {
    const auto beat = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(options.heartbeat_interval));
    const auto watch = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(options.watch_interval));
    for (;;) {
        const Message m = channel.receive();
        if (m.kind == MessageKind::quit) return;
        if (m.kind != MessageKind::task) continue;  // a stop_now that came after the task ended

        const auto sh = std::make_shared<Shared>();
        const auto t0 = Clock::now();
        const bool checkpoints = options.checkpoints;
        std::thread compute([sh, m, &run, t0, checkpoints] {
            Message r = run_task(m, run, *sh, t0, checkpoints);
            {
                std::lock_guard lock(sh->mutex);
                sh->reply = std::move(r);
                sh->done = true;
            }
            sh->done_cv.notify_one();
        });
        auto finished_within = [&](Clock::duration d) {
            std::unique_lock lock(sh->mutex);
            return sh->done_cv.wait_for(lock, d, [&] { return sh->done; });
        };
        bool quit = false;
        std::uint64_t steps_at_beat = 0;
        auto next_beat = t0 + beat;
        const auto every = std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(options.checkpoint_interval));
        const bool periodic = options.checkpoints && options.checkpoint_interval > 0;
        auto next_checkpoint = t0 + every;
        while (!quit && !finished_within(watch)) {
            while (auto msg = channel.poll()) {
                if (msg->kind == MessageKind::stop_now) {
                    if (options.checkpoints) {
                        // Saved at the next time step, then the realization stops.
                        sh->stop_after_checkpoint = true;
                        sh->checkpoint_request = true;
                    } else {
                        sh->stop = true;
                    }
                }
                if (msg->kind == MessageKind::checkpoint_now && options.checkpoints)
                    sh->checkpoint_request = true;
                if (msg->kind == MessageKind::quit) {
                    sh->stop = true;
                    quit = true;
                }
            }
            if (periodic && Clock::now() >= next_checkpoint) {
                sh->checkpoint_request = true;
                next_checkpoint = Clock::now() + every;
            }
            // A state saved while the realization goes on: to the master, which writes it.
            if (options.checkpoints && !sh->stop_after_checkpoint) {
                Message ck = Message::make(MessageKind::checkpoint, m.task, m.attempt);
                {
                    std::lock_guard lock(sh->mutex);
                    if (sh->state_ready && !sh->done) {
                        ck.payload = std::move(sh->state);
                        ck.seconds = sh->state_seconds;
                        sh->state_ready = false;
                    }
                }
                if (!ck.payload.empty()) channel.send(ck);
            }
            // A heartbeat only while the realization advances: a computation that hangs goes
            // silent like a stopped node.
            if (options.heartbeat_interval > 0 && Clock::now() >= next_beat) {
                const std::uint64_t now_steps = sh->steps.load(std::memory_order_relaxed);
                if (now_steps != steps_at_beat)
                    channel.send(Message::make(MessageKind::heartbeat, m.task, m.attempt));
                steps_at_beat = now_steps;
                next_beat = Clock::now() + beat;
            }
        }
        if (quit) {
            // The master no longer listens. A realization stops at its next step; one that
            // does not within a few seconds hangs and is left behind.
            if (finished_within(std::chrono::seconds(5)))
                compute.join();
            else
                compute.detach();
            return;
        }
        compute.join();
        Message reply = std::move(sh->reply);
        reply.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        channel.send(reply);
    }
}

}  // namespace hopper::campaign
