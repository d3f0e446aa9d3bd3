// fuzz_inputs: malformed-input fuzzing of sweep files and stores (issue 6, item 4).
//
// Generates cases deterministically from a seed (even ids: a mutated sweep file, odd ids: a
// damaged store), runs each in a forked child with a wall-clock limit, and classifies it:
//   ok-run       every operation succeeded and its results are sane (finite)
//   clean-error  an operation failed with the project's own error type and a clear message
//   CRASH        the child died of a signal (segfault, abort, sanitizer report) or exited
//                without reporting
//   HANG         the child did not finish within --timeout seconds (killed)
//   BAD          an unexpected exception type, an empty or unclear message, non-finite values,
//                or a store that a successful run did not repair
//   KNOWN        a BAD case matching a known, reported failure (tests/fuzz/README.md)
// Exit code 1 when any case is CRASH, HANG or BAD; 2 for a bad command line.
//
//   fuzz_inputs [--cases N] [--long] [--seed S] [--case N] [--workdir DIR] [--timeout S]
//               [--campaigns DIR] [--in-process] [--keep] [--verbose]

#include <execinfo.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz.hpp"
#include "hopper/core/error.hpp"

#ifndef HOPPER_SOURCE_DIR
#define HOPPER_SOURCE_DIR "."
#endif

