#pragma once
// MPI, behind the channel interface. src/campaign/mpi.cpp is the only translation unit that
// includes <mpi.h>; nothing here exposes MPI types.
//
// Waiting never spins: a receive polls MPI_Iprobe and sleeps between polls (every ~20 us for the
// first 2 ms, then doubling up to 2 ms), because Open MPI's blocking MPI_Recv busy-polls a core
// -- which would take the core from a worker when ranks outnumber cores (--oversubscribe).

#include <memory>
#include <string>
#include <vector>

#include "hopper/campaign/channel.hpp"

namespace hopper::campaign {

// Whether this process was started by an MPI launcher (mpirun, mpiexec, srun with PMI/PMIx).
// Without one, `campaign run` does not initialise MPI at all.
bool launched_by_mpi();

class MpiSession {
  public:
    MpiSession();   // MPI_Init; throws std::runtime_error when it fails
    ~MpiSession();  // MPI_Finalize
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    // Collective: the host name of every rank, in rank order, on rank 0 (empty elsewhere).
    std::vector<std::string> hosts() const;
    // Collective: true when `mine` is true on every rank.
    bool all_ok(bool mine) const;
    // The master's channel (rank 0; workers are ranks 1..size-1) and a worker's.
    std::unique_ptr<MasterChannel> master_channel() const;
    std::unique_ptr<WorkerChannel> worker_channel() const;
    // MPI_Abort: ends every rank (used when the master fails while workers are busy).
    [[noreturn]] void abort(int code) const;

  private:
    struct Impl;  // the campaign's communicator (an MPI type)
    std::unique_ptr<Impl> impl_;
    int rank_ = 0;
    int size_ = 1;
};

}  // namespace hopper::campaign
