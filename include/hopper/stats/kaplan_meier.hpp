#pragma once
// Kaplan–Meier (product-limit) estimate of the survival function from right-censored intervals,
// with Greenwood standard errors, for plotting and for the censored goodness-of-fit test.
// (Kaplan & Meier, J. Am. Stat. Assoc. 53, 457 (1958); Greenwood 1926; Lawless 2003, sec. 3.2.)

#include <span>
#include <vector>

namespace hopper::stats {

struct KaplanMeierCurve {
    // One entry per distinct uncensored (event) time, ascending. S is a right-continuous step
    // function: S(t) = 1 for t < time[0], S(t) = survival[j] for time[j] <= t < time[j+1].
    std::vector<double> time;  // t_j (s)
    std::vector<int> at_risk;  // n_j: intervals with t_i >= t_j (censored ties count as at risk)
    std::vector<int> events;   // d_j: uncensored intervals with t_i = t_j
    std::vector<double> survival;  // S(t_j) = prod_{l <= j} (1 - d_l / n_l)
    // Greenwood: se_j = S(t_j) sqrt( sum_{l <= j} d_l / (n_l (n_l - d_l)) ). Where S reaches 0
    // (every interval at risk ended in a jam) the formula is 0 * inf; we store 0 there, the
    // limit of the product, and the curve carries no information beyond that point.
    std::vector<double> std_err;
    double last_time = 0.0;  // largest observed interval (event or censored): S is known up to here
    int n = 0;               // intervals used
};

// Product-limit estimate. t: interval lengths (finite, >= 0); censored[i]: interval i is
// right-censored. Sizes must match; bad input throws std::invalid_argument.
KaplanMeierCurve kaplan_meier(std::span<const double> t, const std::vector<bool>& censored);

}  // namespace hopper::stats