namespace hopper::fuzz {

std::string_view to_string(Category c) {
    switch (c) {
        case Category::ok_run:
            return "ok-run";
        case Category::clean_error:
            return "clean-error";
        case Category::crash:
            return "CRASH";
        case Category::hang:
            return "HANG";
        case Category::bad:
            return "BAD";
        case Category::known:
            return "KNOWN";
    }
    return "?";
}

void Outcome::mark_bad(const std::string& why) {
    if (category != Category::bad) bad_reason = why;
    category = Category::bad;
}

void Outcome::clean(const std::string& op, const std::string& message) {
    messages.push_back(op + ": " + one_line(message));
    if (category == Category::ok_run) category = Category::clean_error;
}

void Outcome::note(const std::string& op, const std::string& message) {
    messages.push_back(op + ": " + one_line(message));
}

namespace {
int report_fd = -1;  // the child's end of the pipe to the parent (-1: in process)

void write_fd(int fd, const std::string& s) {
    std::size_t done = 0;
    while (done < s.size()) {
        const ssize_t w = ::write(fd, s.data() + done, s.size() - done);
        if (w <= 0) return;
        done += static_cast<std::size_t>(w);
    }
}
}  // namespace

void announce_operation(const std::string& name) {
    if (report_fd >= 0) write_fd(report_fd, "op " + one_line(name, 100) + "\n");
}

void Outcome::announce() const {
    if (report_fd >= 0)
        write_fd(report_fd,
                 "kind " + one_line(kind, 200) + "\ndesc " + one_line(description, 600) + "\n");
}

std::string read_file(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

void write_file(const fs::path& p, std::string_view bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("fuzz_inputs: cannot write " + p.string());
}

std::string one_line(std::string_view s, std::size_t max) {
    std::string out;
    for (char c : s) {
        if (out.size() >= max) {
            out += "...";
            break;
        }
        if (c == '\n')
            out += " | ";
        else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            out += '?';
        else
            out += c;
    }
    return out;
}

bool mentions_nonfinite(std::string_view text) {
    // Whole words only: "inf" inside "info" or "nan" inside "nano" do not count.
    auto word_char = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    for (std::string_view w : {"nan", "NaN", "inf", "Inf", "-nan", "infinity", "Infinity"}) {
        for (std::size_t at = text.find(w); at != std::string_view::npos;
             at = text.find(w, at + 1)) {
            const bool left = at == 0 || !word_char(text[at - 1]);
            const bool right = at + w.size() >= text.size() || !word_char(text[at + w.size()]);
            if (left && right) return true;
        }
    }
    return false;
}

// The child's last words: a backtrace on stderr when it crashes (fatal signals, when no
// sanitizer reports them) or when the parent says it hangs (SIGUSR2), so that the parent can
// tell whose code it was in. backtrace() is async-signal-safe enough once libgcc is loaded,
// which install_last_words() makes sure of.
extern "C" void fuzz_last_words(int sig) {
    void* frames[64];
    const int n = ::backtrace(frames, 64);
    const char head[] = "fuzz_inputs: child backtrace (innermost first):\n";
    [[maybe_unused]] auto w = ::write(2, head, sizeof head - 1);
    // Frames 0 and 1 are this handler and the kernel's signal trampoline.
    if (n > 2) ::backtrace_symbols_fd(frames + 2, n - 2, 2);
    if (sig == SIGUSR2) ::_exit(97);
    ::signal(sig, SIG_DFL);
    ::raise(sig);
}

namespace {

void install_last_words() {
    void* warm[2];
    ::backtrace(warm, 2);
    // On an alternate stack, so that a stack overflow is reported too.
    static std::vector<char> alt(1 << 16);
    stack_t ss{};
    ss.ss_sp = alt.data();
    ss.ss_size = alt.size();
    ::sigaltstack(&ss, nullptr);
    struct sigaction sa {};
    sa.sa_handler = fuzz_last_words;
    sa.sa_flags = SA_ONSTACK;
    ::sigemptyset(&sa.sa_mask);
    ::sigaction(SIGUSR2, &sa, nullptr);
#if !defined(__SANITIZE_ADDRESS__)
    // Under AddressSanitizer its own report (with the stack) comes first.
    for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL})
        ::sigaction(sig, &sa, nullptr);
#endif
}

// Whose code a crashing or hanging child was in: the library of the innermost frame of its
// backtrace (our handler's, or a sanitizer's report) that is not the C or C++ runtime or a
// sanitizer. "" when there is no backtrace.
std::string innermost_library(const fs::path& stderr_file) {
    static const char* const runtime_parts[] = {
        "libc.so",          "libstdc++",      "libasan",         "libubsan",     "libgcc_s",
        "sanitizer_common", "__interceptor_", "fuzz_last_words", "libsanitizer", "libm.so"};
    std::istringstream in(read_file(stderr_file));
    bool in_trace = false;
    for (std::string line; std::getline(in, line);) {
        if (line.find("child backtrace") != std::string::npos ||
            line.find("ERROR: AddressSanitizer") != std::string::npos ||
            line.find("ERROR: LeakSanitizer") != std::string::npos ||
            line.find("runtime error:") != std::string::npos) {
            in_trace = true;
            continue;
        }
        if (!in_trace) continue;
        // A frame: "#3 0x... in f (/lib/x.so+0x12)" or ".../lib.so(+0x12)[0x...]".
        const bool frame =
            line.find("#") != std::string::npos || line.find("[0x") != std::string::npos;
        if (!frame) continue;
        const bool runtime =
            std::any_of(std::begin(runtime_parts), std::end(runtime_parts),
                        [&](const char* part) { return line.find(part) != std::string::npos; });
        if (runtime) continue;
        if (line.find("libhdf5") != std::string::npos) return "libhdf5";
        if (line.find("libtomlplusplus") != std::string::npos) return "libtomlplusplus";
        return "hopper";
    }
    return "";
}

// --------------------------------------------------------------------------------------------
// Known failures: non-clean cases whose cause lies outside the code this harness's author may
// change, reported in tests/fuzz/README.md ("Known failures"). A case matches when its category
// is `category`, its kind one of `kinds` (any when empty), its reason contains `reason_part`
// and its description `description_part`; it then counts as KNOWN, which does not fail the run.
struct Known {
    Category category;
    std::vector<std::string> kinds;
    const char* reason_part;
    const char* description_part;
    const char* reference;
};

// Byte-level damage of the HDF5 file: only there may HDF5 itself be blamed (a crash inside HDF5
// on a valid but unexpected file, h5_schema or h5_foreign_*, more likely means a misuse by us).
const std::vector<std::string> h5_byte_damage = {"h5_bitflip",    "h5_overwrite", "h5_truncate",
                                                 "both_truncate", "garbage",      "combination"};

const std::vector<Known> known_failures = {
    // HDF5 1.10.8 (Debian 12) itself crashes, loops or leaks on some damaged files (global
    // heap: heap overflow in H5HG_insert, SEGV and endless loop reading variable-length strings;
    // absurd allocations in H5C_protect; leaks when an open fails).
    {Category::crash, h5_byte_damage, "innermost frame in libhdf5", "",
     "K1 HDF5 library on a damaged file"},
    {Category::hang, h5_byte_damage, "innermost frame in libhdf5", "",
     "K1 HDF5 library on a damaged file"},
};

// --------------------------------------------------------------------------------------------
// The report a child writes to its pipe: one field per line, newlines escaped by one_line().

std::string encode_report(const Outcome& o) {
    std::string s;
    s += "category " + std::string(to_string(o.category)) + "\n";
    s += "kind " + one_line(o.kind, 200) + "\n";
    s += "desc " + one_line(o.description, 600) + "\n";
    s += "bad " + one_line(o.bad_reason, 600) + "\n";
    for (const auto& m : o.messages)
        s += "msg " + one_line(m, 600) + "\n";
    s += "end\n";
    return s;
}

std::optional<Outcome> decode_report(const std::string& text, Outcome& partial) {
    Outcome o;
    bool ended = false;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        const auto sp = line.find(' ');
        const std::string key = line.substr(0, sp);
        const std::string value = sp == std::string::npos ? "" : line.substr(sp + 1);
        if (key == "category") {
            for (auto c : {Category::ok_run, Category::clean_error, Category::bad})
                if (value == to_string(c)) o.category = c;
        } else if (key == "kind") {
            o.kind = value;
        } else if (key == "desc") {
            o.description = value;
        } else if (key == "bad") {
            o.bad_reason = value;
        } else if (key == "op") {
            o.operation = value;
        } else if (key == "msg") {
            o.messages.push_back(value);
        } else if (key == "end") {
            ended = true;
        }
    }
    if (!ended) {
        partial = o;
        return std::nullopt;
    }
    return o;
}

