#pragma once
// Stop requests: what the master does when asked to stop.
//
//   SIGUSR1, SIGINT (first)  drain: hand out no new tasks; running realizations may finish within
//                            the grace time (--grace), then they are stopped.
//   SIGTERM                  stop now: running realizations are stopped at once (they run again
//                            on resume). mpirun forwards SIGTERM to every rank and kills the job a
//                            second later; Slurm sends it at the time limit.
//   any second signal        stop now.
// Either way the master stores every result that arrives, closes the store in step with its
// journal and exits with the resumable exit code.

#include <atomic>
#include <mutex>
#include <string>

namespace hopper::campaign {

enum class StopLevel { none = 0, drain = 1, now = 2 };

class StopRequests {
  public:
    virtual ~StopRequests() = default;
    virtual StopLevel level() const = 0;
    virtual std::string reason() const = 0;  // e.g. "SIGTERM"
};

// Catches SIGINT, SIGTERM and SIGUSR1 while it exists (restores the previous handlers after).
// The handlers only set lock-free atomics. One watcher at a time per process.
class SignalWatcher : public StopRequests {
  public:
    SignalWatcher();
    ~SignalWatcher() override;
    SignalWatcher(const SignalWatcher&) = delete;
    SignalWatcher& operator=(const SignalWatcher&) = delete;
    StopLevel level() const override;
    std::string reason() const override;
    int count() const;  // signals received
};

// Stop requests made by code (tests, embedding programs).
class ManualStop : public StopRequests {
  public:
    void request(StopLevel level, std::string reason);
    StopLevel level() const override { return level_.load(); }
    std::string reason() const override;

  private:
    std::atomic<StopLevel> level_{StopLevel::none};
    mutable std::mutex mutex_;
    std::string reason_;
};

}  // namespace hopper::campaign
