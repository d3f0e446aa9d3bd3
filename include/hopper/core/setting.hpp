#pragma once
// One named, typed setting of a campaign point, under the sweep file's own name ("D_cm",
// "theta_deg", "material.mu", "hopper.density_kg_m3", "integrator.scheme") and in the sweep
// file's units (cm, degrees, SI otherwise). Numbers are doubles (integers included), choices are
// their names. The config layer makes them (its key table is the one list of names); the store
// keeps them; analysis reads them. No layer parses them back out of labels or scene texts.

#include <string>
#include <variant>

namespace hopper::core {

struct Setting {
    std::string name;
    std::variant<double, std::string> value;
    bool operator==(const Setting&) const = default;
};

}  // namespace hopper::core