std::string family_of(std::uint64_t id) {
    return id % 2 == 0 ? "sweep" : "store";
}

// Runs case `id` in this process (the child's body, or --in-process).
Outcome run_here(const Context& ctx, std::uint64_t id) {
    Outcome o;
    try {
        if (id % 2 == 0)
            sweep_case(ctx, id, o);
        else
            store_case(ctx, id, o);
    } catch (const std::exception& e) {
        o.mark_bad(std::string("uncaught exception escaped the harness: ") + e.what());
    } catch (...) {
        o.mark_bad("uncaught non-standard exception escaped the harness");
    }
    return o;
}

struct CaseRecord {
    std::uint64_t id = 0;
    Outcome outcome;
    double seconds = 0.0;
    std::string stderr_tail;
};

// The interesting part of a child's stderr: from the first sanitizer report or backtrace, else
// the last lines.
std::string tail_lines(const fs::path& p, int n) {
    const std::string s = read_file(p);
    std::vector<std::string> lines;
    std::istringstream in(s);
    for (std::string l; std::getline(in, l);)
        lines.push_back(l);
    std::string out;
    std::size_t from = lines.size() > static_cast<std::size_t>(n) ? lines.size() - n : 0;
    for (std::size_t i = 0; i < lines.size(); ++i)
        if (lines[i].find("ERROR: AddressSanitizer") != std::string::npos ||
            lines[i].find("ERROR: LeakSanitizer") != std::string::npos ||
            lines[i].find("runtime error:") != std::string::npos ||
            lines[i].find("child backtrace") != std::string::npos) {
            from = i;
            break;
        }
    const std::size_t to = std::min(lines.size(), from + static_cast<std::size_t>(n));
    for (std::size_t i = from; i < to; ++i)
        out += "      " + one_line(lines[i], 300) + "\n";
    return out;
}

