#include "hopper/config/sweep.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <system_error>

#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/core/units.hpp"

namespace hopper::config {

namespace {

using core::ConfigError;
using engine::SceneParams;
using Value = std::variant<double, std::string>;
namespace fs = std::filesystem;

// Limits that keep a campaign's task list (ints, held in memory on every rank) sane.
constexpr double max_realizations = 1e6;
constexpr std::size_t max_points = 100'000;
constexpr long long max_tasks = 10'000'000;

// ---------------------------------------------------------------------------------------------
// Number text

// Shortest text that reads back as the same double (std::to_chars): labels and seeds use it.
std::string format_number(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// Text for messages: integral values without an exponent ("10000000", not "1e+07").
std::string message_number(double v) {
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15) {
        return std::to_string(static_cast<long long>(v));
    }
    return format_number(v);
}

// Text of a derived (converted-back) quantity for messages, e.g. 0.027 m / cm -> "2.7".
std::string approx_number(double v) {
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

std::string value_text(const Value& v) {
    return std::holds_alternative<double>(v) ? format_number(std::get<double>(v))
                                             : std::get<std::string>(v);
}

double num(const Value& v) {
    return std::get<double>(v);
}

// The option of a choice key whose engine name (to_string) the file gave. The parser has checked
// the string against the key's list already, so the fallback is never taken.
template <class E>
E choice_of(const Value& v, std::initializer_list<E> options) {
    for (const E e : options)
        if (engine::to_string(e) == std::get<std::string>(v)) return e;
    return *options.begin();
}

// ---------------------------------------------------------------------------------------------
// The key table: every scene parameter a sweep file may set, its type, range (in file units)
// and how it lands in SceneParams (SI). This is the single place that maps file keys to fields;
// the defaults stay in engine/params.hpp.

enum class Kind { real, integer, choice, boolean };

struct KeyDef {
    std::string_view section;  // the file's table: "hopper", "material", ...
    std::string_view key;      // the key inside it: "width_cm"
    std::string_view name;     // canonical setting name: "hopper.width_cm", "D_cm"
    Kind kind;
    double lo, hi;
    bool open_lo, open_hi;
    std::string_view unit;  // unit in the file, for messages ("" = dimensionless)
    void (*apply)(SceneParams&, const Value&);
    std::string_view choices = {};  // Kind::choice: the allowed strings, comma-separated
};

using core::cm;
using core::deg;
using P = SceneParams;
using V = const Value&;

constexpr bool open = true;
constexpr bool closed = false;

// clang-format off
const std::array key_table = {
    // [hopper]: geometry and particles
    KeyDef{"hopper", "D_cm", "D_cm", Kind::real, 0, 1e4, open, closed, "cm",
           [](P& p, V v) { p.hopper.outlet = num(v) * cm; }},
    KeyDef{"hopper", "theta_deg", "theta_deg", Kind::real, 0, 90, closed, closed, "deg",
           [](P& p, V v) { p.hopper.theta = num(v) * deg; }},
    KeyDef{"hopper", "width_cm", "hopper.width_cm", Kind::real, 0, 1e4, open, closed, "cm",
           [](P& p, V v) { p.hopper.width = num(v) * cm; }},
    KeyDef{"hopper", "particles", "hopper.particles", Kind::integer, 1, 1e7, closed, closed, "",
           [](P& p, V v) { p.particles.count = static_cast<int>(num(v)); }},
    KeyDef{"hopper", "small_fraction", "hopper.small_fraction", Kind::real, 0, 1, closed, closed, "",
           [](P& p, V v) { p.particles.small_fraction = num(v); }},
    KeyDef{"hopper", "d_small_cm", "hopper.d_small_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.d_small = num(v) * cm; }},
    KeyDef{"hopper", "d_large_cm", "hopper.d_large_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.d_large = num(v) * cm; }},
    KeyDef{"hopper", "thickness_cm", "hopper.thickness_cm", Kind::real, 0, 100, open, closed, "cm",
           [](P& p, V v) { p.particles.thickness = num(v) * cm; }},
    KeyDef{"hopper", "density_kg_m3", "hopper.density_kg_m3", Kind::real, 0, 1e5, open, closed, "kg/m^3",
           [](P& p, V v) { p.particles.density = num(v); }},
    KeyDef{"hopper", "outlet_measure", "hopper.outlet_measure", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using M = engine::OutletMeasure;
               p.hopper.outlet_measure = choice_of(v, {M::surface_gap, M::centre_gap, M::inner_envelope});
           }, "surface_gap,centre_gap,inner_envelope"},
    // [material]: particle-particle contacts and stiffness
    KeyDef{"material", "e_n", "material.e_n", Kind::real, 0, 1, open, closed, "",
           [](P& p, V v) { p.material.system.e_n = num(v); }},
    KeyDef{"material", "mu", "material.mu", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.system.mu = num(v); }},
    KeyDef{"material", "kt_over_kn", "material.kt_over_kn", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.kt_over_kn = num(v); }},
    KeyDef{"material", "youngs_modulus_pa", "material.youngs_modulus_pa", Kind::real, 1, 1e13, closed, closed, "Pa",
           [](P& p, V v) { p.material.youngs_modulus = num(v); }},
    KeyDef{"material", "poisson_ratio", "material.poisson_ratio", Kind::real, -1, 0.5, open, closed, "",
           [](P& p, V v) { p.material.poisson_ratio = num(v); }},
    KeyDef{"material", "collision_time_s", "material.collision_time_s", Kind::real, 1e-9, 1, closed, closed, "s",
           [](P& p, V v) { p.material.collision_time = num(v); }},
    KeyDef{"material", "gamma_t_over_gamma_n", "material.gamma_t_over_gamma_n", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.gamma_t_over_gamma_n = num(v); }},
    KeyDef{"material", "slip_rule", "material.slip_rule", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using R = engine::SlipRule;
               p.material.slip_rule = choice_of(v, {R::spring_and_dashpot, R::spring_only});
           }, "spring_and_dashpot,spring_only"},
    KeyDef{"material", "lever_arm", "material.lever_arm", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.material.lever_arm = choice_of(v, {engine::LeverArm::radius, engine::LeverArm::contact});
           }, "radius,contact"},
    KeyDef{"material", "normal_damping", "material.normal_damping", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using N = engine::NormalDamping;
               p.material.normal_damping = choice_of(v, {N::nominal, N::exact_restitution});
           }, "nominal,exact_restitution"},
    // [walls]: particle-wall contacts and wall roughness
    KeyDef{"walls", "e_n", "walls.e_n", Kind::real, 0, 1, open, closed, "",
           [](P& p, V v) { p.material.wall.e_n = num(v); }},
    KeyDef{"walls", "mu", "walls.mu", Kind::real, 0, 10, closed, closed, "",
           [](P& p, V v) { p.material.wall.mu = num(v); }},
    KeyDef{"walls", "particle_diameter_cm", "walls.particle_diameter_cm", Kind::real, 0.01, 100, closed, closed, "cm",
           [](P& p, V v) { p.hopper.wall_diameter = num(v) * cm; }},
    KeyDef{"walls", "spacing", "walls.spacing", Kind::real, 0.1, 100, closed, closed, "wall diameters",
           [](P& p, V v) { p.hopper.wall_spacing = num(v); }},
    KeyDef{"walls", "edge_diameter_cm", "walls.edge_diameter_cm", Kind::real, 0.01, 100, closed, closed, "cm",
           [](P& p, V v) { p.hopper.edge_diameter = num(v) * cm; }},
    KeyDef{"walls", "edge_offset", "walls.edge_offset", Kind::real, 0, 10, closed, closed, "wall diameters",
           [](P& p, V v) { p.hopper.edge_offset = num(v); }},
    // [integrator]
    KeyDef{"integrator", "scheme", "integrator.scheme", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.integrator.scheme = std::get<std::string>(v) == "verlet" ? engine::Scheme::verlet
                                                                         : engine::Scheme::gear4;
           }, "gear4,verlet"},
    KeyDef{"integrator", "steps_per_collision", "integrator.steps_per_collision", Kind::real, 2, 1e5, closed, closed, "",
           [](P& p, V v) { p.integrator.steps_per_collision = num(v); }},
    KeyDef{"integrator", "contact_corrections", "integrator.contact_corrections", Kind::boolean, 0, 0, closed, closed, "",
           [](P& p, V v) { p.integrator.contact_corrections = std::get<std::string>(v) == "true"; }},
    KeyDef{"integrator", "skin", "integrator.skin", Kind::real, 0, 10, open, closed, "d_small",
           [](P& p, V v) { p.integrator.skin = num(v); }},
    // [protocol]: fill, settle, jam detection, shaking, limits, sampling, guards
    KeyDef{"protocol", "fill_gap", "protocol.fill_gap", Kind::real, 0, 10, closed, closed, "d_large",
           [](P& p, V v) { p.protocol.fill_gap = num(v); }},
    KeyDef{"protocol", "fill_speed_m_s", "protocol.fill_speed_m_s", Kind::real, 0, 10, closed, closed, "m/s",
           [](P& p, V v) { p.protocol.fill_speed = num(v); }},
    KeyDef{"protocol", "fill_base", "protocol.fill_base", Kind::real, 0, 1000, closed, closed, "d_large",
           [](P& p, V v) { p.protocol.fill_base = num(v); }},
    KeyDef{"protocol", "settle_ke", "protocol.settle_ke", Kind::real, 0, 1, open, closed, "m_large g d_large",
           [](P& p, V v) { p.protocol.settle_ke = num(v); }},
    KeyDef{"protocol", "settle_hold_s", "protocol.settle_hold_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.settle_hold = num(v); }},
    KeyDef{"protocol", "settle_max_time_s", "protocol.settle_max_time_s", Kind::real, 0, 1e5, open, closed, "s",
           [](P& p, V v) { p.protocol.settle_max_time = num(v); }},
    KeyDef{"protocol", "jam_region_height", "protocol.jam_region_height", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.jam_region_height = num(v); }},
    KeyDef{"protocol", "t_check_s", "protocol.t_check_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.t_check = num(v); }},
    KeyDef{"protocol", "detector_interval_s", "protocol.detector_interval_s", Kind::real, 0, 1, open, closed, "s",
           [](P& p, V v) { p.protocol.detector_interval = num(v); }},
    KeyDef{"protocol", "shake_amplitude", "protocol.shake_amplitude", Kind::real, 0, 100, open, closed, "d_large",
           [](P& p, V v) { p.protocol.shake_amplitude = num(v); }},
    KeyDef{"protocol", "shake_period_s", "protocol.shake_period_s", Kind::real, 0, 100, open, closed, "s",
           [](P& p, V v) { p.protocol.shake_period = num(v); }},
    KeyDef{"protocol", "shake_direction_deg", "protocol.shake_direction_deg", Kind::real, -180, 180, closed, closed, "deg",
           [](P& p, V v) { p.protocol.shake_direction = num(v) * deg; }},
    KeyDef{"protocol", "max_shakes", "protocol.max_shakes", Kind::integer, 0, 1e5, closed, closed, "",
           [](P& p, V v) { p.protocol.max_shakes = static_cast<int>(num(v)); }},
    KeyDef{"protocol", "max_time_s", "protocol.max_time_s", Kind::real, 0, 1e7, open, closed, "s",
           [](P& p, V v) { p.protocol.max_time = num(v); }},
    KeyDef{"protocol", "exit_depth", "protocol.exit_depth", Kind::real, 0, 1000, open, closed, "d_large",
           [](P& p, V v) { p.protocol.exit_depth = num(v); }},
    KeyDef{"protocol", "empty_threshold", "protocol.empty_threshold", Kind::integer, 0, 1e7, closed, closed, "",
           [](P& p, V v) { p.protocol.empty_threshold = static_cast<int>(num(v)); }},
    KeyDef{"protocol", "sample_interval_s", "protocol.sample_interval_s", Kind::real, 0, 1e3, open, closed, "s",
           [](P& p, V v) { p.protocol.sample_interval = num(v); }},
    KeyDef{"protocol", "max_overlap", "protocol.max_overlap", Kind::real, 0, 1, open, closed, "d_small",
           [](P& p, V v) { p.protocol.max_overlap = num(v); }},
    KeyDef{"protocol", "mode", "protocol.mode", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               using M = engine::ProtocolMode;
               p.protocol.mode = choice_of(v, {M::published, M::steady_state});
           }, "published,steady_state"},
    KeyDef{"protocol", "jams_per_realization", "protocol.jams_per_realization", Kind::integer, 0, 1e7, closed, closed, "",
           [](P& p, V v) { p.protocol.jams_per_realization = static_cast<int>(num(v)); }},
    // [fields]: coarse-grained velocity and pressure fields of the discharge (off by default)
    KeyDef{"fields", "enabled", "fields.enabled", Kind::boolean, 0, 0, closed, closed, "",
           [](P& p, V v) { p.fields.enabled = std::get<std::string>(v) == "true"; }},
    KeyDef{"fields", "window_s", "fields.window_s", Kind::real, 0, 1e4, open, closed, "s",
           [](P& p, V v) { p.fields.window = num(v); }},
    KeyDef{"fields", "cell_dlarge", "fields.cell_dlarge", Kind::real, 0.25, 1000, closed, closed, "d_large",
           [](P& p, V v) { p.fields.cell = num(v); }},
    KeyDef{"fields", "sample_interval_s", "fields.sample_interval_s", Kind::real, 0, 1e4, closed, closed, "s",
           [](P& p, V v) { p.fields.sample_interval = num(v); }},
    KeyDef{"fields", "start_s", "fields.start_s", Kind::real, 0, 1e6, closed, closed, "s",
           [](P& p, V v) { p.fields.start = num(v); }},
    KeyDef{"fields", "end_s", "fields.end_s", Kind::real, 0, 1e6, open, closed, "s",
           [](P& p, V v) { p.fields.end = num(v); }},
    KeyDef{"fields", "kernel", "fields.kernel", Kind::choice, 0, 0, closed, closed, "",
           [](P& p, V v) {
               p.fields.kernel = std::get<std::string>(v) == "gaussian" ? engine::FieldKernel::gaussian
                                                                       : engine::FieldKernel::cell;
           }, "cell,gaussian"},
    KeyDef{"fields", "kernel_width_dlarge", "fields.kernel_width_dlarge", Kind::real, 0.05, 100, closed, closed, "d_large",
           [](P& p, V v) { p.fields.kernel_width = num(v); }},
};
// clang-format on

