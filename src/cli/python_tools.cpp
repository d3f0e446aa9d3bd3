#include "cli/python_tools.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/program_options.hpp>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <system_error>

#include "cli/parse.hpp"
#include "hopper/analysis/store_analysis.hpp"
#include "hopper/campaign/point_columns.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/store.hpp"

#ifndef HOPPER_ANALYSIS_DIR
#define HOPPER_ANALYSIS_DIR "analysis"
#endif

extern char** environ;

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace hopper::cli {

namespace {

const char* const known_formats[] = {"png", "pdf", "svg"};

po::options_description plot_options() {
    po::options_description d("plot options");
    d.add_options()  //
        ("out", po::value<std::string>()->value_name("DIR"),
         "directory for the figures (default: STORE without .h5, plus _plots)")  //
        ("format", po::value<std::string>()->value_name("LIST"),
         "comma-separated formats: png, pdf, svg (default png)")  //
        ("width", po::value<std::string>()->value_name("W"),
         "figure width: column (3.4 in, one journal column) or page (7 in; default)")  //
        ("help,h", "show this help");
    return d;
}

po::options_description export_options() {
    po::options_description d("export options");
    d.add_options()                                                                              //
        ("csv", po::value<std::string>()->value_name("DIR"), "one CSV file per table into DIR")  //
        ("vtk", po::value<std::string>()->value_name("DIR"),
         "the merged field maps as VTK image data (.vti, ParaView) into DIR")  //
        ("snapshot", po::value<std::string>()->value_name("FILE"),
         "the store as it stands, also while a run writes it: FILE and FILE.journal, a closed "
         "store of its own (hopper_store.open_store uses it during a run)")  //
        ("help,h", "show this help");
    return d;
}

std::string existing_store(const po::variables_map& vm) {
    const std::string store = single_positional(vm, "store", "store", "STORE.h5");
    std::error_code ec;
    if (!fs::exists(store, ec)) throw core::ConfigError("no store at '" + store + "'");
    return store;
}

// What the Python tools read: the store itself when no run writes it and its HDF5 file is in
// step with the journal; otherwise a snapshot of it (store::write_snapshot) in a directory of
// its own, removed when this goes away (docs/store.md, "Reading a store during a run").
class ReaderView {
  public:
    ReaderView(const std::string& store, bool with_analysis) : path_(store) {
        if (!fs::exists(store::journal_path(store))) return;  // a file without its journal
        const store::StoreStatus st = store::read_status(store);
        if (!st.writer_active && st.hdf5_in_step) return;
        static int counter = 0;
        dir_ = fs::temp_directory_path() /
               ("hopper-view-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        path_ = (dir_ / fs::path(store).filename()).string();
        const store::Snapshot snap =
            store::write_snapshot(store, path_, campaign::point_parameter_columns);
        std::cerr << "campaign: note: "
                  << (snap.writer_active ? "a `campaign run` is writing '" + store + "'"
                                         : "the HDF5 file '" + store +
                                               "' is not in step with its journal (a run was "
                                               "interrupted)")
                  << "; reading the " << snap.realizations
                  << " realization(s) its journal holds now (a snapshot; the store is not "
                     "touched)"
                  << std::endl;
        if (with_analysis) analysis::write_analysis_group(path_, analysis::analyze_store(path_));
    }
    ~ReaderView() {
        std::error_code ec;
        if (!dir_.empty()) fs::remove_all(dir_, ec);
    }
    ReaderView(const ReaderView&) = delete;
    ReaderView& operator=(const ReaderView&) = delete;
    const std::string& path() const { return path_; }

  private:
    std::string path_;
    fs::path dir_;
};

}  // namespace

fs::path analysis_dir() {
    if (const char* d = std::getenv("HOPPER_ANALYSIS_DIR"); d && *d) return d;
    // An installed campaign (`cmake --install`): PREFIX/bin/campaign beside
    // PREFIX/share/hopper/analysis; a build tree's campaign uses the source tree's scripts.
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const fs::path installed = exe.parent_path().parent_path() / "share/hopper/analysis";
        if (fs::exists(installed / "plots.py", ec)) return installed;
    }
    return HOPPER_ANALYSIS_DIR;
}

fs::path python_interpreter() {
    if (const char* p = std::getenv("HOPPER_PYTHON"); p && *p) return p;
    return "/usr/bin/python3";
}

int run_python(const fs::path& script, const std::vector<std::string>& args) {
    const fs::path python = python_interpreter();
    std::error_code ec;
    if (!fs::exists(python, ec))
        throw std::runtime_error(
            "no Python interpreter at '" + python.string() +
            "' (install python3 with ./install-deps.sh, or set HOPPER_PYTHON)");
    if (!fs::exists(script, ec))
        throw std::runtime_error("no script '" + script.string() +
                                 "' (set HOPPER_ANALYSIS_DIR to the source tree's analysis/)");
    std::vector<std::string> argv_s{python.string(), script.string()};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    std::cout.flush();
    pid_t pid = 0;
    if (const int rc = posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ); rc != 0)
        throw std::runtime_error("cannot start '" + python.string() + "': " + std::strerror(rc));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) throw std::runtime_error("waiting for the Python tool failed");
    }
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    std::cerr << "campaign: error: " << script.filename().string() << " was killed by signal "
              << WTERMSIG(status) << '\n';
    return 1;
}

