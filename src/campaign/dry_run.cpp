// `campaign run --dry-run` (run.hpp): what the sweep would run on its store and what it would cost,
// from the cost model scaled by what the store measured; nothing is run or written.
#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include "hopper/campaign/adaptive.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/campaign/report.hpp"
#include "hopper/campaign/run.hpp"
#include "hopper/store/store.hpp"
#include "run_detail.hpp"

namespace hopper::campaign {

namespace fs = std::filesystem;

namespace {

// With a target, what the run would do now per point: its rounds replayed from the stored
// results (as `campaign run` and `campaign status` do), not the store's plan, which a journal
// written before issue 29 fills with every seed up to max_realizations.
std::vector<int> missing_in_round(const config::CampaignSpec& spec, const fs::path& store_path,
                                  bool existing) {
    std::vector<int> missing(spec.points.size(), 0);
    const std::map<std::string, PointResults> results =
        existing ? read_round_results(store_path) : std::map<std::string, PointResults>();
    std::vector<double> expected;
    for (const auto& pt : spec.points)
        expected.push_back(expected_cost(pt.scene));
    const RoundState rounds = replay_rounds(spec, results, expected);
    if (!rounds.finished)
        for (const auto& [p, i] : rounds.missing)
            ++missing[std::size_t(p)];
    return missing;
}

// The dry run's last lines: what 'to run' means with a target, the cost model's basis (seconds
// per particle-step measured on the store, or the prior), the wall time on the workers.
void dry_run_basis(std::ostream& out, const config::CampaignSpec& spec,
                   std::optional<double> measured_per_cost, double total_h, int workers) {
    if (spec.target)
        out << "target " << config::to_string(spec.target->quantity)
            << ": 'to run' is the current round; each point that needs more gets "
            << spec.target->round
            << " more per round, up to max_realizations = " << spec.target->max_realizations
            << " (later rounds depend on the results)\n";
    out << "basis: cost model (mobile particles x time steps: settling the packing, emptying it "
           "at the 2-D Beverloo rate of the outlet and wall angle, jams and shakes; "
           "docs/performance.md) x ";
    if (measured_per_cost)
        out << *measured_per_cost * 1e9
            << " ns per particle-step (measured on the store's realizations of these points)";
    else
        out << "the engine's speed measured on one core (" << prior_seconds_per_particle_step * 1e9
            << " ns per particle-step at 8750 particles, less for smaller systems)";
    out << "; core-hours count worker time only (the master sleeps)\n";
    out << "on " << workers << " worker" << (workers == 1 ? "" : "s") << ": about "
        << format_duration(total_h * 3600.0 / workers) << " of wall time if the load balances\n";
}

}  // namespace

int dry_run(const RunOptions& opt, std::ostream& out, std::ostream& err, DryRunTotals* totals) {
    const config::SweepFile sweep = detail::load_campaign_sweep(opt.sweep);
    const auto& spec = sweep.campaign;
    const fs::path store_path = opt.store ? *opt.store : spec.store;
    fs::path journal = store_path;
    journal += ".journal";
    store::StoreStatus status;
    const bool existing = fs::exists(journal);
    if (existing) {
        status = store::read_status(store_path);
        if (status.has_plan) {
            for (const auto& n : check_compatible(status.plan, make_plan(spec)))
                err << "campaign: note: " << n << '\n';
        }
    }
    // Measured worker seconds per particle-step over the stored realizations of these points.
    double measured_s = 0.0, measured_cost = 0.0;
    std::vector<double> cost(spec.points.size()), prior(spec.points.size());
    std::map<std::string_view, const store::PointStatus*> status_of;  // not a scan per point
    for (const auto& ps : status.points)
        status_of.emplace(ps.label, &ps);
    const auto stored_status = [&](const config::Point& pt) -> const store::PointStatus* {
        const auto it = status_of.find(pt.label);
        return it == status_of.end() ? nullptr : it->second;
    };
    for (std::size_t p = 0; p < spec.points.size(); ++p) {
        const CostEstimate e = estimate_cost(spec.points[p].scene);
        cost[p] = e.particle_steps;
        prior[p] = e.seconds;
        if (const store::PointStatus* ps = stored_status(spec.points[p]); ps && ps->timed > 0) {
            measured_s += ps->task_seconds;
            measured_cost += ps->timed * cost[p];
        }
    }
    const bool measured = measured_cost > 0;
    const double per_cost = measured ? measured_s / measured_cost : 0.0;
    out << "dry run: " << sweep.path.string() << " on " << store_path.string()
        << (existing ? "" : " (new)") << "; nothing is run or written\n";
    // The point column as wide as the longest label (at least 40): a label cut short can hide
    // what tells two points apart ("hopper.particles=3" for 300 and for 3000).
    int width = 40;
    for (const auto& pt : spec.points)
        width = std::max(width, static_cast<int>(pt.label.size()));
    std::vector<char> buffer(static_cast<std::size_t>(width) + 128);
    char* const line = buffer.data();
    const std::size_t line_size = buffer.size();
    std::snprintf(line, line_size, "%-*s %9s %7s %7s %12s %11s\n", width, "point", "particles",
                  "stored", "to run", "s/realiz.", "core-hours");
    out << line;
    const std::vector<int> missing =
        spec.target ? missing_in_round(spec, store_path, existing) : std::vector<int>();
    double total_h = 0.0;
    int total_runs = 0;
    for (std::size_t p = 0; p < spec.points.size(); ++p) {
        const auto& pt = spec.points[p];
        const store::PointStatus* ps = stored_status(pt);
        // Stored results (failed ones included) count from the lowest index.
        const int results = ps ? ps->done + ps->failed - ps->errors : 0;
        // Planned now: every realization, or with a target what the current round still lacks
        // (not max_realizations, issue 29).
        const int stored = std::clamp(results, 0, pt.realizations);
        const int to_run = spec.target ? missing[p] : pt.realizations - stored;
        const double each = measured ? cost[p] * per_cost : prior[p];
        const double hours = to_run * each / 3600.0;
        total_h += hours;
        total_runs += to_run;
        if (totals && to_run > 0) totals->longest_seconds = std::max(totals->longest_seconds, each);
        std::snprintf(line, line_size, "%-*s %9d %7d %7d %12.1f %11.3f\n", width, pt.label.c_str(),
                      pt.scene.particles.count, stored, to_run, each, hours);
        out << line;
    }
    std::snprintf(line, line_size, "%-*s %9s %7s %7d %12s %11.3f\n", width, "total", "", "",
                  total_runs, "", total_h);
    out << line;
    if (totals) {
        totals->worker_seconds = total_h * 3600.0;
        totals->realizations = total_runs;
    }
    dry_run_basis(out, spec, measured ? std::optional<double>(per_cost) : std::nullopt, total_h,
                  std::max(1, opt.threads));
    return 0;
}

}  // namespace hopper::campaign
