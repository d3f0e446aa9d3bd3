#include "cli/run.hpp"
#include "cli/parse.hpp"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cctype>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <thread>

#include "cli/analyze.hpp"
#include "cli/deadline.hpp"
#include "cli/exit_codes.hpp"
#include "cli/options.hpp"
#include "cli/python_tools.hpp"
#include "hopper/campaign/run.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/records.hpp"

#include "hopper_version.h"  // HOPPER_VERSION, generated at build time (version.cmake)

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace hopper::cli {

namespace {

po::options_description run_options() {
    po::options_description d("run options");
    d.add_options()  //
        ("store", po::value<std::string>()->value_name("PATH"),
         "the HDF5 store (default: [campaign] store of the sweep file, relative to it); its "
         "journal is PATH.journal")  //
        ("progress-interval", po::value<std::string>()->value_name("S"),
         "seconds between progress lines on stderr (default 10; 0 = none)")  //
        ("grace", po::value<std::string>()->value_name("S"),
         "after SIGUSR1/SIGINT, seconds running realizations may take to finish before they "
         "are stopped (default 60)")  //
        ("threads", po::value<std::string>()->value_name("N"),
         "worker threads: without mpirun, of the one process (default 1); under mpirun, of "
         "every worker rank (hybrid: ranks 1..N-1 each run N realizations at once; default 1)")  //
        ("flush-interval", po::value<std::string>()->value_name("S"),
         "seconds between HDF5 flushes while running (default 1; the journal is synced after "
         "every realization regardless)")  //
        ("no-file-locking",
         "for file systems without locks (NFS without a lock daemon, Lustre without flock): "
         "write the store without the journal's lock and with HDF5's file locking off "
         "(HDF5_USE_FILE_LOCKING=FALSE). Then nothing keeps two runs from writing one store: "
         "make sure only one runs at a time")  //
        ("worker-timeout", po::value<std::string>()->value_name("S"),
         "seconds a busy worker may send no heartbeat before its realization is handed to "
         "another worker (default: 5 x the realization's expected duration, at least 300)")  //
        ("no-plots", po::bool_switch(),
         "do not draw the figures at the end (campaign plot draws them later)")  //
        ("deadline", po::value<std::string>()->value_name("T"),
         "when the run must have ended: realizations the cost model (scaled by the durations "
         "measured so far) expects to end after T minus --grace are not started, running ones "
         "are stopped (their states saved) at T minus --grace, and the run exits 4 (resumable). "
         "T: slurm (the job's end time; the default inside a Slurm job), slurm-S (S seconds "
         "before it), none, @SECONDS_SINCE_1970, "
         "2026-11-24T15:00:00Z (UTC), 2026-11-24T16:00:00+0100 (date +%FT%T%z), "
         "2026-11-24T16:00:00 (local time), or from now: +3600, +90m, +2h, +1d, +1:30:00")  //
        ("checkpoint-interval", po::value<std::string>()->value_name("S"),
         "seconds of wall time between checkpoints of each running realization, written beside "
         "the store in STORE.checkpoints/ (default 600; 0 = only when a realization is stopped)")  //
        ("max-deaths", po::value<std::string>()->value_name("N"),
         "a realization that was running each of the last N times the job died (its processes "
         "killed: the kernel's OOM killer under a memory limit, a crash, a lost node) is set "
         "aside, recorded as an error with the reason and not handed out again; 0 = no limit "
         "(default 3)")  //
        ("no-checkpoints", po::bool_switch(),
         "no checkpoints: a stopped realization starts over in the next run")  //
        ("dry-run", po::bool_switch(),
         "list the realizations to run and the estimated core-hours per point and in total "
         "(cost model); run and write nothing")  //
        ("allow-mixed", po::bool_switch(),
         "accept new points whose settings, not varied by the sweep, differ from the store's "
         "points (refused by default: the fits would pool different physics)")  //
        ("help,h", "show this help");
    return d;
}

double non_negative(const char* option, const std::string& text) {
    const double v = parse_finite(option, text);
    if (v < 0) throw core::ConfigError(std::string(option) + " must be >= 0, got '" + text + "'");
    return v;
}

}  // namespace

void print_run_help(std::ostream& os) {
    os << "usage: campaign run SWEEP.toml [--store PATH] [--progress-interval S] [--grace S]\n"
          "                    [--threads N] [--flush-interval S] [--worker-timeout S]\n"
          "                    [--deadline T] [--checkpoint-interval S] [--no-checkpoints]\n"
          "                    [--max-deaths N] [--dry-run] [--no-file-locking]\n"
          "                    [--allow-mixed] [--no-plots]\n"
          "       mpirun -np N campaign run SWEEP.toml ...\n\n"
          "Runs the campaign of the sweep file, or resumes it: only realizations missing from\n"
          "the store run. Under mpirun rank 0 hands out realizations and writes the store, the\n"
          "other ranks simulate (use one rank more than cores: the master sleeps while waiting).\n"
          "A store whose physics differs from the sweep file's is refused; more points or\n"
          "realizations extend it, unless the new points differ from the stored ones in a\n"
          "setting the sweep does not vary (refused unless --allow-mixed). At the end it\n"
          "analyzes the store (campaign analyze) and draws the figures into STORE_plots/\n"
          "(campaign plot; not with --no-plots or HOPPER_PLOTS=0).\n\n"
          "Signals: SIGUSR1 or SIGINT: no new realizations, running ones may finish within\n"
          "--grace seconds; SIGTERM or a second signal: stop running ones now. Either way what\n"
          "finished is stored and the exit code is 4; the same command resumes. A stopped\n"
          "realization's state is saved in STORE.checkpoints/ (also every --checkpoint-interval\n"
          "seconds) and continues from there, bit-identical, in the next run.\n\n"
          "Before anything runs, settings in the wrong unit are refused (an outlet narrower than\n"
          "a disk, a packing taller than 20 hopper widths, contacts too soft for its weight); 3\n"
          "realizations of one point failing alike before the outlet opens stop the run.\n\n"
          "exit codes: 0 all stored, 2 bad sweep file or refused store, 1 store or I/O error,\n"
          "            3 finished with failed realizations (or stopped early by identical\n"
          "            failures), 4 stopped by a signal (resumable), 5 every realization\n"
          "            stored but the analysis not written (disk full?)\n\n"
       << run_options();
}

namespace {

// `word` as one shell word: as it is when it is plain, else in single quotes.
std::string shell_quoted(const std::string& word) {
    const bool plain = !word.empty() && std::all_of(word.begin(), word.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || std::strchr("-_./=:,+@%", ch);
    });
    if (plain) return word;
    std::string out = "'";
    for (char ch : word)
        out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return out + "'";
}

// The options that shape the run: the store, the master's intervals and limits, threads,
// checkpoints (each checked, naming what is allowed).
void read_run_options(const po::variables_map& vm, campaign::RunOptions& opt) {
    if (vm.count("store")) {
        const std::string& s = vm["store"].as<std::string>();
        if (s.empty()) throw core::ConfigError("--store must not be empty");
        opt.store = s;
    }
    if (vm.count("progress-interval"))
        opt.master.progress_interval =
            non_negative("--progress-interval", vm["progress-interval"].as<std::string>());
    if (vm.count("grace"))
        opt.master.grace = non_negative("--grace", vm["grace"].as<std::string>());
    if (vm.count("flush-interval"))
        opt.store_options.flush_interval =
            non_negative("--flush-interval", vm["flush-interval"].as<std::string>());
    if (vm.count("no-file-locking")) {
        opt.store_options.require_lock = false;
        // HDF5's own switch, read when the library starts (no HDF5 call has been made yet);
        // every rank parses the same command line, so every rank sets it.
        ::setenv("HDF5_USE_FILE_LOCKING", "FALSE", 1);
    }
    if (vm.count("worker-timeout")) {
        const std::string& t = vm["worker-timeout"].as<std::string>();
        const double v = parse_finite("--worker-timeout", t);
        if (!(v >= 0.2))
            throw core::ConfigError("--worker-timeout must be at least 0.2 (seconds), got '" + t +
                                    "'");
        opt.master.worker_timeout = v;
    }
    if (vm.count("max-deaths")) {
        const std::string& t = vm["max-deaths"].as<std::string>();
        const std::uint64_t n = parse_seed("--max-deaths", t);
        if (n > 255)
            throw core::ConfigError("--max-deaths must be between 0 (no limit) and 255, got '" + t +
                                    "'");
        opt.max_deaths = static_cast<int>(n);
    }
    if (vm.count("threads")) {
        const std::string& t = vm["threads"].as<std::string>();
        const std::uint64_t n = parse_seed("--threads", t);
        if (n < 1 || n > 4096)
            throw core::ConfigError("--threads must be between 1 and 4096, got '" + t + "'");
        opt.threads = static_cast<int>(n);
        opt.threads_given = true;
    }
    opt.allow_mixed = vm["allow-mixed"].as<bool>();
    opt.dry_run = vm["dry-run"].as<bool>();
    opt.checkpoints = !vm["no-checkpoints"].as<bool>();
    if (vm.count("checkpoint-interval")) {
        if (!opt.checkpoints)
            throw core::ConfigError(
                "--checkpoint-interval and --no-checkpoints contradict each other: give one");
        opt.checkpoint_interval =
            non_negative("--checkpoint-interval", vm["checkpoint-interval"].as<std::string>());
    }
}

// --deadline (or the Slurm job's end): checked now on every rank (a bad value is an error before
// anything starts); the Slurm end time is asked for on the master only (no squeue call per rank).
void read_deadline(const po::variables_map& vm, campaign::RunOptions& opt) {
    const bool given = vm.count("deadline") > 0;
    const std::string text = given ? vm["deadline"].as<std::string>() : "";
    const char* job = std::getenv("SLURM_JOB_ID");
    const bool in_job = job && *job;
    const bool slurm = text == "slurm" || text.starts_with("slurm-");
    if (given && !slurm) {
        const auto d = parse_deadline(text, store::unix_now());
        if (d) opt.deadline = [d](std::ostream&) { return d; };
    } else if (given && !in_job) {
        parse_deadline(text, 0.0);  // throws: not inside a Slurm job (or a bad value)
    } else if (given || in_job) {
        opt.deadline = [given, text](std::ostream& err) -> std::optional<double> {
            if (given) return parse_deadline(text, 0.0);  // throws, naming the reason
            std::string why;
            if (auto t = slurm_job_end(&why)) return t;
            err << "campaign: note: no deadline (" << why
                << "); give --deadline to stop starting realizations that cannot finish"
                << std::endl;
            return std::nullopt;
        };
    }
}

// The store's test hooks (not for users), from the environment.
void read_test_hooks(campaign::RunOptions& opt) {
    // Test hook (not for users): HOPPER_STORE_CRASH=<point>:<n> makes the store raise SIGKILL
    // the n-th time it passes <point> (journal, hdf5, rebuild, close); see store.hpp.
    if (const char* crash = std::getenv("HOPPER_STORE_CRASH")) {
        const std::string c = crash;
        const auto colon = c.find(':');
        if (colon == std::string::npos)
            throw core::ConfigError("HOPPER_STORE_CRASH must be <point>:<n>, got '" + c + "'");
        opt.store_options.crash_point = c.substr(0, colon);
        opt.store_options.crash_after =
            static_cast<int>(parse_seed("HOPPER_STORE_CRASH", c.substr(colon + 1)));
    }
    // Test hook (not for users): HOPPER_STORE_STOP=result:<n> makes the store raise SIGSTOP once
    // the n-th result of the run is durable (tests act on the run frozen there; see store.hpp).
    if (const char* stop = std::getenv("HOPPER_STORE_STOP")) {
        const std::string c = stop;
        const std::string prefix = "result:";
        if (c.rfind(prefix, 0) != 0)
            throw core::ConfigError("HOPPER_STORE_STOP must be result:<n>, got '" + c + "'");
        const std::uint64_t n = parse_seed("HOPPER_STORE_STOP", c.substr(prefix.size()));
        if (n < 1 || n > 1000000)
            throw core::ConfigError("HOPPER_STORE_STOP's n must be 1 to 1000000, got '" + c + "'");
        opt.store_options.stop_after_results = static_cast<int>(n);
    }
    // Test hook (not for users): HOPPER_STORE_PAUSE=journal_link:<ms> pauses a run that creates
    // a new store's journal before linking it into place (the race of two runs on a new store).
    if (const char* pause = std::getenv("HOPPER_STORE_PAUSE")) {
        const std::string c = pause;
        const std::string prefix = "journal_link:";
        if (c.rfind(prefix, 0) != 0)
            throw core::ConfigError("HOPPER_STORE_PAUSE must be journal_link:<ms>, got '" + c +
                                    "'");
        const auto ms =
            std::chrono::milliseconds(parse_seed("HOPPER_STORE_PAUSE", c.substr(prefix.size())));
        opt.store_options.before_journal_link = [ms] { std::this_thread::sleep_for(ms); };
    }
}

// At the end of a run that was not stopped: the same analysis as `campaign analyze`, then the
// figures unless `plots` is off. Returns the run's exit code.
int analyze_and_plot(const std::filesystem::path& store, int code, bool plots) {
    if (code == campaign::run_stopped) return code;
    std::cout << '\n';
    // Issue 29, item 5: a run whose analysis could not be written (a full disk) must not
    // exit 0: a script or a Slurm chain takes 0 as "done, analyzed".
    const int not_written = code != exit_ok ? code : exit_analysis_not_written;
    try {
        bool written = false;
        const int a = analyze_store(store, false, true, std::cout, std::cerr, &written);
        if (!written) {
            std::cerr << "campaign: every realization is stored (the journal holds them), but "
                         "the analysis is not in the store: free space and run `campaign "
                         "analyze "
                      << store.string() << "`" << std::endl;
            return not_written;
        }
        if (a != 0) return code;
    } catch (const std::exception& e) {
        std::cerr << "campaign: the analysis failed (the realizations are stored; retry with "
                     "`campaign analyze "
                  << store.string() << "`): " << e.what() << std::endl;
        return not_written;
    }
    fs::path out = store;
    out.replace_extension();
    const std::string dir = out.string() + "_plots";
    if (!plots) {
        std::cout << "figures: campaign plot " << store.string() << " --out " << dir << '\n';
        std::cout.flush();
        return code;
    }
    // The figures, drawn by analysis/plots.py (a failure here never changes the run's code:
    // the realizations and the analysis are stored).
    std::cout << "figures (campaign plot " << store.string() << " --out " << dir << "):\n";
    try {
        if (run_python(analysis_dir() / "plots.py", {store.string(), "--out", dir}) != 0)
            std::cerr << "campaign: note: the figures could not be drawn (see above); the "
                         "store is complete: retry with `campaign plot "
                      << store.string() << "`\n";
    } catch (const std::exception& e) {
        std::cerr << "campaign: note: no figures: " << e.what() << '\n';
    }
    std::cout.flush();
    return code;
}

}  // namespace

