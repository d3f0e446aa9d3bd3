#pragma once
// Summary of a sample of per-realization values (empty times, discharge rates, ...).

#include <optional>
#include <span>
#include <string>

namespace hopper::stats {

struct SampleSummary {
    int n = 0;
    std::optional<double> mean;     // xbar = (1/n) sum x_i                       (n >= 1)
    std::optional<double> std_dev;  // s = sqrt( sum (x_i - xbar)^2 / (n - 1) )   (n >= 2)
    std::optional<double> std_err;  // s / sqrt(n), standard error of the mean    (n >= 2)
    std::string reason;             // why a field is missing; empty when all are set
};

// Mean, sample standard deviation (Bessel-corrected) and standard error of the mean.
// Two-pass (mean first, then squared deviations) for accuracy. Non-finite values throw
// std::invalid_argument: the caller must drop undefined entries (e.g. realizations that did not
// empty have no empty time) and say so.
SampleSummary summarize(std::span<const double> x);

}  // namespace hopper::stats
