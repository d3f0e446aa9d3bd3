// The campaign executable end to end on campaigns/tiny.toml (250 particles, about a second per
// run): exit codes, error messages, JSON content and determinism, snapshots.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path exe = HOPPER_CAMPAIGN_EXE;
const fs::path source_dir = HOPPER_SOURCE_DIR;
const fs::path tiny = source_dir / "campaigns" / "tiny.toml";
const fs::path failing = source_dir / "tests" / "cli" / "data" / "failing_cli.toml";
// The scene most runs use: D = 2.2 cm (about 3.3 mean diameters), theta = 60 deg.
const std::string scene = " --D 2.2 --theta 60";
// A scene that jams many times in every realization (D = 1.8 cm, about 2.7 mean diameters:
// 10-20 jams per run), so that the JSON's jam arrays are exercised whatever the trajectory.
const std::string jam_scene = " --D 1.8 --theta 60";

// Single-quoted for the shell (built by appending: GCC 12 warns falsely on "'" + string).
std::string quote(const fs::path& p) {
    std::string q = "'";
    q.append(p.string()).append("'");
    return q;
}

// A scratch directory per test (ctest may run tests in parallel).
fs::path scratch() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::path(HOPPER_BINARY_DIR) / "tests" / "cli" / "tmp" /
                         (std::string(info->test_suite_name()) + "." + info->name());
    fs::create_directories(dir);
    return dir;
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Outcome {
    int code = -1;
    std::string out, err;
};