constexpr std::array<std::string_view, 6> scene_sections = {"hopper",     "material", "walls",
                                                            "integrator", "protocol", "fields"};
constexpr std::array<std::string_view, 8> campaign_keys = {"name",
                                                           "store",
                                                           "seed",
                                                           "realizations",
                                                           "target",
                                                           "target_rel_ci",
                                                           "max_realizations",
                                                           "round_realizations"};

bool is_scene_section(std::string_view s) {
    return std::find(scene_sections.begin(), scene_sections.end(), s) != scene_sections.end();
}

const KeyDef* find_key(std::string_view section, std::string_view key) {
    for (const auto& d : key_table)
        if (d.section == section && d.key == key) return &d;
    return nullptr;
}

const KeyDef* find_name(std::string_view name) {
    for (const auto& d : key_table)
        if (d.name == name) return &d;
    return nullptr;
}

std::vector<std::string> keys_of(std::string_view section) {
    std::vector<std::string> out;
    for (const auto& d : key_table)
        if (d.section == section) out.emplace_back(d.key);
    return out;
}

std::string join(const std::vector<std::string>& items, std::string_view sep = ", ") {
    std::string out;
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (i) out += sep;
        out += items[i];
    }
    return out;
}

// Canonical order of settings: D_cm, theta_deg, then by name.
bool canonical_less(std::string_view a, std::string_view b) {
    auto rank = [](std::string_view n) { return n == "D_cm" ? 0 : n == "theta_deg" ? 1 : 2; };
    const int ra = rank(a), rb = rank(b);
    return ra != rb ? ra < rb : a < b;
}

