#pragma once
// The config layer's private TOML front end (not installed): the text -> toml++ table step with
// its guards (NUL bytes, absurd nesting, 64-bit overflow named by key), the same table from a
// tree of values (the Python module's dict scene), and how a TOML node is described in messages.
// The only header that includes toml++.

#include <toml++/toml.h>
#include <nlohmann/json_fwd.hpp>

#include <string>
#include <string_view>

namespace hopper::config::detail {

// Parses `text` (named `file` in messages). Throws core::ConfigError "file:line:col: ...".
toml::table parse_toml(std::string_view text, const std::string& file);

// The table a TOML text with the same keys and values would give (sweep.hpp, parse_sweep_tree).
// Throws core::ConfigError "file: key: ..." for what TOML cannot hold.
toml::table table_from_tree(const nlohmann::json& tree, const std::string& file);

// "a string", "an integer", ... for "expected X, got Y" messages.
std::string type_name(const toml::node& n);
// The node's value as the file wrote it, shortened ("\"abc\"", "2.7", "[1, 2]").
std::string node_text(const toml::node& n);

}  // namespace hopper::config::detail
