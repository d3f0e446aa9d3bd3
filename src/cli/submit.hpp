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

}  // namespace hopper::cli