std::string range_text(const KeyDef& d) {
    std::string s = std::string(d.open_lo ? "(" : "[") + message_number(d.lo) + ", " +
                    message_number(d.hi) + (d.open_hi ? ")" : "]");
    if (!d.unit.empty()) s += " " + std::string(d.unit);
    return s;
}

// Empty when v is allowed for d, else the reason.
// `shown` is the value as the file wrote it (default: v formatted).
std::optional<std::string> range_error(const KeyDef& d, double v, const std::string& shown = "") {
    const bool ok = std::isfinite(v) && (d.open_lo ? v > d.lo : v >= d.lo) &&
                    (d.open_hi ? v < d.hi : v <= d.hi);
    if (ok) return std::nullopt;
    return std::string(d.name) + " = " + (shown.empty() ? message_number(v) : shown) +
           " is out of range: allowed " + range_text(d);
}

// A close match among the options, for "did you mean" hints.
// A name from the file, shortened for messages (a 1 MB key must not make a 1 MB message).
std::string clip(std::string_view name, std::size_t limit = 64) {
    if (name.size() <= limit) return std::string(name);
    return std::string(name.substr(0, limit)) + "... (" + std::to_string(name.size()) +
           " characters)";
}

std::string suggestion(std::string_view word, const std::vector<std::string>& options) {
    if (word.size() > 64) return "";  // no real key is that long; and keep the work bounded
    auto distance = [](std::string_view a, std::string_view b) {
        std::vector<std::size_t> row(b.size() + 1);
        for (std::size_t j = 0; j <= b.size(); ++j)
            row[j] = j;
        for (std::size_t i = 1; i <= a.size(); ++i) {
            std::size_t diag = row[0];
            row[0] = i;
            for (std::size_t j = 1; j <= b.size(); ++j) {
                const std::size_t up = row[j];
                const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                                  std::tolower(static_cast<unsigned char>(b[j - 1]));
                row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (same ? 0 : 1)});
                diag = up;
            }
        }
        return row[b.size()];
    };
    std::string best;
    std::size_t best_d = std::max<std::size_t>(2, word.size() / 3) + 1;
    for (const auto& o : options) {
        const std::size_t dd = distance(word, o);
        if (dd < best_d) {
            best_d = dd;
            best = o;
        }
    }
    return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

