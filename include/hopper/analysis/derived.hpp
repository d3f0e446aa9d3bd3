#pragma once
// The /analysis group of a store (written by store::write_derived_group): one row per point
// (/analysis/points), the Kaplan–Meier curves (/analysis/km), the fits per group
// (/analysis/beverloo, /analysis/jam_rate, /analysis/avalanche) and each point's merged fields
// as maps (/analysis/fields/<label>). Optional values are 0 plus a has_<name> flag.

#include <string>

#include "hopper/analysis/analyze.hpp"
#include "hopper/store/analysis.hpp"

namespace hopper::analysis {

// `json` is kept as the group's attribute of that name (analysis_json's text).
store::DerivedGroup analysis_group(const Analysis& a, const std::string& json);

}  // namespace hopper::analysis