int run_command(const std::vector<std::string>& args, const std::string& command_line) {
    const po::variables_map vm = parse_command(args, run_options(), "sweep");
    if (vm.count("help")) {
        print_run_help(std::cout);
        return 0;
    }
    const std::string sweep_path = single_positional(vm, "sweep", "sweep file", "SWEEP.toml");
    campaign::RunOptions opt;
    opt.sweep = sweep_path;
    read_run_options(vm, opt);
    read_deadline(vm, opt);
    read_test_hooks(opt);
    opt.code_version = HOPPER_VERSION;
    opt.command_line = command_line;
    opt.resume_command = "campaign run";
    for (const auto& a : args)
        opt.resume_command += " " + shell_quoted(a);
    // At the end of a run that was not stopped: the same analysis as `campaign analyze`.
    // Figures at the end unless --no-plots (or HOPPER_PLOTS=0, which the test suite sets so
    // that its many small runs do not each start Python).
    const char* env_plots = std::getenv("HOPPER_PLOTS");
    const bool plots = !vm["no-plots"].as<bool>() && !(env_plots && std::string(env_plots) == "0");
    opt.after_run = [plots](const std::filesystem::path& store, int code) {
        return analyze_and_plot(store, code, plots);
    };
    // SIGUSR1 asks for a drain while the master runs (it installs its own handler then); before
    // and after that, e.g. while the analysis runs at the end, it must not kill the process
    // (its default action): under Slurm the warning signal can arrive just as a run that its
    // deadline ended is finishing (exit 138 before this).
    std::signal(SIGUSR1, SIG_IGN);
    return campaign::run_campaign(opt, std::cout, std::cerr);
}

}  // namespace hopper::cli