// ---------------------------------------------------------------------------------------------
// TOML node description for messages

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

// ---------------------------------------------------------------------------------------------
// The parser

struct Given {
    const KeyDef* def;
    Value value;
};
using Assignments = std::map<std::string, Given, std::less<>>;  // by canonical name

struct PointDraft {
    std::vector<Given> overrides;
    std::optional<int> realizations;
    std::string origin;  // for messages: "[sweep] combination 3", "[[points]] #2 (line 40)"
};

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

class Parser {
  public:
    Parser(std::string_view text, fs::path source) : text_(text), path_(std::move(source)) {
        file_ = path_.string();
    }

    SweepFile run();

  private:
    [[noreturn]] void fail(const toml::source_region& where, const std::string& msg) const {
        if (where.begin.line == 0) throw ConfigError(file_ + ": " + msg);
        throw ConfigError(file_ + ":" + std::to_string(where.begin.line) + ":" +
                          std::to_string(where.begin.column) + ": " + msg);
    }
    [[noreturn]] void fail(const std::string& msg) const { throw ConfigError(file_ + ": " + msg); }

    toml::table parse_toml() const;
    Value read_value(const toml::node& n, const KeyDef& d) const;
    void read_scene_section(std::string_view section, const toml::node& node);
    void read_campaign(const toml::node& node, SweepFile& out) const;
    std::vector<PointDraft> read_sweep(const toml::node& node) const;
    std::vector<PointDraft> read_points(const toml::node& node) const;
    std::optional<int> read_realizations(const toml::node& n, std::string_view name) const;
    SceneParams build_scene(const std::vector<Given>& overrides, const std::string& context) const;
    Point make_point(const PointDraft& draft, int default_realizations) const;

    std::string_view text_;
    fs::path path_;
    std::string file_;
    Assignments base_;  // values given in the scene sections
};

toml::table Parser::parse_toml() const {
    // toml++ rejects most garbage itself; a NUL byte is the clearest sign of a binary file.
    if (const auto nul = text_.find('\0'); nul != std::string_view::npos) {
        const auto before = text_.substr(0, nul);
        const auto line = 1 + std::count(before.begin(), before.end(), '\n');
        const auto last_nl = before.rfind('\n');
        const auto col = nul - (last_nl == std::string_view::npos ? 0 : last_nl + 1) + 1;
        throw ConfigError(file_ + ":" + std::to_string(line) + ":" + std::to_string(col) +
                          ": not a TOML text file (contains a NUL byte)");
    }
    // toml++ recurses once per part of a dotted key and per level of nested arrays and inline
    // tables: refuse absurd depths before it sees them (a sweep file needs a handful).
    constexpr int max_depth = 64;
    int line = 1, dots = 0, depth = 0;
    bool in_key = true;  // before the first '=' of the line
    char quote = 0;
    bool comment = false;
    const bool multiline_strings = text_.find("\"\"\"") != std::string_view::npos ||
                                   text_.find("'''") != std::string_view::npos;
    for (const char c : text_) {
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
            throw ConfigError(file_ + ":" + std::to_string(line) + ": " +
                              (dots > max_depth ? "a dotted key" : "nested arrays or tables") +
                              " deeper than " + std::to_string(max_depth) +
                              " levels; a sweep file needs a few");
    }
    try {
        return toml::parse(text_, file_);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        const std::string at =
            file_ + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) + ": ";
        if (auto msg = integer_overflow_message(text_, static_cast<int>(b.line), e.description()))
            throw ConfigError(at + *msg);
        throw ConfigError(at + "TOML syntax error: " + std::string(e.description()));
    }
}

Value Parser::read_value(const toml::node& n, const KeyDef& d) const {
    const std::string name(d.name);
    const std::string got = node_text(n) + " has the wrong type: expected ";
    double v = 0.0;
    switch (d.kind) {
        case Kind::real:
            if (auto i = n.as_integer())
                v = static_cast<double>(i->get());
            else if (auto f = n.as_floating_point())
                v = f->get();
            else
                fail(n.source(), name + " = " + got + "a number, got " + type_name(n));
            break;
        case Kind::integer:
            if (auto i = n.as_integer())
                v = static_cast<double>(i->get());
            else
                fail(n.source(),
                     name + " = " + got + "an integer, got " + type_name(n) +
                         (n.is_floating_point() ? " (write it without a decimal point)" : ""));
            break;
        case Kind::choice: {
            std::vector<std::string> options;
            for (std::string_view rest = d.choices; !rest.empty();) {
                const auto comma = rest.find(',');
                options.emplace_back(rest.substr(0, comma));
                rest =
                    comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
            }
            std::string allowed;  // "a", "b"
            for (const auto& o : options)
                allowed += (allowed.empty() ? "\"" : ", \"") + o + "\"";
            auto s = n.as_string();
            if (!s)
                fail(n.source(),
                     name + " = " + got + "a string (" + allowed + "), got " + type_name(n));
            if (std::find(options.begin(), options.end(), s->get()) == options.end())
                fail(n.source(),
                     name + " = " + node_text(n) + " is not one of the allowed values " + allowed);
            return s->get();
        }
        case Kind::boolean: {
            auto b = n.as_boolean();
            if (!b) fail(n.source(), name + " = " + got + "true or false, got " + type_name(n));
            return std::string(b->get() ? "true" : "false");
        }
    }
    if (v == 0.0) v = 0.0;  // no "-0" in labels and seeds
    if (auto err = range_error(d, v, node_text(n))) fail(n.source(), *err);
    return v;
}

