// The `campaign` executable: parses the command line and dispatches to a command. Nothing else
// lives here; the commands are in src/cli/<command>.cpp.
//
// Exit codes: 0 success, 1 unexpected error (I/O, store, internal), 2 bad command line or sweep
// file (or a store refused for different physics), 3 the realization failed (simulate) or some
// realizations failed (run), 4 stopped by a signal (run; resumable).

#include <boost/program_options.hpp>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "cli/analyze.hpp"
#include "cli/options.hpp"
#include "cli/parse.hpp"
#include "cli/python_tools.hpp"
#include "cli/run.hpp"
#include "cli/simulate.hpp"
#include "cli/status.hpp"
#include "cli/submit.hpp"
#include "hopper/core/error.hpp"

#ifndef HOPPER_VERSION
#define HOPPER_VERSION "unknown"
#endif

namespace po = boost::program_options;

namespace {

using hopper::cli::exit_error;
using hopper::cli::exit_usage;
using hopper::cli::parse_command;
using hopper::cli::single_positional;

struct Command {
    std::string_view name;
    std::string_view summary;
    void (*help)(std::ostream&);  // `campaign help <name>`
};

void print_simulate_help(std::ostream& os);

// The commands this build has.
constexpr Command commands[] = {
    {"run", "run or resume the campaign of a sweep file (mpirun for many ranks)",
     hopper::cli::print_run_help},
    {"status", "progress, rate, ETA and failures of a store (works while a run writes it)",
     hopper::cli::print_status_help},
    {"analyze", "statistics and fits of a store, written into its /analysis group",
     hopper::cli::print_analyze_help},
    {"plot", "figures of a store (survival, jam rate, Beverloo, fields; png, pdf, svg)",
     hopper::cli::print_plot_help},
    {"export", "a store's tables as CSV files and its field maps for ParaView",
     hopper::cli::print_export_help},
    {"simulate", "run one realization: of a sweep file's scene, or a stored one again",
     print_simulate_help},
    {"submit", "submit a campaign to Slurm; it drains before the limit and resubmits itself",
     hopper::cli::print_submit_help},
};

std::string available_commands() {
    std::string s;
    for (const auto& c : commands)
        s += (s.empty() ? "" : ", ") + std::string(c.name);
    return s;
}

void print_usage(std::ostream& os) {
    os << "usage: campaign <command> [arguments]\n"
          "       campaign --help | --version | help <command>\n\n"
          "commands:\n";
    for (const auto& c : commands)
        os << "  " << c.name << std::string(12 - c.name.size(), ' ') << c.summary << '\n';
    os << "\nexit codes: 0 success, 1 unexpected or store error, 2 bad command line or sweep\n"
          "            file, 3 realization(s) failed, 4 stopped by a signal (run; resumable)\n";
}

po::options_description simulate_options() {
    po::options_description d("simulate options");
    // Numbers are read as text and checked by cli/options.hpp, so that "-1", "1.5", "nan" get a
    // clear message (Boost's lexical casts would wrap "-1" into a huge unsigned seed).
    d.add_options()                                                                //
        ("D", po::value<std::string>()->value_name("CM"), "outlet width D in cm")  //
        ("theta", po::value<std::string>()->value_name("DEG"),
         "wall angle to the horizontal in degrees")  //
        ("seed", po::value<std::string>()->value_name("N"),
         "random seed, a non-negative integer")  //
        ("store", po::value<std::string>()->value_name("STORE.h5"),
         "with --point: the store holding the realization")  //
        ("point", po::value<std::string>()->value_name("LABEL"),
         "re-run a stored realization of this point (its label, as `campaign status` lists it)")  //
        ("realization", po::value<std::string>()->value_name("I"),
         "with --point: the realization's index (0-based)")                          //
        ("json", po::bool_switch(), "print one JSON object instead of the summary")  //
        ("snapshots", po::value<std::string>()->value_name("DIR"),
         "write particle snapshots into DIR: VTK files hopper.NNNNNN.vtu with the series "
         "hopper.pvd (open hopper.pvd in ParaView) and LAMMPS dump files hopper.NNNNNN.dump "
         "(OVITO); earlier frames in DIR are removed")  //
        ("snapshot-format", po::value<std::string>()->value_name("LIST"),
         "vtu, dump or vtu,dump (default vtu,dump)")  //
        ("snapshot-interval", po::value<std::string>()->value_name("S"),
         "seconds of simulated time between snapshots (default 0.05)")                            //
        ("progress", po::bool_switch(), "progress line on stderr every 0.5 s of simulated time")  //
        ("help,h", "show this help");
    return d;
}

void print_simulate_help(std::ostream& os) {
    os << "usage: campaign simulate SWEEP.toml --D CM --theta DEG --seed N [OPTIONS]\n"
          "       campaign simulate --store STORE.h5 --point LABEL --realization I [OPTIONS]\n"
          "OPTIONS: [--json] [--snapshots DIR] [--snapshot-interval S]\n"
          "         [--snapshot-format vtu,dump] [--progress]\n\n"
          "Runs one realization of the sweep file's base scene with outlet D and wall angle\n"
          "theta, or runs a stored realization again (any point, whatever its settings: the\n"
          "scene comes from the sweep text the store recorded, checked against the point's\n"
          "stored physics, and the seed from the store; the outcome is compared with the\n"
          "stored one), and prints a summary (or, with --json, one JSON object) on stdout.\n"
          "--progress prints the simulated time, the wall-clock rate and an estimate of the\n"
          "time left on stderr.\n\n"
          "exit codes: 0 done, 1 error (or the re-run differs from the stored realization),\n"
          "            2 bad command line or sweep file, 3 the realization failed\n\n"
       << simulate_options();
}

const std::string& required(const po::variables_map& vm, const char* name) {
    if (!vm.count(name))
        throw hopper::core::ConfigError(std::string("missing required option --") + name);
    return vm[name].as<std::string>();
}

int simulate_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, simulate_options(), "sweep");
    if (vm.count("help")) {
        print_simulate_help(std::cout);
        return 0;
    }

    using hopper::cli::parse_finite;
    hopper::cli::SimulateOptions opt;
    if (vm.count("point")) {
        for (const char* o : {"D", "theta", "seed", "sweep"})
            if (vm.count(o))
                throw hopper::core::ConfigError(
                    std::string(o == std::string("sweep") ? "a sweep file"
                                                          : "--" + std::string(o)) +
                    " cannot be given with --point: the store has the point's scene and seed");
        opt.store = required(vm, "store");
        opt.point = vm["point"].as<std::string>();
        const std::uint64_t r =
            hopper::cli::parse_seed("--realization", required(vm, "realization"));
        if (r > 100000000)
            throw hopper::core::ConfigError("--realization " + std::to_string(r) + " is too large");
        opt.realization = static_cast<int>(r);
    } else {
        for (const char* o : {"store", "realization"})
            if (vm.count(o))
                throw hopper::core::ConfigError(std::string("--") + o +
                                                " needs --point LABEL (a stored realization)");
        opt.sweep = single_positional(vm, "sweep", "sweep file", "SWEEP.toml");
        opt.D_cm = parse_finite("--D", required(vm, "D"));
        opt.theta_deg = parse_finite("--theta", required(vm, "theta"));
        opt.seed = hopper::cli::parse_seed("--seed", required(vm, "seed"));
    }
    opt.json = vm["json"].as<bool>();
    opt.progress = vm["progress"].as<bool>();
    if (vm.count("snapshots")) opt.snapshot_dir = vm["snapshots"].as<std::string>();
    if (vm.count("snapshot-format")) {
        if (!opt.snapshot_dir)
            throw hopper::core::ConfigError("--snapshot-format needs --snapshots DIR");
        opt.snapshot_formats =
            hopper::cli::parse_snapshot_formats(vm["snapshot-format"].as<std::string>());
    }
    if (vm.count("snapshot-interval")) {
        if (!opt.snapshot_dir)
            throw hopper::core::ConfigError("--snapshot-interval needs --snapshots DIR");
        const std::string& text = vm["snapshot-interval"].as<std::string>();
        opt.snapshot_interval = parse_finite("--snapshot-interval", text);
        if (opt.snapshot_interval <= 0.0)
            throw hopper::core::ConfigError("--snapshot-interval must be > 0, got '" + text + "'");
    }
    return hopper::cli::run_simulate(opt, std::cout, std::cerr);
}

