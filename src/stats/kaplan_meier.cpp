#include "hopper/stats/kaplan_meier.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hopper::stats {

KaplanMeierCurve kaplan_meier(std::span<const double> t, const std::vector<bool>& censored) {
    if (t.size() != censored.size())
        throw std::invalid_argument("kaplan_meier: " + std::to_string(t.size()) +
                                    " intervals but " + std::to_string(censored.size()) +
                                    " censoring flags");
    for (double v : t)
        if (!(v >= 0.0) || !std::isfinite(v))
            throw std::invalid_argument("kaplan_meier: an interval is negative or not finite");

    KaplanMeierCurve km;
    km.n = static_cast<int>(t.size());
    std::vector<std::size_t> order(t.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return t[a] < t[b]; });

    int remaining = km.n;  // at risk just before the current time
    double S = 1.0;
    double greenwood = 0.0;
    for (std::size_t i = 0; i < order.size();) {
        const double ti = t[order[i]];
        int d = 0, c = 0;
        for (; i < order.size() && t[order[i]] == ti; ++i)
            (censored[order[i]] ? c : d) += 1;
        km.last_time = ti;
        if (d > 0) {
            // Censored ties at t_j are still at risk at t_j (censoring just after the event).
            const int n_j = remaining;
            S *= 1.0 - static_cast<double>(d) / n_j;
            if (n_j > d)
                greenwood += static_cast<double>(d) / (static_cast<double>(n_j) * (n_j - d));
            km.time.push_back(ti);
            km.at_risk.push_back(n_j);
            km.events.push_back(d);
            km.survival.push_back(S);
            km.std_err.push_back(S > 0.0 ? S * std::sqrt(greenwood) : 0.0);
        }
        remaining -= d + c;
    }
    return km;
}

}  // namespace hopper::stats