void Parser::read_scene_section(std::string_view section, const toml::node& node) {
    const auto* tbl = node.as_table();
    if (!tbl)
        fail(node.source(), std::string(section) + " must be a table ([" + std::string(section) +
                                "]), got " + type_name(node));
    for (auto&& [k, v] : *tbl) {
        const KeyDef* d = find_key(section, k.str());
        if (!d) {
            const auto allowed = keys_of(section);
            fail(k.source(), "unknown key '" + clip(k.str()) + "' in [" + std::string(section) +
                                 "]; allowed: " + join(allowed) + suggestion(k.str(), allowed));
        }
        base_[std::string(d->name)] = Given{d, read_value(v, *d)};
    }
}

void Parser::read_campaign(const toml::node& node, SweepFile& out) const {
    const auto* tbl = node.as_table();
    if (!tbl) fail(node.source(), "campaign must be a table ([campaign]), got " + type_name(node));
    CampaignSpec& c = out.campaign;
    c.seed = 1;
    c.realizations = 1;
    bool target_given = false;
    for (auto&& [k, v] : *tbl) {
        const std::string key(k.str());
        if (key == "name") {
            auto s = v.as_string();
            if (!s)
                fail(v.source(), "campaign.name = " + node_text(v) +
                                     " has the wrong type: expected a string, got " + type_name(v));
            const std::string& name = s->get();
            const bool chars_ok = std::all_of(name.begin(), name.end(), [](char ch) {
                return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' ||
                       ch == '.';
            });
            if (name.empty() || name.size() > 100 || !chars_ok || name.front() == '.')
                fail(v.source(), "campaign.name = " + node_text(v) +
                                     " is not allowed: use 1 to 100 letters, digits, '-', '_' or "
                                     "'.' (not first), since it names the default store file");
            c.name = name;
        } else if (key == "store") {
            auto s = v.as_string();
            if (!s)
                fail(v.source(), "campaign.store = " + node_text(v) +
                                     " has the wrong type: expected a string (a path), got " +
                                     type_name(v));
            if (s->get().empty()) fail(v.source(), "campaign.store = \"\" is empty: give a path");
            c.store = s->get();
        } else if (key == "seed") {
            auto i = v.as_integer();
            if (!i)
                fail(v.source(), "campaign.seed = " + node_text(v) +
                                     " has the wrong type: expected a non-negative integer, got " +
                                     type_name(v));
            if (i->get() < 0)
                fail(v.source(), "campaign.seed = " + std::to_string(i->get()) +
                                     " is out of range: allowed [0, " +
                                     std::to_string(std::numeric_limits<std::int64_t>::max()) +
                                     "]");
            c.seed = static_cast<std::uint64_t>(i->get());
        } else if (key == "realizations") {
            c.realizations = *read_realizations(v, "campaign.realizations");
        } else if (key == "target") {
            auto s = v.as_string();
            if (!s || (s->get() != "tau" && s->get() != "mean_s"))
                fail(v.source(), "campaign.target = " + node_text(v) +
                                     " is not allowed: use \"tau\" (mean survival time) or "
                                     "\"mean_s\" (mean avalanche size)");
            if (!c.target) c.target.emplace();
            c.target->quantity = s->get() == "tau" ? CampaignTarget::Quantity::tau
                                                   : CampaignTarget::Quantity::mean_s;
            target_given = true;
        } else if (key == "target_rel_ci") {
            const auto x = v.value<double>();
            if (!x || !(*x > 0.0 && *x <= 1.0))
                fail(v.source(), "campaign.target_rel_ci = " + node_text(v) +
                                     " is out of range: allowed (0, 1] (the relative half-width "
                                     "of the 95 % interval, e.g. 0.1)");
            if (!c.target) c.target.emplace();
            c.target->rel_half_width = *x;
        } else if (key == "max_realizations") {
            if (!c.target) c.target.emplace();
            c.target->max_realizations = *read_realizations(v, "campaign.max_realizations");
        } else if (key == "round_realizations") {
            if (!c.target) c.target.emplace();
            c.target->round = *read_realizations(v, "campaign.round_realizations");
        } else {
            std::vector<std::string> allowed(campaign_keys.begin(), campaign_keys.end());
            fail(k.source(), "unknown key '" + clip(key) + "' in [campaign]; allowed: " +
                                 join(allowed) + suggestion(key, allowed));
        }
    }
    if (c.name.empty()) fail(node.source(), "[campaign] needs a name, e.g. name = \"survival\"");
    if (c.target && !target_given)
        fail(node.source(),
             "[campaign] target_rel_ci, max_realizations and round_realizations need "
             "target = \"tau\" or \"mean_s\" (a campaign that stops when good enough)");
    if (c.target && c.target->round == 0) c.target->round = c.realizations;
    if (c.target && c.target->max_realizations == 0)
        fail(node.source(),
             "[campaign] target needs max_realizations (the most realizations a "
             "point may get), e.g. max_realizations = 100");
    const fs::path dir = path_.parent_path();
    if (c.store.empty()) c.store = c.name + ".h5";
    if (c.store.is_relative()) c.store = dir / c.store;
}

std::optional<int> Parser::read_realizations(const toml::node& n, std::string_view name) const {
    auto i = n.as_integer();
    if (!i)
        fail(n.source(), std::string(name) + " = " + node_text(n) +
                             " has the wrong type: expected an integer, got " + type_name(n));
    if (i->get() < 1 || static_cast<double>(i->get()) > max_realizations)
        fail(n.source(), std::string(name) + " = " + std::to_string(i->get()) +
                             " is out of range: allowed [1, " + message_number(max_realizations) +
                             "]");
    return static_cast<int>(i->get());
}

