// Sweep-file cases: a shipped sweep file (campaigns/*.toml, campaigns/paper/*.toml) mutated by
// one of the kinds below, then loaded with config::load_sweep. The outcome must be a
// core::ConfigError whose message is non-empty, bounded and names the file (and so the line and
// key, which the config layer puts after it), or a successful parse whose every point validates,
// whose derived constants are finite, whose task list and store plan can be made, and whose first
// scene can be built (engine::build_scene, and engine::Realization when small).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fuzz.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/scene.hpp"
#include "hopper/store/records.hpp"

namespace hopper::fuzz {

namespace {

// --------------------------------------------------------------------------------------------
// A line model of a TOML file: enough for the shipped sweep files (one key = value per line,
// values are scalars, one-line arrays or one-line inline tables, '#' comments).

using Lines = std::vector<std::string>;

Lines split_lines(const std::string& text) {
    Lines out;
    std::string cur;
    for (char c : text) {
        if (c == '\n') {
            out.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) out.push_back(cur);
    return out;
}

std::string join_lines(const Lines& lines) {
    std::string s;
    for (const auto& l : lines)
        s += l + "\n";
    return s;
}

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string::npos) return "";
    const auto e = s.find_last_not_of(" \t");
    return s.substr(b, e - b + 1);
}

bool is_header(const std::string& line) {
    const std::string t = trim(line);
    return !t.empty() && t[0] == '[';
}

// Position of the first '=' or '#' (whichever `c` is) outside quotes, or npos.
std::size_t find_outside_quotes(const std::string& s, char c, std::size_t from = 0) {
    char quote = 0;
    for (std::size_t i = from; i < s.size(); ++i) {
        if (quote) {
            if (s[i] == '\\' && quote == '"') {
                ++i;
                continue;
            }
            if (s[i] == quote) quote = 0;
            continue;
        }
        if (s[i] == '"' || s[i] == '\'') {
            quote = s[i];
            continue;
        }
        if (s[i] == c) return i;
    }
    return std::string::npos;
}

struct Span {
    std::size_t line, begin, end;  // [begin, end) within the line
};

// The value span of an assignment line ("key = value # comment"), if it is one.
std::optional<Span> value_span(const Lines& lines, std::size_t i) {
    const std::string& s = lines[i];
    if (is_header(s)) return std::nullopt;
    const std::size_t hash = find_outside_quotes(s, '#');
    const std::size_t eq = find_outside_quotes(s, '=');
    if (eq == std::string::npos || (hash != std::string::npos && hash < eq)) return std::nullopt;
    std::size_t b = eq + 1;
    while (b < s.size() && (s[b] == ' ' || s[b] == '\t'))
        ++b;
    std::size_t e = hash == std::string::npos ? s.size() : hash;
    while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t'))
        --e;
    if (e <= b) return std::nullopt;
    return Span{i, b, e};
}

// The element spans of a one-line array or inline table value (values only, one level deep).
std::vector<Span> element_spans(const Lines& lines, const Span& v) {
    std::vector<Span> out;
    const std::string& s = lines[v.line];
    if (v.end - v.begin < 2) return out;
    const char open = s[v.begin];
    if (open != '[' && open != '{') return out;
    std::size_t i = v.begin + 1;
    const std::size_t stop = v.end - 1;  // the closing bracket
    while (i < stop) {
        // One element: up to the next top-level ','.
        int depth = 0;
        char quote = 0;
        std::size_t j = i;
        for (; j < stop; ++j) {
            const char c = s[j];
            if (quote) {
                if (c == quote) quote = 0;
                continue;
            }
            if (c == '"' || c == '\'') quote = c;
            if (c == '[' || c == '{') ++depth;
            if (c == ']' || c == '}') --depth;
            if (c == ',' && depth == 0) break;
        }
        std::size_t b = i, e = j;
        if (open == '{') {  // "key = value": the value
            const std::size_t eq = s.find('=', b);
            if (eq != std::string::npos && eq < e) b = eq + 1;
        }
        while (b < e && (s[b] == ' ' || s[b] == '\t'))
            ++b;
        while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t'))
            --e;
        if (e > b) out.push_back(Span{v.line, b, e});
        i = j + 1;
    }
    return out;
}

std::vector<std::size_t> assignment_lines(const Lines& lines) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < lines.size(); ++i)
        if (value_span(lines, i)) out.push_back(i);
    return out;
}

// Every value span: whole values and their elements.
std::vector<Span> all_spans(const Lines& lines) {
    std::vector<Span> out;
    for (std::size_t i : assignment_lines(lines)) {
        const Span v = *value_span(lines, i);
        out.push_back(v);
        for (const Span& e : element_spans(lines, v))
            out.push_back(e);
    }
    return out;
}

std::string key_of(const Lines& lines, std::size_t i) {
    const std::size_t eq = find_outside_quotes(lines[i], '=');
    return eq == std::string::npos ? "" : trim(lines[i].substr(0, eq));
}

// The header line of the section that holds line i ("" at the top level).
std::string section_of(const Lines& lines, std::size_t i) {
    for (std::size_t k = i + 1; k-- > 0;)
        if (is_header(lines[k]))
            return trim(lines[k].substr(0, find_outside_quotes(lines[k], '#')));
    return "";
}

struct Section {
    std::size_t header;  // line index of the header
    std::size_t end;     // one past its last line
};

std::vector<Section> sections(const Lines& lines) {
    std::vector<Section> out;
    for (std::size_t i = 0; i < lines.size(); ++i)
        if (is_header(lines[i])) {
            if (!out.empty()) out.back().end = i;
            out.push_back(Section{i, lines.size()});
        }
    return out;
}

std::string replace_span(Lines& lines, const Span& s, const std::string& text) {
    std::string& l = lines[s.line];
    const std::string old = l.substr(s.begin, s.end - s.begin);
    l = l.substr(0, s.begin) + text + l.substr(s.end);
    return old;
}

