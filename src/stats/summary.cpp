#include "hopper/stats/summary.hpp"

#include <cmath>
#include <stdexcept>

namespace hopper::stats {

SampleSummary summarize(std::span<const double> x) {
    SampleSummary s;
    s.n = static_cast<int>(x.size());
    for (double v : x)
        if (!std::isfinite(v)) throw std::invalid_argument("summarize: non-finite value");
    if (s.n == 0) {
        s.reason = "no values";
        return s;
    }
    double sum = 0.0;
    for (double v : x)
        sum += v;
    const double mean = sum / s.n;
    s.mean = mean;
    if (s.n < 2) {
        s.reason = "one value: no standard deviation";
        return s;
    }
    double ss = 0.0;
    for (double v : x)
        ss += (v - mean) * (v - mean);
    const double sd = std::sqrt(ss / (s.n - 1));
    s.std_dev = sd;
    s.std_err = sd / std::sqrt(static_cast<double>(s.n));
    return s;
}

}  // namespace hopper::stats
