#pragma once
// `campaign submit SWEEP.toml [options]`: renders the Slurm batch template (slurm/hopper.sbatch.in,
// compiled in) for the sweep's campaign, writes it next to the store as STORE.sbatch and submits
// it with sbatch; --dry-run prints it instead. The batch script runs `campaign run`, drains on the
// pre-limit signal and resubmits itself until the store has no pending realization.

#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace hopper::cli {

void print_submit_help(std::ostream& os);
int submit_command(const std::vector<std::string>& args);

// The batch template compiled into the executable (generated from slurm/hopper.sbatch.in).
extern const char* const sbatch_template;

// Replaces every {{NAME}} of `tmpl` with values.at(NAME). A line starting with "#SBATCH" whose
// placeholders are all empty is left out. Throws core::ConfigError for an unknown or unclosed
// placeholder.
std::string render_template(const std::string& tmpl,
                            const std::map<std::string, std::string>& values);

// A Slurm time limit ("MM", "MM:SS", "HH:MM:SS", "D-HH", "D-HH:MM", "D-HH:MM:SS") in seconds.
// Throws core::ConfigError naming `option` when the text is not one of these forms or is zero.
long parse_slurm_time(const std::string& option, const std::string& text);

// The chain of allocations a submission makes: at most 1 + max_resubmits allocations of
// `time_s` seconds, of which the last `lead_s` drain, on `workers` worker threads; `ntasks`
// ranks of `threads` threads each, one of which is the master's own when `own_master`.
struct Chain {
    long allocations = 1;
    long time_s = 3600;
    long lead_s = 120;
    long workers = 1;
    long ntasks = 1;
    long threads = 1;
    bool own_master = false;
};

// Empty when the chain's worker time holds `worker_seconds` (the dry run's estimate) with 20 %
// to spare for the load balance; otherwise a warning with the shortfall and an --ntasks (same
// --time) and a --time (same --ntasks) that would finish it. A realization longer than one
// allocation (`longest_s`) needs its checkpoints: said too.
std::string chain_warning(const Chain& chain, double worker_seconds, double longest_s);

}  // namespace hopper::cli