std::string shown(const std::string& s, std::size_t max = 60) {
    return one_line(
        s.size() > max ? s.substr(0, max) + "...(" + std::to_string(s.size()) + " B)" : s,
        max + 40);
}

// --------------------------------------------------------------------------------------------
// Value pools.

const std::vector<std::string> type_values = {"\"text\"",
                                              "'literal'",
                                              "42",
                                              "4.5",
                                              "true",
                                              "false",
                                              "[1, 2]",
                                              "[]",
                                              "{ a = 1 }",
                                              "{}",
                                              "\"\"",
                                              "\"4.5\"",
                                              "[[1], [2]]",
                                              "[{ x = 1 }]",
                                              "1979-05-27T07:32:00Z",
                                              "07:32:00",
                                              "1979-05-27",
                                              "\"\"\"multi\nline\"\"\"",
                                              "[\"gear4\"]",
                                              "\"verlet\"",
                                              "\"gear4\"",
                                              "{ mu = 0.5 }",
                                              "0x10",
                                              "1e3",
                                              "-7"};

const std::vector<std::string> edge_numbers = {"nan",
                                               "+nan",
                                               "-nan",
                                               "inf",
                                               "+inf",
                                               "-inf",
                                               "-0",
                                               "-0.0",
                                               "+0",
                                               "0",
                                               "0.0",
                                               "0e0",
                                               "1e308",
                                               "1.7976931348623157e308",
                                               "-1.7976931348623157e308",
                                               "4.9e-324",
                                               "5e-324",
                                               "2.2250738585072014e-308",
                                               "1e-300",
                                               "1e-30",
                                               "1e-12",
                                               "-1",
                                               "-1.0",
                                               "-1e300",
                                               "9223372036854775807",
                                               "-9223372036854775808",
                                               "9223372036854775808",
                                               "2147483647",
                                               "2147483648",
                                               "-2147483649",
                                               "4294967296",
                                               "4294967297",
                                               "10000000",
                                               "10000001",
                                               "1e7",
                                               "1e400",
                                               "-1e400",
                                               "99999999999999999999",
                                               "0x7FFFFFFF",
                                               "0xFFFFFFFFFFFFFFFF",
                                               "0o777",
                                               "0b101",
                                               "1_000",
                                               "1__0",
                                               "01",
                                               "1.",
                                               ".5",
                                               "1e",
                                               "1e-7",
                                               "0.1",
                                               "1e5",
                                               "100000",
                                               "100001",
                                               "1e13",
                                               "1.0000001e13",
                                               "90",
                                               "90.0000001",
                                               "89.99999999999",
                                               "180",
                                               "180.0000001",
                                               "-180",
                                               "-180.0000001",
                                               "1000",
                                               "0.5",
                                               "0.5000001",
                                               "1",
                                               "1.0000001",
                                               "0.9999999",
                                               "2",
                                               "1e4",
                                               "10000.0000001",
                                               "100",
                                               "100.0000001",
                                               "0.1",
                                               "0.0999999",
                                               "-0.9999999",
                                               "-1.0000001",
                                               "1000000",
                                               "1000001",
                                               "1e6",
                                               "3.0",
                                               "12.0",
                                               "2e-7"};

// The number in a span scaled (a value of the same kind near or far from the original).
std::optional<std::string> scaled(const std::string& text, Gen& g) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end || !std::isfinite(v)) return std::nullopt;
    static const std::vector<double> factors = {
        -1.0, 0.0,  1e-12, 1e-6,    0.5,    1.0 + 1e-15, 2.0, 10.0,
        1e6,  1e12, 1e300, -1e-300, 1e-300, 1.0 - 1e-16, 3.0, 1e-308};
    const double f = g.pick(factors);
    const double r = v * f;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", r);
    std::string s = buf;
    if (!std::isfinite(r)) s = r > 0 ? "inf" : r < 0 ? "-inf" : "nan";
    // Keep it a float when the original was one.
    if (text.find_first_of(".eE") != std::string::npos &&
        s.find_first_of(".eEn") == std::string::npos)
        s += ".0";
    return s;
}

const std::vector<std::string> unknown_keys = {"foo",
                                               "width",
                                               "D",
                                               "d",
                                               "particle",
                                               "mu2",
                                               "hopper",
                                               "campaign",
                                               "sweep",
                                               "points",
                                               "\"quoted key\"",
                                               "'lit key'",
                                               "a.b",
                                               "material.mu",
                                               "Width_cm",
                                               "width_CM",
                                               "D_CM",
                                               "theta",
                                               "realisations",
                                               "seeds",
                                               "name2",
                                               "\"\"",
                                               "e-n",
                                               "_",
                                               "x-y_z",
                                               "123",
                                               "true",
                                               "scheme",
                                               "skin",
                                               "store",
                                               "seed"};

const std::vector<std::string> unknown_sections = {
    "[bogus]\nx = 1",
    "[hopper.extra]\ny = 2",
    "[[hopper]]\nwidth_cm = 20.0",
    "[campaign.sub]",
    "[[sweep]]\nD_cm = [3.0]",
    "[points]\nD_cm = 3.0",
    "[sweep.material]\nmu = [0.5]",
    "[\"quoted\"]\nk = 1",
    "[ hopper ]\nparticles = 100",
    "[Hopper]\nwidth_cm = 20.0",
    "[protocol]\n",
    "[walls]\nspacing = 1.0",
    "[integrator]\nscheme = \"euler\"",
    "[material]\nmu = 0.5",
    "[campaign]\nname = \"dup\"",
    "[[points]]",
    "[[points]]\nD_cm = 3.0",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = 2",
    "[[points.material]]\nmu = 0.5",
    "[sweep]\nD_cm = [3.0]",
    "[a.b.c]\nd = 1",
    "top = 1",
    "points = []",
    "points = 3",
    "sweep = [1]",
    "campaign = \"x\"",
    "hopper = 1",
    "[[campaign]]\nname = \"x\""};

