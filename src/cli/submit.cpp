#include "cli/submit.hpp"
#include "cli/parse.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <boost/program_options.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <vector>

#include "cli/options.hpp"
#include "cli/simulate.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/run.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"

namespace hopper::cli {

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

using core::ConfigError;

po::options_description submit_options() {
    po::options_description d("submit options");
    d.add_options()  //
        ("store", po::value<std::string>()->value_name("PATH"),
         "the store (default: [campaign] store of the sweep file, relative to it)")               //
        ("nodes", po::value<std::string>()->value_name("N"), "nodes per allocation (default 1)")  //
        ("ntasks", po::value<std::string>()->value_name("N"),
         "tasks per allocation (default 2): N workers, the master an extra rank beside them "
         "(--master-slot shared), or 1 master + N-1 workers (--master-slot own)")  //
        ("time", po::value<std::string>()->value_name("T"),
         "time limit of each allocation: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS "
         "(default 1:00:00)")                                                        //
        ("partition", po::value<std::string>()->value_name("P"), "Slurm partition")  //
        ("account", po::value<std::string>()->value_name("A"), "Slurm account")      //
        ("max-resubmits", po::value<std::string>()->value_name("K"),
         "resubmit at most K times while realizations are pending (default 10)")  //
        ("signal-lead", po::value<std::string>()->value_name("S"),
         "ask Slurm for SIGUSR1 S seconds before the limit (default 120; Slurm may send it up "
         "to a minute later)")  //
        ("grace", po::value<std::string>()->value_name("S"),
         "after the signal, running realizations may finish within S seconds (default 60; "
         "less than --signal-lead)")  //
        ("launcher", po::value<std::string>()->value_name("L"),
         "srun (srun --mpi=pmix, default), mpirun, or none (one process)")  //
        ("setup", po::value<std::string>()->value_name("FILE"),
         "a shell file the job sources first (module load ...)")  //
        ("job-name", po::value<std::string>()->value_name("NAME"),
         "Slurm job name (default: hopper-<campaign name>)")  //
        ("template", po::value<std::string>()->value_name("FILE"),
         "render FILE instead of the built-in slurm/hopper.sbatch.in")  //
        ("cpus-per-task", po::value<std::string>()->value_name("N"),
         "#SBATCH --cpus-per-task=N; under srun or mpirun each rank then runs N realizations at "
         "once (--threads N) unless --threads says otherwise (a warning when they differ)")  //
        ("mem", po::value<std::string>()->value_name("SIZE"),
         "#SBATCH --mem=SIZE per node: a number with an optional unit K, M, G or T (e.g. 4G)")  //
        ("qos", po::value<std::string>()->value_name("Q"), "#SBATCH --qos=Q")                   //
        ("constraint", po::value<std::string>()->value_name("EXPR"),
         "#SBATCH --constraint=EXPR (node features: letters, digits and _ . & | , * [ ] : ( ))")  //
        ("mail-type", po::value<std::string>()->value_name("TYPES"),
         "#SBATCH --mail-type=TYPES: comma-separated NONE, BEGIN, END, FAIL, REQUEUE, ALL, "
         "INVALID_DEPEND, STAGE_OUT, TIME_LIMIT, TIME_LIMIT_90, TIME_LIMIT_80, TIME_LIMIT_50, "
         "ARRAY_TASKS")                                                                          //
        ("mail-user", po::value<std::string>()->value_name("ADDR"), "#SBATCH --mail-user=ADDR")  //
        ("exclusive", po::bool_switch(), "#SBATCH --exclusive (whole nodes)")                    //
        ("sbatch-arg", po::value<std::vector<std::string>>()->value_name("ARG"),
         "any other sbatch option, as one #SBATCH line each (repeatable), e.g. "
         "--sbatch-arg=--gres=gpu:0 --sbatch-arg=--reservation=r1")  //
        ("launcher-arg", po::value<std::vector<std::string>>()->value_name("ARG"),
         "an argument added to the srun or mpirun command line (repeatable), e.g. "
         "--launcher-arg=--cpu-bind=cores; a warning with --launcher none")  //
        ("master-slot", po::value<std::string>()->value_name("M"),
         "shared (default): the launcher starts one rank more than --ntasks, the master, "
         "oversubscribed (it sleeps while waiting, 1-2 % of a core): N tasks give N workers; "
         "own: the master takes one of the N tasks (N-1 workers)")  //
        ("threads", po::value<std::string>()->value_name("N"),
         "worker threads: with --launcher none, of the one process (default: --ntasks); under "
         "srun or mpirun, of every rank (hybrid: each rank runs N realizations at once; default "
         "--cpus-per-task, else 1)")  //
        ("checkpoint-interval", po::value<std::string>()->value_name("S"),
         "campaign run --checkpoint-interval S (default 600: running realizations save their "
         "state every S s; 0 = only when stopped)")  //
        ("no-checkpoints", po::bool_switch(),
         "campaign run --no-checkpoints (a realization stopped at the limit starts over)")  //
        ("max-deaths", po::value<std::string>()->value_name("N"),
         "campaign run --max-deaths N (default 3: a realization running each of the last 3 "
         "times the job died, killed for memory, is set aside; 0 = no limit)")  //
        ("deadline", po::value<std::string>()->value_name("D"),
         "slurm (default: campaign run --deadline slurm-(LEAD-GRACE): it starts no realization "
         "expected to end after the moment the warning signal is due, and stops running ones "
         "then, saving their states) or none (dispatch ignores the limit)")  //
        ("dry-run", po::bool_switch(),
         "print the batch script and, on stderr, the realizations to run and their estimated "
         "core-hours; write and submit nothing")  //
        ("help,h", "show this help");
    return d;
}

// Positive integer option in [1, max].
long positive(const po::variables_map& vm, const char* name, long fallback, long max) {
    if (!vm.count(name)) return fallback;
    const std::string& text = vm[name].as<std::string>();
    const std::uint64_t v = parse_seed(std::string("--") + name, text);
    if (v < 1 || v > static_cast<std::uint64_t>(max))
        throw ConfigError(std::string("--") + name + " must be between 1 and " +
                          std::to_string(max) + ", got '" + text + "'");
    return static_cast<long>(v);
}

// A Slurm name (partition, account, job name): letters, digits, '_', '-', '.'.
std::string slurm_name(const po::variables_map& vm, const char* name, const std::string& fallback) {
    if (!vm.count(name)) return fallback;
    const std::string& text = vm[name].as<std::string>();
    static const std::regex ok("[A-Za-z0-9_.-]{1,64}");
    if (!std::regex_match(text, ok))
        throw ConfigError(std::string("--") + name +
                          " must be 1-64 letters, digits, '_', '-' or '.', got '" + text + "'");
    return text;
}

// A path for the batch script, in single quotes (no quote, newline or NUL inside).
std::string quoted(const std::string& what, const fs::path& p) {
    const std::string s = p.string();
    if (s.find_first_of(std::string("'\n\r\0", 4)) != std::string::npos)
        throw ConfigError(what + " must not contain a quote or a newline: '" + s + "'");
    return "'" + s + "'";
}

fs::path self_executable() {
    std::error_code ec;
    const fs::path p = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw std::runtime_error("cannot find the campaign executable: " + ec.message());
    return p;
}

std::string read_file(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    if (!in) throw ConfigError("cannot read the template '" + p.string() + "'");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The first executable `name` on PATH, or empty.
fs::path on_path(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::stringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const fs::path p = fs::path(dir.empty() ? "." : dir) / name;
        if (::access(p.c_str(), X_OK) == 0) return p;
    }
    return {};
}

// Runs argv, returns (exit code, stdout+stderr).
std::pair<int, std::string> run_capture(const std::vector<std::string>& argv) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("fork failed");
    if (pid == 0) {
        ::dup2(fds[1], 1);
        ::dup2(fds[1], 2);
        ::close(fds[0]);
        ::close(fds[1]);
        std::vector<char*> args;
        for (const auto& a : argv)
            args.push_back(const_cast<char*>(a.c_str()));
        args.push_back(nullptr);
        ::execv(args[0], args.data());
        ::_exit(127);
    }
    ::close(fds[1]);
    std::string out;
    std::array<char, 4096> buf;
    ssize_t n;
    while ((n = ::read(fds[0], buf.data(), buf.size())) > 0)
        out.append(buf.data(), static_cast<std::size_t>(n));
    ::close(fds[0]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), out};
}

}  // namespace

