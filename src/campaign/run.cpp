#include "hopper/campaign/run.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>

#include "hopper/campaign/adaptive.hpp"
#include "hopper/campaign/checkpoints.hpp"
#include "hopper/campaign/hybrid.hpp"
#include "hopper/campaign/inproc_channel.hpp"
#include "hopper/campaign/mixing.hpp"
#include "hopper/campaign/mpi.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/point_columns.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/run_end.hpp"
#include "hopper/campaign/running.hpp"
#include "hopper/campaign/signals.hpp"
#include "hopper/campaign/worker.hpp"
#include "hopper/core/error.hpp"
#include "hopper/core/memory.hpp"
#include "run_detail.hpp"

namespace hopper::campaign {

namespace fs = std::filesystem;

std::string compiler_id() {
#if defined(__clang__)
    return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
    return std::string("gcc ") + __VERSION__;
#else
    return "unknown";
#endif
}

config::SweepFile detail::load_campaign_sweep(const fs::path& sweep) {
    config::SweepFile f = config::load_sweep(sweep);
    if (!f.has_campaign)
        throw core::ConfigError(sweep.string() +
                                ": no [campaign] section: `campaign run` needs one (name, seed, "
                                "realizations; see campaigns/README.md)");
    return f;
}

namespace {

// The points' labels, one shared copy each for their tasks (TaskRef).
std::vector<std::shared_ptr<const std::string>> shared_labels(const config::CampaignSpec& spec) {
    std::vector<std::shared_ptr<const std::string>> labels;
    labels.reserve(spec.points.size());
    for (const auto& p : spec.points)
        labels.push_back(std::make_shared<const std::string>(p.label));
    return labels;
}

// Seconds a realization is expected to take, from the cost model (particle-steps) at a
// pessimistic speed (plan.hpp). The default silence limit of a worker depends on it; the
// progress line's ETA and the deadline's estimates scale it by what was measured.
double expected_seconds(double particle_steps) {
    return slow_seconds_per_particle_step * particle_steps;
}

WorkerOptions worker_options(const RunOptions& opt) {
    WorkerOptions w;
    w.checkpoints = opt.checkpoints;
    w.checkpoint_interval = opt.checkpoint_interval;
    if (opt.master.worker_timeout)
        w.heartbeat_interval = heartbeat_interval_for(*opt.master.worker_timeout);
    return w;
}

std::string host_name() {
    char buf[256] = {};
    if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
    return buf;
}

// Sends quit to every worker when the master's part ends, however it ends.
class QuitWorkers {
  public:
    explicit QuitWorkers(MasterChannel& ch) : ch_(ch) {}
    ~QuitWorkers() {
        for (int w = 1; w <= ch_.workers(); ++w)
            try {
                ch_.send(w, Message::make(MessageKind::quit));
            } catch (...) {
            }
    }