std::vector<PointDraft> Parser::read_sweep(const toml::node& node) const {
    const auto* tbl = node.as_table();
    if (!tbl) fail(node.source(), "sweep must be a table ([sweep]), got " + type_name(node));

    struct Axis {
        const KeyDef* def;
        std::vector<Value> values;
    };
    std::vector<Axis> axes;
    std::vector<std::string> all_names;
    for (const auto& d : key_table)
        all_names.emplace_back(d.name);
    const std::string allowed_text =
        "allowed: D_cm, theta_deg, and <section>.<key> for a key of hopper, material, walls, "
        "integrator or protocol (see campaigns/README.md)";

    auto read_axis = [&](const KeyDef& d, const toml::node& v) {
        const auto* arr = v.as_array();
        if (!arr)
            fail(v.source(), std::string(d.name) + " = " + node_text(v) +
                                 " in [sweep] must be a list of values, e.g. " +
                                 std::string(d.name) + " = [" + node_text(v) + "]");
        if (arr->empty())
            fail(v.source(), std::string(d.name) +
                                 " = [] in [sweep] is an empty list: give at "
                                 "least one value or remove the key");
        Axis axis{&d, {}};
        for (const auto& e : *arr)
            axis.values.push_back(read_value(e, d));
        axes.push_back(std::move(axis));
    };

    for (auto&& [k, v] : *tbl) {
        const std::string key(k.str());
        if (key == "D_cm" || key == "theta_deg") {
            read_axis(*find_name(key), v);
        } else if (is_scene_section(key) && v.is_table()) {
            for (auto&& [k2, v2] : *v.as_table()) {
                const std::string full = key + "." + std::string(k2.str());
                if (key == "hopper" && (k2.str() == "D_cm" || k2.str() == "theta_deg"))
                    fail(k2.source(), "write " + clip(k2.str()) +
                                          " = [...] directly in "
                                          "[sweep], not as '" +
                                          full + "'");
                const KeyDef* d = find_key(key, k2.str());
                if (!d) {
                    const auto allowed = keys_of(key);
                    fail(k2.source(), "unknown key '" + clip(full) + "' in [sweep]; allowed in " +
                                          key + ": " + join(allowed) + suggestion(full, all_names));
                }
                read_axis(*d, v2);
            }
        } else {
            std::string shown = key;
            if (auto sub = v.as_table(); sub && !sub->empty())
                shown += "." + std::string(sub->begin()->first.str());
            fail(k.source(), "unknown key '" + clip(shown) + "' in [sweep]; " + allowed_text +
                                 suggestion(shown, all_names));
        }
    }
    if (axes.empty())
        fail(node.source(), "[sweep] has no lists: add e.g. D_cm = [2.7, 2.9] or remove it");

    std::sort(axes.begin(), axes.end(), [](const Axis& a, const Axis& b) {
        return canonical_less(a.def->name, b.def->name);
    });
    std::size_t count = 1;
    for (const auto& a : axes) {
        count *= a.values.size();
        if (count > max_points)
            fail(node.source(),
                 "[sweep] has more than " + std::to_string(max_points) + " combinations");
    }
    // Cartesian product in canonical axis order; the last axis varies fastest.
    std::vector<PointDraft> out;
    std::vector<std::size_t> idx(axes.size(), 0);
    for (std::size_t n = 0; n < count; ++n) {
        PointDraft p;
        p.origin = "[sweep] combination " + std::to_string(n + 1);
        for (std::size_t a = 0; a < axes.size(); ++a)
            p.overrides.push_back(Given{axes[a].def, axes[a].values[idx[a]]});
        out.push_back(std::move(p));
        for (std::size_t a = axes.size(); a-- > 0;) {
            if (++idx[a] < axes[a].values.size()) break;
            idx[a] = 0;
        }
    }
    return out;
}

std::vector<PointDraft> Parser::read_points(const toml::node& node) const {
    const auto* arr = node.as_array();
    if (!arr)
        fail(node.source(),
             "points must be an array of tables ([[points]]), got " + type_name(node));
    if (arr->empty()) fail(node.source(), "points is an empty list: give at least one point");
    const std::string allowed =
        "D_cm, theta_deg, realizations, and inline tables hopper, material, walls, integrator, "
        "protocol, fields";
    std::vector<PointDraft> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
        const toml::node& pn = *arr->get(i);
        const auto* tbl = pn.as_table();
        const std::string origin = "[[points]] #" + std::to_string(i + 1);
        if (!tbl) fail(pn.source(), origin + " must be a table, got " + type_name(pn));
        PointDraft p;
        p.origin = origin + (pn.source().begin.line
                                 ? " (line " + std::to_string(pn.source().begin.line) + ")"
                                 : "");
        for (auto&& [k, v] : *tbl) {
            const std::string key(k.str());
            if (key == "D_cm" || key == "theta_deg") {
                const KeyDef* d = find_name(key);
                p.overrides.push_back(Given{d, read_value(v, *d)});
            } else if (key == "realizations") {
                p.realizations = read_realizations(v, origin + " realizations");
            } else if (is_scene_section(key)) {
                const auto* sub = v.as_table();
                if (!sub)
                    fail(v.source(), key + " in " + origin + " must be a table, e.g. " + key +
                                         " = { key = value }, got " + type_name(v));
                for (auto&& [k2, v2] : *sub) {
                    const std::string full = key + "." + std::string(k2.str());
                    if (key == "hopper" && (k2.str() == "D_cm" || k2.str() == "theta_deg"))
                        fail(k2.source(), "write " + clip(k2.str()) +
                                              " directly in the point, not as '" + full + "'");
                    const KeyDef* d = find_key(key, k2.str());
                    if (!d) {
                        const auto keys = keys_of(key);
                        fail(k2.source(), "unknown key '" + clip(full) + "' in " + origin +
                                              "; allowed in " + key + ": " + join(keys) +
                                              suggestion(k2.str(), keys));
                    }
                    p.overrides.push_back(Given{d, read_value(v2, *d)});
                }
            } else {
                std::vector<std::string> opts = {"D_cm", "theta_deg", "realizations"};
                opts.insert(opts.end(), scene_sections.begin(), scene_sections.end());
                fail(k.source(), "unknown key '" + clip(key) + "' in " + origin +
                                     "; allowed: " + allowed + suggestion(key, opts));
            }
        }
        out.push_back(std::move(p));
    }
    return out;
}

