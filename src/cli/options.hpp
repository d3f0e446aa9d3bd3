#pragma once
// Checked conversions of command-line values. Each throws core::ConfigError with a message that
// names the option and the offending text, e.g. "--seed must be a non-negative integer, got '-1'".

#include <cstdint>
#include <string_view>

namespace hopper::cli {

// A non-negative decimal integer that fits in 64 bits ("42"; not "-1", "1.5", "abc", "").
std::uint64_t parse_seed(std::string_view option, std::string_view text);

// A seed as `parse_seed` takes it, or as the store's `seed_str` writes it: 's' and its digits
// ("s17273..."; the text R and spreadsheets keep exact), so either can be pasted into --seed.
std::uint64_t parse_seed_text(std::string_view option, std::string_view text);

// A finite decimal number ("3", "-2.5", "1e-3", "+4"; not "nan", "inf", "3cm", "").
double parse_finite(std::string_view option, std::string_view text);

}  // namespace hopper::cli
