#include "config/toml_input.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <variant>
#include <vector>

#include "config/key_table.hpp"
#include "hopper/core/error.hpp"

namespace hopper::config::detail {

using core::ConfigError;

std::string type_name(const toml::node& n) {
    switch (n.type()) {
        case toml::node_type::string:
            return "a string";
        case toml::node_type::integer:
            return "an integer";
        case toml::node_type::floating_point:
            return "a float";
        case toml::node_type::boolean:
            return "a boolean";
        case toml::node_type::array:
            return "an array";
        case toml::node_type::table:
            return "a table";
        case toml::node_type::date:
        case toml::node_type::time:
        case toml::node_type::date_time:
            return "a date/time";
        default:
            return "nothing";
    }
}

std::string node_text(const toml::node& n) {
    if (auto s = n.as_string()) {
        std::string t = s->get();
        if (t.size() > 40) t = t.substr(0, 40) + "...";
        return "\"" + t + "\"";
    }
    if (auto i = n.as_integer()) return std::to_string(i->get());
    if (auto f = n.as_floating_point()) return format_number(f->get());
    if (auto b = n.as_boolean()) return b->get() ? "true" : "false";
    if (auto a = n.as_array()) {
        std::string t = "[";
        for (std::size_t k = 0; k < a->size() && k < 8; ++k)
            t += (k ? ", " : "") + node_text(*a->get(k));
        return t + (a->size() > 8 ? ", ...]" : "]");
    }
    if (n.is_table()) return "{...}";
    return "(a date/time)";
}

namespace {
// An integer too large for TOML (64-bit signed) is a syntax error to toml++, which names neither
// the key nor what is allowed ("seed = 2^64"). This finds the key on the error's line (and its
// section) and says both. Empty when the error is something else.
std::optional<std::string> integer_overflow_message(std::string_view text, int line,
                                                    std::string_view description) {
    if (description.find("not representable in 64 bits") == std::string_view::npos)
        return std::nullopt;
    std::string section, key, value;
    int n = 1;
    for (std::size_t pos = 0; pos <= text.size() && n <= line; ++n) {
        const std::size_t end = std::min(text.find('\n', pos), text.size());
        std::string_view l = text.substr(pos, end - pos);
        pos = end + 1;
        const auto first = l.find_first_not_of(" \t");
        if (first == std::string_view::npos) continue;
        l.remove_prefix(first);
        if (l.front() == '[') {
            const auto close = l.find(']');
            if (close != std::string_view::npos)
                section = std::string(
                    l.substr(l.find_first_not_of('['), close - l.find_first_not_of('[')));
        } else if (n == line && l.find('=') != std::string_view::npos) {
            std::string_view k = l.substr(0, l.find('='));
            std::string_view v = l.substr(l.find('=') + 1);
            k = k.substr(0, k.find_last_not_of(" \t") + 1);
            v.remove_prefix(std::min(v.size(), v.find_first_not_of(" \t")));
            v = v.substr(0, v.find_first_of(" \t#,]}"));
            key = std::string(k);
            value = std::string(v);
        }
    }
    if (key.empty()) return std::nullopt;
    const std::string full = section.empty() ? key : section + "." + key;
    constexpr auto max_int = std::numeric_limits<std::int64_t>::max();
    if (full == "campaign.seed")
        return "campaign.seed = " + clip(value) + " is out of range: allowed [0, " +
               std::to_string(max_int) + "] (TOML integers are 64-bit signed)";
    const KeyDef* d = find_name(full);
    if (!d) d = find_name(key);
    if (d)
        return std::string(d->name) + " = " + clip(value) + " is out of range: allowed " +
               range_text(*d);
    return clip(full) + " = " + clip(value) + " is not a 64-bit integer (TOML integers are in [" +
           std::to_string(std::numeric_limits<std::int64_t>::min()) + ", " +
           std::to_string(max_int) + "])";
}
}  // namespace

toml::table parse_toml(std::string_view text, const std::string& file) {
    // toml++ rejects most garbage itself; a NUL byte is the clearest sign of a binary file.
    if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
        const auto before = text.substr(0, nul);
        const auto line = 1 + std::count(before.begin(), before.end(), '\n');
        const auto last_nl = before.rfind('\n');
        const auto col = nul - (last_nl == std::string_view::npos ? 0 : last_nl + 1) + 1;
        throw ConfigError(file + ":" + std::to_string(line) + ":" + std::to_string(col) +
                          ": not a TOML text file (contains a NUL byte)");
    }
    // toml++ recurses once per part of a dotted key and per level of nested arrays and inline
    // tables: refuse absurd depths before it sees them (a sweep file needs a handful).
    constexpr int max_depth = 64;
    int line = 1, dots = 0, depth = 0;
    bool in_key = true;  // before the first '=' of the line
    char quote = 0;
    bool comment = false;
    const bool multiline_strings =
        text.find("\"\"\"") != std::string_view::npos || text.find("'''") != std::string_view::npos;
    for (const char c : text) {
        if (c == '\n') {
            ++line;
            dots = 0;
            in_key = true;
            comment = false;
            if (!multiline_strings) quote = 0;  // single-line strings end with their line
            continue;
        }
        if (comment) continue;
        if (quote != 0) {
            if (c == quote) quote = 0;
            continue;
        }
        if (c == '#') {
            comment = true;
        } else if (c == '"' || c == '\'') {
            quote = c;
        } else if (c == '=') {
            in_key = false;
        } else if (c == '.' && in_key) {
            ++dots;
        } else if (c == '[' || c == '{') {
            ++depth;
        } else if (c == ']' || c == '}') {
            depth = std::max(0, depth - 1);
        }
        if (dots > max_depth || depth > max_depth)
            throw ConfigError(file + ":" + std::to_string(line) + ": " +
                              (dots > max_depth ? "a dotted key" : "nested arrays or tables") +
                              " deeper than " + std::to_string(max_depth) +
                              " levels; a sweep file needs a few");
    }
    try {
        return toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        const std::string at =
            file + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": ";
        if (auto msg = integer_overflow_message(text, static_cast<int>(b.line), e.description()))
            throw ConfigError(at + *msg);
        throw ConfigError(at + "TOML syntax error: " + std::string(e.description()));
    }
}