long parse_slurm_time(const std::string& option, const std::string& text) {
    // D-HH[:MM[:SS]] or MM, MM:SS, HH:MM:SS.
    static const std::regex days(R"((\d+)-(\d+)(?::(\d+)(?::(\d+))?)?)");
    static const std::regex clock(R"((\d+)(?::(\d+)(?::(\d+))?)?)");
    std::smatch m;
    long s = 0;
    auto num = [&](int i) { return m[i].matched ? std::stol(m[i].str()) : 0L; };
    if (text.size() <= 12 && std::regex_match(text, m, days)) {
        s = num(1) * 86400 + num(2) * 3600 + num(3) * 60 + num(4);
    } else if (text.size() <= 12 && std::regex_match(text, m, clock)) {
        if (m[3].matched)
            s = num(1) * 3600 + num(2) * 60 + num(3);
        else
            s = num(1) * 60 + num(2);
    } else {
        throw ConfigError(option +
                          " must be a Slurm time (MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or "
                          "D-HH:MM:SS), got '" +
                          text + "'");
    }
    if (s <= 0) throw ConfigError(option + " must be longer than zero, got '" + text + "'");
    return s;
}

std::string render_template(const std::string& tmpl,
                            const std::map<std::string, std::string>& values) {
    std::string out;
    std::istringstream lines(tmpl);
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        std::string rendered;
        bool any = false, all_empty = true;
        std::size_t pos = 0;
        for (;;) {
            const std::size_t open = line.find("{{", pos);
            if (open == std::string::npos) {
                rendered += line.substr(pos);
                break;
            }
            const std::size_t close = line.find("}}", open);
            if (close == std::string::npos)
                throw ConfigError("template line " + std::to_string(number) +
                                  ": '{{' without '}}'");
            const std::string name = line.substr(open + 2, close - open - 2);
            const auto it = values.find(name);
            if (it == values.end())
                throw ConfigError("template line " + std::to_string(number) +
                                  ": unknown placeholder {{" + name + "}}");
            any = true;
            all_empty = all_empty && it->second.empty();
            rendered += line.substr(pos, open - pos) + it->second;
            pos = close + 2;
        }
        if (any && all_empty && line.starts_with("#SBATCH")) continue;
        out += rendered + '\n';
    }
    return out;
}

