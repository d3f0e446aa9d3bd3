#include "cli/commands.hpp"

#include <boost/program_options.hpp>
#include <iostream>

#include "cli/analyze.hpp"
#include "cli/cite.hpp"
#include "cli/exit_codes.hpp"
#include "cli/merge.hpp"
#include "cli/python_tools.hpp"
#include "cli/run.hpp"
#include "cli/simulate.hpp"
#include "cli/status.hpp"
#include "cli/submit.hpp"
#include "hopper/core/error.hpp"

#include "hopper_version.h"  // HOPPER_VERSION, generated at build time (version.cmake)

namespace hopper::cli {

namespace {

// A command that does not record its command line.
template <int (*F)(const std::vector<std::string>&)>
int without_line(const std::vector<std::string>& args, const std::string&) {
    return F(args);
}

constexpr Command table[] = {
    {"run", "run or resume the campaign of a sweep file (mpirun for many ranks)", print_run_help,
     run_command},
    {"status", "progress, rate, ETA and failures of a store (works while a run writes it)",
     print_status_help, without_line<status_command>},
    {"analyze", "statistics and fits of a store, written into its /analysis group",
     print_analyze_help, without_line<analyze_command>},
    {"plot", "figures of a store (survival, jam rate, Beverloo, fields; png, pdf, svg)",
     print_plot_help, without_line<plot_command>},
    {"export", "a store's tables as CSV files and its field maps for ParaView", print_export_help,
     without_line<export_command>},
    {"simulate", "run one realization: of a sweep file's scene, or a stored one again",
     print_simulate_help, without_line<simulate_command>},
    {"submit", "submit a campaign to Slurm; it drains before the limit and resubmits itself",
     print_submit_help, without_line<submit_command>},
    {"cite", "the references for what a store used (models, methods), plain text and BibTeX",
     print_cite_help, without_line<cite_command>},
    {"merge", "join stores of one campaign (split points, copies resumed elsewhere) into one",
     print_merge_help, merge_command},
};

const Command* find(std::string_view name) {
    for (const auto& c : table)
        if (c.name == name) return &c;
    return nullptr;
}

std::string available_commands() {
    std::string s;
    for (const auto& c : table)
        s += (s.empty() ? "" : ", ") + std::string(c.name);
    return s;
}

int error(const std::string& message, int code) {
    std::cout.flush();
    std::cerr << "campaign: error: " << message << '\n';
    return code;
}

int help(const std::vector<std::string>& args) {
    if (args.size() == 1) {
        print_usage(std::cout);
        return exit_ok;
    }
    if (const Command* c = find(args[1])) {
        c->help(std::cout);
        return exit_ok;
    }
    return error(
        "no help for unknown command '" + args[1] + "' (available: " + available_commands() + ")",
        exit_usage);
}

}  // namespace

std::span<const Command> commands() {
    return table;
}

void print_usage(std::ostream& os) {
    os << "usage: campaign <command> [arguments]\n"
          "       campaign --help | --version | help <command>\n\n"
          "commands:\n";
    for (const auto& c : table)
        os << "  " << c.name << std::string(12 - c.name.size(), ' ') << c.summary << '\n';
    os << "\nexit codes:\n";
    for (const auto& e : exit_code_meanings)
        os << "  " << static_cast<int>(e.code) << "  " << e.meaning << '\n';
}

int dispatch(const std::vector<std::string>& args) {
    std::string command;
    try {
        if (args.empty()) {
            print_usage(std::cerr);
            return exit_usage;
        }
        command = args[0];
        if (command == "--help" || command == "-h") {
            print_usage(std::cout);
            return exit_ok;
        }
        if (command == "--version") {
            std::cout << "campaign (hopper) " << HOPPER_VERSION << '\n';
            return exit_ok;
        }
        if (command == "help") return help(args);
        if (const Command* c = find(command)) {
            std::string line = "campaign";
            for (const auto& a : args)
                line += " " + a;
            return c->run(std::vector<std::string>(args.begin() + 1, args.end()), line);
        }
        if (command.starts_with("-"))
            return error("unknown option '" + command + "' (try 'campaign --help')", exit_usage);
        return error("unknown command '" + command + "' (available: " + available_commands() + ")",
                     exit_usage);
    } catch (const core::ConfigError& e) {
        return error(e.what(), exit_usage);
    } catch (const boost::program_options::error& e) {
        return error(std::string(e.what()) + " (see 'campaign help " + command + "')", exit_usage);
    } catch (const std::exception& e) {
        return error(e.what(), exit_error);
    }
}

}  // namespace hopper::cli
