#pragma once
// `campaign run --deadline T`: when the run must have ended (time-aware dispatch, issue 15).

#include <optional>
#include <string>

namespace hopper::cli {

// Seconds since 1970 of a deadline given as
//   "none"                  no deadline (nullopt)
//   "slurm"                 the Slurm job's end time (slurm_job_end(); an error outside a job)
//   "slurm-120", "slurm-2m" the Slurm job's end time minus that much (the batch template: the
//                           moment Slurm's warning signal is due, plus the grace)
//   "@1767225600"           seconds since 1970
//   "2026-11-24T15:00:00Z"  ISO 8601 UTC, or with a UTC offset: "2026-11-24T16:00:00+01:00" or
//                           "+0100" (date +%FT%T%z); fractional seconds ("15:00:00.25Z");
//                           without a zone, this machine's local time (TZ); a date that does
//                           not exist (2026-02-31; locally, an hour skipped by daylight-saving
//                           time) is refused
//   "+3600", "+90m", "+2h", "+1.5d", "+1:30:00"   from `now` (s, m, h, d)
// Throws core::ConfigError naming the value and the allowed forms; also for a number too large
// or a deadline after 9999-12-31T23:59:59Z.
std::optional<double> parse_deadline(const std::string& text, double now);

// The end time of the Slurm job this process runs in: SLURM_JOB_END_TIME when Slurm sets it,
// else `squeue -h -j $SLURM_JOB_ID -o %e` (local time). nullopt outside a job, for a job
// without a limit, or when neither answers; `why` then says which.
std::optional<double> slurm_job_end(std::string* why);

}  // namespace hopper::cli
