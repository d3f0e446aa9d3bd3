#pragma once
// Command-line parsing shared by every command: one place decides how options are read.

#include <boost/program_options.hpp>
#include <string>
#include <vector>

namespace hopper::cli {

// Parses a command's arguments against `options`, collecting positional arguments under
// `positional_name` (a vector of strings the command then checks). Abbreviated long options
// are not accepted: a typo must be an error, never a silent match of another option.
boost::program_options::variables_map parse_command(
    const std::vector<std::string>& args, boost::program_options::options_description options,
    const char* positional_name);

// The single positional argument collected under `name` (e.g. the sweep file). Throws
// core::ConfigError "missing the <what> (<placeholder>)" when there is none, and
// "expected one <what>, got N: 'a', 'b', ..." when there are several.
std::string single_positional(const boost::program_options::variables_map& vm, const char* name,
                              const std::string& what, const std::string& placeholder);

}  // namespace hopper::cli
