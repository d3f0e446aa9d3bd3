#pragma once
// Random variates drawn from hopper::core::Rng, for the parametric bootstraps of this layer and
// for synthetic data in tests. Our own transforms (not <random>'s distributions, whose
// algorithms are implementation-defined) so that bootstrap p-values are identical everywhere.

#include "hopper/core/random.hpp"

namespace hopper::stats {

// Exponential variate with the given mean by inversion: x = -mean ln(1 - u), u ~ U[0, 1).
double draw_exponential(core::Rng& rng, double mean);

// Standard normal variate by the Box–Muller transform (one of the pair is used):
//   z = sqrt(-2 ln(1 - u1)) cos(2 pi u2).
double draw_normal(core::Rng& rng);

}  // namespace hopper::stats