// --------------------------------------------------------------------------------------------
// Mutations. Each edits the text and returns a description; "" means it did not apply (the
// caller falls back to another kind).

using Mutation = std::function<std::string(std::string& text, Gen& g)>;

std::string mutate_value(std::string& text, Gen& g, const std::vector<std::string>& pool,
                         bool allow_scaled) {
    Lines lines = split_lines(text);
    const auto spans = all_spans(lines);
    if (spans.empty()) return "";
    const Span s = g.pick(spans);
    std::string value = g.pick(pool);
    if (allow_scaled && g.chance(0.3)) {
        const std::string old = lines[s.line].substr(s.begin, s.end - s.begin);
        if (auto v = scaled(old, g)) value = *v;
    }
    const std::string key = key_of(lines, s.line);
    const std::string old = replace_span(lines, s, value);
    text = join_lines(lines);
    return section_of(lines, s.line) + " " + key + ": " + shown(old) + " -> " + shown(value);
}

std::string type_change(std::string& text, Gen& g) {
    return mutate_value(text, g, type_values, false);
}

std::string number_edge(std::string& text, Gen& g) {
    return mutate_value(text, g, edge_numbers, true);
}

std::string remove_line(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    auto a = assignment_lines(lines);
    if (a.empty()) return "";
    // Prefer the keys a campaign needs.
    std::vector<std::size_t> required;
    for (std::size_t i : a) {
        const std::string k = key_of(lines, i);
        if (k == "name" || k == "D_cm" || k == "theta_deg") required.push_back(i);
    }
    const std::size_t i = !required.empty() && g.chance(0.5) ? g.pick(required) : g.pick(a);
    const std::string desc = "removed " + section_of(lines, i) + " " + shown(trim(lines[i]));
    lines.erase(lines.begin() + static_cast<long>(i));
    text = join_lines(lines);
    return desc;
}

std::string remove_section(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    auto secs = sections(lines);
    if (secs.empty()) return "";
    const Section s = g.pick(secs);
    const std::string desc = "removed section " + trim(lines[s.header]) + " (" +
                             std::to_string(s.end - s.header) + " lines)";
    const bool keep_body = g.chance(0.25);  // only the header: its keys move to the previous one
    lines.erase(lines.begin() + static_cast<long>(s.header),
                lines.begin() + static_cast<long>(keep_body ? s.header + 1 : s.end));
    text = join_lines(lines);
    return desc + (keep_body ? ", header only" : "");
}

std::string unknown_key(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    auto a = assignment_lines(lines);
    if (!a.empty() && g.chance(0.35)) {
        // Misspell an existing key.
        const std::size_t i = g.pick(a);
        std::string& l = lines[i];
        const std::size_t eq = find_outside_quotes(l, '=');
        std::string key = trim(l.substr(0, eq));
        if (key.empty()) return "";
        const std::size_t at = g.below(key.size());
        const std::string old = key;
        switch (g.below(3)) {
            case 0:
                key[at] = static_cast<char>('a' + g.below(26));
                break;
            case 1:
                key.erase(at, 1);
                break;
            default:
                key.insert(at, 1, static_cast<char>('a' + g.below(26)));
        }
        if (key.empty()) key = "k";
        l = key + " " + l.substr(eq);
        text = join_lines(lines);
        return "misspelt key " + section_of(lines, i) + " " + old + " -> " + key;
    }
    const std::string key = g.pick(unknown_keys);
    const std::string value = g.pick(type_values);
    const std::size_t at = g.below(lines.size() + 1);
    lines.insert(lines.begin() + static_cast<long>(at), key + " = " + value);
    const std::string desc = "added '" + key + " = " + shown(value) + "' at line " +
                             std::to_string(at + 1) + " in " + section_of(lines, at);
    text = join_lines(lines);
    return desc;
}

std::string unknown_section(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    const std::string add = g.pick(unknown_sections);
    auto secs = sections(lines);
    std::size_t at = lines.size();
    if (!secs.empty() && g.chance(0.6)) at = g.pick(secs).header;  // before a section
    if (g.chance(0.15)) at = 0;
    lines.insert(lines.begin() + static_cast<long>(at), add);
    text = join_lines(lines);
    return "inserted '" + one_line(add) + "' at line " + std::to_string(at + 1);
}

std::string duplicate(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    auto secs = sections(lines);
    const auto a = assignment_lines(lines);
    const int what = static_cast<int>(g.below(3));
    if (what == 0 && !a.empty()) {
        const std::size_t i = g.pick(a);
        const std::string line = lines[i];
        // Same key again: right after, or with another value.
        std::string copy = line;
        if (g.chance(0.5))
            if (auto v = value_span(lines, i))
                copy = line.substr(0, v->begin) + g.pick(edge_numbers) + line.substr(v->end);
        const std::size_t at = std::min(i + 1 + g.below(2), lines.size());
        lines.insert(lines.begin() + static_cast<long>(at), copy);
        text = join_lines(lines);
        return "duplicated key " + section_of(lines, i) + " " + shown(trim(line));
    }
    if (secs.empty()) return "";
    const Section s = g.pick(secs);
    Lines block(lines.begin() + static_cast<long>(s.header),
                lines.begin() + static_cast<long>(s.end));
    const std::size_t at = what == 1 ? lines.size() : s.end;
    lines.insert(lines.begin() + static_cast<long>(at), block.begin(), block.end());
    text = join_lines(lines);
    return "duplicated section " + trim(lines[s.header]) + " (" + std::to_string(block.size()) +
           " lines)" + (what == 1 ? " at the end" : "");
}

std::string truncate(std::string& text, Gen& g) {
    if (text.empty()) return "";
    const std::size_t at = g.below(text.size());
    text.resize(at);
    return "truncated at byte " + std::to_string(at);
}

