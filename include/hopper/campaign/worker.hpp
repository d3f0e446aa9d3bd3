#pragma once
// A worker: runs the tasks the master hands it until told to quit. Workers only simulate; they
// never touch the store.

#include <functional>

#include "hopper/campaign/channel.hpp"
#include "hopper/engine/realization.hpp"

namespace hopper::campaign {

// Runs task `task_id` with the given hooks (the stop flag and the progress callback through which
// the worker watches for a stop message). Exceptions are reported to the master as errors.
using TaskRunner = std::function<engine::RealizationResult(int task_id, const engine::RunHooks&)>;

struct WorkerOptions {
    // Simulated seconds between looks for a stop message while a realization runs.
    double poll_interval = 0.005;
};

// Returns when the master sends quit (at once if it arrives during a task: the task is stopped
// and nothing is sent back, since the master is no longer listening).
void run_worker(WorkerChannel& channel, const TaskRunner& run, WorkerOptions options = {});

}  // namespace hopper::campaign
