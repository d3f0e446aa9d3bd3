// What is generated from the scene schema's rows (key_table.cpp): the fingerprint text, values in
// SI, defaults, and the scene rebuilt from typed parameters.
#include "hopper/config/scene_schema.hpp"

#include <algorithm>
#include <charconv>

#include "config/key_table.hpp"
#include "hopper/core/error.hpp"

namespace hopper::config {

namespace {

// The fingerprint's text of a value: numbers in their shortest round-trip form, integers as
// integers ("10000000", not "1e+07"), choices verbatim, an unset optional "unset".
std::string fingerprint_value(const SchemaRow& row, const SchemaRead& v) {
    if (!v) return "unset";
    if (const auto* s = std::get_if<std::string>(&*v)) return *s;
    const double x = std::get<double>(*v);
    if (row.kind == ValueKind::integer) return std::to_string(static_cast<long long>(x));
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    return std::string(buf, r.ptr);
}

bool off_default(const SchemaRow& row, const engine::SceneParams& p) {
    const SchemaRead v = value_in_si(row, p);
    if (!row.fingerprint.absent_at.empty())
        return fingerprint_value(row, v) != row.fingerprint.absent_at;
    return v != value_in_si(row, engine::SceneParams{});
}

// The rows in fingerprint order (the table's order is the sweep file's).
const std::vector<const SchemaRow*>& by_position() {
    static const std::vector<const SchemaRow*> rows = [] {
        std::vector<const SchemaRow*> out;
        for (const auto& r : scene_schema())
            if (r.fingerprint.enters != Enters::never) out.push_back(&r);
        std::stable_sort(out.begin(), out.end(), [](const SchemaRow* a, const SchemaRow* b) {
            return a->fingerprint.position < b->fingerprint.position;
        });
        return out;
    }();
    return rows;
}

}  // namespace

const SchemaRow* find_row(std::string_view name) {
    for (const auto& r : scene_schema())
        if (r.name == name) return &r;
    return nullptr;
}

SchemaRead value_in_si(const SchemaRow& row, const engine::SceneParams& p) {
    return row.si ? row.si(p) : row.read(p);
}

SchemaRead default_value(const SchemaRow& row) {
    return row.read(engine::SceneParams{});
}

std::string si_unit(const SchemaRow& row) {
    if (row.unit == "cm") return "m";
    if (row.unit == "deg") return "rad";
    if (row.unit.empty()) return "1";
    return std::string(row.unit);
}

namespace {

// The rows a line needs off their default: its `only_with`, and theirs in turn.
bool gate_open(const SchemaRow& row, const engine::SceneParams& p) {
    if (row.fingerprint.only_with.empty()) return true;
    const SchemaRow* gate = find_row(row.fingerprint.only_with);
    return gate && off_default(*gate, p) && gate_open(*gate, p);
}

}  // namespace

bool in_fingerprint(const SchemaRow& row, const engine::SceneParams& p) {
    const FingerprintLine& f = row.fingerprint;
    if (!gate_open(row, p)) return false;
    switch (f.enters) {
        case Enters::always:
            return true;
        case Enters::unless_default:
            return off_default(row, p);
        case Enters::when_set:
            return value_in_si(row, p).has_value();
        case Enters::never:
            return false;
    }
    return false;
}

std::string scene_fingerprint(const engine::SceneParams& p) {
    std::string text;
    for (const SchemaRow* r : by_position()) {
        if (!in_fingerprint(*r, p)) continue;
        text += r->fingerprint.name;
        text += '=';
        text += fingerprint_value(*r, value_in_si(*r, p));
        text += '\n';
    }
    return text;
}

engine::SceneParams scene_from_parameters(const std::vector<core::Setting>& parameters) {
    engine::SceneParams p;
    for (const auto& s : parameters) {
        const SchemaRow* r = find_row(s.name);
        if (!r || !r->in_sweep_file)
            throw core::ConfigError("stored parameter '" + s.name +
                                    "' is not a scene parameter of this version");
        const bool number = r->kind == ValueKind::real || r->kind == ValueKind::integer;
        if (number != std::holds_alternative<double>(s.value))
            throw core::ConfigError("stored parameter '" + s.name +
                                    "' has a value of the wrong type");
        if (number) {
            if (auto err = detail::range_error(*r, std::get<double>(s.value)))
                throw core::ConfigError("stored parameter " + *err);
        } else {
            const std::string& v = std::get<std::string>(s.value);
            const std::string options =
                r->kind == ValueKind::boolean ? "true,false" : std::string(r->choices);
            if (("," + options + ",").find("," + v + ",") == std::string::npos)
                throw core::ConfigError("stored parameter " + s.name + " = " + v +
                                        " is not one of " + options);
        }
        r->apply(p, s.value);
    }
    engine::validate_scene(p);
    return p;
}

}  // namespace hopper::config