// Forks a child for case `id`, waits at most `timeout` seconds.
CaseRecord run_forked(const Context& ctx, std::uint64_t id, double timeout) {
    CaseRecord rec;
    rec.id = id;
    const fs::path err_path = ctx.workdir / ("case-" + std::to_string(id) + ".stderr");
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("fuzz_inputs: pipe failed");
    std::cout.flush();
    std::cerr.flush();
    const auto t0 = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("fuzz_inputs: fork failed");
    if (pid == 0) {
        ::close(fds[0]);
        const int efd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (efd >= 0) {
            ::dup2(efd, 2);
            ::close(efd);
        }
        const int nul = ::open("/dev/null", O_WRONLY);
        if (nul >= 0) {
            ::dup2(nul, 1);
            ::close(nul);
        }
        install_last_words();
        report_fd = fds[1];
        const Outcome o = run_here(ctx, id);
        write_fd(fds[1], encode_report(o));
        ::close(fds[1]);
        std::exit(0);  // a normal exit: LeakSanitizer checks at exit
    }
    ::close(fds[1]);
    std::string report;
    bool timed_out = false;
    char buf[4096];
    for (;;) {
        const double left =
            timeout - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (left <= 0) {
            timed_out = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int r = ::poll(&p, 1, static_cast<int>(std::min(left, 1.0) * 1000) + 1);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) continue;
        const ssize_t n = ::read(fds[0], buf, sizeof buf);
        if (n <= 0) break;  // EOF: the child closed its end (finished or died)
        report.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fds[0]);
    int status = 0;
    // A hanging child is asked for its backtrace first (SIGUSR2), then killed.
    auto stop = [&] {
        ::kill(pid, SIGUSR2);
        for (int i = 0; i < 150; ++i) {
            if (::waitpid(pid, &status, WNOHANG) == pid) return;
            ::usleep(20000);
        }
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
    };
    if (timed_out) {
        stop();
    } else {
        // The report is complete; the child may still run its exit handlers (LeakSanitizer).
        for (;;) {
            const pid_t w = ::waitpid(pid, &status, WNOHANG);
            if (w == pid) break;
            if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
                timeout) {
                timed_out = true;
                stop();
                break;
            }
            ::usleep(2000);
        }
    }
    rec.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    Outcome partial;
    const auto decoded = decode_report(report, partial);
    rec.outcome = decoded ? *decoded : partial;
    const std::string during =
        decoded ? " after its report (at exit)"
                : " during " + (rec.outcome.operation.empty() ? std::string("setup")
                                                              : rec.outcome.operation);
    if (timed_out) {
        rec.outcome.category = Category::hang;
        rec.outcome.bad_reason = "no end within " + std::to_string(static_cast<int>(timeout)) +
                                 " s" + during + " (killed)";
    } else if (WIFSIGNALED(status)) {
        rec.outcome.category = Category::crash;
        rec.outcome.bad_reason = std::string("killed by signal ") +
                                 std::to_string(WTERMSIG(status)) + " (" +
                                 ::strsignal(WTERMSIG(status)) + ")" + during;
    } else if (WIFEXITED(status) && WEXITSTATUS(status) != 0) {
        rec.outcome.category = Category::crash;
        rec.outcome.bad_reason =
            "exited with code " + std::to_string(WEXITSTATUS(status)) + during + " (sanitizer?)";
    } else if (!decoded) {
        rec.outcome.category = Category::crash;
        rec.outcome.bad_reason = "exited without a report" + during;
    }
    if (rec.outcome.category == Category::crash || rec.outcome.category == Category::hang) {
        const std::string lib = innermost_library(err_path);
        if (!lib.empty()) rec.outcome.bad_reason += "; innermost frame in " + lib;
    }
    for (const Known& k : known_failures)
        if (rec.outcome.category == k.category &&
            (k.kinds.empty() ||
             std::find(k.kinds.begin(), k.kinds.end(), rec.outcome.kind) != k.kinds.end()) &&
            rec.outcome.bad_reason.find(k.reason_part) != std::string::npos &&
            rec.outcome.description.find(k.description_part) != std::string::npos) {
            rec.outcome.category = Category::known;
            rec.outcome.bad_reason += " [known: " + std::string(k.reference) + "]";
            break;
        }
    const bool clean = rec.outcome.category == Category::ok_run ||
                       rec.outcome.category == Category::clean_error ||
                       rec.outcome.category == Category::known;
    if (!clean) rec.stderr_tail = tail_lines(err_path, 25);
    if (clean && !ctx.keep_all) {
        std::error_code ec;
        fs::remove(err_path, ec);
        fs::remove_all(ctx.workdir / ("case-" + std::to_string(id)), ec);
    }
    return rec;
}

