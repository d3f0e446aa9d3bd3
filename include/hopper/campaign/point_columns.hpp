#pragma once
// The typed /points/parameters columns of a store's HDF5 view (issue 28; docs/store.md), from
// the scene schema: one dataset per row (named by its fingerprint name, the value in SI, the
// `units` attribute its SI unit, `sweep_name` and `sweep_unit` the sweep file's), one value per
// point, from the point's scene (campaign::point_scenes: its typed parameters, or for a store
// older than them its recorded sweep texts). `typed` says for each point whether its values are
// there (FALSE: no record explains its scene text; then numbers are 0 and texts empty); an
// optional parameter (unset by default: material.collision_time_s, ...) has a flag `has_NAME`
// beside it (unset: 0), as the store writes no NaN.
// store::Store and store::write_snapshot call it (store::PointParameters): the store does not
// know the scene's parameters.

#include <vector>

#include "hopper/store/analysis.hpp"
#include "hopper/store/records.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {

std::vector<store::DerivedDataset> point_parameter_columns(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs);

}  // namespace hopper::campaign