std::string flip_bytes(std::string& text, Gen& g) {
    if (text.empty()) return "";
    const int n = static_cast<int>(g.range(1, 8));
    std::string desc;
    const bool bits = g.chance(0.5);
    for (int k = 0; k < n; ++k) {
        const std::size_t at = g.below(text.size());
        if (bits)
            text[at] = static_cast<char>(text[at] ^ (1 << g.below(8)));
        else
            text[at] = static_cast<char>(g.below(256));
        if (!desc.empty()) desc += ',';
        desc += std::to_string(at);
    }
    return std::string(bits ? "flipped a bit" : "set a random byte") + " at " + desc;
}

std::string binary(std::string& text, Gen& g) {
    const std::size_t n = g.skewed(16384);
    std::string s(n, '\0');
    const bool no_nul = g.chance(0.5);
    for (auto& c : s) {
        c = static_cast<char>(g.below(256));
        if (no_nul && c == 0) c = 1;
    }
    if (g.chance(0.3)) s = text.substr(0, g.below(text.size() + 1)) + s;  // valid start
    text = s;
    return std::to_string(n) + " random bytes" + (no_nul ? " (no NUL)" : "");
}

std::string empty(std::string& text, Gen& g) {
    static const std::vector<std::string> v = {
        "",
        "\n",
        "   \t  ",
        "# only a comment\n",
        "\xEF\xBB\xBF",
        "\r\n\r\n",
        "\n\n\n\n",
        "[campaign]\n",
        "[hopper]\n",
        "[campaign]\nname = \"x\"\n",
        "[sweep]\n",
        "[[points]]\n",
        "\xEF\xBB\xBF[campaign]\nname = \"bom\"\n[hopper]\nD_cm = 3.0\ntheta_deg = 60\n"};
    text = g.pick(v);
    return "replaced by " + shown(text);
}

std::string long_string(std::string& text, Gen& g) {
    static const std::vector<std::size_t> lengths = {300, 5000, 100000, 1000000};
    const std::size_t n = g.pick(lengths);
    const std::string big(n, static_cast<char>('a' + g.below(26)));
    Lines lines = split_lines(text);
    const int what = static_cast<int>(g.below(9));
    std::string desc;
    switch (what) {
        case 0:
            lines.push_back("[campaign]");
            lines.push_back("name = \"" + big + "\"");
            desc = "campaign name of " + std::to_string(n) + " chars";
            break;
        case 1:
            lines.insert(lines.begin(), "[hopper]\n" + big + " = 1");
            desc = "unknown key of " + std::to_string(n) + " chars";
            break;
        case 2:
            lines.push_back("[integrator]\nscheme = \"" + big + "\"");
            desc = "scheme of " + std::to_string(n) + " chars";
            break;
        case 3:
            lines.insert(lines.begin(), "# " + big);
            desc = "comment of " + std::to_string(n) + " chars";
            break;
        case 4:
            lines.insert(lines.begin(), "[hopper]\nwidth_cm = 1" + std::string(n, '0') + ".0");
            desc = "number of " + std::to_string(n) + " digits";
            break;
        case 5: {
            // A long sweep list (many points) or a list of many identical values.
            const std::size_t m = std::min<std::size_t>(n, 3000);
            std::string list = "[";
            const bool same = g.chance(0.5);
            for (std::size_t i = 0; i < m; ++i)
                list += (i ? ", " : "") + std::to_string(same ? 3.0 : 1.0 + 0.001 * i);
            lines.push_back("[sweep]\nD_cm = " + list + "]");
            desc = "sweep D_cm list of " + std::to_string(m) + (same ? " equal" : "") + " values";
            break;
        }
        case 6: {
            const std::size_t m = std::min<std::size_t>(n / 10, 5000);
            for (std::size_t i = 0; i < m; ++i)
                lines.push_back("[[points]]\nD_cm = " + std::to_string(1.0 + 1e-4 * i) +
                                "\ntheta_deg = 60");
            desc = std::to_string(m) + " [[points]]";
            break;
        }
        case 7:
            lines.push_back("[campaign]\nstore = \"" + big + "\"");
            desc = "store path of " + std::to_string(n) + " chars";
            break;
        default:
            lines.insert(lines.begin(), "[" + big + "]");
            desc = "section name of " + std::to_string(n) + " chars";
    }
    text = join_lines(lines);
    return desc;
}

std::string deep_nesting(std::string& text, Gen& g) {
    static const std::vector<std::size_t> depths = {20, 300, 3000, 30000, 300000};
    const std::size_t d = g.pick(depths);
    std::string add;
    const int what = static_cast<int>(g.below(6));
    std::string desc;
    switch (what) {
        case 0:
            add = "x = " + std::string(d, '[') + "1" + std::string(d, ']');
            desc = "array nested " + std::to_string(d) + " deep";
            break;
        case 1: {
            std::string open, close(d, '}');
            for (std::size_t i = 0; i < d; ++i)
                open += "{a=";
            add = "x = " + open + "1" + close;
            desc = "inline table nested " + std::to_string(d) + " deep";
            break;
        }
        case 2: {
            std::string k = "a";
            for (std::size_t i = 1; i < d; ++i)
                k += ".a";
            add = k + " = 1";
            desc = "dotted key " + std::to_string(d) + " deep";
            break;
        }
        case 3: {
            std::string k = "a";
            for (std::size_t i = 1; i < d; ++i)
                k += ".a";
            add = "[" + k + "]\nx = 1";
            desc = "table header " + std::to_string(d) + " deep";
            break;
        }
        case 4:
            add = "[sweep]\nD_cm = " + std::string(d, '[');  // unclosed
            desc = "unclosed array " + std::to_string(d) + " deep";
            break;
        default: {
            std::string k = "material";
            for (std::size_t i = 1; i < d; ++i)
                k += ".mu";
            add = "[campaign]\nname = \"deep\"\n[sweep]\n" + k + " = [0.5]";
            desc = "sweep key " + std::to_string(d) + " deep";
        }
    }
    Lines lines = split_lines(text);
    const std::size_t at = g.chance(0.5) ? 0 : lines.size();
    lines.insert(lines.begin() + static_cast<long>(at), add);
    text = join_lines(lines);
    return desc + (at == 0 ? " at the top" : " at the end");
}