SceneParams Parser::build_scene(const std::vector<Given>& overrides,
                                const std::string& context) const {
    Assignments merged = base_;
    for (const auto& g : overrides)
        merged[std::string(g.def->name)] = g;
    SceneParams p{};
    for (const auto& [name, g] : merged)
        g.def->apply(p, g.value);
    // Walls default to the particles' material and to wall particles of diameter d_large
    // (spec/physics.md): "follow" the values this scene ends up with unless walls are given.
    if (!merged.count("walls.e_n")) p.material.wall.e_n = p.material.system.e_n;
    if (!merged.count("walls.mu")) p.material.wall.mu = p.material.system.mu;
    if (!merged.count("walls.particle_diameter_cm")) p.hopper.wall_diameter = p.particles.d_large;
    // The base scene without a D_cm in [hopper]: the built-in default outlet is never used
    // (every point and `campaign simulate --D` give theirs), so a hopper narrower than it must
    // not be refused for it. It stands at half the width here.
    if (context.empty() && !merged.count("D_cm") && !(p.hopper.outlet < p.hopper.width))
        p.hopper.outlet = 0.5 * p.hopper.width;

    const std::string where = context.empty() ? "" : context + ": ";
    auto in_cm = [](double m) { return approx_number(m / cm); };
    const auto& h = p.hopper;
    const auto& s = p.particles;
    const auto& pr = p.protocol;
    if (s.d_large < s.d_small)
        fail(where + "hopper.d_large_cm = " + in_cm(s.d_large) +
             " must be at least hopper.d_small_cm = " + in_cm(s.d_small));
    if (!(h.width > 2.0 * s.d_large))
        fail(where + "hopper.width_cm = " + in_cm(h.width) +
             " must exceed 2 * hopper.d_large_cm = " + in_cm(2.0 * s.d_large));
    if (!(h.outlet < h.width))
        fail(where + "D_cm = " + in_cm(h.outlet) + " must be smaller than hopper.width_cm = " +
             in_cm(h.width) + " (the outlet must fit inside the hopper)");
    const double max_spacing = 1.0 + s.d_small / h.wall_diameter;
    if (!(h.wall_spacing < max_spacing))
        fail(where + "walls.spacing = " + approx_number(h.wall_spacing) +
             " must be below 1 + d_small / " + "wall diameter = " + approx_number(max_spacing) +
             " so that no particle slips between two wall particles");
    if (!(pr.exit_depth > pr.jam_region_height))
        fail(where + "protocol.exit_depth = " + approx_number(pr.exit_depth) +
             " must exceed protocol.jam_region_height = " + approx_number(pr.jam_region_height) +
             " (particles are removed only below the jam region)");
    if (pr.empty_threshold >= s.count)
        fail(where + "protocol.empty_threshold = " + std::to_string(pr.empty_threshold) +
             " must be smaller than hopper.particles = " + std::to_string(s.count));
    const auto& f = p.fields;
    if (f.sample_interval > f.window)
        fail(where + "fields.sample_interval_s = " + approx_number(f.sample_interval) +
             " must not exceed fields.window_s = " + approx_number(f.window) +
             " (every window needs samples)");
    if (f.end && !(*f.end > f.start))
        fail(where + "fields.end_s = " + approx_number(*f.end) +
             " must exceed fields.start_s = " + approx_number(f.start));
    try {
        engine::validate_scene(p);
    } catch (const ConfigError& e) {
        fail(where + e.what());
    }
    return p;
}

Point Parser::make_point(const PointDraft& draft, int default_realizations) const {
    Point pt;
    for (const auto& g : draft.overrides)
        pt.settings.push_back(ParamSetting{std::string(g.def->name), g.value});
    for (const char* required : {"D_cm", "theta_deg"}) {
        const bool given = std::any_of(pt.settings.begin(), pt.settings.end(),
                                       [&](const ParamSetting& s) { return s.name == required; });
        if (given) continue;
        const auto it = base_.find(required);
        if (it == base_.end())
            fail(draft.origin + " has no " + required +
                 ": D_cm and theta_deg are needed for every "
                 "point; give them in the point, in [sweep], or as defaults in [hopper]");
        pt.settings.push_back(ParamSetting{required, it->second.value});
    }
    std::sort(pt.settings.begin(), pt.settings.end(),
              [](const ParamSetting& a, const ParamSetting& b) {
                  return canonical_less(a.name, b.name);
              });
    for (const auto& s : pt.settings)
        pt.label += (pt.label.empty() ? "" : " ") + to_string(s);
    pt.realizations = draft.realizations.value_or(default_realizations);
    pt.scene = build_scene(draft.overrides, "in point '" + pt.label + "' (" + draft.origin + ")");
    return pt;
}

