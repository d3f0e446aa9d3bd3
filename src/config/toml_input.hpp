#pragma once
// The config layer's private TOML front end (not installed): the text -> toml++ table step with
// its guards (NUL bytes, absurd nesting, 64-bit overflow named by key), and how a TOML node is
// described in messages. The only header that includes toml++.

#include <toml++/toml.h>

#include <string>
#include <string_view>

namespace hopper::config::detail {

// Parses `text` (named `file` in messages). Throws core::ConfigError "file:line:col: ...".
toml::table parse_toml(std::string_view text, const std::string& file);

// "a string", "an integer", ... for "expected X, got Y" messages.
std::string type_name(const toml::node& n);
// The node's value as the file wrote it, shortened ("\"abc\"", "2.7", "[1, 2]").
std::string node_text(const toml::node& n);

}  // namespace hopper::config::detail