Outcome run_command(const std::string& command) {
    static int counter = 0;
    const fs::path dir = scratch();
    const fs::path out = dir / ("out" + std::to_string(counter) + ".txt");
    const fs::path err = dir / ("err" + std::to_string(counter) + ".txt");
    ++counter;
    const std::string cmd = command + " > " + quote(out) + " 2> " + quote(err);
    const int status = std::system(cmd.c_str());
    Outcome r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

Outcome campaign(const std::string& args) {
    return run_command(quote(exe) + " " + args);
}

// The JSON with the wall-clock lines removed (see src/cli/result_output.hpp).
std::string without_wall_clock(const std::string& json) {
    static const std::regex wall_clock(
        R"re("(wall_seconds|ns_per_particle_step|seconds_[a-z_]+)":)re");
    std::istringstream is(json);
    std::string kept;
    for (std::string line; std::getline(is, line);)
        if (!std::regex_search(line, wall_clock)) kept += line + '\n';
    return kept;
}

TEST(CampaignCli, SameSeedGivesIdenticalJsonApartFromWallClock) {
    const Outcome a = campaign("simulate " + quote(tiny) + scene + " --seed 1 --json");
    // the store's seed_str form ('s' and the digits) is the same seed (issue 43, item 7)
    const Outcome b = campaign("simulate " + quote(tiny) + scene + " --seed s1 --json");
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_EQ(b.code, 0) << b.err;
    const std::string sa = without_wall_clock(a.out), sb = without_wall_clock(b.out);
    EXPECT_GT(sa.size(), 500u);
    EXPECT_EQ(sa, sb);
    // Exactly the eight wall-clock lines were dropped (2 top level, 6 in diagnostics).
    auto count_lines = [](const std::string& s) { return std::count(s.begin(), s.end(), '\n'); };
    EXPECT_EQ(count_lines(a.out) - count_lines(sa), 8);
}

TEST(CampaignCli, AnotherSeedGivesAnotherRealization) {
    const Outcome a = campaign("simulate " + quote(tiny) + scene + " --seed 1 --json");
    const Outcome b = campaign("simulate " + quote(tiny) + scene + " --seed 2 --json");
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_NE(without_wall_clock(a.out), without_wall_clock(b.out));
    EXPECT_NE(a.out.find("\"seed\": 1,"), std::string::npos);
    EXPECT_NE(b.out.find("\"seed\": 2,"), std::string::npos);
}

// Parses the JSON with Python's json module and checks keys, types and consistent lengths.
TEST(CampaignCli, JsonParsesAndIsConsistent) {
    const Outcome r = campaign("simulate " + quote(tiny) + jam_scene + " --seed 3 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path dir = scratch();
    std::ofstream(dir / "result.json") << r.out;
    std::ofstream(dir / "check.py") << R"py(
import json, math, sys
d = json.load(open(sys.argv[1]))
problems = []
def need(cond, what):
    if not cond: problems.append(what)
number = (int, float)
nullable = {"empty_time", "discharge_rate", "discharge_rate_kg_s"}
keys = {"status": str, "message": str, "D_cm": number, "theta_deg": number, "seed": int,
        "particles": int, "n_jams": int, "survival_times": list, "censored": list,
        "jam_onsets": list, "n_shakes": int, "n_jams_multi_shake": int, "shakes_per_jam": list,
        "empty_time": number, "discharge_rate": number, "discharge_rate_kg_s": number,
        "discharged": int, "steps": int, "wall_seconds": number, "ns_per_particle_step": number,
        "diagnostics": dict, "discharge_curve": dict, "events": list}
for k, t in keys.items():
    need(k in d, "missing key " + k)
    if k in d and not (d[k] is None and k in nullable):
        need(isinstance(d[k], t) and not isinstance(d[k], bool), "bad type of " + k)
need(d["status"] in ("complete", "arrested", "time_limit", "failed"), "status")
need(d["D_cm"] == 1.8 and d["theta_deg"] == 60 and d["seed"] == 3, "echoed request")
need(len(d["censored"]) == len(d["survival_times"]), "censored vs survival_times")
need(d["n_jams"] >= 3, "D = 1.8 cm should jam several times (test scene changed?)")
need(all(isinstance(c, bool) for c in d["censored"]), "censored are bools")
need(len(d["jam_onsets"]) == d["n_jams"] == len(d["shakes_per_jam"]), "jam counts")
need(sum(d["shakes_per_jam"]) == d["n_shakes"], "shakes add up")
need(all(isinstance(x, number) for x in d["survival_times"] + d["jam_onsets"]), "times numbers")
need((d["empty_time"] is None) == (d["status"] != "complete"), "empty_time iff complete")
c = d["discharge_curve"]
need(len(c["time"]) == len(c["in_hopper"]) > 0, "curve lengths")
need(all(isinstance(x, number) for x in c["time"]), "curve time numbers")
diag = ["steps", "settle_steps", "neighbor_rebuilds", "settle_time", "shake_time",
        "wall_seconds", "ns_per_particle_step", "max_overlap_ratio", "settled_kinetic_energy",
        "potential_energy_released", "dt", "tau_c", "k_n", "seconds_forces",
        "seconds_integration", "seconds_neighbors", "seconds_observers"]
for k in diag:
    need(isinstance(d["diagnostics"].get(k), number), "diagnostics." + k)
need(d["diagnostics"]["steps"] == d["steps"] > 0, "steps")
need(len(d["events"]) > 0, "events")
for e in d["events"]:
    need(set(e) == {"kind", "time", "sim_time", "in_hopper"}, "event keys")
    need(all(isinstance(e[k], number) for k in ("time", "sim_time", "in_hopper")), "event types")
if problems:
    print("\n".join(problems)); sys.exit(1)
)py";
    const Outcome check = run_command(std::string(HOPPER_PYTHON) + " " + quote(dir / "check.py") +
                                      " " + quote(dir / "result.json"));
    EXPECT_EQ(check.code, 0) << check.out << check.err << "\n" << r.out;
}

TEST(CampaignCli, SummaryIsReadable) {
    const Outcome r = campaign("simulate " + quote(tiny) + scene + " --seed 1 --progress");
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* text :
         {"status", "particles", "jams", "shakes", "survival times", "empty time", "discharge rate",
          "steps", "wall time", "ns per particle-step"})
        EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
    EXPECT_EQ(r.out.find('{'), std::string::npos);
    // --progress: lines on stderr naming phase, times, particles left and jams.
    EXPECT_NE(r.err.find("settle"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("discharge"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("in hopper ="), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("jams ="), std::string::npos) << r.err;
}

TEST(CampaignCli, FailedRealizationExitsThree) {
    const Outcome r = campaign("simulate " + quote(failing) + scene + " --seed 1 --json");
    EXPECT_EQ(r.code, 3) << r.out << r.err;
    EXPECT_NE(r.out.find("\"status\": \"failed\""), std::string::npos) << r.out;
}

// Issue 27: `campaign submit --dry-run` estimated 241.7 core-hours for the survival study and
// said nothing of its default chain's 22 worker-hours.
TEST(CampaignCli, SubmitDryRunWarnsWhenTheChainCannotFinish) {
    const fs::path survival = source_dir / "campaigns" / "paper" / "survival.toml";
    const Outcome r =
        campaign("submit " + quote(survival) + " --dry-run --store " + quote(scratch() / "s.h5"));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("warning: the chain cannot finish the estimate: 11 allocation(s) x "
                         "1:00:00 x 2 worker(s)"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("Use --ntasks "), std::string::npos) << r.err;
    // Enough ranks: no warning.
    const Outcome ok = campaign("submit " + quote(survival) + " --dry-run --ntasks 64 --store " +
                                quote(scratch() / "s.h5"));
    ASSERT_EQ(ok.code, 0) << ok.err;
    EXPECT_EQ(ok.err.find("warning: the chain"), std::string::npos) << ok.err;
}

// The dry run's point column cut labels at 40 characters: the head scan's points read
// "D_cm=2.7 theta_deg=45 hopper.particles=3" for 300 disks (and would for 3000).
TEST(CampaignCli, DryRunShowsWholeLabels) {
    const fs::path heads = source_dir / "campaigns" / "open-question" / "head-scan.toml";
    const Outcome r =
        campaign("run " + quote(heads) + " --dry-run --store " + quote(scratch() / "h.h5"));
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* n : {"300", "500", "700", "1500"})
        EXPECT_NE(r.out.find(std::string("D_cm=2.7 theta_deg=45 hopper.particles=") + n + " "),
                  std::string::npos)
            << r.out;
}

struct BadLine {
    std::string args;
    std::vector<std::string> mentions;  // the message must name these
};

TEST(CampaignCli, BadCommandLinesExitTwoNamingTheProblem) {
    const std::string t = quote(tiny);
    const std::vector<BadLine> cases = {
        {"simulate " + t + " --theta 60 --seed 1", {"missing required option --D"}},
        {"simulate " + t + " --D 3 --seed 1", {"--theta"}},
        {"simulate " + t + scene, {"--seed"}},
        {"simulate " + t + scene + " --seed abc", {"--seed", "non-negative integer", "'abc'"}},
        {"simulate " + t + scene + " --seed -1", {"--seed", "'-1'"}},
        {"simulate " + t + scene + " --seed 1.5", {"--seed", "'1.5'"}},
        {"simulate " + t + " --D nan --theta 60 --seed 1", {"--D", "finite", "'nan'"}},
        {"simulate " + t + " --D 3 --theta inf --seed 1", {"--theta", "'inf'"}},
        {"simulate " + t + scene + " --seed 1 --bogus", {"--bogus"}},
        {"simulate " + t + scene + " --seed 1 --snapshot-interval 0.1", {"--snapshots"}},
        {"simulate" + scene + " --seed 1", {"sweep file"}},
        {"simulate " + t + " " + t + scene + " --seed 1", {"one sweep file"}},
        {"simulate /nonexistent/sweep.toml" + scene + " --seed 1", {"/nonexistent/sweep.toml"}},
        {"simulate " + t + " --D 500 --theta 60 --seed 1", {"D_cm"}},
        // a value in the wrong unit gets the sweep file's check and hint (issue 43, item 3)
        {"simulate " + t + " --D 0.023 --theta 60 --seed 1",
         {"D_cm = 0.023", "in centimetres", "write D_cm = 2.3"}},
        {"simulate " + t + " --D 2.2 --theta 0.785 --seed 1",
         {"theta_deg = 0.785", "in degrees", "theta_deg = 45"}},
        {"simulate " + t + scene + " --seed s1.5", {"--seed", "seed_str", "'s1.5'"}},
        {"run " + t + " --thread 2", {"--thread", "did you mean '--threads'"}},
        {"run " + t + " --max-deaths 256",
         {"--max-deaths", "between 0 (no limit) and 255", "'256'"}},
        {"run " + t + " --max-deaths -1", {"--max-deaths", "'-1'"}},
        {"run " + t + " --max-deaths two", {"--max-deaths", "'two'"}},
        {"frobnicate", {"unknown command 'frobnicate'", "simulate"}},
        {"run", {"missing the sweep file"}},
        {"help frobnicate", {"frobnicate"}},
        // campaign merge (issue 43): its refusals are exit 2 (tests/campaign/merge.sh has more)
        {"merge --store /nonexistent/c.h5", {"missing the stores to merge"}},
        {"merge /nonexistent/a.h5", {"missing --store"}},
        {"merge /nonexistent/a.h5 --store /nonexistent/c.h5",
         {"merge refused", "no store at '/nonexistent/a.h5'", "nothing was written"}},
    };
    for (const auto& c : cases) {
        const Outcome r = campaign(c.args);
        EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("campaign: error: ", 0), 0u) << c.args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << "\n" << r.err;
        for (const auto& m : c.mentions)
            EXPECT_NE(r.err.find(m), std::string::npos) << c.args << "\nwanted: " << m << "\n"
                                                        << r.err;
        EXPECT_TRUE(r.out.empty()) << c.args << "\n" << r.out;
    }
    const Outcome none = campaign("");
    EXPECT_EQ(none.code, 2);
    EXPECT_NE(none.err.find("usage: campaign"), std::string::npos);
}

