#pragma once
// The config layer's private pieces (not installed): the key table -- the rows of the scene
// schema (hopper/config/scene_schema.hpp) that a sweep file may set, under their one canonical
// name -- and the text helpers the parser's messages share. The table is the single list of setting
// names: labels, seeds, `parameter_names()` and the typed `parameters` of a point (core::Setting)
// all come from it.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hopper/config/scene_schema.hpp"
#include "hopper/core/setting.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::config::detail {

// The rows are the scene schema's (hopper/config/scene_schema.hpp); these names are the parser's.
using Value = SchemaValue;
using Read = SchemaRead;
using Kind = ValueKind;
using KeyDef = SchemaRow;

// The rows a sweep file may set (every row of scene_schema() but those not in the file), in the
// order of campaigns/README.md: D_cm, theta_deg, then by section.
const std::vector<KeyDef>& key_table();

inline constexpr std::array<std::string_view, 6> scene_sections = {
    "hopper", "material", "walls", "integrator", "protocol", "fields"};

bool is_scene_section(std::string_view s);
const KeyDef* find_key(std::string_view section, std::string_view key);
const KeyDef* find_name(std::string_view name);
// The row a quoted key such as "material.mu" names (TOML reads it as one key with a dot in it,
// not as mu inside material; users mean the latter), or nullptr when it names none.
const KeyDef* quoted_dotted_key(std::string_view name);
std::vector<std::string> keys_of(std::string_view section);

// Canonical order of settings: D_cm, theta_deg, then by name.
bool canonical_less(std::string_view a, std::string_view b);

// "[0, 90] deg", "(0, 1]".
std::string range_text(const KeyDef& d);
// Empty when v is allowed for d, else the reason. `shown` is the value as the file wrote it
// (default: v formatted).
std::optional<std::string> range_error(const KeyDef& d, double v, const std::string& shown = "");

// Shortest text that reads back as the same double (std::to_chars): labels and seeds use it.
std::string format_number(double v);
// Text for messages: integral values without an exponent ("10000000", not "1e+07").
std::string message_number(double v);
// Text of a derived (converted-back) quantity for messages, e.g. 0.027 m / cm -> "2.7".
std::string approx_number(double v);
// A setting's value as labels show it.
std::string value_text(const Value& v);

std::string join(const std::vector<std::string>& items, std::string_view sep = ", ");
// A name from the file, shortened for messages (a 1 MB key must not make a 1 MB message).
std::string clip(std::string_view name, std::size_t limit = 64);
// A close match among the options, for "did you mean" hints ("" when none is close).
std::string suggestion(std::string_view word, const std::vector<std::string>& options);

}  // namespace hopper::config::detail