void print_submit_help(std::ostream& os) {
    os << "usage: campaign submit SWEEP.toml [--nodes N] [--ntasks N] [--time T]\n"
          "                       [--partition P] [--account A] [--max-resubmits K]\n"
          "                       [--signal-lead S] [--grace S] [--launcher srun|mpirun|none]\n"
          "                       [--setup FILE] [--job-name NAME] [--template FILE]\n"
          "                       [--cpus-per-task N] [--mem SIZE] [--qos Q] [--constraint E]\n"
          "                       [--mail-type T] [--mail-user A] [--exclusive]\n"
          "                       [--sbatch-arg ARG]... [--launcher-arg ARG]...\n"
          "                       [--master-slot shared|own] [--threads N]\n"
          "                       [--checkpoint-interval S] [--no-checkpoints]\n"
          "                       [--max-deaths N] [--deadline slurm|none] [--store PATH]\n"
          "                       [--dry-run]\n\n"
          "Submits the campaign of a sweep file to Slurm. The batch script (written next to the\n"
          "store as STORE.sbatch, its log STORE.slurm.log) runs `campaign run` under srun or\n"
          "mpirun, asks Slurm for SIGUSR1 before the time limit, drains on it (running\n"
          "realizations finish within the grace time and are stored, or are stopped with their\n"
          "state saved in STORE.checkpoints/ to continue in the next allocation) and resubmits\n"
          "itself while the store has pending realizations, at most K times. The run starts no\n"
          "realization that cannot end before the warning signal is due (--deadline).\n"
          "Submitting again resumes.\n\n"
          "exit codes: 0 submitted (or, with --dry-run, the script and estimate printed),\n"
          "            2 bad command line or sweep file, 1 sbatch failed or another error\n\n"
       << submit_options();
}

