#pragma once
// Checks of a scene's orders of magnitude before a campaign starts (docs/model.md, "Checked
// before a run"): values in the wrong unit pass every range check (D_cm = 0.025 is a valid
// number of centimetres) but make every realization jam at t = 0, or fail while settling. Each
// estimate is a bound that a sensible scene is far from, so no working scene is refused.

#include <string>

#include "hopper/engine/params.hpp"

namespace hopper::config {

// The densest random packing of a 2-D bidisperse disk mixture; the fill height below uses it,
// so it is a lower bound of the settled height.
inline constexpr double dense_packing_fraction = 0.85;
// A packing taller than this many hopper widths is refused: a tube, not a hopper (most likely a
// slip in width_cm or particles).
inline constexpr double max_fill_widths = 20.0;

// Height of the settled packing above the outlet plane (m): the particles' area over the
// packing fraction, filled into the container from the outlet up.
double settled_fill_height(const engine::SceneParams& p);

// Overlap (m) of the contacts under the bottom disk of the settled packing at rest: the weight
// of a column of large disks, min(fill height, W/2) high (Janssen: wall friction carries the
// rest; W/2 bounds the depth for an effective wall friction up to 1), shared by two contacts,
// over k_n.
double settled_overlap(const engine::SceneParams& p);

// The first of these problems, as a message naming the key, the value and what would work;
// empty when there is none:
//   the outlet's free gap is narrower than one small disk (no particle can leave),
//   the settled packing is taller than max_fill_widths hopper widths,
//   the settled packing alone overlaps by more than protocol.max_overlap (the collision time
//   is too long: every realization fails while settling).
std::string scene_problem(const engine::SceneParams& p);

}  // namespace hopper::config