int error(const std::string& message, int code) {
    std::cout.flush();
    std::cerr << "campaign: error: " << message << '\n';
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    const std::vector<std::string> args(argv + 1, argv + argc);
    std::string command;
    try {
        if (args.empty()) {
            print_usage(std::cerr);
            return exit_usage;
        }
        command = args[0];
        if (command == "--help" || command == "-h") {
            print_usage(std::cout);
            return 0;
        }
        if (command == "--version") {
            std::cout << "campaign (hopper) " << HOPPER_VERSION << '\n';
            return 0;
        }
        if (command == "help") {
            if (args.size() == 1) {
                print_usage(std::cout);
                return 0;
            }
            for (const auto& c : commands)
                if (args[1] == c.name) {
                    c.help(std::cout);
                    return 0;
                }
            return error("no help for unknown command '" + args[1] +
                             "' (available: " + available_commands() + ")",
                         exit_usage);
        }
        const std::vector<std::string> rest(args.begin() + 1, args.end());
        if (command == "simulate") return simulate_command(rest);
        if (command == "run") {
            std::string line = "campaign";
            for (const auto& a : args)
                line += " " + a;
            return hopper::cli::run_command(rest, line);
        }
        if (command == "status") return hopper::cli::status_command(rest);
        if (command == "analyze") return hopper::cli::analyze_command(rest);
        if (command == "submit") return hopper::cli::submit_command(rest);
        if (command == "plot") return hopper::cli::plot_command(rest);
        if (command == "export") return hopper::cli::export_command(rest);
        if (command.starts_with("-"))
            return error("unknown option '" + command + "' (try 'campaign --help')", exit_usage);
        return error("unknown command '" + command + "' (available: " + available_commands() + ")",
                     exit_usage);
    } catch (const hopper::core::ConfigError& e) {
        return error(e.what(), exit_usage);
    } catch (const po::error& e) {
        return error(std::string(e.what()) + " (see 'campaign help " + command + "')", exit_usage);
    } catch (const std::exception& e) {
        return error(e.what(), exit_error);
    }
}