namespace {

// The job: the store and its files, the allocation, the time limit and the signal's lead,
// resubmissions, the launcher and the job's name (each checked, naming what is allowed).
struct Job {
    fs::path store, script, log;
    long nodes = 1, ntasks = 2, limit = 0, lead = 0, max_resubmits = 10;
    std::string time, launcher, setup = "# (no --setup file)", job_name;
    double grace = 60.0;
};

Job read_job(const po::variables_map& vm, const config::SweepFile& sweep) {
    Job j;
    fs::path store = sweep.campaign.store;
    if (vm.count("store")) {
        const std::string& s = vm["store"].as<std::string>();
        if (s.empty()) throw ConfigError("--store must not be empty");
        store = s;
    }
    j.store = fs::absolute(store).lexically_normal();
    j.script = j.store.string() + ".sbatch";
    j.log = j.store.string() + ".slurm.log";

    j.nodes = positive(vm, "nodes", 1, 100000);
    j.ntasks = positive(vm, "ntasks", 2, 10000000);
    if (j.ntasks < j.nodes)
        throw ConfigError("--ntasks (" + std::to_string(j.ntasks) + ") must be at least --nodes (" +
                          std::to_string(j.nodes) + ")");
    j.time = vm.count("time") ? vm["time"].as<std::string>() : "1:00:00";
    j.limit = parse_slurm_time("--time", j.time);
    j.lead = positive(vm, "signal-lead", 120, 65535);
    j.max_resubmits = vm.count("max-resubmits")
                          ? static_cast<long>(parse_seed("--max-resubmits",
                                                         vm["max-resubmits"].as<std::string>()))
                          : 10;
    if (j.max_resubmits > 10000)
        throw ConfigError("--max-resubmits must be at most 10000, got " +
                          std::to_string(j.max_resubmits));
    if (vm.count("grace")) {
        j.grace = parse_finite("--grace", vm["grace"].as<std::string>());
        if (j.grace < 0) throw ConfigError("--grace must be >= 0");
    }
    if (j.lead >= j.limit)
        throw ConfigError("--signal-lead (" + std::to_string(j.lead) +
                          " s) must be shorter than --time (" + j.time + " = " +
                          std::to_string(j.limit) + " s)");
    if (j.grace >= static_cast<double>(j.lead))
        throw ConfigError("--grace (" + std::to_string(static_cast<long>(j.grace)) +
                          " s) must be shorter than --signal-lead (" + std::to_string(j.lead) +
                          " s), so that the drain ends before the limit");
    j.launcher = vm.count("launcher") ? vm["launcher"].as<std::string>() : "srun";
    if (j.launcher != "srun" && j.launcher != "mpirun" && j.launcher != "none")
        throw ConfigError("--launcher must be srun, mpirun or none, got '" + j.launcher + "'");
    if (vm.count("setup")) {
        const fs::path f = fs::absolute(vm["setup"].as<std::string>());
        if (!fs::is_regular_file(f))
            throw ConfigError("--setup file '" + f.string() + "' does not exist");
        j.setup = "source " + quoted("--setup", f);
    }
    j.job_name = slurm_name(
        vm, "job-name",
        "hopper-" + (sweep.campaign.name.empty() ? std::string("campaign") : sweep.campaign.name));
    if (!std::regex_match(j.job_name, std::regex("[A-Za-z0-9_.-]{1,64}")))
        throw ConfigError("the campaign name makes a bad job name '" + j.job_name +
                          "': give --job-name");

    return j;
}

// The site's options (issue 15): CPUs, memory, QOS, constraints, mail, extra sbatch and
// launcher arguments.
struct Site {
    std::string cpus, mem, qos, constraint, mail_type, mail_user, sbatch_args, launcher_args;
};

Site read_site(const po::variables_map& vm, const std::string& launcher) {
    Site site;
    auto matching = [&](const char* name, const std::regex& re, const std::string& allowed) {
        if (!vm.count(name)) return std::string();
        const std::string& text = vm[name].as<std::string>();
        if (!std::regex_match(text, re))
            throw ConfigError(std::string("--") + name + " must be " + allowed + ", got '" + text +
                              "'");
        return text;
    };
    site.cpus =
        vm.count("cpus-per-task") ? std::to_string(positive(vm, "cpus-per-task", 1, 4096)) : "";
    site.mem = matching("mem", std::regex("[0-9]{1,12}[KMGT]?"),
                        "a number with an optional unit K, M, G or T (e.g. 4G)");
    site.qos = slurm_name(vm, "qos", "");
    site.constraint = matching("constraint", std::regex(R"([A-Za-z0-9_.&|,*\[\]:()]{1,256})"),
                               "node features: letters, digits and _ . & | , * [ ] : ( )");
    site.mail_type =
        matching("mail-type",
                 std::regex("((NONE|BEGIN|END|FAIL|REQUEUE|ALL|INVALID_DEPEND|STAGE_OUT|TIME_"
                            "LIMIT|TIME_LIMIT_90|TIME_LIMIT_80|TIME_LIMIT_50|ARRAY_TASKS),?)+"),
                 "a comma-separated list of NONE, BEGIN, END, FAIL, REQUEUE, ALL, "
                 "INVALID_DEPEND, STAGE_OUT, TIME_LIMIT, TIME_LIMIT_90, TIME_LIMIT_80, "
                 "TIME_LIMIT_50, ARRAY_TASKS");
    site.mail_user =
        matching("mail-user", std::regex(R"([A-Za-z0-9._%+-]{1,64}(@[A-Za-z0-9.-]{1,190})?)"),
                 "a user name or e-mail address");
    if (!site.mail_user.empty() && site.mail_type.empty())
        std::cerr << "campaign: warning: --mail-user without --mail-type: Slurm mails only what "
                     "the site's default mail type says (give --mail-type END,FAIL, say)\n";
    if (!site.mail_type.empty() && site.mail_user.empty())
        std::cerr << "campaign: note: --mail-type without --mail-user: mail goes to the "
                     "submitting user\n";
    auto no_newline = [](const std::string& option, const std::string& a) {
        if (a.empty() || a.find_first_of(std::string("\n\r\0'", 4)) != std::string::npos)
            throw ConfigError(option +
                              " must be one non-empty argument without quotes or "
                              "newlines, got '" +
                              a + "'");
    };
    if (vm.count("sbatch-arg"))
        for (const std::string& a : vm["sbatch-arg"].as<std::vector<std::string>>()) {
            no_newline("--sbatch-arg", a);
            if (!a.starts_with("-"))
                throw ConfigError("--sbatch-arg must be an sbatch option starting with '-', got '" +
                                  a + "'");
            for (const char* own : {"--signal", "--output", "--open-mode", "--job-name",
                                    "--dependency", "-o", "-J", "-d"})
                if (a == own || a.starts_with(std::string(own) + "=") ||
                    (std::string(own).size() == 2 && a.starts_with(own)))
                    throw ConfigError("--sbatch-arg '" + a +
                                      "' would override what the template needs (" + own +
                                      "); use the first-class option or --template");
            site.sbatch_args += (site.sbatch_args.empty() ? "" : "\n#SBATCH ") + a;
        }
    if (vm.count("launcher-arg")) {
        for (const std::string& a : vm["launcher-arg"].as<std::vector<std::string>>()) {
            no_newline("--launcher-arg", a);
            site.launcher_args += (site.launcher_args.empty() ? "'" : " '") + a + "'";
        }
        if (launcher == "none")
            std::cerr << "campaign: warning: --launcher-arg is ignored with --launcher none (no "
                         "launcher runs)\n";
    }
    return site;
}

// Where the master runs and how many worker threads each process has: of the one process
// (--launcher none; default --ntasks), or of every rank (hybrid; default 1, or --cpus-per-task).
struct Workers {
    std::string master_slot;
    long threads = 1;
    // Workers in all: what the cost estimate divides by.
    long total(const Job& j) const {
        const long ranks = master_slot == "shared" ? j.ntasks : j.ntasks - 1;
        return std::max(1L, j.launcher == "none" ? threads : ranks * threads);
    }
};

Workers read_workers(const po::variables_map& vm, const Job& j, const std::string& cpus) {
    Workers w;
    w.master_slot = vm.count("master-slot") ? vm["master-slot"].as<std::string>() : "shared";
    if (w.master_slot != "shared" && w.master_slot != "own")
        throw ConfigError("--master-slot must be shared or own, got '" + w.master_slot + "'");
    if (j.launcher == "none" && vm.count("master-slot"))
        std::cerr << "campaign: warning: --master-slot is ignored with --launcher none (one "
                     "process: the master is a thread beside the worker threads)\n";
    if (j.launcher != "none" && w.master_slot == "own" && j.ntasks < 2)
        throw ConfigError("--master-slot own needs --ntasks of at least 2 (1 master + workers)");
    const long cpt = cpus.empty() ? 1 : std::stol(cpus);
    long& threads = w.threads;
    threads = j.launcher == "none" ? j.ntasks : cpt;
    if (vm.count("threads")) threads = positive(vm, "threads", 1, 4096);
    if (j.launcher != "none" && threads < cpt)
        std::cerr << "campaign: warning: --cpus-per-task " << cpt << " with " << threads
                  << " thread(s) per rank: " << (cpt - threads) << " of every " << cpt
                  << " CPUs stay idle (give --threads " << cpt << ")\n";
    if (j.launcher != "none" && threads > cpt)
        std::cerr << "campaign: warning: --threads " << threads << " with --cpus-per-task " << cpt
                  << ": each rank runs " << threads << " realizations on " << cpt
                  << " CPU(s) (give --cpus-per-task " << threads << ")\n";
    if (j.launcher == "none" && !cpus.empty())
        std::cerr << "campaign: warning: --cpus-per-task is only an #SBATCH line with --launcher "
                     "none: the one process runs --threads workers\n";
    if (j.launcher == "none" && j.ntasks > 1 && !vm.count("threads"))
        std::cerr << "campaign: note: --launcher none: one process with " << j.ntasks
                  << " worker threads (--ntasks)\n";
    return w;
}

// The arguments the batch script gives `campaign run`: threads, checkpoints, deaths, deadline.
std::string run_arguments(const po::variables_map& vm, const Job& j, const Workers& w) {
    std::string run_args;
    if (j.launcher == "none" || w.threads > 1) run_args += "--threads " + std::to_string(w.threads);
    auto add_run = [&](const std::string& a) { run_args += (run_args.empty() ? "" : " ") + a; };
    if (vm["no-checkpoints"].as<bool>()) {
        if (vm.count("checkpoint-interval"))
            throw ConfigError(
                "--checkpoint-interval and --no-checkpoints contradict each other: give one");
        add_run("--no-checkpoints");
    } else if (vm.count("checkpoint-interval")) {
        const double ci =
            parse_finite("--checkpoint-interval", vm["checkpoint-interval"].as<std::string>());
        if (ci < 0) throw ConfigError("--checkpoint-interval must be >= 0");
        std::ostringstream t;
        t << ci;
        add_run("--checkpoint-interval " + t.str());
    }
    if (vm.count("max-deaths")) {
        const std::string& t = vm["max-deaths"].as<std::string>();
        const std::uint64_t n = parse_seed("--max-deaths", t);
        if (n > 255)
            throw ConfigError("--max-deaths must be between 0 (no limit) and 255, got '" + t + "'");
        add_run("--max-deaths " + std::to_string(n));
    }
    {
        // The run's deadline: when Slurm's warning signal is due (the end time minus the lead)
        // plus the grace, so that what the master starts ends before the signal would drain it.
        const std::string d = vm.count("deadline") ? vm["deadline"].as<std::string>() : "slurm";
        if (d != "slurm" && d != "none")
            throw ConfigError(
                "--deadline must be slurm or none for submit (the job's end "
                "time, or no time-aware dispatch), got '" +
                d + "'");
        std::ostringstream t;
        t << (static_cast<double>(j.lead) - j.grace);
        add_run(d == "none" ? "--deadline none" : "--deadline slurm-" + t.str());
    }

    return run_args;
}

// The batch template's values (slurm/README.md lists them).
std::map<std::string, std::string> template_values(const po::variables_map& vm, const Job& j,
                                                   const Site& site, const Workers& w,
                                                   const std::string& run_args,
                                                   const std::string& sweep_path) {
    std::ostringstream grace_text;
    grace_text << j.grace;
    return {
        {"JOB_NAME", j.job_name},
        {"NODES", std::to_string(j.nodes)},
        {"NTASKS", std::to_string(j.ntasks)},
        {"TIME", j.time},
        {"PARTITION", slurm_name(vm, "partition", "")},
        {"ACCOUNT", slurm_name(vm, "account", "")},
        {"SIGNAL_LEAD", std::to_string(j.lead)},
        {"LOG", j.log.string()},
        {"CAMPAIGN", quoted("the campaign executable's path", self_executable())},
        {"SWEEP", quoted("the sweep file's path", fs::absolute(sweep_path).lexically_normal())},
        {"STORE", quoted("the store's path", j.store)},
        {"SCRIPT", quoted("the batch script's path", j.script)},
        {"LAUNCHER", j.launcher},
        {"GRACE", grace_text.str()},
        {"MAX_RESUBMITS", std::to_string(j.max_resubmits)},
        {"SETUP", j.setup},
        {"CPUS_PER_TASK", site.cpus},
        {"MEM", site.mem},
        {"QOS", site.qos},
        {"CONSTRAINT", site.constraint},
        {"MAIL_TYPE", site.mail_type},
        {"MAIL_USER", site.mail_user},
        {"EXCLUSIVE", vm["exclusive"].as<bool>() ? "--exclusive" : ""},
        {"SBATCH_ARGS", site.sbatch_args},
        {"LAUNCHER_ARGS", site.launcher_args},
        {"MASTER_SLOT", w.master_slot},
        {"RUN_ARGS", run_args},
    };
}

// --dry-run: the script on stdout; what the batch job would run and its cost (campaign run
// --dry-run), and whether the chain of allocations can finish, on stderr.
int print_dry_run(const std::string& text, const Job& j, const Workers& w,
                  const std::string& sweep_path) {
    std::cout << text;
    std::cout.flush();
    // What the batch job would run, and its cost (campaign run --dry-run), on stderr.
    campaign::RunOptions ro;
    ro.sweep = sweep_path;
    ro.store = j.store;
    const long workers = w.total(j);
    ro.threads = static_cast<int>(workers);
    std::ostringstream est;
    campaign::DryRunTotals totals;
    campaign::dry_run(ro, est, std::cerr, &totals);
    std::cerr << est.str();
    const Chain chain{1 + j.max_resubmits,
                      j.limit,
                      j.lead,
                      workers,
                      j.ntasks,
                      j.launcher == "none" ? 1 : w.threads,
                      j.launcher != "none" && w.master_slot == "own"};
    std::cerr << chain_warning(chain, totals.worker_seconds, totals.longest_seconds);
    return 0;
}

// Writes the script beside the store and hands it to sbatch.
int submit_script(const std::string& text, const Job& j) {
    const fs::path sbatch = on_path("sbatch");
    if (sbatch.empty())
        throw std::runtime_error(
            "sbatch not found on PATH: submit on a Slurm login node, or use --dry-run to see the "
            "batch script (slurm/slurm-up.sh starts a single-node Slurm on this machine)");
    fs::create_directories(j.store.parent_path());
    {
        std::ofstream out(j.script, std::ios::trunc);
        out << text;
        if (!out.flush()) throw std::runtime_error("cannot write '" + j.script.string() + "'");
    }
    fs::permissions(j.script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
    const auto [code, output] = run_capture(
        {sbatch.string(), "--parsable", "--export=ALL,HOPPER_ALLOCATION=1", j.script.string()});
    if (code != 0)
        throw std::runtime_error("sbatch " + j.script.string() + " failed (exit " +
                                 std::to_string(code) + "): " + output);
    std::string job = output.substr(0, output.find_first_of(";\n"));
    std::cout << "submitted job " << job << " (" << j.job_name << ", " << j.nodes << " node(s), "
              << j.ntasks << " task(s), --time " << j.time << " per allocation, at most "
              << j.max_resubmits << " resubmission(s))\n"
              << "  script  " << j.script.string() << "\n"
              << "  follow  squeue -u $USER -n " << j.job_name << "\n"
              << "          tail -f " << j.log.string() << "\n"
              << "          campaign status " << j.store.string() << "\n";
    return 0;
}

}  // namespace

int submit_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, submit_options(), "sweep");
    if (vm.count("help")) {
        print_submit_help(std::cout);
        return 0;
    }
    const std::string sweep_path = single_positional(vm, "sweep", "sweep file", "SWEEP.toml");

    // The sweep file is checked here, on the login node, not in the queue.
    const config::SweepFile sweep = config::load_sweep(sweep_path);
    if (!sweep.has_campaign)
        throw ConfigError("'" + sweep_path + "' has no [campaign] section: nothing to submit");
    const Job j = read_job(vm, sweep);
    const Site site = read_site(vm, j.launcher);
    const Workers w = read_workers(vm, j, site.cpus);
    const std::string run_args = run_arguments(vm, j, w);
    quoted("the log's path", j.log);  // #SBATCH --output= takes no quotes: no spaces either
    if (j.log.string().find_first_of(" \t%") != std::string::npos)
        throw ConfigError(
            "the store's path must not contain spaces or '%' for Slurm's --output: '" +
            j.log.string() + "'");
    const std::string tmpl =
        vm.count("template") ? read_file(vm["template"].as<std::string>()) : sbatch_template;
    const std::string text =
        render_template(tmpl, template_values(vm, j, site, w, run_args, sweep_path));

    if (vm["dry-run"].as<bool>()) return print_dry_run(text, j, w, sweep_path);
    return submit_script(text, j);
}