TEST(CampaignCli, HelpAndVersion) {
    const Outcome help = campaign("--help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("simulate"), std::string::npos);
    const Outcome sim = campaign("help simulate");
    EXPECT_EQ(sim.code, 0);
    for (const char* opt :
         {"--D", "--theta", "--seed", "--json", "--snapshots", "--snapshot-interval", "--progress"})
        EXPECT_NE(sim.out.find(opt), std::string::npos) << opt;
    EXPECT_EQ(campaign("simulate --help").out, sim.out);
    const Outcome version = campaign("--version");
    EXPECT_EQ(version.code, 0);
    EXPECT_EQ(version.out.rfind("campaign (hopper) ", 0), 0u) << version.out;
}

TEST(CampaignCli, EveryListedCommandHasHelpAndRuns) {
    // One table (src/cli/commands.hpp) drives the list, `help NAME` and dispatch: every command
    // `--help` lists answers `help NAME` and `NAME --help` with the same text, and the list has
    // the commands and exit codes this build documents.
    const Outcome help = campaign("--help");
    ASSERT_EQ(help.code, 0);
    const auto begin = help.out.find("commands:\n");
    const auto end = help.out.find("\n\n", begin);
    ASSERT_NE(begin, std::string::npos) << help.out;
    std::istringstream list(help.out.substr(begin + 10, end - begin - 10));
    std::vector<std::string> names;
    for (std::string line; std::getline(list, line);) {
        std::istringstream words(line);
        std::string name;
        words >> name;
        names.push_back(name);
    }
    EXPECT_EQ(names, (std::vector<std::string>{"run", "status", "analyze", "plot", "export",
                                               "simulate", "submit", "cite", "merge"}));
    for (const auto& name : names) {
        const Outcome h = campaign("help " + name);
        EXPECT_EQ(h.code, 0) << name << "\n" << h.err;
        EXPECT_NE(h.out.find("usage: campaign " + name), std::string::npos) << name << h.out;
        EXPECT_EQ(campaign(name + " --help").out, h.out) << name;
        // the README: "`campaign help COMMAND` shows each command's options and exit codes"
        EXPECT_NE(h.out.find("\nexit codes: 0 "), std::string::npos) << name << "\n" << h.out;
    }
    for (const char* code :
         {"  0  success", "  1  unexpected or store error", "  2  bad command line or sweep file",
          "  3  realization(s) failed", "  4  stopped by a signal (run; resumable)"})
        EXPECT_NE(help.out.find(code), std::string::npos) << code << "\n" << help.out;
}

// `campaign cite STORE` (issue 43): the references for what a real store used, from its
// journal: the published study, the store's integrator (tiny.toml: gear4) and not the others.
TEST(CampaignCli, CiteListsWhatTheStoreUsed) {
    const fs::path dir = scratch();
    const fs::path sweep = dir / "one.toml", store = dir / "one.h5";
    fs::remove(store);
    fs::remove(fs::path(store.string() + ".journal"));
    std::string text = slurp(tiny);
    text = std::regex_replace(text, std::regex("realizations = 2"), "realizations = 1");
    text = std::regex_replace(text, std::regex(R"(D_cm = \[3.0, 4.5\])"), "D_cm = [4.5]");
    std::ofstream(sweep) << text;
    const Outcome run = campaign("run " + quote(sweep) + " --store " + quote(store) +
                                 " --progress-interval 0 --no-plots");
    ASSERT_EQ(run.code, 0) << run.err;
    const Outcome all = campaign("cite " + quote(store));
    ASSERT_EQ(all.code, 0) << all.err;
    for (const char* want : {"[kondic2014] Lou Kondic", "[tang2011]", "[gear1971]", "[hopper]",
                             "version 0.4", "@article{kondic2014,", "@book{gear1971,"})
        EXPECT_NE(all.out.find(want), std::string::npos) << want << "\n" << all.out;
    for (const char* not_used : {"swope1982", "hertz1882", "welford1962"})
        EXPECT_EQ(all.out.find(not_used), std::string::npos) << not_used;
    const Outcome bib = campaign("cite " + quote(store) + " --bibtex");
    EXPECT_EQ(bib.code, 0);
    EXPECT_EQ(bib.out.rfind("@misc{hopper,", 0), 0u) << bib.out;
    EXPECT_EQ(bib.out.find("[kondic2014]"), std::string::npos);
    EXPECT_EQ(campaign("cite " + quote(store) + " --bibtex --text").code, 2);
    const Outcome none = campaign("cite " + quote(dir / "none.h5"));
    EXPECT_EQ(none.code, 1) << none.err;
    // analyze ends its text with the cite command and the same keys; --json stays JSON alone
    const Outcome an = campaign("analyze " + quote(store) + " --no-write");
    ASSERT_EQ(an.code, 0) << an.err;
    const std::string line = "to cite: `campaign cite " + store.string() + "` lists ";
    const auto at = an.out.find(line);
    ASSERT_NE(at, std::string::npos) << an.out;
    const std::string tail = an.out.substr(at);
    EXPECT_EQ(std::count(tail.begin(), tail.end(), '\n'), 1) << "not the last line: " << tail;
    for (const char* key : {"hopper", "kondic2014", "tang2011", "gear1971"})
        EXPECT_NE(tail.find(key), std::string::npos) << key << ": " << tail;
    EXPECT_EQ(tail.find("hertz1882"), std::string::npos) << tail;
    const Outcome js = campaign("analyze " + quote(store) + " --no-write --json");
    EXPECT_EQ(js.out.find("to cite"), std::string::npos);
}

TEST(CampaignCli, SnapshotsWriteDumpFrames) {
    const fs::path dir = scratch() / "frames";
    fs::remove_all(dir);
    const Outcome r = campaign("simulate " + quote(tiny) + scene + " --seed 1 --snapshots " +
                               quote(dir) + " --snapshot-interval 0.1");
    ASSERT_EQ(r.code, 0) << r.err;
    int frames = 0, vtu = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        EXPECT_TRUE(std::regex_match(name, std::regex(R"(hopper\.([0-9]{6}\.(dump|vtu)|pvd))")))
            << e.path();
        frames += name.ends_with(".dump");
        vtu += name.ends_with(".vtu");
    }
    EXPECT_EQ(vtu, frames);  // both formats by default, frame by frame
    EXPECT_TRUE(fs::exists(dir / "hopper.pvd"));
    EXPECT_GE(frames, 2);
    EXPECT_NE(r.out.find(std::to_string(frames) + " frames"), std::string::npos) << r.out;

    std::istringstream first(slurp(dir / "hopper.000001.dump"));
    std::vector<std::string> lines;
    for (std::string l; std::getline(first, l);)
        lines.push_back(l);
    ASSERT_GT(lines.size(), 11u);
    EXPECT_EQ(lines[0], "ITEM: TIME");
    EXPECT_NEAR(std::stod(lines[1]), 0.1, 0.02);  // about one interval after the first frame
    EXPECT_EQ(lines[2], "ITEM: TIMESTEP");
    EXPECT_GT(std::stoll(lines[3]), 100);  // the step number, not the frame index 1
    EXPECT_EQ(lines[4], "ITEM: NUMBER OF ATOMS");
    const int atoms = std::stoi(lines[5]);
    EXPECT_GT(atoms, 250);  // 250 mobile particles plus the walls
    EXPECT_EQ(lines[10], "ITEM: ATOMS id type x y z vx vy vz radius omegaz contact_force");
    EXPECT_EQ(static_cast<int>(lines.size()), 11 + atoms);
    int mobile = 0, walls = 0;
    for (std::size_t i = 11; i < lines.size(); ++i) {
        std::istringstream is(lines[i]);
        long long id = 0;
        int type = 0;
        is >> id >> type;
        mobile += type == 1;
        walls += type == 2;
    }
    EXPECT_EQ(mobile, 250);
    EXPECT_EQ(mobile + walls, atoms);
}

}  // namespace
