#pragma once
// What people read: the progress line, durations, the per-point summary table.

#include <ostream>
#include <string>
#include <vector>

#include "hopper/store/store.hpp"

namespace hopper::campaign {

// "45s", "12m05s", "3h07m", "2d04h".
std::string format_duration(double seconds);

// "campaign: 12/40 done, 2 running, 1 failed, 0.21/s, ETA 2m13s, elapsed 57s"
// `eta_seconds` < 0: the time left from the count of realizations and the rate.
std::string progress_line(int done, int total, int running, int failed, double rate, double elapsed,
                          double eta_seconds = -1.0);

// A realization being computed, for CostEta::seconds_left: its expected cost and the worker
// seconds it has run (those of the checkpoint it continued from included).
struct RunningCost {
    double cost = 0.0;
    double elapsed = 0.0;
};

// The time left, weighted by the cost model: the queued tasks' expected costs (expected_cost in
// plan.hpp: particle-steps, or a multiple of them) times the measured worker seconds per cost
// unit, plus each running task's expected cost less what it has run, over the workers. Before
// any task has finished, `prior_seconds_per_cost` (the cost model's prior, plan.hpp), so there
// is an estimate from the start; unlike a count of realizations it does not mislead when the
// most expensive tasks run first. The speed is measured on what finished tasks actually
// computed (`done_cost`: the engine's particle-steps) when it is known, so realizations that
// ended early (arrested after a few jams) do not make the others look cheap.
// `campaign status` and the master's progress line use it.
class CostEta {
  public:
    explicit CostEta(int workers, double prior_seconds_per_cost);
    void add_pending(double cost, int tasks = 1);
    // `tasks` tasks of expected cost `cost` each finished (removed from the pending cost if they
    // were added), taking `worker_seconds` of worker time in all; `done_cost` is the cost they
    // computed (the same units), < 0 when unknown (then their expected cost counts).
    void finished(double cost, double worker_seconds, int tasks = 1, bool was_pending = true,
                  double done_cost = -1.0);
    double seconds_per_cost() const;
    // 0 when nothing is pending. `running` are pending tasks being computed: each counts with
    // its expected seconds less those it has run (at least a twentieth of them: it has not
    // ended), and the time left is never below the longest of these remainders.
    double seconds_left(const std::vector<RunningCost>& running = {}) const;
    bool measured() const { return cost_done_ > 0; }

  private:
    int workers_;
    double prior_;
    double pending_cost_ = 0.0;
    double cost_done_ = 0.0;
    double seconds_done_ = 0.0;
};

// One row per point of `labels` (the sweep's points, in order): realizations stored/planned,
// failed, jams, mean survival time (total survival time / jams: the censored-exponential
// maximum-likelihood mean; "-" without jams), mean empty time over the realizations that
// emptied; then a line saying what tau is.
void write_summary(std::ostream& out, const store::StoreStatus& status,
                   const std::vector<std::string>& labels);

}  // namespace hopper::campaign
