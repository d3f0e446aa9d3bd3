#pragma once
// A worker: runs the tasks the master hands it until told to quit. Workers only simulate; they
// never touch the store.
//
// The realization runs in a thread of its own while the calling thread (the only one that uses
// the channel, so MPI needs just MPI_THREAD_FUNNELED) watches the channel: a stop or quit from
// the master is acted on at the next time step however long a step takes, and a heartbeat goes
// to the master every heartbeat_interval seconds while the realization advances. A worker that
// stops sending them (a hung node, a stopped process, a computation that no longer advances) is
// found by the master, which hands its realization to another worker.

#include <cstdint>
#include <functional>
#include <span>

#include "hopper/campaign/channel.hpp"
#include "hopper/engine/realization.hpp"

namespace hopper::campaign {

// Runs task `task_id` with the given hooks (the stop flag and the progress callback through which
// the worker watches for a stop message). Exceptions are reported to the master as errors.
using TaskRunner = std::function<engine::RealizationResult(int task_id, const engine::RunHooks&)>;
// The same, continuing from a saved engine state when `state` is not empty
// (engine::resume_realization).
using ResumableTaskRunner = std::function<engine::RealizationResult(
    int task_id, std::span<const std::uint8_t> state, const engine::RunHooks&)>;

struct WorkerOptions {
    // Wall-clock seconds between heartbeats while a realization advances (0: none).
    double heartbeat_interval = 10.0;
    // Longest wait of the watching thread between looks at the channel and the realization.
    double watch_interval = 0.02;
    // Checkpoints (issue 15): when on, a stop_now is answered with the realization's state
    // (saved at its next time step, then it stops), and every checkpoint_interval seconds of
    // wall time (0: never) the running realization's state goes to the master.
    bool checkpoints = false;
    double checkpoint_interval = 0.0;
};

// The heartbeat interval that suits a master's silence limit: a few per limit, at most every 10 s.
double heartbeat_interval_for(double worker_timeout);

// Returns when the master sends quit (at once if it arrives during a task: the task is stopped
// and nothing is sent back, since the master is no longer listening).
void run_worker(WorkerChannel& channel, const ResumableTaskRunner& run, WorkerOptions options = {});
// A runner that cannot resume: a state sent with a task is ignored (the realization starts over).
void run_worker(WorkerChannel& channel, const TaskRunner& run, WorkerOptions options = {});

}  // namespace hopper::campaign
