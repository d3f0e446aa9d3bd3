#pragma once
// The JSON of `campaign analyze --json` (and the /analysis group's `json` attribute), through
// nlohmann::ordered_json: keys in the order written. Numbers in their shortest round-trip form,
// integral values without a fraction (as before the library: "3", not "3.0"). A value that
// cannot be computed is null with a `<key>_reason` beside it.

#include <nlohmann/json.hpp>
#include <string>

#include "hopper/analysis/analyze.hpp"

namespace hopper::analysis {

using Json = nlohmann::ordered_json;

// A double as JSON: an integer when its shortest text is one ("3", "-2"), else the double.
// Throws std::logic_error for a non-finite value (never written).
Json json_number(double v);

// The same, but null for a non-finite value (JSON has no NaN or infinity): for reports of one
// realization (`campaign simulate --json`), where a NaN diagnostic is shown, not fatal.
Json json_number_or_null(double v);

// The summary of merged fields as JSON members: kernel, kernel_width_m (Gaussian only), cell_m,
// x0_m, y0_m, nx, ny, samples, total_windows, t_first, t_last, cells_with_data,
// max_mean_speed, max_mean_pressure.
void add_fields_summary(Json& j, const engine::FieldMoments& m);

// The JSON object of `campaign analyze --json`, as text (2-space indent).
std::string analysis_json(const Analysis& a, const std::string& store, const std::string& name);

}  // namespace hopper::analysis