namespace {

// As parse_toml's guard: a sweep file needs a handful of levels.
constexpr int max_tree_depth = 64;

void fill_table(toml::table& t, const nlohmann::json& object, const std::string& where, int depth,
                const std::string& file);

[[noreturn]] void tree_error(const std::string& file, const std::string& msg) {
    throw ConfigError(file + ": " + msg);
}

// A TOML value of any kind (a variant, not a template: the recursion of arrays in arrays stays
// one function).
using TomlValue = std::variant<toml::table, toml::array, std::string, bool, std::int64_t, double>;

// One value of the tree as the TOML value it stands for; `where` names it in messages
// ("material.mu", "points[1].D_cm").
TomlValue convert(const nlohmann::json& v, const std::string& where, int depth,
                  const std::string& file) {
    using Type = nlohmann::json::value_t;
    if (depth > max_tree_depth)
        tree_error(file, clip(where) + ": nested deeper than " + std::to_string(max_tree_depth) +
                             " levels; a sweep file needs a few");
    switch (v.type()) {
        case Type::object: {
            toml::table t;
            fill_table(t, v, where, depth + 1, file);
            return t;
        }
        case Type::array: {
            toml::array a;
            for (std::size_t i = 0; i < v.size(); ++i)
                std::visit([&a](auto&& x) { a.push_back(std::move(x)); },
                           convert(v[i], where + "[" + std::to_string(i) + "]", depth + 1, file));
            return a;
        }
        case Type::string:
            return v.get<std::string>();
        case Type::boolean:
            return v.get<bool>();
        case Type::number_integer:
            return v.get<std::int64_t>();
        case Type::number_unsigned: {
            const auto u = v.get<std::uint64_t>();
            constexpr auto max_int = std::numeric_limits<std::int64_t>::max();
            if (u > static_cast<std::uint64_t>(max_int))
                tree_error(file, clip(where) + " = " + std::to_string(u) +
                                     " is not a 64-bit integer (TOML integers are in [" +
                                     std::to_string(std::numeric_limits<std::int64_t>::min()) +
                                     ", " + std::to_string(max_int) + "])");
            return static_cast<std::int64_t>(u);
        }
        case Type::number_float:
            return v.get<double>();
        case Type::null:
            tree_error(file, clip(where) +
                                 " has no value (None): a sweep file has none; leave the key out "
                                 "for its default");
        default:
            tree_error(file, clip(where) + ": not a value a sweep file can hold");
    }
    return false;  // not reached
}

// The members of `object` into `t`; a key with dots is a dotted key, as in a TOML text
// ("material.mu" = material = {mu = ...}).
void fill_table(toml::table& t, const nlohmann::json& object, const std::string& where, int depth,
                const std::string& file) {
    for (const auto& [key, value] : object.items()) {
        std::vector<std::string> parts;
        for (std::size_t start = 0;;) {
            const std::size_t dot = key.find('.', start);
            parts.push_back(key.substr(start, dot - start));
            if (dot == std::string::npos) break;
            start = dot + 1;
        }
        std::string path = where;
        toml::table* at = &t;
        for (std::size_t i = 0; i < parts.size(); ++i) {
            if (parts[i].empty())
                tree_error(file, "key '" + clip(key) + "'" +
                                     (where.empty() ? "" : " in " + clip(where)) +
                                     " has an empty part between its dots");
            path += (path.empty() ? "" : ".") + parts[i];
            toml::node* existing = at->get(parts[i]);
            const bool last = i + 1 == parts.size();
            if (!last || value.is_object()) {
                if (!existing) {
                    at->insert(parts[i], toml::table{});
                    existing = at->get(parts[i]);
                }
                if (!existing || !existing->is_table())
                    tree_error(file, clip(path) + " is given twice: as a value and as a table");
                at = existing->as_table();
                if (last)
                    fill_table(*at, value, path, depth + static_cast<int>(parts.size()), file);
            } else {
                if (existing) tree_error(file, clip(path) + " is given twice");
                std::visit([&](auto&& x) { at->insert(parts[i], std::move(x)); },
                           convert(value, path, depth + static_cast<int>(parts.size()), file));
            }
        }
    }
}

}  // namespace

toml::table table_from_tree(const nlohmann::json& tree, const std::string& file) {
    if (!tree.is_object())
        throw ConfigError(file +
                          ": a scene is a table of sections ({\"hopper\": {...}, ...}), got " +
                          std::string(tree.type_name()));
    toml::table root;
    fill_table(root, tree, "", 0, file);
    return root;
}

}  // namespace hopper::config::detail