SweepFile Parser::run() {
    SweepFile out;
    out.path = path_;
    out.text = std::string(text_);
    const toml::table root = parse_toml();

    const toml::node* sweep = nullptr;
    const toml::node* points = nullptr;
    const toml::node* campaign = nullptr;
    std::vector<std::string> sections(scene_sections.begin(), scene_sections.end());
    sections.insert(sections.end(), {"campaign", "sweep", "points"});
    for (auto&& [k, v] : root) {
        const std::string key(k.str());
        if (is_scene_section(key))
            read_scene_section(key, v);
        else if (key == "campaign")
            campaign = &v;
        else if (key == "sweep")
            sweep = &v;
        else if (key == "points")
            points = &v;
        else if (v.is_table())
            fail(k.source(), "unknown section [" + clip(key) + "]; allowed: " + join(sections) +
                                 suggestion(key, sections));
        else
            fail(k.source(), "unknown key '" + clip(key) +
                                 "' at the top level (outside any section); "
                                 "allowed sections: " +
                                 join(sections) + suggestion(key, sections));
    }

    out.base = build_scene({}, "");

    if (!campaign) {
        if (sweep) fail(sweep->source(), "[sweep] needs a [campaign] section (at least a name)");
        if (points)
            fail(points->source(), "[[points]] needs a [campaign] section (at least a name)");
        return out;
    }
    out.has_campaign = true;
    read_campaign(*campaign, out);

    std::vector<PointDraft> drafts;
    if (sweep) drafts = read_sweep(*sweep);
    if (points) {
        auto more = read_points(*points);
        drafts.insert(drafts.end(), std::make_move_iterator(more.begin()),
                      std::make_move_iterator(more.end()));
    }
    if (drafts.empty()) {
        if (!base_.count("D_cm") || !base_.count("theta_deg"))
            fail(campaign->source(),
                 "[campaign] has neither [sweep] nor [[points]], so it runs the base scene, which "
                 "needs D_cm and theta_deg: give both in [hopper]");
        drafts.push_back(PointDraft{{}, std::nullopt, "the base scene"});
    }
    if (drafts.size() > max_points)
        fail("the campaign has " + std::to_string(drafts.size()) + " points; at most " +
             std::to_string(max_points) + " are allowed");

    std::map<std::string, std::string> seen;  // label -> origin
    long long tasks = 0;
    for (const auto& d : drafts) {
        Point pt = make_point(d, out.campaign.realizations);
        if (const auto& t = out.campaign.target) {
            // Rounds: the point's realizations are the first round; the plan holds
            // max_realizations (their seeds are fixed by the index, so the set run stays
            // deterministic whatever the rounds decide).
            if (pt.realizations > t->max_realizations)
                fail("point '" + pt.label + "' (" + d.origin + ") has " +
                     std::to_string(pt.realizations) +
                     " realizations in its first round, more than campaign.max_realizations = " +
                     std::to_string(t->max_realizations) + "; allowed: at most max_realizations");
            pt.first_round = pt.realizations;
            pt.realizations = t->max_realizations;
        }
        if (auto [it, fresh] = seen.emplace(pt.label, d.origin); !fresh)
            fail("duplicate point '" + pt.label + "': " + it->second + " and " + d.origin +
                 " have the same settings (to run a point more often, raise its realizations)");
        tasks += pt.realizations;
        if (tasks > max_tasks)
            fail("the campaign has more than " + std::to_string(max_tasks) + " tasks");
        out.campaign.points.push_back(std::move(pt));
    }
    return out;
}

std::string display_name(const fs::path& p) {
    return p.string();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

SweepFile load_sweep(const fs::path& path) {
    const std::string file = display_name(path);
    std::error_code ec;
    const auto st = fs::status(path, ec);
    if (ec || !fs::exists(st)) {
        throw ConfigError(file + ": cannot read the sweep file: " +
                          (ec ? ec.message() : std::string("no such file")));
    }
    if (fs::is_directory(st))
        throw ConfigError(file + ": cannot read the sweep file: it is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw ConfigError(file + ": cannot read the sweep file: " + std::strerror(errno));
    }
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw ConfigError(file + ": cannot read the sweep file: read error");
    return parse_sweep(text, path);
}

SweepFile parse_sweep(std::string_view text, const fs::path& source_name) {
    return Parser(text, source_name).run();
}

engine::SceneParams scene_at(const SweepFile& sweep, double D_cm, double theta_deg) {
    const std::string file = display_name(sweep.path);
    const KeyDef& dD = *find_name("D_cm");
    const KeyDef& dT = *find_name("theta_deg");
    if (auto err = range_error(dD, D_cm)) throw ConfigError(file + ": " + *err);
    if (auto err = range_error(dT, theta_deg)) throw ConfigError(file + ": " + *err);
    SceneParams p = sweep.base;
    dD.apply(p, D_cm);
    dT.apply(p, theta_deg);
    if (!(p.hopper.outlet < p.hopper.width))
        throw ConfigError(
            file + ": D_cm = " + message_number(D_cm) + " must be smaller than hopper.width_cm = " +
            approx_number(p.hopper.width / cm) + " (the outlet must fit inside the hopper)");
    try {
        engine::validate_scene(p);
    } catch (const ConfigError& e) {
        throw ConfigError(file + ": " + e.what());
    }
    return p;
}

std::string to_string(CampaignTarget::Quantity q) {
    return q == CampaignTarget::Quantity::tau ? "tau" : "mean_s";
}

std::string to_string(const ParamSetting& setting) {
    return setting.name + "=" + value_text(setting.value);
}

std::vector<std::string> parameter_names() {
    std::vector<std::string> out;
    for (const auto& d : key_table)
        out.emplace_back(d.name);
    return out;
}

std::uint64_t derive_seed(std::uint64_t campaign_seed, const std::vector<ParamSetting>& settings,
                          int realization) {
    if (realization < 0)
        throw ConfigError("derive_seed: realization index " + std::to_string(realization) +
                          " is negative");
    // Canonical order, whatever order the caller holds them in, so that the seed is a function
    // of the point's parameter set alone.
    std::vector<const ParamSetting*> sorted;
    for (const auto& s : settings)
        sorted.push_back(&s);
    std::sort(sorted.begin(), sorted.end(), [](const ParamSetting* a, const ParamSetting* b) {
        return canonical_less(a->name, b->name);
    });
    std::uint64_t seed = campaign_seed;
    for (const auto* s : sorted)
        seed = core::mix_seed(seed, std::string_view(to_string(*s)));
    return core::mix_seed(seed, static_cast<std::uint64_t>(realization));
}

std::vector<Task> expand_tasks(const CampaignSpec& spec) {
    std::vector<Task> tasks;
    long long total = 0;
    for (const auto& p : spec.points) {
        if (p.realizations < 0)
            throw ConfigError("point '" + p.label + "' has a negative number of realizations");
        total += p.realizations;
    }
    if (total > INT_MAX) throw ConfigError("the campaign has too many tasks for one list");
    tasks.reserve(static_cast<std::size_t>(total));
    int id = 0;
    for (int pi = 0; pi < static_cast<int>(spec.points.size()); ++pi) {
        const Point& p = spec.points[static_cast<std::size_t>(pi)];
        for (int r = 0; r < p.realizations; ++r)
            tasks.push_back(Task{id++, pi, r, derive_seed(spec.seed, p.settings, r)});
    }
    return tasks;
}

}  // namespace hopper::config
