#pragma once
// Hybrid runs (issue 15): under MPI with --threads T, every worker rank runs T realizations at
// once, in T worker threads (run_worker, each in a thread of its own). The rank's main thread
// relays messages between the master (the MPI channel; it alone calls MPI, as
// MPI_THREAD_FUNNELED requires) and its threads (in-process channels), by the message's slot.
// The master sees (ranks - 1) x T workers: worker w is slot (w - 1) % T of rank (w - 1) / T + 1.
// Results are bit-identical whatever the split: every realization depends only on its task.

#include <memory>

#include "hopper/campaign/channel.hpp"
#include "hopper/campaign/worker.hpp"

namespace hopper::campaign {

// The master's view of `inner` (one worker per rank) with `threads` workers per rank.
std::unique_ptr<MasterChannel> slotted_master(MasterChannel& inner, int threads);

// A worker rank: runs `threads` workers and relays until the master sends quit.
void run_hybrid_worker(WorkerChannel& channel, int threads, const ResumableTaskRunner& run,
                       WorkerOptions options);

}  // namespace hopper::campaign