// --------------------------------------------------------------------------------------------

struct Options {
    std::uint64_t cases = 300;
    bool long_run = false;
    std::uint64_t seed = 1;
    std::optional<std::uint64_t> only;
    fs::path workdir;
    fs::path campaigns = fs::path(HOPPER_SOURCE_DIR) / "campaigns";
    double timeout = 20.0;
    bool in_process = false;
    bool keep = false;
    bool verbose = false;
};

[[noreturn]] void usage_error(const std::string& msg) {
    std::cerr << "fuzz_inputs: " << msg
              << "\nusage: fuzz_inputs [--cases N] [--long] [--seed S] [--case N] [--workdir DIR]\n"
                 "                   [--timeout S] [--campaigns DIR] [--in-process] [--keep] "
                 "[--verbose]\n";
    std::exit(2);
}

std::uint64_t parse_u64(const std::string& opt, const std::string& v) {
    if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos)
        usage_error(opt + " needs a non-negative integer, got '" + v + "'");
    try {
        return std::stoull(v);
    } catch (...) {
        usage_error(opt + " is out of range: '" + v + "'");
    }
}

Options parse_options(int argc, char** argv) {
    Options o;
    bool cases_given = false;
    if (std::getenv("HOPPER_FUZZ_LONG")) o.long_run = true;  // as HOPPER_STRESS_LONG does
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage_error(a + " needs a value");
            return argv[++i];
        };
        if (a == "--cases") {
            o.cases = parse_u64(a, value());
            cases_given = true;
        } else if (a == "--long") {
            o.long_run = true;
        } else if (a == "--seed") {
            o.seed = parse_u64(a, value());
        } else if (a == "--case") {
            o.only = parse_u64(a, value());
        } else if (a == "--workdir") {
            o.workdir = value();
        } else if (a == "--campaigns") {
            o.campaigns = value();
        } else if (a == "--timeout") {
            const std::string v = value();
            char* end = nullptr;
            o.timeout = std::strtod(v.c_str(), &end);
            if (end == v.c_str() || *end || !(o.timeout > 0) || !std::isfinite(o.timeout))
                usage_error("--timeout needs a positive number of seconds, got '" + v + "'");
        } else if (a == "--in-process") {
            o.in_process = true;
        } else if (a == "--keep") {
            o.keep = true;
        } else if (a == "--verbose" || a == "-v") {
            o.verbose = true;
        } else if (a == "--help" || a == "-h") {
            std::cout << "fuzz_inputs: malformed sweep files and damaged stores (see "
                         "tests/fuzz/README.md)\n"
                         "  --cases N       number of cases (default 300; half sweep, half store)\n"
                         "  --long          2400 cases (>= 1000 of each family) unless --cases\n"
                         "  --seed S        seed of the case generator (default 1)\n"
                         "  --case N        run only case N (as numbered by a run with the same "
                         "seed)\n"
                         "  --workdir DIR   scratch directory (default: a new one in $TMPDIR)\n"
                         "  --timeout S     wall-clock limit per case (default 20 s)\n"
                         "  --campaigns DIR the shipped sweep files (default: the source tree's)\n"
                         "  --in-process    run the case(s) without forking (for a debugger)\n"
                         "  --keep          keep every case's files (default: failures only)\n"
                         "  --verbose       print every case\n";
            std::exit(0);
        } else {
            usage_error("unknown option '" + a + "'");
        }
    }
    if (o.long_run && !cases_given) o.cases = 2400;
    return o;
}

