#include "cli/status.hpp"
#include "cli/parse.hpp"

#include <boost/program_options.hpp>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <map>

#include "hopper/analysis/json.hpp"
#include "hopper/campaign/adaptive.hpp"
#include "hopper/campaign/checkpoints.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/running.hpp"
#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/codec.hpp"

namespace po = boost::program_options;

namespace hopper::cli {

namespace {

po::options_description status_options() {
    po::options_description d("status options");
    d.add_options()("json", po::bool_switch(), "one JSON object instead of the text report")  //
        ("help,h", "show this help");
    return d;
}

std::string hosts_text(const std::vector<std::string>& hosts) {
    // "node1 x4, node2 x4" in rank order of first appearance.
    std::vector<std::pair<std::string, int>> counts;
    for (const auto& h : hosts) {
        auto it = std::find_if(counts.begin(), counts.end(), [&](auto& c) { return c.first == h; });
        if (it == counts.end())
            counts.emplace_back(h, 1);
        else
            ++it->second;
    }
    std::string s;
    for (const auto& [h, n] : counts)
        s += (s.empty() ? "" : ", ") + h + (n > 1 ? " x" + std::to_string(n) : "");
    return s;
}

// "2024-05-01T12:00:00Z" -> s since 1970 (0 when unreadable).
double iso_to_unix(const std::string& t) {
    std::tm tm{};
    if (!strptime(t.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm)) return 0.0;
    return static_cast<double>(timegm(&tm));
}

// The running realizations (the master's STORE.running file) while a run writes the store.
std::vector<campaign::RunningTask> running_tasks(const store::StoreStatus& s) {
    if (!s.writer_active) return {};
    const auto f = campaign::read_running(campaign::running_path(s.store));
    return f ? f->tasks : std::vector<campaign::RunningTask>{};
}

int checkpoint_files(const store::StoreStatus& s) {
    return campaign::CheckpointFiles(s.store, "").count();
}

}  // namespace

ProgressEstimate estimate_progress(const store::StoreStatus& s, double now_unix) {
    ProgressEstimate e;
    if (s.runs.empty()) return e;
    const auto& last = s.runs.back();
    e.workers = std::max(1, last.info.workers);
    const double start = iso_to_unix(last.info.start_time);
    const double end = last.end ? iso_to_unix(last.end->end_time) : now_unix;
    if (start > 0 && end > start) e.per_hour = last.stored / (end - start) * 3600.0;
    // Cost of one realization of each point, from its scene (typed parameters, or for a store
    // older than them the recorded sweep texts: campaign::point_scenes).
    std::map<std::string, double> cost;
    const auto scenes = campaign::point_scenes(s.plan, s.runs);
    for (std::size_t i = 0; i < scenes.size(); ++i)
        if (scenes[i])
            cost.try_emplace(s.plan.points[i].label, campaign::expected_cost(*scenes[i]));
    double known = 0.0;
    for (const auto& [label, c] : cost)
        known += c;
    const double mean_cost = cost.empty() ? 0.0 : known / static_cast<double>(cost.size());
    campaign::CostEta eta(e.workers, campaign::prior_seconds_per_particle_step);
    int pending = 0;
    auto cost_of = [&](const std::string& label) {
        const auto it = cost.find(label);
        return it != cost.end() ? it->second : mean_cost;
    };
    for (const auto& p : s.points) {
        const double c = cost_of(p.label);
        eta.add_pending(c, p.pending);
        eta.finished(c, p.task_seconds, p.timed, false);
        pending += p.pending;
    }
    // The realizations running now (the running file) count with what they have left.
    std::vector<campaign::RunningCost> running;
    for (const auto& t : running_tasks(s))
        running.push_back({cost_of(t.label), std::max(0.0, now_unix - t.start_unix)});
    e.basis = eta.measured() ? "cost model, scaled to the worker time of the stored realizations"
                             : "cost model at 35 ns per particle-step (nothing measured yet)";
    if (pending > 0 && eta.seconds_left(running) > 0) e.eta_seconds = eta.seconds_left(running);
    if (s.writer_active && !last.end) {
        for (int rank = 1; rank <= e.workers; ++rank) {
            const auto it = last.last_result_unix.find(rank);
            const double since = it != last.last_result_unix.end() ? it->second : start;
            if (since > 0) e.busy.emplace_back(rank, std::max(0.0, now_unix - since));
        }
    }
    return e;
}

void print_status_help(std::ostream& os) {
    os << "usage: campaign status STORE.h5 [--json]\n\n"
          "Progress and failures of a campaign store, from its journal (STORE.h5.journal).\n"
          "Safe while `campaign run` is writing the store: it never locks or blocks it.\n\n"
          "exit codes: 0 shown, 1 no store or not a hopper store (unreadable journal),\n"
          "            2 bad command line\n\n"
       << status_options();
}

std::string status_json(const store::StoreStatus& s) {
    using analysis::Json;
    using analysis::json_number;
    Json j;
    j["store"] = s.store.string();
    j["campaign"] = s.campaign_name;
    j["physics_hash"] = store::hex64(s.physics_hash);
    j["active"] = s.writer_active;
    j["hdf5_in_step"] = s.hdf5_in_step;
    j["total"] = s.total;
    j["done"] = s.done;
    j["failed"] = s.failed;
    j["errors"] = s.errors;
    j["died"] = s.died;  // of the errors: running when their job died (--max-deaths)
    j["pending"] = s.pending;
    const ProgressEstimate pe = estimate_progress(s, store::unix_now());
    j["per_hour"] = json_number(pe.per_hour);
    j["eta_seconds"] = pe.eta_seconds ? json_number(*pe.eta_seconds) : Json(nullptr);
    j["eta_basis"] = pe.basis;
    Json busy = Json::array();
    for (const auto& [rank, age] : pe.busy)
        // "worker" is the name the text uses; "rank" kept for readers of the 0.4 JSON
        busy.push_back(Json{{"worker", rank}, {"rank", rank}, {"seconds", json_number(age)}});
    j["busy_workers"] = std::move(busy);
    const double now = store::unix_now();
    Json running = Json::array();
    for (const auto& t : running_tasks(s))
        running.push_back(Json{{"worker", t.worker},
                               {"label", t.label},
                               {"realization", t.realization},
                               {"attempt", t.attempt},
                               {"seconds", json_number(std::max(0.0, now - t.start_unix))},
                               {"resumed", t.resumed}});
    j["running"] = std::move(running);
    j["checkpoints"] = checkpoint_files(s);
    Json points = Json::array();
    for (const auto& p : s.points)
        points.push_back(Json{{"label", p.label},
                              {"total", p.planned},
                              {"limit", p.limit},
                              {"done", p.done},
                              {"failed", p.failed},
                              {"errors", p.errors},
                              {"pending", p.pending},
                              {"beyond_sweep", p.beyond_sweep},
                              {"stored_beyond_plan", p.extra}});
    j["points"] = std::move(points);
    Json failures = Json::array();
    for (const auto& f : s.failures)
        failures.push_back(Json{{"label", f.label},
                                {"realization", f.realization},
                                {"seed", f.seed},
                                {"kind", f.exception ? "error" : "failed"},
                                {"reason", f.reason}});
    j["failures"] = std::move(failures);
    Json runs = Json::array();
    for (const auto& r : s.runs) {
        Json o;
        o["start_time"] = r.info.start_time;
        o["end_time"] = r.end ? Json(r.end->end_time) : Json(nullptr);
        o["end_reason"] = r.end ? Json(r.end->reason) : Json(nullptr);
        o["code_version"] = r.info.code_version;
        o["mpi_size"] = r.info.mpi_size;
        o["workers"] = r.info.workers;
        o["hosts"] = r.info.hosts;
        o["stored"] = r.stored;
        o["running_when_died"] = r.end ? Json(nullptr) : Json(r.died_running);
        o["lost_worker_seconds"] = json_number(r.end ? r.end->lost_worker_seconds : 0.0);
        o["saved_worker_seconds"] = json_number(r.end ? r.end->saved_worker_seconds : 0.0);
        runs.push_back(std::move(o));
    }
    j["runs"] = std::move(runs);
    return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

void write_status(std::ostream& out, const store::StoreStatus& s) {
    out << "store     " << s.store.string() << '\n';
    out << "campaign  " << (s.campaign_name.empty() ? "(no run yet)" : s.campaign_name)
        << "  (physics " << store::hex64(s.physics_hash) << ")\n";
    out << "state     "
        << (s.writer_active  ? "a `campaign run` is writing the store"
            : s.hdf5_in_step ? "idle; the HDF5 file is complete"
            : s.runs.empty() ? "idle; nothing stored yet"
                             : "idle; the HDF5 file is not in step with the journal (a run "
                               "killed, or a write that failed: disk full?): the next `campaign "
                               "run` rebuilds it from the journal")
        << '\n';
    out << "progress  " << s.done << "/" << s.total << " done, " << s.failed << " failed";
    if (s.errors) {
        out << " (" << s.errors << " in error, retried by the next run";
        if (s.died)
            out << "; " << s.died << " of them were running when their job died: those set "
                << "aside after --max-deaths deaths are handed out only with a higher limit";
        out << ")";
    }
    out << ", " << s.pending << " pending\n";
    const ProgressEstimate pe = estimate_progress(s, store::unix_now());
    if (!s.runs.empty()) {
        char line[256];
        std::snprintf(line, sizeof line,
                      pe.per_hour >= 10 ? "rate      %.0f realizations per hour (last run)"
                                        : "rate      %.2g realizations per hour (last run)",
                      pe.per_hour);
        out << line;
        if (pe.eta_seconds)
            out << "; " << (s.writer_active ? "ETA " : "the pending ones take about ")
                << campaign::format_duration(*pe.eta_seconds) << " on " << pe.workers
                << " worker(s) (" << pe.basis << ")";
        out << '\n';
        const auto running = running_tasks(s);
        if (!running.empty()) {
            const double now = store::unix_now();
            for (std::size_t k = 0; k < running.size(); ++k) {
                const auto& t = running[k];
                out << (k ? "          " : "running   ") << "worker " << t.worker << ": '"
                    << t.label << "' #" << t.realization << " for "
                    << campaign::format_duration(std::max(0.0, now - t.start_unix))
                    << (t.attempt > 1 ? " (attempt " + std::to_string(t.attempt) + ")" : "")
                    << (t.resumed ? " (continued from its checkpoint)" : "") << '\n';
            }
        }
        if (!pe.busy.empty()) {
            out << "workers   ";
            for (std::size_t k = 0; k < pe.busy.size(); ++k)
                out << (k ? ", " : "") << "worker " << pe.busy[k].first << " busy "
                    << campaign::format_duration(pe.busy[k].second);
            out << " (since its last result or the run's start)\n";
        }
    }
    if (!s.runs.empty()) {
        const auto& r = s.runs.back();
        out << "runs      " << s.runs.size() << "; last started " << r.info.start_time << " on "
            << r.info.mpi_size << " process(es) (" << hosts_text(r.info.hosts) << "), "
            << (r.end             ? "ended " + r.end->end_time + " (" + r.end->reason + ")"
                : s.writer_active ? std::string("running")
                                  : "did not end (killed?) while running " +
                                        std::to_string(r.died_running) + " realization(s)")
            << ", stored " << r.stored << '\n';
        if (r.end && (r.end->lost_worker_seconds > 0 || r.end->saved_worker_seconds > 0))
            out << "          its interrupted realizations: "
                << campaign::format_duration(r.end->saved_worker_seconds)
                << " of worker time kept in checkpoints, "
                << campaign::format_duration(r.end->lost_worker_seconds) << " thrown away\n";
    }
    if (const int n = checkpoint_files(s); n > 0)
        out << "checkpts  " << n << " realization(s) have a saved state in "
            << campaign::CheckpointFiles::dir_for(s.store).string()
            << " (they continue from it in the next run)\n";
    if (!s.points.empty()) {
        std::size_t width = 5;
        bool limits = false;  // a target campaign: its rounds so far, then "up to" its limit
        for (const auto& p : s.points) {
            width = std::max(width, p.label.size());
            limits = limits || p.limit > p.planned;
        }
        char buf[512];
        std::snprintf(buf, sizeof buf, "\n%-*s  %7s  %7s  %7s  %7s%s\n", static_cast<int>(width),
                      "point", "total", "done", "failed", "pending", limits ? "    up to" : "");
        out << buf;
        for (const auto& p : s.points) {
            std::snprintf(buf, sizeof buf, "%-*s  %7d  %7d  %7d  %7d", static_cast<int>(width),
                          p.label.c_str(), p.planned, p.done, p.failed, p.pending);
            out << buf;
            if (limits) {
                std::snprintf(buf, sizeof buf, "  %7d", p.limit);
                out << buf;
            }
            out << '\n';
        }
        if (limits)
            out << "(total: the realizations the rounds allotted so far; up to: "
                   "max_realizations)\n";
        int beyond = 0, lowered = 0, kept = 0;
        for (const auto& p : s.points)
            if (p.beyond_sweep > 0) {
                beyond += p.beyond_sweep;
                kept += p.extra;
                ++lowered;
            }
        if (beyond > 0)
            out << "(the last run's sweep lowered the realizations of " << lowered
                << " point(s): " << beyond << " realization(s) an earlier run planned are left "
                << "out of total and pending, " << kept
                << " of them stored and kept; raising the count again runs the rest)\n";
    }
    if (!s.failures.empty()) {
        out << "\nfailures\n";
        for (const auto& f : s.failures)
            out << "  '" << f.label << "' #" << f.realization << " (seed " << f.seed << ", "
                << (f.exception ? "exception, " + std::to_string(f.attempt) + " attempt(s)"
                                : std::string("status failed"))
                << "): " << f.reason << '\n';
    }
}

// The store's plan only grows (each planned task is a row of /tasks), but a sweep may lower a
// point's realizations, and `campaign run` then runs the sweep's count: the counts of the last
// run's sweep (recorded with the run) where they are below the plan, for read_status to cap
// the points with. None for a campaign with a target (apply_target's).
std::map<std::string, int> lowered_counts(const store::StoreStatus& s,
                                          const std::optional<config::CampaignSpec>& recorded) {
    std::map<std::string, int> lowered;
    if (!recorded || recorded->target) return lowered;
    std::map<std::string, int> planned;
    for (const auto& p : s.points)
        planned.emplace(p.label, p.planned);
    for (const auto& p : recorded->points)
        if (const auto it = planned.find(p.label);
            it != planned.end() && p.realizations < it->second)
            lowered.emplace(p.label, p.realizations);
    return lowered;
}

// A campaign with a target (adaptive.hpp) runs up to max_realizations per point, as its rounds
// decide: pending is what the current round still lacks (0 once the target is met),
// replayed from the stored results as `campaign run` does. Without this, the batch script would
// resubmit a finished target campaign up to its cap. Returns the description of the rounds
// (empty without a target).
std::string apply_target(store::StoreStatus& s,
                         const std::optional<config::CampaignSpec>& recorded) {
    if (!recorded || !recorded->target) return {};
    const config::CampaignSpec& spec = *recorded;
    const std::map<std::string, campaign::PointResults> stored =
        campaign::read_round_results(s.store);
    std::vector<double> cost;
    for (const auto& p : spec.points)
        cost.push_back(campaign::expected_cost(p.scene));
    const campaign::RoundState rs = campaign::replay_rounds(spec, stored, cost);
    std::map<std::string, int> missing;
    for (const auto& [p, i] : rs.missing)
        ++missing[spec.points[std::size_t(p)].label];
    s.pending = 0;
    for (auto& p : s.points) {
        p.pending = rs.finished ? 0 : missing[p.label];
        s.pending += p.pending;
    }
    return (rs.finished ? "target met: no point needs more after round " : "target: round ") +
           std::to_string(rs.round + 1) + "\n" +
           campaign::describe_rounds(rs, spec.target->quantity);
}

int status_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, status_options(), "store");
    if (vm.count("help")) {
        print_status_help(std::cout);
        return 0;
    }
    const std::filesystem::path path = single_positional(vm, "store", "store", "STORE.h5");
    store::StoreStatus s = store::read_status(path);
    // The last run's sweep, parsed once: its lowered counts, or its target's rounds.
    const std::optional<config::CampaignSpec> recorded = campaign::recorded_campaign(s.runs);
    // Read again with the caps (a second scan of the journal) only where a sweep lowered a count.
    if (const auto lowered = lowered_counts(s, recorded); !lowered.empty())
        s = store::read_status(path, lowered);
    const std::string rounds = apply_target(s, recorded);
    if (vm["json"].as<bool>()) {
        std::cout << status_json(s) << '\n';
    } else {
        write_status(std::cout, s);
        std::cout << rounds;
    }
    return 0;
}

}  // namespace hopper::cli
