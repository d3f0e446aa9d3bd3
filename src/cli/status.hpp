#pragma once
// `campaign status STORE [--json]`: progress and failures of a store, read from its journal
// without locking (works while a run is writing).
//
// JSON (one object): store, campaign, physics_hash, active (a run holds the store),
// hdf5_in_step, total, done, failed, errors (of failed: exceptions, retried by the next run),
// pending, points [{label, total, done, failed, errors, pending}],
// failures [{label, realization, seed, kind ("failed" | "error"), reason}],
// runs [{start_time, end_time (null: running or killed), end_reason, code_version, mpi_size,
// workers, hosts, stored}]. total = done + failed + pending.

#include <ostream>
#include <string>
#include <vector>

#include "hopper/store/store.hpp"

namespace hopper::cli {

void print_status_help(std::ostream& os);
int status_command(const std::vector<std::string>& args);

std::string status_json(const store::StoreStatus& s);
void write_status(std::ostream& out, const store::StoreStatus& s);

}  // namespace hopper::cli