// A scratch directory this program may wipe: new, empty, or one it made before.
fs::path prepare_workdir(const Options& o) {
    fs::path dir = o.workdir;
    if (dir.empty()) {
        const char* tmp = std::getenv("TMPDIR");
        std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/fuzz_inputs.XXXXXX";
        if (!::mkdtemp(templ.data())) usage_error("cannot create a scratch directory");
        dir = templ;
    } else if (fs::exists(dir)) {
        if (!fs::is_directory(dir)) usage_error("--workdir '" + dir.string() + "' is a file");
        const bool ours = fs::exists(dir / ".fuzz_inputs");
        if (!ours && !fs::is_empty(dir))
            usage_error("--workdir '" + dir.string() +
                        "' is not empty and was not made by fuzz_inputs; give a new directory");
        for (const auto& e : fs::directory_iterator(dir))
            fs::remove_all(e.path());
    }
    fs::create_directories(dir);
    write_file(dir / ".fuzz_inputs", "scratch directory of fuzz_inputs; wiped by the next run\n");
    return fs::absolute(dir);
}

bool is_failure(Category c) {
    return c == Category::crash || c == Category::hang || c == Category::bad;
}

void print_case(const Options& o, const CaseRecord& r, std::ostream& os) {
    os << "case " << r.id << " (" << family_of(r.id) << ", " << r.outcome.kind
       << "): " << to_string(r.outcome.category);
    if (!r.outcome.bad_reason.empty()) os << ": " << r.outcome.bad_reason;
    os << "  [" << static_cast<int>(r.seconds * 1000) << " ms]\n";
    os << "    what: " << r.outcome.description << "\n";
    for (const auto& m : r.outcome.messages)
        os << "    " << m << "\n";
    if (!r.stderr_tail.empty()) os << "    stderr (last lines):\n" << r.stderr_tail;
    if (is_failure(r.outcome.category) || r.outcome.category == Category::known)
        os << "    reproduce: fuzz_inputs --seed " << o.seed << " --case " << r.id << "\n";
}

