#pragma once
// The in-process channel: the master and its workers are threads of one process, talking through
// queues guarded by a mutex and condition variables (blocking waits, no spinning). Used by
// `campaign run` without mpirun (one worker thread beside the master) and by the unit tests.

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

#include "hopper/campaign/channel.hpp"

namespace hopper::campaign {

class InProcessChannels {
  public:
    // Workers numbered first_id, first_id + 1, ...
    explicit InProcessChannels(int workers, int first_id = 1);
    ~InProcessChannels();
    InProcessChannels(const InProcessChannels&) = delete;
    InProcessChannels& operator=(const InProcessChannels&) = delete;

    MasterChannel& master();
    WorkerChannel& worker(int index);  // 0-based index
    int workers() const;

    // Messages sent so far in each direction (for tests).
    std::size_t sent_to_workers() const;
    std::size_t sent_to_master() const;

  private:
    struct Shared;
    class Master;
    class Worker;
    std::shared_ptr<Shared> shared_;
    std::unique_ptr<Master> master_;
    std::vector<std::unique_ptr<Worker>> workers_;
};

}  // namespace hopper::campaign
