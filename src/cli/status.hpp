#pragma once
// `campaign status STORE [--json]`: progress and failures of a store, read from its journal
// without locking (works while a run is writing).
//
// JSON (one object): store, campaign, physics_hash, active (a run holds the store),
// hdf5_in_step, total, done, failed, errors (of failed: exceptions, retried by the next run),
// pending, per_hour (stored per hour by the last run), eta_seconds (null: nothing pending),
// eta_basis, busy_workers [{rank, seconds since its last result}] (while a run writes),
// points [{label, total, done, failed, errors, pending}],
// failures [{label, realization, seed, kind ("failed" | "error"), reason}],
// runs [{start_time, end_time (null: running or killed), end_reason, code_version, mpi_size,
// workers, hosts, stored}]. total = done + failed + pending.

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "hopper/store/store.hpp"

namespace hopper::cli {

// How far a campaign is and how long the rest takes: the realizations stored per hour by the last
// run, the time left for the pending ones on the last run's workers, weighted by the cost model
// (campaign::expected_cost: particle-steps, from the scenes of the sweep texts the store recorded)
// and corrected by the measured seconds per cost unit of the stored realizations (before any, 50
// ns per particle-step, the README's benchmark), and per worker of a running campaign the time
// since its last result (what it is running is not journaled, only when it finished).
struct ProgressEstimate {
    double per_hour = 0.0;              // stored by the last run per hour of its wall time
    std::optional<double> eta_seconds;  // none: nothing pending, or no scene known
    std::string basis;                  // how the estimate was made
    int workers = 0;
    std::vector<std::pair<int, double>> busy;  // (rank, seconds since its last result or start)
};
ProgressEstimate estimate_progress(const store::StoreStatus& s, double now_unix);

void print_status_help(std::ostream& os);
int status_command(const std::vector<std::string>& args);

std::string status_json(const store::StoreStatus& s);
void write_status(std::ostream& out, const store::StoreStatus& s);

}  // namespace hopper::cli
