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

}  // namespace hopper::cli
