#pragma once
// Shared by the campaign run's files (private to the campaign layer): run.cpp and dry_run.cpp.

#include <filesystem>

#include "hopper/config/sweep.hpp"

namespace hopper::campaign::detail {

// The sweep file at `sweep`, which must have a [campaign] section (core::ConfigError otherwise).
config::SweepFile load_campaign_sweep(const std::filesystem::path& sweep);

}  // namespace hopper::campaign::detail
