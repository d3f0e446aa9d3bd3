#include "hopper/campaign/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace hopper::campaign {

std::string format_duration(double s) {
    if (!std::isfinite(s) || s < 0) return "?";
    if (s >= 1e12) return "over 30000 years";  // and no overflow of the integer below
    const long long t = std::llround(s);
    char buf[32];
    if (t < 60)
        std::snprintf(buf, sizeof buf, "%llds", t);
    else if (t < 3600)
        std::snprintf(buf, sizeof buf, "%lldm%02llds", t / 60, t % 60);
    else if (t < 86400)
        std::snprintf(buf, sizeof buf, "%lldh%02lldm", t / 3600, (t % 3600) / 60);
    else
        std::snprintf(buf, sizeof buf, "%lldd%02lldh", t / 86400, (t % 86400) / 3600);
    return buf;
}

std::string progress_line(int done, int total, int running, int failed, double rate, double elapsed,
                          double eta_seconds) {
    char buf[256];
    const int left = std::max(0, total - done);
    const std::string eta = left == 0          ? "0s"
                            : eta_seconds >= 0 ? format_duration(eta_seconds)
                            : rate > 0         ? format_duration(left / rate)
                                               : "?";
    std::snprintf(buf, sizeof buf,
                  "campaign: %d/%d done, %d running, %d failed, %.3g/s, ETA %s, elapsed %s", done,
                  total, running, failed, rate, eta.c_str(), format_duration(elapsed).c_str());
    return buf;
}

CostEta::CostEta(int workers, double prior_seconds_per_cost)
    : workers_(std::max(1, workers)), prior_(prior_seconds_per_cost) {}

void CostEta::add_pending(double cost, int tasks) {
    pending_cost_ += cost * tasks;
}

void CostEta::finished(double cost, double worker_seconds, int tasks, bool was_pending,
                       double done_cost) {
    if (was_pending) pending_cost_ = std::max(0.0, pending_cost_ - cost * tasks);
    const double computed = done_cost >= 0 ? done_cost : cost * tasks;
    if (computed > 0 && worker_seconds > 0) {
        cost_done_ += computed;
        seconds_done_ += worker_seconds;
    }
}

double CostEta::seconds_per_cost() const {
    return cost_done_ > 0 ? seconds_done_ / cost_done_ : prior_;
}

double CostEta::seconds_left(const std::vector<RunningCost>& running) const {
    const double speed = seconds_per_cost();
    double queued = pending_cost_, running_left = 0.0, longest = 0.0;
    for (const auto& r : running) {
        queued -= r.cost;
        const double expected = r.cost * speed;
        const double left = std::max(expected - r.elapsed, expected / 20);
        running_left += left;
        longest = std::max(longest, left);
    }
    return std::max((std::max(0.0, queued) * speed + running_left) / workers_, longest);
}

void write_summary(std::ostream& out, const store::StoreStatus& status,
                   const std::vector<std::string>& labels) {
    std::map<std::string, const store::PointStatus*> by_label;
    for (const auto& p : status.points)
        by_label[p.label] = &p;
    std::size_t width = 5;
    for (const auto& l : labels)
        width = std::max(width, l.size());
    // Stored / planned, and "of" the limit of a target campaign's point ("25/26 of 1000000").
    const auto stored_text = [](const store::PointStatus& p) {
        return std::to_string(p.done + p.failed - p.errors) + "/" + std::to_string(p.planned) +
               (p.limit > p.planned ? " of " + std::to_string(p.limit) : std::string());
    };
    int column = 13;
    for (const auto& p : status.points)
        column = std::max(column, static_cast<int>(stored_text(p).size()));
    char buf[512];
    std::snprintf(buf, sizeof buf, "%-*s  %*s  %6s  %6s  %14s  %14s\n", static_cast<int>(width),
                  "point", column, "realizations", "failed", "jams", "tau (s)", "mean empty (s)");
    out << buf;
    for (const auto& l : labels) {
        const auto it = by_label.find(l);
        if (it == by_label.end()) continue;
        const store::PointStatus& p = *it->second;
        const std::string stored = stored_text(p);
        char surv[32] = "-", empty[32] = "-";
        if (p.uncensored > 0)
            std::snprintf(surv, sizeof surv, "%.4g", p.survival_sum / p.uncensored);
        if (p.emptied > 0) std::snprintf(empty, sizeof empty, "%.4g", p.empty_sum / p.emptied);
        std::snprintf(buf, sizeof buf, "%-*s  %*s  %6d  %6d  %14s  %14s\n", static_cast<int>(width),
                      l.c_str(), column, stored.c_str(), p.failed, p.jams, surv, empty);
        out << buf;
    }
    out << "(tau: mean survival time, the censored maximum-likelihood mean = flow time / jams)\n";
}

}  // namespace hopper::campaign
