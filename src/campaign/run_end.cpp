#include "hopper/campaign/run_end.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/run.hpp"

namespace hopper::campaign {

Outcome count_outcome(const store::Store& st, const config::CampaignSpec& spec,
                      const config::TaskList& tasks) {
    const auto allotted = allotments(st.plan());  // the rounds may have grown them
    Outcome o;
    for (std::size_t p = 0; p < spec.points.size(); ++p) {
        const auto it = allotted.find(spec.points[p].label);
        const int n = std::min(tasks.realizations(static_cast<int>(p)),
                               it == allotted.end() ? 0 : it->second);
        for (int r = 0; r < n; ++r) {
            const store::TaskEntry* e = st.task(spec.points[p].label, r);
            const store::TaskState s = e ? e->state : store::TaskState::pending;
            if (s == store::TaskState::pending) ++o.left;
            if (s == store::TaskState::failed || s == store::TaskState::error) ++o.failed;
        }
    }
    return o;
}

Ending ending_of(const MasterReport& rep, const Outcome& o, bool has_target) {
    const bool stopped_nothing =
        o.left == 0 && rep.interrupted == 0 && !has_target && !rep.stopped_running;
    if (rep.stopped && !stopped_nothing) return Ending::interrupted;
    if (!rep.fail_fast.empty()) return Ending::stopped_early;
    return o.failed > 0 ? Ending::with_failures : Ending::complete;
}

int finish_run(store::Store& st, const config::CampaignSpec& spec, const config::TaskList& tasks,
               const MasterReport& rep, const RunEndContext& ctx, std::ostream& out,
               std::ostream& err) {
    const Outcome o = count_outcome(st, spec, tasks);
    const Ending ending = ending_of(rep, o, ctx.has_target);
    if (rep.stopped && ending != Ending::interrupted)
        err << "campaign: " << rep.stop_reason << " came after the last realization was handed "
            << "out, and it finished: the run is complete" << std::endl;
    const std::string reason = ending == Ending::interrupted ? "interrupted by " + rep.stop_reason
                               : ending == Ending::stopped_early ? "stopped early: " + rep.fail_fast
                                                                 : std::string("complete");
    st.end_run(store::RunEndRecord{store::utc_now(), reason, rep.stored, rep.wall_seconds,
                                   rep.cpu_seconds, rep.lost_worker_seconds,
                                   rep.saved_worker_seconds});

    const store::StoreStatus status = st.status();
    std::vector<std::string> labels;
    for (const auto& p : spec.points)
        labels.push_back(p.label);
    write_summary(out, status, labels);
    out.flush();

    char share[64];
    std::snprintf(share, sizeof share, "%.2f%%",
                  rep.wall_seconds > 0 ? 100.0 * rep.cpu_seconds / rep.wall_seconds : 0.0);
    err << "campaign: this run stored " << rep.stored << " realization(s) in "
        << format_duration(rep.wall_seconds) << "; master CPU " << share << " of wall time"
        << std::endl;
    if (rep.reassigned > 0)
        err << "campaign: " << rep.reassigned << " realization(s) were handed to another worker "
            << "after their worker went silent; late results: " << rep.late_identical
            << " identical, " << rep.late_different << " different" << std::endl;
    if (rep.interrupted > 0 || rep.resumed > 0)
        err << "campaign: worker time of interrupted realizations: "
            << format_duration(rep.saved_worker_seconds) << " kept in checkpoints, "
            << format_duration(rep.lost_worker_seconds) << " thrown away; " << rep.resumed
            << " realization(s) continued from a checkpoint" << std::endl;
    switch (ending) {
        case Ending::interrupted:
            err << "campaign: stopped by " << rep.stop_reason << "; " << o.left + o.failed
                << " realization(s) not stored yet (" << rep.interrupted
                << " interrupted). Resume with:\n  " << ctx.resume_command << std::endl;
            return run_stopped;
        case Ending::stopped_early:
            err << "campaign: stopped early: " << rep.fail_fast
                << ". The scene fails, not a seed: " << o.left
                << " realization(s) were not run. Fix the sweep file (the message names "
                << "what fails; check the units of its settings) and run it on another --store"
                << std::endl;
            return run_with_failures;
        case Ending::with_failures:
            err << "campaign: finished with " << o.failed
                << " failed realization(s); see `campaign status " << ctx.store_path.string()
                << "`. Exceptions are retried by running the same command again (a realization set "
                << "aside after the job died with it running: with a higher --max-deaths)."
                << std::endl;
            return run_with_failures;
        case Ending::complete:
            break;
    }
    if (ctx.has_target)
        err << "campaign: finished: every point met the target or reached max_realizations; "
            << status.done + status.failed << " realizations are in " << ctx.store_path.string()
            << std::endl;
    else
        err << "campaign: finished: all " << ctx.total << " realizations are in "
            << ctx.store_path.string() << std::endl;
    return run_ok;
}

}  // namespace hopper::campaign