std::vector<std::string> parse_formats(const std::string& text) {
    std::vector<std::string> out;
    std::size_t begin = 0;
    while (begin <= text.size()) {
        const std::size_t comma = text.find(',', begin);
        const std::string f =
            text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
        bool known = false;
        for (const char* k : known_formats)
            known = known || f == k;
        if (!known)
            throw core::ConfigError("--format: unknown format '" + f + "' in '" + text +
                                    "' (allowed: png, pdf, svg, comma-separated)");
        for (const auto& seen : out)
            if (seen == f)
                throw core::ConfigError("--format: '" + f + "' given twice in '" + text + "'");
        out.push_back(f);
        if (comma == std::string::npos) break;
        begin = comma + 1;
    }
    return out;
}

void print_plot_help(std::ostream& os) {
    os << "usage: campaign plot STORE.h5 [--out DIR] [--format png,pdf,svg] [--width W]\n\n"
          "Draws the figures of a store after its analysis (campaign run analyzes at its end;\n"
          "otherwise run `campaign analyze STORE.h5` first): survival functions of every\n"
          "outlet per group with their exponential fits, tau and the jam rate versus D, flow\n"
          "rate and empty time versus D with Beverloo, k versus theta, particles in the hopper,\n"
          "jam onsets, and the field maps. Legends name only the settings that vary. Runs\n"
          "analysis/plots.py with /usr/bin/python3 (python3-matplotlib, -pandas, -h5py).\n"
          "While a `campaign run` writes the store: the realizations stored so far, from a\n"
          "snapshot of its journal analyzed on the spot (the store is not touched).\n\n"
          "exit codes: 0 figures written, 2 bad arguments or a store without /analysis,\n"
          "            3 no realization to draw (every one failed), 1 other errors\n\n"
       << plot_options();
}

void print_export_help(std::ostream& os) {
    os << "usage: campaign export STORE.h5 [--csv DIR] [--vtk DIR] | --snapshot FILE\n\n"
          "Writes the store's tables as CSV files (points with every setting, realizations,\n"
          "survival intervals as duration and event, events, discharge curves, jams, exits,\n"
          "arches, and after the analysis its tables with the avalanche fits) and the field\n"
          "maps as VTK image data for ParaView. survival.csv is ready for R's survreg and\n"
          "lifelines: a jam at the opening (stored duration 0) has half the detector interval.\n"
          "In Python, analysis/hopper_store.py reads the same tables as pandas DataFrames.\n"
          "While a `campaign run` writes the store, export, plot and open_store() read a\n"
          "snapshot of its journal: every realization stored at that moment.\n\n"
          "exit codes: 0 written, 2 bad arguments or nothing to export, 1 other errors\n\n"
       << export_options();
}

int plot_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, plot_options(), "store");
    if (vm.count("help")) {
        print_plot_help(std::cout);
        return 0;
    }
    const std::string store = existing_store(vm);
    const ReaderView view(store, true);
    std::vector<std::string> py{view.path(), "--out"};
    if (vm.count("out")) {
        py.push_back(vm["out"].as<std::string>());
    } else {
        fs::path out = store;
        out.replace_extension();
        py.push_back(out.string() + "_plots");
    }
    if (vm.count("format")) {
        std::string joined;
        for (const auto& f : parse_formats(vm["format"].as<std::string>()))
            joined += (joined.empty() ? "" : ",") + f;
        py.insert(py.end(), {"--format", joined});
    }
    if (vm.count("width")) {
        const std::string& w = vm["width"].as<std::string>();
        if (w != "column" && w != "page")
            throw core::ConfigError("--width must be column or page, got '" + w + "'");
        py.insert(py.end(), {"--width", w});
    }
    return run_python(analysis_dir() / "plots.py", py);
}

int export_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, export_options(), "store");
    if (vm.count("help")) {
        print_export_help(std::cout);
        return 0;
    }
    const std::string store = existing_store(vm);
    if (vm.count("snapshot")) {
        if (vm.count("csv") || vm.count("vtk"))
            throw core::ConfigError(
                "--snapshot writes a store: give it alone, then export from "
                "the snapshot");
        const std::string& out = vm["snapshot"].as<std::string>();
        if (out.empty()) throw core::ConfigError("--snapshot must not be empty");
        const store::Snapshot snap =
            store::write_snapshot(store, out, campaign::point_parameter_columns);
        std::cout << "snapshot: " << out << " (" << snap.realizations << " realization(s)"
                  << (snap.writer_active ? ", taken while a `campaign run` writes the store" : "")
                  << ")\n";
        return 0;
    }
    if (!vm.count("csv") && !vm.count("vtk"))
        throw core::ConfigError(
            "nothing to export: give --csv DIR and/or --vtk DIR (or --snapshot FILE)");
    const ReaderView view(store, false);
    std::vector<std::string> py{view.path()};
    for (const char* opt : {"csv", "vtk"})
        if (vm.count(opt)) {
            const std::string& dir = vm[opt].as<std::string>();
            if (dir.empty())
                throw core::ConfigError(std::string("--") + opt + " must not be empty");
            py.insert(py.end(), {std::string("--") + opt, dir});
        }
    return run_python(analysis_dir() / "export.py", py);
}

}  // namespace hopper::cli
