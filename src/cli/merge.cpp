#include "cli/merge.hpp"

#include <unistd.h>

#include <boost/program_options.hpp>
#include <iostream>

#include "cli/parse.hpp"
#include "hopper/campaign/point_columns.hpp"
#include "hopper/campaign/run.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"

#include "hopper_version.h"  // HOPPER_VERSION

namespace hopper::cli {

namespace po = boost::program_options;

namespace {

po::options_description merge_options() {
    po::options_description d("merge options");
    d.add_options()                                                                               //
        ("store", po::value<std::string>(), "the new store to write (required; must not exist)")  //
        ("help,h", "show this help");
    return d;
}

std::string hostname() {
    char buf[256] = {};
    if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
    return buf;
}

}  // namespace

void print_merge_help(std::ostream& os) {
    os << "usage: campaign merge A.h5 B.h5 ... --store C.h5\n\n"
          "Joins stores of one campaign into a new store C.h5 (with its journal): halves of\n"
          "a sweep's points run on two machines, or a copy of a store resumed elsewhere.\n"
          "Every realization is stored once, byte for byte as in the first input that has\n"
          "it; one found in several inputs must be identical in each (seed, status,\n"
          "physics digest). Every run of the inputs becomes a row of C's /runs once (a run\n"
          "two inputs share, as a copy resumed elsewhere shares the runs before the copy,\n"
          "counts once), then one row for the merge. `campaign run SWEEP --store C.h5`\n"
          "then resumes it and runs only what none of them had.\n\n"
          "Refused (nothing written) when an input is being written by a `campaign run`,\n"
          "when an input's HDF5 file disagrees with its journal, when the campaign names\n"
          "or seeds differ, when a point in two inputs has other physics (the differing\n"
          "parameters are named), when two copies of a realization differ, and when C.h5\n"
          "or its journal exists (a merge never overwrites: choose a new path). The inputs\n"
          "are only read, also when one was killed mid-run (its journal holds what\n"
          "finished; the incomplete last record is left out).\n\n"
          "exit codes: 0 merged, 1 unexpected or store error (I/O, a full disk; nothing is\n"
          "left at C.h5), 2 bad command line or a merge refused (the message says why)\n\n"
       << merge_options();
}

int merge_command(const std::vector<std::string>& args, const std::string& command_line) {
    const po::variables_map vm = parse_command(args, merge_options(), "inputs");
    if (vm.count("help")) {
        print_merge_help(std::cout);
        return 0;
    }
    if (!vm.count("inputs"))
        throw core::ConfigError(
            "missing the stores to merge (campaign merge A.h5 B.h5 ... --store C.h5)");
    if (!vm.count("store")) throw core::ConfigError("missing --store C.h5, the new store to write");
    std::vector<std::filesystem::path> inputs;
    for (const auto& s : vm["inputs"].as<std::vector<std::string>>())
        inputs.emplace_back(s);
    const std::filesystem::path out = vm["store"].as<std::string>();

    store::RunInfo run;
    run.start_time = store::utc_now();
    run.code_version = HOPPER_VERSION;
    run.compiler = campaign::compiler_id();
    run.command = command_line;
    run.mpi_size = 1;
    run.workers = 0;
    run.hosts = {hostname()};
    run.pid = static_cast<std::int64_t>(getpid());
    const store::MergeReport r =
        store::merge_stores(inputs, out, run, campaign::point_parameter_columns);

    for (const auto& in : r.inputs) {
        std::cout << "  " << in.store.string() << ": " << in.realizations << " realizations, "
                  << in.runs << " run(s)";
        if (in.torn_bytes)
            std::cout << " (an incomplete last record of " << in.torn_bytes
                      << " bytes left out: a killed run's)";
        std::cout << '\n';
    }
    std::cout << "merged " << r.inputs.size() << " stores into " << out.string() << ": " << r.points
              << " points, " << r.realizations << " realizations (" << r.identical_copies
              << " identical copies stored once), " << r.runs << " runs (" << r.shared_runs
              << " shared by several inputs, kept once)\n";
    return 0;
}

}  // namespace hopper::cli
