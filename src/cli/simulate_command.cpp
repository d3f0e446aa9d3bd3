// `campaign simulate`'s command line: its options, checked (cli/options.hpp), into
// SimulateOptions for run_simulate (simulate.cpp).
#include <boost/program_options.hpp>
#include <iostream>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "cli/parse.hpp"
#include "cli/simulate.hpp"
#include "hopper/core/error.hpp"

namespace po = boost::program_options;

namespace hopper::cli {

namespace {

po::options_description simulate_options() {
    po::options_description d("simulate options");
    // Numbers are read as text and checked by cli/options.hpp, so that "-1", "1.5", "nan" get a
    // clear message (Boost's lexical casts would wrap "-1" into a huge unsigned seed).
    d.add_options()                                                                //
        ("D", po::value<std::string>()->value_name("CM"), "outlet width D in cm")  //
        ("theta", po::value<std::string>()->value_name("DEG"),
         "wall angle to the horizontal in degrees")  //
        ("seed", po::value<std::string>()->value_name("N"),
         "random seed: a non-negative integer, or a store's seed_str (s and its digits)")  //
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
         "vtu (binary, compressed) or vtu-ascii, and/or dump (default vtu,dump)")  //
        ("snapshot-interval", po::value<std::string>()->value_name("S"),
         "seconds of simulated time between snapshots (default 0.05)")                            //
        ("progress", po::bool_switch(), "progress line on stderr every 0.5 s of simulated time")  //
        ("help,h", "show this help");
    return d;
}

const std::string& required(const po::variables_map& vm, const char* name) {
    if (!vm.count(name)) throw core::ConfigError(std::string("missing required option --") + name);
    return vm[name].as<std::string>();
}

}  // namespace

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

int simulate_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, simulate_options(), "sweep");
    if (vm.count("help")) {
        print_simulate_help(std::cout);
        return 0;
    }

    SimulateOptions opt;
    if (vm.count("point")) {
        for (const char* o : {"D", "theta", "seed", "sweep"})
            if (vm.count(o))
                throw core::ConfigError(
                    std::string(o == std::string("sweep") ? "a sweep file"
                                                          : "--" + std::string(o)) +
                    " cannot be given with --point: the store has the point's scene and seed");
        opt.store = required(vm, "store");
        opt.point = vm["point"].as<std::string>();
        const std::uint64_t r = parse_seed("--realization", required(vm, "realization"));
        if (r > 100000000)
            throw core::ConfigError("--realization " + std::to_string(r) + " is too large");
        opt.realization = static_cast<int>(r);
    } else {
        for (const char* o : {"store", "realization"})
            if (vm.count(o))
                throw core::ConfigError(std::string("--") + o +
                                        " needs --point LABEL (a stored realization)");
        opt.sweep = single_positional(vm, "sweep", "sweep file", "SWEEP.toml");
        opt.D_cm = parse_finite("--D", required(vm, "D"));
        opt.theta_deg = parse_finite("--theta", required(vm, "theta"));
        opt.seed = parse_seed_text("--seed", required(vm, "seed"));
    }
    opt.json = vm["json"].as<bool>();
    opt.progress = vm["progress"].as<bool>();
    if (vm.count("snapshots")) opt.snapshot_dir = vm["snapshots"].as<std::string>();
    if (vm.count("snapshot-format")) {
        if (!opt.snapshot_dir) throw core::ConfigError("--snapshot-format needs --snapshots DIR");
        opt.snapshot_formats = parse_snapshot_formats(vm["snapshot-format"].as<std::string>());
    }
    if (vm.count("snapshot-interval")) {
        if (!opt.snapshot_dir) throw core::ConfigError("--snapshot-interval needs --snapshots DIR");
        const std::string& text = vm["snapshot-interval"].as<std::string>();
        opt.snapshot_interval = parse_finite("--snapshot-interval", text);
        if (opt.snapshot_interval <= 0.0)
            throw core::ConfigError("--snapshot-interval must be > 0, got '" + text + "'");
    }
    return run_simulate(opt, std::cout, std::cerr);
}

}  // namespace hopper::cli
