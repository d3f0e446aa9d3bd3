#pragma once
// The commands of the `campaign` executable, as one table: `campaign --help` lists it,
// `campaign help NAME` and dispatch look names up in it. A new command is one row here.

#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hopper::cli {

struct Command {
    std::string_view name;
    std::string_view summary;     // one line of `campaign --help`
    void (*help)(std::ostream&);  // `campaign help NAME`, `campaign NAME --help`
    // Runs the command on the arguments after its name; `command_line` is the whole command
    // line ("campaign run ..."), which `run` records in the store's runs table.
    int (*run)(const std::vector<std::string>& args, const std::string& command_line);
};

std::span<const Command> commands();

// The usage: the commands' summaries and the exit codes (exit_codes.hpp).
void print_usage(std::ostream& os);

// The whole command line after the program name: `--help`, `--version`, `help [NAME]` or a
// command with its arguments. Errors are printed on stderr as "campaign: error: ..." and turned
// into exit codes (core::ConfigError and bad options: exit_usage; anything else: exit_error).
int dispatch(const std::vector<std::string>& args);

}  // namespace hopper::cli
