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
std::string progress_line(int done, int total, int running, int failed, double rate,
                          double elapsed);

// One row per point of `labels` (the sweep's points, in order): realizations stored/planned,
// failed, jams, mean survival time (total survival time / jams: the censored-exponential
// maximum-likelihood mean; "-" without jams), mean empty time over the realizations that
// emptied; then a line saying what tau is.
void write_summary(std::ostream& out, const store::StoreStatus& status,
                   const std::vector<std::string>& labels);

}  // namespace hopper::campaign