const std::vector<std::string> sweep_lists = {"[]",
                                              "[\"a\", 1]",
                                              "[3.0, 3.0]",
                                              "[3, 3.0]",
                                              "[-0.0, 0.0]",
                                              "[[1]]",
                                              "[1, [2]]",
                                              "3.0",
                                              "\"[3.0]\"",
                                              "[nan]",
                                              "[inf]",
                                              "[1e308]",
                                              "[-1]",
                                              "[0]",
                                              "[true]",
                                              "[{ a = 1 }]",
                                              "[3.0, \"4.5\"]",
                                              "[1e-300]",
                                              "[3.0,]",
                                              "[ ]",
                                              "[3.0 4.0]",
                                              "[\"gear4\", \"verlet\"]",
                                              "[\"gear4\", \"gear4\"]",
                                              "[\"euler\"]",
                                              "[1979-05-27]"};

const std::vector<std::string> sweep_keys = {"D_cm",
                                             "theta_deg",
                                             "material.mu",
                                             "integrator.scheme",
                                             "hopper.particles",
                                             "protocol.empty_threshold",
                                             "walls.spacing",
                                             "hopper.width_cm",
                                             "material.e_n",
                                             "protocol.max_shakes",
                                             "hopper.D_cm",
                                             "material.bogus",
                                             "bogus.mu",
                                             "campaign.seed",
                                             "hopper",
                                             "material",
                                             "\"D_cm\"",
                                             "integrator.steps_per_collision",
                                             "protocol.t_check_s",
                                             "material.collision_time_s",
                                             "hopper.d_large_cm",
                                             "hopper.d_small_cm"};

std::string sweep_array(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    // The [sweep] section, made when missing (with a campaign so that it is allowed).
    std::size_t sweep_at = lines.size();
    for (std::size_t i = 0; i < lines.size(); ++i)
        if (trim(lines[i].substr(0, find_outside_quotes(lines[i], '#'))) == "[sweep]") sweep_at = i;
    std::string desc;
    if (sweep_at == lines.size()) {
        bool has_campaign = false;
        for (const auto& l : lines)
            if (trim(l) == "[campaign]") has_campaign = true;
        if (!has_campaign && g.chance(0.8)) lines.push_back("[campaign]\nname = \"fuzz\"");
        lines.push_back("[sweep]");
        sweep_at = lines.size() - 1;
        desc = "new [sweep]; ";
    }
    // Existing arrays in [sweep]: replace one; or add an axis.
    std::vector<std::size_t> axes;
    for (std::size_t i = sweep_at + 1; i < lines.size() && !is_header(lines[i]); ++i)
        if (value_span(lines, i)) axes.push_back(i);
    const std::string list = g.pick(sweep_lists);
    if (!axes.empty() && g.chance(0.6)) {
        const std::size_t i = g.pick(axes);
        const Span v = *value_span(lines, i);
        const std::string key = key_of(lines, i);
        const std::string old = replace_span(lines, v, list);
        desc += "[sweep] " + key + ": " + shown(old) + " -> " + list;
    } else {
        const std::string key = g.pick(sweep_keys);
        lines.insert(lines.begin() + static_cast<long>(sweep_at + 1), key + " = " + list);
        desc += "[sweep] added " + key + " = " + list;
    }
    text = join_lines(lines);
    return desc;
}