int run(const Options& o) {
    Context ctx;
    ctx.seed = o.seed;
    ctx.workdir = prepare_workdir(o);
    ctx.campaigns = o.campaigns;
    ctx.keep_all = o.keep;
    if (!fs::is_directory(ctx.campaigns))
        usage_error("no campaigns directory '" + ctx.campaigns.string() + "' (--campaigns DIR)");

    const auto t0 = std::chrono::steady_clock::now();
    prepare_stores(ctx);

    std::vector<std::uint64_t> ids;
    if (o.only)
        ids.push_back(*o.only);
    else
        for (std::uint64_t i = 0; i < o.cases; ++i)
            ids.push_back(i);

    std::cout << "fuzz_inputs: seed " << o.seed << ", " << ids.size() << " case(s), timeout "
              << o.timeout << " s, workdir " << ctx.workdir.string() << std::endl;

    std::vector<CaseRecord> records;
    for (std::uint64_t id : ids) {
        CaseRecord r;
        if (o.in_process) {
            r.id = id;
            const auto c0 = std::chrono::steady_clock::now();
            r.outcome = run_here(ctx, id);
            r.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
        } else {
            r = run_forked(ctx, id, o.timeout);
        }
        if (o.verbose || o.only || is_failure(r.outcome.category)) print_case(o, r, std::cout);
        records.push_back(std::move(r));
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    // Summary: counts by category, then by family and kind.
    const std::vector<Category> cats = {Category::ok_run, Category::clean_error, Category::crash,
                                        Category::hang,   Category::bad,         Category::known};
    std::map<std::string, std::map<Category, int>> table;  // "family kind" -> counts
    std::map<Category, int> total;
    std::map<std::string, std::map<Category, int>> by_family;
    double slowest = 0.0;
    std::uint64_t slowest_id = 0;
    for (const auto& r : records) {
        table[family_of(r.id) + " " + r.outcome.kind][r.outcome.category]++;
        by_family[family_of(r.id)][r.outcome.category]++;
        total[r.outcome.category]++;
        if (r.seconds > slowest) {
            slowest = r.seconds;
            slowest_id = r.id;
        }
    }
    std::cout << "\nfuzz_inputs summary: " << records.size() << " cases in " << std::fixed
              << std::setprecision(1) << seconds << " s (slowest: case " << slowest_id << ", "
              << slowest << " s)\n\n";
    std::cout << std::left << std::setw(34) << "family kind";
    for (auto c : cats)
        std::cout << std::right << std::setw(12) << to_string(c);
    std::cout << "\n";
    auto row = [&](const std::string& name, const std::map<Category, int>& counts) {
        std::cout << std::left << std::setw(34) << name;
        for (auto c : cats) {
            const auto it = counts.find(c);
            std::cout << std::right << std::setw(12) << (it == counts.end() ? 0 : it->second);
        }
        std::cout << "\n";
    };
    for (const auto& [name, counts] : table)
        row(name, counts);
    std::cout << "\n";
    for (const auto& [name, counts] : by_family)
        row(name + " (all)", counts);
    row("total", total);

    // Notes that are not failures but worth knowing (see README.md, "Findings").
    int diverged = 0, forged = 0, not_built = 0, engine_refused = 0;
    for (const auto& r : records)
        for (const auto& m : r.outcome.messages) {
            if (m.rfind("DIVERGED", 0) == 0) ++diverged;
            if (m.find("forged journal record") != std::string::npos) ++forged;
            if (m.rfind("scene: not built", 0) == 0) ++not_built;
            if (m.rfind("scene (", 0) == 0) ++engine_refused;
        }
    std::cout << "\nnotes: " << diverged
              << " store case(s) whose HDF5 view differed from the journal after a run (damage "
                 "inside a file that looked in step); "
              << forged << " forged journal value(s) passed through; " << not_built
              << " parsed sweep(s) whose scene was too large to build here; " << engine_refused
              << " parsed sweep(s) whose scene the engine refused\n";

    // The first few distinct messages of each kind.
    std::cout << "\nfirst messages per kind:\n";
    std::map<std::string, std::vector<std::string>> shown;
    for (const auto& r : records) {
        auto& v = shown[family_of(r.id) + " " + r.outcome.kind];
        for (const auto& m : r.outcome.messages) {
            if (v.size() >= 3) break;
            if (std::find(v.begin(), v.end(), m) == v.end()) v.push_back(m);
        }
    }
    for (const auto& [name, msgs] : shown) {
        std::cout << "  " << name << ":\n";
        for (const auto& m : msgs)
            std::cout << "    " << one_line(m, 240) << "\n";
    }

    int failures = 0;
    std::vector<const CaseRecord*> listed;
    for (const auto& r : records)
        if (is_failure(r.outcome.category) || r.outcome.category == Category::known)
            listed.push_back(&r);
    if (!listed.empty()) {
        std::cout << "\nnon-clean cases:\n";
        for (const auto* r : listed) {
            std::cout << "  case " << r->id << " " << family_of(r->id) << " " << r->outcome.kind
                      << ": " << to_string(r->outcome.category) << ": " << r->outcome.bad_reason
                      << "  (fuzz_inputs --seed " << o.seed << " --case " << r->id << ")\n";
            if (is_failure(r->outcome.category)) ++failures;
        }
    }
    std::cout << "\nfuzz_inputs: " << (failures ? "FAILED" : "passed") << ": " << failures
              << " CRASH/HANG/BAD case(s) of " << records.size() << "; files of non-clean cases in "
              << ctx.workdir.string() << std::endl;
    if (!failures && !o.keep && o.workdir.empty()) {
        std::error_code ec;
        fs::remove_all(ctx.workdir, ec);
    }
    return failures ? 1 : 0;
}

}  // namespace

}  // namespace hopper::fuzz

int main(int argc, char** argv) {
    const auto options = hopper::fuzz::parse_options(argc, argv);
    try {
        return hopper::fuzz::run(options);
    } catch (const std::exception& e) {
        std::cerr << "fuzz_inputs: error: " << e.what() << "\n";
        return 2;
    }
}
