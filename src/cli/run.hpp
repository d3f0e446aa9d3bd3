#pragma once
// `campaign run SWEEP.toml`: parses the command line into campaign::RunOptions.

#include <ostream>
#include <string>
#include <vector>

namespace hopper::cli {

void print_run_help(std::ostream& os);

// Parses `args` (after the command name) and runs the campaign. Returns the exit code.
int run_command(const std::vector<std::string>& args, const std::string& command_line);

}  // namespace hopper::cli