const std::vector<std::string> point_blocks = {
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = 0",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = -1",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = 1000000",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = 1000001",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = \"3\"",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nrealizations = 3.5",
    "[[points]]\nD_cm = 3.0",
    "[[points]]\ntheta_deg = 60",
    "[[points]]",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nbogus = { a = 1 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nhopper = { D_cm = 3 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nmaterial = 0.5",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nmaterial = { mu = \"high\" }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nmaterial = { nu = 0.3 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nmaterial = { mu = 0.5, mu = 0.6 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nintegrator = { scheme = \"verlet\" }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nprotocol = { max_shakes = 100001 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nhopper = { particles = 1 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nhopper = { width_cm = 1e-300 }",
    "[[points]]\nD_cm = 1e4\ntheta_deg = 90",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 0\nwalls = { spacing = 1.7 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\n[[points]]\nD_cm = 3.0\ntheta_deg = 60",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60\nprotocol = { empty_threshold = 10000000 }",
    "[[points]]\nD_cm = 3.0\ntheta_deg = 60.0\n[[points]]\nD_cm = 3\ntheta_deg = 60",
    "[[points]]\nD_cm = -0.0\ntheta_deg = -0.0",
    "[[points]]\nD_cm = 5e-324\ntheta_deg = 0",
    "points = [ { D_cm = 3.0, theta_deg = 60 } ]",
    "points = [ 1, 2 ]",
    "points = []"};

std::string points(std::string& text, Gen& g) {
    Lines lines = split_lines(text);
    bool has_campaign = false;
    for (const auto& l : lines)
        if (trim(l) == "[campaign]") has_campaign = true;
    if (!has_campaign && g.chance(0.8)) lines.push_back("[campaign]\nname = \"fuzz\"");
    const std::string block = g.pick(point_blocks);
    lines.push_back(block);
    text = join_lines(lines);
    return "appended " + one_line(block);
}

std::string encoding(std::string& text, Gen& g) {
    const int what = static_cast<int>(g.below(9));
    switch (what) {
        case 0: {  // CRLF line ends
            std::string s;
            for (char c : text)
                s += c == '\n' ? std::string("\r\n") : std::string(1, c);
            text = s;
            return "CRLF line ends";
        }
        case 1:
            text = "\xEF\xBB\xBF" + text;
            return "UTF-8 byte order mark";
        case 2:
            text = "\xFF\xFE" + text;
            return "UTF-16 byte order mark";
        case 3: {  // invalid UTF-8 in a string or comment
            const std::size_t q = text.find('"');
            const std::size_t at = q == std::string::npos ? 0 : q + 1;
            text.insert(at, g.chance(0.5) ? "\xC3\x28" : "\xED\xA0\x80");
            return "invalid UTF-8 at byte " + std::to_string(at);
        }
        case 4: {
            const std::size_t at = g.below(text.size() + 1);
            text.insert(at, 1, '\0');
            return "NUL byte at " + std::to_string(at);
        }
        case 5:
            text += "[campaign]\nname = \"a\\u0000b\"\n";
            return "\\u0000 escape in the campaign name";
        case 6: {
            const std::size_t at = g.below(text.size() + 1);
            text.insert(at, 1, static_cast<char>(1 + g.below(31)));
            return "control character at " + std::to_string(at);
        }
        case 7:
            text += "[hopper]\n\"w\xC3\xA9idth_cm\" = 20.0\n";
            return "non-ASCII key";
        default: {
            std::string s;
            for (char c : text)
                s += c == ' ' ? '\t' : c;
            text = s;
            return "tabs for spaces";
        }
    }
}

const std::vector<std::string> cross_key = {
    "[hopper]\nd_small_cm = 0.9\nd_large_cm = 0.8",
    "[hopper]\nparticles = 5\n[protocol]\nempty_threshold = 5",
    "[protocol]\njam_region_height = 4.0\nexit_depth = 4.0",
    "[hopper]\nwidth_cm = 3.0\nD_cm = 3.0",
    "[hopper]\nwidth_cm = 1.5",
    "[walls]\nspacing = 1.8",
    "[walls]\nparticle_diameter_cm = 1e-300",
    "[hopper]\nparticles = 10000000\n[campaign]\nname = \"big\"\nrealizations = 1000000",
    "[campaign]\nname = \"many\"\nrealizations = 1000000\n[sweep]\nD_cm = [3.0, 3.1, 3.2, "
    "3.3, 3.4, 3.5, 3.6, 3.7, 3.8, 3.9, 4.0]",
    "[material]\ncollision_time_s = 1e-300",
    "[material]\ncollision_time_s = 5e-324",
    "[material]\nyoungs_modulus_pa = 1e-300",
    "[material]\nyoungs_modulus_pa = 5e-324\npoisson_ratio = 0.5",
    "[material]\npoisson_ratio = -0.9999999999999999",
    "[hopper]\nd_small_cm = 1e-300\nd_large_cm = 1e-300",
    "[hopper]\nd_small_cm = 5e-324",
    "[hopper]\nd_small_cm = 1e-6\nd_large_cm = 1e-6",
    "[hopper]\nthickness_cm = 1e-300",
    "[hopper]\ndensity_kg_m3 = 1e-300",
    "[hopper]\nd_small_cm = 100\nd_large_cm = 100\nwidth_cm = 10000\nthickness_cm = 100\n"
    "density_kg_m3 = 100000",
    "[material]\ne_n = 5e-324",
    "[material]\ne_n = 1e-300",
    "[walls]\ne_n = 1e-300",
    "[integrator]\nsteps_per_collision = 100000\n[material]\ncollision_time_s = 1e-12",
    "[integrator]\nskin = 1e-300",
    "[protocol]\ndetector_interval_s = 1e-300",
    "[protocol]\nsample_interval_s = 1e-300",
    "[protocol]\nshake_period_s = 1e-300",
    "[protocol]\nsettle_ke = 1e-300",
    "[protocol]\nt_check_s = 1e-300",
    "[protocol]\nmax_time_s = 1e-300",
    "[hopper]\ntheta_deg = 90\nD_cm = 1e-300",
    "[hopper]\ntheta_deg = 0\nD_cm = 9999.999",
    "[hopper]\nsmall_fraction = 0\n",
    "[hopper]\nsmall_fraction = 1\n",
    "[hopper]\nparticles = 1\n",
    "[campaign]\nname = \"s\"\nseed = 9223372036854775807\n",
    "[campaign]\nname = \"s\"\nseed = -1\n",
    "[campaign]\nname = \".hidden\"\n",
    "[campaign]\nname = \"a/b\"\n",
    "[campaign]\nname = \"ok\"\nstore = \"/\"\n",
    "[campaign]\nname = \"ok\"\nstore = \"\"\n",
    "[campaign]\nname = \"ok\"\nstore = \"/dev/null\"\n"};

std::string semantic(std::string& text, Gen& g) {
    // Replace the sections that the snippet sets (so that the keys are not duplicates).
    const std::string snippet = g.pick(cross_key);
    Lines lines = split_lines(text);
    Lines add = split_lines(snippet);
    std::string current;
    for (const auto& a : add) {
        if (is_header(a)) {
            current = trim(a);
            continue;
        }
        const std::string k = key_of(add, static_cast<std::size_t>(&a - &add[0]));
        // Drop the same key from the same section of the file.
        for (std::size_t i = 0; i < lines.size();) {
            if (value_span(lines, i) && key_of(lines, i) == k && section_of(lines, i) == current) {
                lines.erase(lines.begin() + static_cast<long>(i));
                continue;
            }
            ++i;
        }
    }
    // Merge: each snippet key goes under its section (created when missing).
    current.clear();
    for (const auto& a : add) {
        if (is_header(a)) {
            current = trim(a);
            continue;
        }
        std::size_t at = lines.size();
        bool found = false;
        for (std::size_t i = 0; i < lines.size(); ++i)
            if (trim(lines[i].substr(0, find_outside_quotes(lines[i], '#'))) == current) {
                at = i + 1;
                found = true;
                break;
            }
        if (!found) {
            lines.push_back(current);
            at = lines.size();
        }
        lines.insert(lines.begin() + static_cast<long>(at), a);
    }
    text = join_lines(lines);
    return "set " + one_line(snippet);
}

struct Kind {
    const char* name;
    Mutation apply;
};

const std::vector<Kind>& kinds() {
    static const std::vector<Kind> k = {
        {"type_change", type_change},
        {"number_edge", number_edge},
        {"remove_key", remove_line},
        {"remove_section", remove_section},
        {"unknown_key", unknown_key},
        {"unknown_section", unknown_section},
        {"duplicate", duplicate},
        {"truncate", truncate},
        {"flip_bytes", flip_bytes},
        {"binary", binary},
        {"empty", empty},
        {"long_string", long_string},
        {"deep_nesting", deep_nesting},
        {"sweep_array", sweep_array},
        {"points", points},
        {"encoding", encoding},
        {"cross_key", semantic},
        {"combination",
         [](std::string& text, Gen& g) {
             static const std::vector<Mutation> parts = {type_change, number_edge, remove_line,
                                                         unknown_key, sweep_array, semantic,
                                                         duplicate};
             std::string desc;
             const int n = static_cast<int>(g.range(2, 4));
             for (int i = 0; i < n; ++i) {
                 const std::string d = g.pick(parts)(text, g);
                 if (!d.empty()) desc += (desc.empty() ? "" : "; ") + d;
             }
             return desc;
         }},
        {"unchanged", [](std::string&, Gen&) { return std::string("the shipped file as is"); }},
    };
    return k;
}

// --------------------------------------------------------------------------------------------
// Checks of a successful parse.

void check_derived(const engine::SceneParams& p, const std::string& where, Outcome& out) {
    const engine::DerivedConstants c = engine::derive_constants(p);
    const std::pair<const char*, double> positive[] = {
        {"m_small", c.m_small}, {"m_large", c.m_large}, {"I_small", c.I_small},
        {"I_large", c.I_large}, {"tau_c", c.tau_c},     {"k_n", c.k_n},
        {"dt", c.dt},           {"t_check", c.t_check}};
    for (const auto& [name, v] : positive)
        if (!std::isfinite(v) || !(v > 0.0)) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%.6g", v);
            out.mark_bad("derived constant " + std::string(name) + " = " + buf + " (" + where +
                         ")");
            return;
        }
    const std::pair<const char*, double> finite[] = {{"hertz_time", c.hertz_time},
                                                     {"k_t", c.k_t},
                                                     {"gamma_n_system", c.gamma_n_system},
                                                     {"gamma_n_wall", c.gamma_n_wall}};
    for (const auto& [name, v] : finite)
        if (!std::isfinite(v) || v < 0.0) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%.6g", v);
            out.mark_bad("derived constant " + std::string(name) + " = " + buf + " (" + where +
                         ")");
            return;
        }
}

// Whether building the scene of `p` is cheap enough for the harness (a few hundred thousand
// particles and walls at most): a rough upper estimate of the fill rows and the wall length.
bool scene_is_cheap(const engine::SceneParams& p, std::string& why) {
    const auto& s = p.particles;
    const auto& h = p.hopper;
    const double a = s.d_large * (1.0 + p.protocol.fill_gap);
    const double narrowest = std::max(std::min(h.outlet, h.width), a);
    const double fill_height = static_cast<double>(s.count) * a * a / narrowest + h.width;
    const double walls = 2.0 * (fill_height + h.width) / (h.wall_spacing * h.wall_diameter);
    const double rows = fill_height / a;
    if (!(walls < 2e9) || !(rows < 2e9)) {
        // engine::build_scene counts wall particles and rows in an int.
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "wall particle or lattice row count overflows an int (about %.3g walls, "
                      "%.3g rows)",
                      walls, rows);
        why = buf;
        return false;
    }
    if (s.count > 20000 || !(walls < 2e5) || !(rows < 2e5)) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "%d particles, about %.3g wall particles and %.3g rows",
                      s.count, walls, rows);
        why = buf;
        return false;
    }
    return true;
}

