#include "hopper/stats/sampling.hpp"

#include <cmath>
#include <numbers>

namespace hopper::stats {

double draw_exponential(core::Rng& rng, double mean) {
    return -mean * std::log1p(-rng.uniform());  // 1 - u in (0, 1]: the log is finite
}

double draw_normal(core::Rng& rng) {
    const double r = std::sqrt(-2.0 * std::log1p(-rng.uniform()));
    return r * std::cos(2.0 * std::numbers::pi * rng.uniform());
}

}  // namespace hopper::stats