namespace {

// "1:05:00", "2-04:00:00" (Slurm's --time), rounded up to whole minutes.
std::string slurm_time(double seconds) {
    const long minutes = static_cast<long>(std::ceil(seconds / 60.0));
    char buf[64];
    if (minutes >= 24 * 60)
        std::snprintf(buf, sizeof buf, "%ld-%02ld:%02ld:00", minutes / 1440, minutes % 1440 / 60,
                      minutes % 60);
    else
        std::snprintf(buf, sizeof buf, "%ld:%02ld:00", minutes / 60, minutes % 60);
    return buf;
}

}  // namespace

std::string chain_warning(const Chain& c, double worker_seconds, double longest_s) {
    constexpr double spare = 1.2;  // the load balance: the last realizations leave workers idle
    const double usable = static_cast<double>(std::max(1L, c.time_s - c.lead_s));
    const double capacity = static_cast<double>(c.allocations) * usable * c.workers;
    std::ostringstream w;
    if (worker_seconds * spare > capacity) {
        const double need = worker_seconds * spare;
        // More workers at the same --time: whole ranks of `threads` workers (+ the master's).
        const double workers = std::ceil(need / (c.allocations * usable));
        const long ranks =
            static_cast<long>(std::ceil(workers / c.threads)) + (c.own_master ? 1 : 0);
        // A longer --time at the same --ntasks.
        const double time = need / (static_cast<double>(c.allocations) * c.workers) + c.lead_s;
        w << "campaign: warning: the chain cannot finish the estimate: " << c.allocations
          << " allocation(s) x " << slurm_time(static_cast<double>(c.time_s)) << " x " << c.workers
          << " worker(s) hold " << campaign::format_duration(capacity)
          << " of worker time, the estimate needs " << campaign::format_duration(worker_seconds)
          << " (" << campaign::format_duration(need)
          << " with 20 % for the load balance). Use --ntasks " << ranks
          << " (same --time), or --time " << slurm_time(time) << " (same --ntasks), or "
          << "more --max-resubmits; the chain stops at its last allocation with realizations "
             "pending (the same command submits it again)\n";
    }
    if (longest_s > usable)
        w << "campaign: note: one realization is expected to take "
          << campaign::format_duration(longest_s) << ", longer than an allocation's "
          << campaign::format_duration(usable)
          << " of work: it finishes across allocations from its checkpoints (keep them on)\n";
    return w.str();
}

}  // namespace hopper::cli
