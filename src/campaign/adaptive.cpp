#include "hopper/campaign/adaptive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "hopper/stats/exponential_fit.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

namespace {

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

std::string percent(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * v);
    return buf;
}

}  // namespace

PointPrecision precision(const PointResults& results, int n,
                         config::CampaignTarget::Quantity quantity) {
    PointPrecision out;
    std::vector<double> x;
    std::vector<bool> censored;
    for (const auto& [index, r] : results) {
        if (index >= n) break;
        if (r.status == engine::Status::failed) continue;
        if (quantity == config::CampaignTarget::Quantity::tau) {
            for (std::size_t i = 0; i < r.survival_times.size(); ++i) {
                x.push_back(r.survival_times[i]);
                censored.push_back(i < r.censored.size() && r.censored[i]);
            }
        } else {
            // Results stored before avalanche sizes existed have none: they do not count.
            if (r.avalanche_sizes.size() != r.survival_times.size()) continue;
            for (std::size_t i = 0; i < r.avalanche_sizes.size(); ++i) {
                x.push_back(double(r.avalanche_sizes[i]));
                censored.push_back(i < r.censored.size() && r.censored[i]);
            }
        }
        ++out.used;
    }
    if (x.empty()) return out;
    const stats::ExponentialFit f = stats::fit_censored_exponential(x, censored);
    out.jams = f.n_uncensored;
    if (f.tau && f.tau_lo && f.tau_hi && *f.tau > 0.0) {
        out.has_estimate = true;
        out.estimate = *f.tau;
        out.rel_half_width = (*f.tau_hi - *f.tau_lo) / (2.0 * *f.tau);
    }
    return out;
}

RoundState replay_rounds(const config::CampaignSpec& spec,
                         const std::map<std::string, PointResults>& stored,
                         const std::vector<double>& cost) {
    const config::CampaignTarget& t = *spec.target;
    RoundState s;
    const PointResults none;
    const auto results_of = [&](std::size_t p) -> const PointResults& {
        const auto it = stored.find(spec.points[p].label);
        return it == stored.end() ? none : it->second;
    };
    for (const auto& pt : spec.points)
        s.points.push_back(
            PointRounds{pt.label, std::clamp(pt.first_round, 1, pt.realizations), false, "", {}});
    // Realizations a point still needs by the last estimate (for the order within a round).
    std::vector<double> need(spec.points.size(), double(t.max_realizations));
    for (;;) {
        s.missing.clear();
        for (std::size_t p = 0; p < s.points.size(); ++p) {
            if (s.points[p].done) continue;
            const PointResults& r = results_of(p);
            for (int i = 0; i < s.points[p].allotted; ++i)
                if (!r.count(i)) s.missing.emplace_back(int(p), i);
        }
        if (!s.missing.empty()) {
            std::stable_sort(s.missing.begin(), s.missing.end(), [&](const auto& a, const auto& b) {
                const double ka = cost[std::size_t(a.first)] * need[std::size_t(a.first)];
                const double kb = cost[std::size_t(b.first)] * need[std::size_t(b.first)];
                if (ka != kb) return ka < kb;
                return a < b;
            });
            return s;
        }
        // The round is complete: decide.
        bool more = false;
        for (std::size_t p = 0; p < s.points.size(); ++p) {
            PointRounds& pr = s.points[p];
            if (pr.done) continue;
            pr.precision = precision(results_of(p), pr.allotted, t.quantity);
            const PointPrecision& q = pr.precision;
            const std::string where =
                std::to_string(pr.allotted) + " realizations, " + std::to_string(q.jams) + " jams";
            if (q.has_estimate && q.rel_half_width <= t.rel_half_width) {
                pr.done = true;
                pr.why = "target met: relative 95 % half-width " + percent(q.rel_half_width) +
                         " <= " + percent(t.rel_half_width) + " after " + where;
            } else if (pr.allotted >= t.max_realizations) {
                pr.done = true;
                pr.why = "max_realizations = " + std::to_string(t.max_realizations) + " reached (" +
                         where + ", relative half-width " +
                         (q.has_estimate ? percent(q.rel_half_width) : std::string("unknown")) +
                         ")";
            } else {
                // The half-width shrinks about as 1/sqrt(realizations).
                need[p] =
                    q.has_estimate
                        ? std::max(1.0,
                                   pr.allotted * std::pow(q.rel_half_width / t.rel_half_width, 2) -
                                       pr.allotted)
                        : double(t.max_realizations - pr.allotted);
                pr.allotted = std::min(t.max_realizations, pr.allotted + t.round);
                pr.why = "needs more: " +
                         (q.has_estimate ? "relative half-width " + percent(q.rel_half_width)
                                         : std::string("no jams yet")) +
                         " after " + where;
                more = true;
            }
        }
        if (!more) {
            s.finished = true;
            return s;
        }
        ++s.round;
    }
}

std::string describe_rounds(const RoundState& s, config::CampaignTarget::Quantity quantity) {
    std::ostringstream out;
    const char* name = quantity == config::CampaignTarget::Quantity::tau ? "tau (s)" : "<s>";
    for (std::size_t i = 0; i < s.points.size(); ++i) {
        const PointRounds& p = s.points[i];
        out << "  " << p.label << ": " << p.allotted << " realizations";
        if (p.precision.has_estimate)
            out << ", " << name << " = " << num(p.precision.estimate) << " +- "
                << percent(p.precision.rel_half_width);
        out << "; ";
        if (!p.why.empty()) {
            out << p.why << '\n';
            continue;
        }
        // Still in the first round: say how much of it is stored, so that a point whose
        // first round is complete does not read as running.
        const auto missing = std::count_if(s.missing.begin(), s.missing.end(),
                                           [&](const auto& m) { return m.first == int(i); });
        if (missing == 0)
            out << "first round stored; decided when every point's first round is\n";
        else
            out << "first round running (" << p.allotted - missing << " of " << p.allotted
                << " stored)\n";
    }
    return out.str();
}

std::map<std::string, PointResults> read_round_results(const std::filesystem::path& store) {
    std::map<std::string, PointResults> stored;
    store::for_each_journal_realization(store, [&](store::StoredRealization&& r) {
        engine::RealizationResult slim;
        slim.status = r.result.status;
        slim.survival_times = std::move(r.result.survival_times);
        slim.censored = std::move(r.result.censored);
        slim.avalanche_sizes = std::move(r.result.avalanche_sizes);
        stored[r.label][r.record.realization] = std::move(slim);
    });
    return stored;
}

}  // namespace hopper::campaign