  private:
    MasterChannel& ch_;
};

struct Campaign {
    config::SweepFile sweep;
    config::TaskList tasks;  // made task by task: a target campaign plans max_realizations
};

Campaign load(const RunOptions& opt) {
    Campaign c;
    c.sweep = detail::load_campaign_sweep(opt.sweep);
    c.tasks = config::TaskList(c.sweep.campaign);
    return c;
}

ResumableTaskRunner make_runner(const RunOptions& opt, const Campaign& c) {
    return [&opt, &c](int task_id, std::span<const std::uint8_t> state,
                      const engine::RunHooks& hooks) {
        const config::Task t = c.tasks.at(task_id);  // std::out_of_range for an unknown id
        const engine::SceneParams& scene =
            c.sweep.campaign.points[static_cast<std::size_t>(t.point_index)].scene;
        if (opt.runner) return opt.runner(t, scene, hooks);
        if (!state.empty()) {
            try {
                return engine::resume_realization(scene, t.seed, state, hooks);
            } catch (const core::ConfigError& e) {
                // The master checked the file's code version, physics and checksum; a state the
                // engine still refuses (another engine format, a broken invariant) goes back to
                // the master with the reason: it removes the file and restarts the realization.
                throw std::runtime_error(std::string(checkpoint_refused) + e.what());
            }
        }
        return engine::run_realization(scene, t.seed, hooks);
    };
}

// Records what a round allots beyond the store's plan: the new seeds of every point whose
// allotment grows (replay_rounds decides; the record only lists).
void allot_round(store::Store& st, const Campaign& c, const RoundState& rs) {
    const auto& spec = c.sweep.campaign;
    const auto have = allotments(st.plan());
    store::AllotmentRecord rec;
    for (std::size_t p = 0; p < rs.points.size(); ++p) {
        const auto it = have.find(spec.points[p].label);
        const int from = it == have.end() ? 0 : it->second;
        const int to = std::min(rs.points[p].allotted, c.tasks.realizations(static_cast<int>(p)));
        if (to <= from) continue;
        store::PointAllotment a{spec.points[p].label, from, {}};
        for (int r = from; r < to; ++r)
            a.seeds.push_back(c.tasks.at(static_cast<int>(p), r).seed);
        rec.points.push_back(std::move(a));
    }
    st.allot(rec);
}

// A realization that was running each time its run died, max_deaths times (TaskEntry::deaths;
// 0: no limit), is taken for what killed it: a worker killed by the kernel's OOM killer under a
// memory limit takes the whole job with it, and would again in every run that hands it out.
// It is set aside: recorded once as an error with the reason (campaign status lists it, the run
// ends with exit 3) and not handed out; --max-deaths hands it out again (issue 44).
bool set_aside(store::Store& st, const store::TaskEntry* e, const std::string& label, int r,
               std::uint64_t seed, int max_deaths) {
    if (max_deaths <= 0 || !e || e->deaths < max_deaths) return false;
    if (e->state != store::TaskState::error) {
        const std::string n = std::to_string(e->deaths);
        st.append(store::ErrorRecord{
            label, r, seed, 0, e->errors + 1, store::unix_now(),
            "set aside: the job died each of the " + n +
                " times this realization was running "
                "(its process killed, by the kernel's OOM killer under a memory limit, a crash, a "
                "lost node or a kill -9), so it is not handed out again. Run it alone to see what "
                "it needs (campaign simulate --store " +
                st.path().string() + " --point '" + label + "' --realization " + std::to_string(r) +
                "), then resume with --max-deaths " + std::to_string(e->deaths + 1) +
                " (or 0: no limit) to hand it out again"});
    }
    return true;
}

void announce_set_aside(std::ostream& err, int n, int max_deaths) {
    if (n > 0)
        err << "campaign: " << n << " realization(s) set aside: each was running every time "
            << "the job died, " << max_deaths << " times or more (--max-deaths " << max_deaths
            << "; killed with its worker, by the kernel for memory?); see `campaign status`"
            << std::endl;
}

// A campaign with a target (adaptive.hpp): rounds until no point needs more. Each round's
// decisions are replayed from the journal, so an interrupted run resumes the same sequence.
MasterReport run_rounds(Master& master, const Campaign& c, store::Store& st,
                        const std::vector<double>& cost, int max_deaths, Totals totals,
                        std::ostream& err) {
    const auto& spec = c.sweep.campaign;
    const auto quantity = spec.target->quantity;
    const fs::path& store_path = st.path();
    MasterReport all;
    for (;;) {
        const std::map<std::string, PointResults> stored = read_round_results(store_path);
        const RoundState rs = replay_rounds(spec, stored, cost);
        if (rs.finished) {
            err << "campaign: target " << config::to_string(quantity)
                << ": no point needs more after round " << rs.round + 1 << ":\n"
                << describe_rounds(rs, quantity) << std::flush;
            break;
        }
        // The round's allotments into the plan (issue 29: the plan grows round by round; the
        // store records only what is new), then its missing realizations as tasks.
        allot_round(st, c, rs);
        std::vector<TaskRef> todo;
        const auto labels = shared_labels(spec);
        int aside = 0;
        for (const auto& [p, i] : rs.missing) {
            const config::Task t = c.tasks.at(p, i);
            const auto& label = spec.points[std::size_t(p)].label;
            if (set_aside(st, st.task(label, i), label, i, t.seed, max_deaths)) {
                ++aside;
                continue;
            }
            todo.push_back(TaskRef{t.task_id, labels[std::size_t(p)], i, t.seed,
                                   expected_seconds(cost[std::size_t(p)])});
        }
        // Progress counts within the allotments so far (not max_realizations per point).
        totals.finished = 0;
        for (const auto& [label, results] : stored)
            totals.finished += static_cast<int>(results.size());
        totals.total = totals.finished + static_cast<int>(todo.size());
        err << "campaign: round " << rs.round + 1 << " (target " << config::to_string(quantity)
            << ", relative 95 % half-width <= " << spec.target->rel_half_width
            << "): " << todo.size() << " realization(s) to run\n"
            << describe_rounds(rs, quantity) << std::flush;
        announce_set_aside(err, aside, max_deaths);
        const MasterReport r = master.run(todo, totals);
        add_round(all, r);
        if (r.stopped || !r.fail_fast.empty()) break;
        if (r.gave_up > 0 || r.stored == 0 || aside > 0) {
            err << "campaign: round " << rs.round + 1 << " is incomplete (realizations left in "
                << "error); run the same command again to retry them and go on" << std::endl;
            break;
        }
    }
    return all;
}

// What the caller of run_master() needs to know about how it ended.
struct MasterState {
    bool dispatching = false;  // inside Master::run (workers may be busy)
    int silent_workers = 0;    // workers still silent at the end (hung or stopped)
};

// ----- the master's part, step by step (run_master below reads as their sequence) -----------

// Before the store is touched: a deadline that cannot be known is an error, and one already
// past starts nothing (issue 29, item 4).
std::optional<double> checked_deadline(const RunOptions& opt, std::ostream& err) {
    const std::optional<double> deadline = opt.deadline ? opt.deadline(err) : std::nullopt;
    if (deadline && *deadline <= store::unix_now())
        throw core::ConfigError("the deadline has already passed (" +
                                format_duration(store::unix_now() - *deadline) +
                                " ago): no realization is started; give a later --deadline");
    return deadline;
}

store::StoreOptions store_options_of(const RunOptions& opt) {
    store::StoreOptions o = opt.store_options;
    if (!o.point_parameters) o.point_parameters = point_parameter_columns;
    return o;
}

// A resumed store against the sweep: incompatible physics throws (check_compatible), points
// that differ in unvaried settings need --allow-mixed, another code version is noted.
void check_resume(const store::Store& st, const store::CampaignPlan& plan, const RunOptions& opt,
                  std::ostream& err) {
    // Typed settings restored for old points (a copy only where some lack them: the plan of
    // 10^5 points is large).
    std::optional<store::CampaignPlan> restored;
    if (std::any_of(st.plan().points.begin(), st.plan().points.end(),
                    [](const auto& p) { return p.settings.empty() || p.parameters.empty(); })) {
        restored = st.plan();
        restore_settings(*restored, st.status().runs);
    }
    const store::CampaignPlan& stored = restored ? *restored : st.plan();
    for (const auto& n : check_compatible(stored, plan))
        err << "campaign: note: " << n << '\n';
    if (const auto mixed = mixed_settings(stored, plan); !mixed.empty()) {
        if (!opt.allow_mixed)
            throw core::ConfigError(
                "the sweep adds points whose settings, not varied by the sweep, differ "
                "from points already in the store:" +
                describe(mixed) +
                "\n  Fits would pool different physics. Use another --store, vary the "
                "setting in the sweep so that labels tell the points apart, or pass "
                "--allow-mixed (the Python figures then group by every differing setting).");
        err << "campaign: note: --allow-mixed: new points differ from stored ones in"
            << describe(mixed) << '\n';
    }
    const auto status = st.status();
    if (!status.runs.empty() && status.runs.back().info.code_version != opt.code_version)
        err << "campaign: note: the store's last run used code version "
            << status.runs.back().info.code_version << "; this is " << opt.code_version
            << " (results are compared per realization only within one version)\n";
}

// The run's start record: who runs what where, and what the sweep adds to the store's plan (all
// of it for a new store; a resume records its new points and realizations, not the whole plan
// again: issue 29).
void begin_run(store::Store& st, const RunOptions& opt, const Campaign& c, store::CampaignPlan plan,
               bool resumed, std::vector<std::string> hosts, int mpi_size, int workers) {
    store::RunStartRecord start;
    start.run.start_time = store::utc_now();
    start.run.code_version = opt.code_version;
    start.run.compiler = compiler_id();
    start.run.command = opt.command_line;
    start.run.sweep_path = c.sweep.path.string();
    start.run.sweep_text = c.sweep.text;
    start.run.mpi_size = mpi_size;
    start.run.workers = workers;
    start.run.hosts = std::move(hosts);
    start.run.pid = static_cast<std::int64_t>(getpid());
    start.plan = resumed ? plan_additions(st.plan(), std::move(plan)) : std::move(plan);
    st.begin_run(std::move(start));
}

// The realizations planned so far per point: all of them, or with a target those the rounds
// allotted (the store's plan; run_rounds extends it), never max_realizations (issue 29).
std::vector<int> planned_realizations(const Campaign& c, const store::Store& st) {
    const auto& spec = c.sweep.campaign;
    std::vector<int> planned(spec.points.size());
    const auto have = allotments(st.plan());
    for (std::size_t p = 0; p < spec.points.size(); ++p) {
        planned[p] = c.tasks.realizations(static_cast<int>(p));
        if (spec.target) {
            const auto it = have.find(spec.points[p].label);
            planned[p] = std::min(planned[p], it == have.end() ? 0 : it->second);
        }
    }
    return planned;
}

store::TaskState task_state(const store::Store& st, const std::string& label, int r) {
    const store::TaskEntry* e = st.task(label, r);
    return e ? e->state : store::TaskState::pending;
}

bool has_result(store::TaskState s) {
    return s == store::TaskState::done || s == store::TaskState::failed;
}

// What to run: the planned tasks with no result yet (pending, or left in error), the most
// expensive first (ties in task order), less those set aside; none with a target (the rounds
// decide). `totals` counts the planned and the stored (and the set aside, as failed). Built in its
// final order, points by cost (stable), each point's realizations in order, with one look at each
// task: at 10^6 tasks a list sorted afterwards held two lists and their index vectors at once
// (issue 44).
std::vector<TaskRef> tasks_to_run(const Campaign& c, store::Store& st,
                                  const std::vector<int>& planned, const std::vector<double>& cost,
                                  const std::vector<std::uint64_t>& physics, int max_deaths,
                                  Totals& totals, std::ostream& err) {
    const auto& spec = c.sweep.campaign;
    std::vector<std::size_t> points(spec.points.size());
    std::iota(points.begin(), points.end(), std::size_t{0});
    std::stable_sort(points.begin(), points.end(),
                     [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
    const auto labels = shared_labels(spec);
    std::vector<TaskRef> todo;
    int aside = 0;
    for (const std::size_t p : points) {
        totals.total += planned[p];
        for (int r = 0; r < planned[p]; ++r) {
            const store::TaskEntry* e = st.task(spec.points[p].label, r);  // one look a task
            const store::TaskState state = e ? e->state : store::TaskState::pending;
            if (has_result(state)) {
                ++totals.finished;
                if (state == store::TaskState::failed) ++totals.failed;
                continue;
            }
            if (spec.target) continue;  // the rounds decide what runs (run_rounds)
            const config::Task t = c.tasks.at(static_cast<int>(p), r);
            if (set_aside(st, e, spec.points[p].label, r, t.seed, max_deaths)) {
                ++aside;
                ++totals.finished;
                ++totals.failed;
                continue;
            }
            todo.push_back(
                TaskRef{t.task_id, labels[p], r, t.seed, expected_seconds(cost[p]), physics[p]});
        }
    }
    announce_set_aside(err, aside, max_deaths);
    return todo;
}

void announce(std::ostream& err, const fs::path& store_path, bool resumed, const Campaign& c,
              const Totals& totals, std::size_t to_run, int workers) {
    const auto& spec = c.sweep.campaign;
    err << "campaign: store " << store_path.string() << (resumed ? " (resumed)" : " (new)") << ": "
        << totals.total
        << (spec.target ? " realizations allotted so far (rounds, up to max_realizations = " +
                              std::to_string(spec.target->max_realizations) + " per point)"
                        : std::string(" realizations in the sweep"))
        << ", " << totals.finished << " stored"
        << (totals.failed ? " (" + std::to_string(totals.failed) + " failed)" : std::string());
    if (spec.target)
        err << "; the rounds decide what runs on ";
    else
        err << ", " << to_run << " to run on ";
    err << workers << " worker" << (workers == 1 ? "" : "s") << std::endl;
}

// The store's checkpoint directory, without the files a crash left between storing a result
// and removing its checkpoint.
void open_checkpoints(CheckpointFiles& files, const Campaign& c, const store::Store& st,
                      const std::vector<int>& planned) {
    const auto& spec = c.sweep.campaign;
    for (std::size_t p = 0; p < spec.points.size(); ++p)
        for (int r = 0; r < planned[p]; ++r) {
            const auto& label = spec.points[p].label;
            if (has_result(task_state(st, label, r)))
                files.remove(CheckpointKey{label, r, c.tasks.at(static_cast<int>(p), r).seed, 0});
        }
    files.remove_dir_if_empty();
}

// The cost model's correction from what this campaign measured so far (every run).
void measured_cost(MasterOptions& mo, const Campaign& c, const store::Store& st,
                   const std::vector<double>& cost) {
    const auto& spec = c.sweep.campaign;
    const store::StoreStatus before = st.status();
    std::map<std::string_view, std::size_t> index;  // not a scan per point: 10^5 points
    for (std::size_t p = 0; p < spec.points.size(); ++p)
        index.emplace(spec.points[p].label, p);
    for (const auto& ps : before.points)
        if (const auto it = index.find(ps.label); it != index.end() && ps.timed > 0) {
            mo.measured_seconds += ps.task_seconds;
            mo.measured_expected += ps.timed * expected_seconds(cost[it->second]);
        }
}

void announce_deadline(std::ostream& err, const MasterOptions& mo) {
    err << "campaign: deadline " << format_duration(*mo.deadline - store::unix_now())
        << " from now (grace " << format_duration(mo.grace) << "): realizations expected to "
        << "end later are not started (cost model x "
        << (mo.measured_expected > 0 ? mo.measured_seconds / mo.measured_expected : 1.0)
        << ", measured on "
        << (mo.measured_expected > 0 ? "the stored realizations" : "nothing yet") << ")"
        << std::endl;
}

// The master's whole part: store, plan check, dispatch, summary. Returns the exit code.
int run_master(const RunOptions& opt, const Campaign& c, MasterChannel& channel,
               std::vector<std::string> hosts, int mpi_size, MasterState* state, std::ostream& out,
               std::ostream& err) {
    const auto& spec = c.sweep.campaign;
    const fs::path store_path = opt.store ? *opt.store : spec.store;
    SignalWatcher signals;
    const std::optional<double> deadline = checked_deadline(opt, err);
    store::Store st(store_path, store_options_of(opt));
    for (const auto& n : st.notes())
        err << "campaign: note: " << n << '\n';

    store::CampaignPlan plan = make_plan(spec);
    std::vector<std::uint64_t> physics;  // per point of the sweep
    for (const auto& p : plan.points)
        physics.push_back(p.physics_hash());
    const bool resumed = !st.is_new();
    if (resumed) check_resume(st, plan, opt, err);
    begin_run(st, opt, c, std::move(plan), resumed, std::move(hosts), mpi_size, channel.workers());

    std::vector<double> cost(spec.points.size());
    for (std::size_t p = 0; p < spec.points.size(); ++p)
        cost[p] = expected_cost(spec.points[p].scene);
    const std::vector<int> planned = planned_realizations(c, st);
    Totals totals;
    const std::vector<TaskRef> todo =
        tasks_to_run(c, st, planned, cost, physics, opt.max_deaths, totals, err);
    announce(err, store_path, resumed, c, totals, todo.size(), channel.workers());

    MasterOptions mo = opt.master;
    std::optional<CheckpointFiles> checkpoints;
    if (opt.checkpoints) {
        checkpoints.emplace(store_path, opt.code_version);
        open_checkpoints(*checkpoints, c, st, planned);
        mo.checkpoints = &*checkpoints;
    }
    mo.running_file = running_path(store_path);
    mo.deadline = deadline;
    if (resumed) measured_cost(mo, c, st, cost);
    if (mo.deadline) announce_deadline(err, mo);

    // What the setup freed (the parsed sweep's temporaries, the encoded plan of the run's first
    // journal record) goes back to the system before the master settles into dispatching.
    core::release_free_memory();
    state->dispatching = true;
    Master master(channel, st, signals, mo, err);
    const MasterReport rep = spec.target
                                 ? run_rounds(master, c, st, cost, opt.max_deaths, totals, err)
                                 : master.run(todo, totals);
    state->dispatching = false;
    state->silent_workers = rep.silent_at_end;

    const std::string resume =
        !opt.resume_command.empty()
            ? opt.resume_command
            : "campaign run " + c.sweep.path.string() +
                  (opt.store ? " --store " + opt.store->string() : std::string());
    return finish_run(st, spec, c.tasks, rep,
                      RunEndContext{store_path, resume, totals.total, spec.target.has_value()}, out,
                      err);
}

}  // namespace

int run_campaign(const RunOptions& opt, std::ostream& out, std::ostream& err) {
    if (opt.threads < 1) throw core::ConfigError("--threads must be at least 1");
    if (opt.dry_run) return dry_run(opt, out, err);
    std::optional<MpiSession> mpi;
    if (launched_by_mpi()) mpi.emplace();
    const int rank = mpi ? mpi->rank() : 0;
    const int size = mpi ? mpi->size() : 1;
    // After the master's run (its Store closed): the caller's after_run hook, if any.
    const auto finish = [&opt](const Campaign& c, int code) {
        if (!opt.after_run) return code;
        return opt.after_run(opt.store ? *opt.store : c.sweep.campaign.store, code);
    };

    if (size > 1) {
        // Every rank reads the sweep; all must succeed before anyone goes on.
        Campaign c;
        std::exception_ptr failure;
        try {
            c = load(opt);
        } catch (...) {
            failure = std::current_exception();
        }
        const bool ok = mpi->all_ok(!failure);
        if (!ok) {
            if (rank != 0) return 2;
            if (failure) std::rethrow_exception(failure);
            throw core::ConfigError("another rank could not read the sweep file '" +
                                    opt.sweep.string() + "' (is it on a shared file system?)");
        }
        std::vector<std::string> hosts = mpi->hosts();
        // Hybrid: --threads T makes every worker rank run T realizations at once (hybrid.hpp).
        const int per_rank = opt.threads_given ? opt.threads : 1;
        if (rank == 0 && per_rank > 1)
            err << "campaign: " << size - 1 << " worker rank(s) x " << per_rank
                << " threads = " << (size - 1) * per_rank
                << " workers (store and status number them 1.." << (size - 1) * per_rank
                << "; rank r runs workers (r-1) x " << per_rank << " + 1..)" << std::endl;
        if (rank != 0) {
            SignalWatcher ignore;  // the master decides; a forwarded signal must not kill us
            auto ch = mpi->worker_channel();
            if (per_rank > 1)
                run_hybrid_worker(*ch, per_rank, make_runner(opt, c), worker_options(opt));
            else
                run_worker(*ch, make_runner(opt, c), worker_options(opt));
            return 0;
        }
        auto mpi_ch = mpi->master_channel();
        auto ch = per_rank > 1 ? slotted_master(*mpi_ch, per_rank) : std::move(mpi_ch);
        MasterState state;
        QuitWorkers quit(*ch);
        try {
            const int code =
                finish(c, run_master(opt, c, *ch, std::move(hosts), size, &state, out, err));
            if (state.silent_workers > 0) {
                // MPI_Finalize would wait for them for ever. Everything is stored and closed.
                err << "campaign: " << state.silent_workers << " worker(s) still silent; ending "
                    << "the MPI job without them (MPI_Abort with exit code " << code << ")"
                    << std::endl;
                mpi->abort(code);
            }
            return code;
        } catch (const std::exception& e) {
            if (!state.dispatching) throw;
            // Workers may be busy (and blocked sending a large result): end the job. Every
            // stored realization is safe in the journal.
            err << "campaign: error: " << e.what() << "\ncampaign: aborting the MPI job"
                << std::endl;
            mpi->abort(1);
        }
    }

    // One process: the master here, the workers in threads.
    const Campaign c = load(opt);
    InProcessChannels channels(opt.threads);
    const ResumableTaskRunner runner = make_runner(opt, c);
    std::vector<std::thread> threads;
    for (int i = 0; i < opt.threads; ++i)
        threads.emplace_back(
            [&, i] { run_worker(channels.worker(i), runner, worker_options(opt)); });
    struct Join {
        std::vector<std::thread>& t;
        ~Join() {
            for (auto& th : t)
                th.join();
        }
    } join{threads};
    QuitWorkers quit(channels.master());
    MasterState state;
    return finish(c, run_master(opt, c, channels.master(), {host_name()}, size, &state, out, err));
}

}  // namespace hopper::campaign