void check_scene(const engine::SceneParams& p, std::uint64_t seed, const std::string& where,
                 Outcome& out) {
    std::string why;
    if (!scene_is_cheap(p, why)) {
        if (why.find("overflows") != std::string::npos)
            out.mark_bad("accepted a scene whose " + why + " (" + where + ")");
        else
            out.note("scene", "not built (too large for the harness: " + why + ")");
        return;
    }
    try {
        announce_operation("scene");
        core::Rng rng(seed);
        const engine::SceneLayout layout = engine::build_scene(p, rng);
        for (const auto& f : layout.fill)
            if (!std::isfinite(f.pos.x()) || !std::isfinite(f.pos.y()) ||
                !std::isfinite(f.vel.x()) || !std::isfinite(f.vel.y())) {
                out.mark_bad("build_scene made a non-finite particle (" + where + ")");
                return;
            }
        for (const auto& w : layout.walls)
            if (!std::isfinite(w.pos.x()) || !std::isfinite(w.pos.y())) {
                out.mark_bad("build_scene made a non-finite wall particle (" + where + ")");
                return;
            }
        if (static_cast<int>(layout.fill.size()) != p.particles.count) {
            out.mark_bad("build_scene placed " + std::to_string(layout.fill.size()) + " of " +
                         std::to_string(p.particles.count) + " particles (" + where + ")");
            return;
        }
        if (p.particles.count <= 10000) {
            engine::Realization r(p, seed);
            out.note("scene", "built: " + std::to_string(layout.fill.size()) + " particles, " +
                                  std::to_string(layout.walls.size()) +
                                  " walls; realization constructed");
        } else {
            out.note("scene", "built: " + std::to_string(layout.fill.size()) + " particles, " +
                                  std::to_string(layout.walls.size()) + " walls");
        }
    } catch (const core::ConfigError& e) {
        // The engine refuses a scene the config layer accepted: a clear error, but reported.
        if (std::string(e.what()).empty())
            out.mark_bad("the engine's ConfigError has an empty message (" + where + ")");
        else
            out.clean("scene (" + where + ")", e.what());
    }
}

