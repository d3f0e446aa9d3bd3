#pragma once
// The scene schema (issue 28): the one description of every scene parameter. One row per
// parameter: its sweep-file name, type, range and unit, how it sets engine::SceneParams and how
// it reads back (file units and SI), and its line in the physics fingerprint (the scene text a
// store hashes and compares: its name, its place, and when it enters). Everything else is
// generated from the rows: the parser's keys, labels and seeds (config), a point's typed
// `parameters`, the fingerprint text (`scene_fingerprint`, byte for byte what stores since the
// first round hold), the scene rebuilt from stored parameters, and the typed /points/parameters
// columns of a store's HDF5 view (campaign/point_columns.hpp). A new sweep key is one row here
// (and its SceneParams field); tests/campaign/test_fingerprint_rows.cpp fails for a row whose
// change does not reach the fingerprint.
//
// Defaults are not repeated here: a row's default is what it reads from `engine::SceneParams{}`
// (the published values of docs/model.md, in one place).

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hopper/core/setting.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::config {

// A value in the sweep file's terms: numbers (integers included) as doubles, choices and
// booleans as their names ("verlet", "true").
using SchemaValue = std::variant<double, std::string>;
using SchemaRead = std::optional<SchemaValue>;  // absent: an optional parameter that is unset

enum class ValueKind { real, integer, choice, boolean };

// When a row's line enters the fingerprint.
enum class Enters {
    always,          // in every scene (the rows of the first stores); an unset optional: "unset"
    unless_default,  // only off its default (or off `absent_at`): rows added in later rounds, so
                     // that a store written before them keeps its text
    when_set,        // an optional parameter, only when set
    never,           // not itself: it shows through the rows that are `only_with` it
};

struct FingerprintLine {
    std::string_view name;  // "hopper.outlet_m": the SI unit in the name; empty with Enters::never
    int position = 0;       // place of the line in the text (ascending)
    Enters enters = Enters::always;
    // The sweep name of a row that must be off its default (and itself allowed in) for this line
    // to be listed: the fields' settings need fields.enabled, the largest shake a growing shake.
    std::string_view only_with = {};
    // Enters::unless_default: the value (as text) at which the line is left out, when that is
    // not the default (integrator.contact_corrections: "false", as before issue 12).
    std::string_view absent_at = {};
};

struct SchemaRow {
    std::string_view section;  // the file's table: "hopper", "material", ...
    std::string_view key;      // the key inside it: "width_cm"
    std::string_view name;     // canonical setting name: "hopper.width_cm", "D_cm"
    ValueKind kind;
    double lo, hi;
    bool open_lo, open_hi;
    std::string_view unit;  // unit in the file ("" = dimensionless)
    void (*apply)(engine::SceneParams&, const SchemaValue&);
    // The value in file units (the inverse of apply, shortest decimal that applies back to the
    // same bits): what a scene that was not given this key has.
    SchemaRead (*read)(const engine::SceneParams&);
    FingerprintLine fingerprint;
    // The value in SI, as the fingerprint writes it; null when the file unit is SI (then `read`).
    SchemaRead (*si)(const engine::SceneParams&) = nullptr;
    std::string_view choices = {};  // ValueKind::choice: the allowed strings, comma-separated
    // False for a parameter the sweep file cannot set (gravity): in the fingerprint and the
    // typed columns, not among the keys.
    bool in_sweep_file = true;
};

// Every row: the sweep file's keys in the order of campaigns/README.md (D_cm, theta_deg, then
// by section), then the parameters a sweep file cannot set.
const std::vector<SchemaRow>& scene_schema();
// The row of a canonical name ("D_cm", "material.mu", "gravity_m_s2"); null when none.
const SchemaRow* find_row(std::string_view name);

// The row's value in SI (what the fingerprint lists) and its default (that of SceneParams{}).
SchemaRead value_in_si(const SchemaRow& row, const engine::SceneParams& p);
SchemaRead default_value(const SchemaRow& row);  // file units
// The SI unit of value_in_si: "m" for cm, "rad" for deg, "1" when dimensionless, else the file's
// unit (ratios such as "d_large" stay ratios).
std::string si_unit(const SchemaRow& row);

// Whether the row's line is in the fingerprint of `p`.
bool in_fingerprint(const SchemaRow& row, const engine::SceneParams& p);

// The physics fingerprint: one "name=value" line per row in the fingerprint, in position order;
// numbers in their shortest round-trip form (integers as integers), unset optionals "unset".
// Two scenes give the same text exactly when they give the same physics.
std::string scene_fingerprint(const engine::SceneParams& p);

// The scene of typed parameters (a point's `parameters`, sweep names and file units): the
// defaults with each applied, validated. Throws core::ConfigError for an unknown name, a value
// of the wrong type or out of range, or an invalid scene.
engine::SceneParams scene_from_parameters(const std::vector<core::Setting>& parameters);

}  // namespace hopper::config