void check_parsed(const config::SweepFile& sf, Outcome& out) {
    check_derived(sf.base, "base scene", out);
    engine::validate_scene(sf.base);
    // The scene `campaign simulate` would run.
    const engine::SceneParams at =
        config::scene_at(sf, sf.base.hopper.outlet / core::cm, sf.base.hopper.theta / core::deg);
    check_derived(at, "scene_at", out);
    if (!sf.has_campaign) {
        check_scene(at, 1, "base scene", out);
        out.note("parse", "scene only");
        return;
    }
    const config::CampaignSpec& spec = sf.campaign;
    long long total = 0;
    for (const auto& pt : spec.points) {
        if (pt.label.empty()) out.mark_bad("a point has an empty label");
        if (pt.realizations < 1) out.mark_bad("point '" + pt.label + "' has no realizations");
        engine::validate_scene(pt.scene);
        check_derived(pt.scene, "point '" + pt.label + "'", out);
        const double cost = campaign::expected_cost(pt.scene);
        if (!std::isfinite(cost) || cost < 0.0)
            out.mark_bad("expected_cost of point '" + pt.label + "' is " + std::to_string(cost));
        total += pt.realizations;
        if (out.category == Category::bad) return;
    }
    if (spec.points.empty()) {
        out.mark_bad("a campaign without points was accepted");
        return;
    }
    // The task list and the store's plan, as `campaign run` makes them; for huge campaigns only
    // on a copy with the first point and a few realizations (the rest is the same code).
    config::CampaignSpec small = spec;
    if (total > 200000) {
        small.points.resize(1);
        small.points[0].realizations = std::min(small.points[0].realizations, 1000);
        out.note("tasks", std::to_string(total) + " tasks: expanded for the first point only");
    }
    long long small_total = 0;
    for (const auto& pt : small.points)
        small_total += pt.realizations;
    const auto tasks = config::expand_tasks(small);
    if (static_cast<long long>(tasks.size()) != small_total)
        out.mark_bad("expand_tasks made " + std::to_string(tasks.size()) + " tasks, expected " +
                     std::to_string(small_total));
    for (std::size_t i = 0; i < tasks.size(); ++i)
        if (tasks[i].task_id != static_cast<int>(i)) {
            out.mark_bad("task ids are not 0..n-1");
            break;
        }
    const store::CampaignPlan plan = campaign::make_plan(small);
    (void)campaign::check_compatible(plan, plan);  // a plan agrees with itself
    if (plan.points.size() != small.points.size())
        out.mark_bad("make_plan made " + std::to_string(plan.points.size()) + " points");
    const config::Task& first = tasks.front();
    check_scene(small.points[static_cast<std::size_t>(first.point_index)].scene, first.seed,
                "point '" + small.points[static_cast<std::size_t>(first.point_index)].label + "'",
                out);
    out.note("parse",
             std::to_string(spec.points.size()) + " points, " + std::to_string(total) + " tasks");
}

std::vector<fs::path> shipped_files(const fs::path& campaigns) {
    std::vector<fs::path> files;
    for (const fs::path& dir : {campaigns, campaigns / "paper"}) {
        if (!fs::is_directory(dir)) continue;
        for (const auto& e : fs::directory_iterator(dir))
            if (e.is_regular_file() && e.path().extension() == ".toml") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    if (files.empty())
        throw std::runtime_error("fuzz_inputs: no sweep files in " + campaigns.string());
    return files;
}

}  // namespace

void sweep_case(const Context& ctx, std::uint64_t id, Outcome& out) {
    Gen g(core::mix_seed(ctx.seed, id));
    const auto files = shipped_files(ctx.campaigns);
    const fs::path base = g.pick(files);
    std::string text = read_file(base);
    const auto& all = kinds();
    announce_operation("mutate");
    std::size_t k = g.below(all.size());
    std::string desc = all[k].apply(text, g);
    for (int tries = 0; desc.empty() && tries < 5; ++tries) {  // the kind did not apply
        k = g.below(all.size());
        desc = all[k].apply(text, g);
    }
    out.kind = all[k].name;
    out.description =
        base.parent_path().filename().string() + "/" + base.filename().string() + ": " + desc;
    out.announce();

    const fs::path dir = ctx.workdir / ("case-" + std::to_string(id));
    fs::create_directories(dir);
    const fs::path file = dir / ("sweep-" + std::to_string(id) + ".toml");
    write_file(file, text);

    config::SweepFile sf;
    try {
        announce_operation("load_sweep");
        sf = config::load_sweep(file);
    } catch (const core::ConfigError& e) {
        const std::string msg = e.what();
        if (msg.empty())
            out.mark_bad("ConfigError with an empty message");
        else if (msg.find(file.string()) == std::string::npos)
            out.mark_bad("ConfigError does not name the file: " + one_line(msg, 300));
        else if (msg.size() > 2000)
            out.mark_bad("ConfigError message of " + std::to_string(msg.size()) +
                         " chars (echoes the input unbounded): " + one_line(msg, 200));
        out.clean("load_sweep", msg);
        return;
    } catch (const std::exception& e) {
        out.mark_bad(std::string("unexpected exception type from the config layer: ") + e.what());
        return;
    }
    if (sf.text != text) out.mark_bad("the sweep's text differs from the file's bytes");
    // Whatever the layers below throw for a file the config layer accepted is a gap.
    try {
        announce_operation("checks");
        check_parsed(sf, out);
    } catch (const std::exception& e) {
        out.mark_bad(std::string("a parsed sweep file fails later: ") + e.what());
    }
}

}  // namespace hopper::fuzz
