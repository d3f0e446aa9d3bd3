#include "cli/result_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string_view>
#include <vector>

#include "hopper/store/result_fields.hpp"

#include "hopper_version.h"  // HOPPER_VERSION, generated at build time (version.cmake)

namespace hopper::cli {

namespace {

// A readable number for people: %.*g, or "n/a" when not finite.
std::string num(double v, int precision = 6) {
    if (!std::isfinite(v)) return "n/a";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

using analysis::Json;

// One value as JSON, by its C++ type: numbers (null when not finite), texts and optionals (null
// when absent), arrays, the diagnostics as an object, the events as an array of objects.
Json as_json(double v) {
    return analysis::json_number_or_null(v);
}
Json as_json(engine::Status v) {
    return engine::to_string(v);
}
Json as_json(engine::Event::Kind v) {
    return engine::to_string(v);
}
template <class T>
Json as_json(const T& v) {
    return v;  // integers, bools and texts as they are
}
template <class T>
Json as_json(const std::optional<T>& v) {
    return v ? as_json(*v) : Json(nullptr);
}
Json as_json(const engine::Diagnostics& d);
Json as_json(const engine::Event& e);
template <class T>
Json as_json(const std::vector<T>& v) {
    Json a = Json::array();
    for (const auto& x : v)
        a.push_back(as_json(static_cast<const T&>(x)));  // vector<bool>'s proxy read as bool
    return a;
}

Json as_json(const engine::Diagnostics& d) {
    Json o = Json::object();
    store::for_each_diagnostic(
        [&](const auto& f) { o[std::string(f.name)] = as_json(d.*f.member); });
    return o;
}

Json as_json(const engine::Event& e) {
    Json o = Json::object();
    store::for_each_event_field(
        [&](const auto& f) { o[std::string(f.name)] = as_json(e.*f.member); });
    return o;
}

// The member `name` of the result (or of its diagnostics) into `j` under the key `key` (default:
// name). The fields go in as their summary, and only when the scene samples them; the arches are
// not in this JSON.
struct Members {
    Json& j;
    const engine::RealizationResult& r;

    template <class T>
    void put(std::string_view key, const T& v) const {
        j[std::string(key)] = as_json(v);
    }
    void put(std::string_view key, const std::optional<engine::FieldMoments>& m) const {
        if (!m) return;
        Json o = Json::object();
        analysis::add_fields_summary(o, *m);
        j[std::string(key)] = std::move(o);
    }
    void put(std::string_view, const std::vector<engine::Arch>&) const {}

    void operator()(std::string_view name, std::string_view key = {}) const {
        store::for_each_result_field([&](const auto& f) {
            if (f.name == name) put(key.empty() ? name : key, r.*f.member);
        });
    }
    void diagnostic(std::string_view name) const {
        store::for_each_diagnostic([&](const auto& f) {
            if (f.name == name) put(name, r.diagnostics.*f.member);
        });
    }
};

// A scalar, or a key, as JSON text (invalid UTF-8 replaced by U+FFFD, so the text stays JSON).
std::string scalar_text(const Json& j) {
    return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// `j` on one line, members and elements separated by ", ".
void write_inline(std::string& out, const Json& j) {
    if (!j.is_structured()) {
        out += scalar_text(j);
        return;
    }
    out += j.is_object() ? '{' : '[';
    for (auto it = j.begin(); it != j.end(); ++it) {
        if (it != j.begin()) out += ", ";
        if (j.is_object()) out += scalar_text(it.key()) + ": ";
        write_inline(out, it.value());
    }
    out += j.is_object() ? '}' : ']';
}

// `j` at nesting depth `depth` in the layout of result_output.hpp: objects one member per line,
// arrays of objects one object per line, everything else (and all inside an array, and the
// fields summary) on one line.
void write_block(std::string& out, const Json& j, int depth) {
    const bool of_objects =
        j.is_array() && !j.empty() &&
        std::all_of(j.begin(), j.end(), [](const Json& x) { return x.is_object(); });
    if (!(j.is_object() || of_objects) || j.empty()) {
        write_inline(out, j);
        return;
    }
    const std::string indent(static_cast<std::size_t>(2 * (depth + 1)), ' ');
    out += j.is_object() ? '{' : '[';
    for (auto it = j.begin(); it != j.end(); ++it) {
        out += it == j.begin() ? "\n" : ",\n";
        out += indent;
        if (j.is_object()) {
            out += scalar_text(it.key()) + ": ";
            if (depth == 0 && it.key() == "fields")
                write_inline(out, it.value());  // a summary: one line, as documented
            else
                write_block(out, it.value(), depth + 1);
        } else {
            write_inline(out, it.value());
        }
    }
    out += '\n' + indent.substr(2) + (j.is_object() ? '}' : ']');
}

}  // namespace

bool is_wall_clock_key(std::string_view key) {
    bool wall_clock = false;
    store::for_each_diagnostic([&](const auto& f) { wall_clock |= f.wall_clock && f.name == key; });
    return wall_clock;
}

// The values come from the result's description (store/result_fields.hpp); what is written
// here is the JSON's layout: its keys in their documented order (result_output.hpp).
Json result_object(const RunRequest& req, const engine::RealizationResult& r) {
    Json j = Json::object();
    const Members member{j, r};
    member("status");
    member("message");
    j["version"] = HOPPER_VERSION;
    j["sweep"] = req.sweep;
    j["D_cm"] = as_json(req.D_cm);
    j["theta_deg"] = as_json(req.theta_deg);
    for (const char* name : {"seed", "particles", "wall_particles", "discharged", "n_jams",
                             "n_shakes", "n_jams_multi_shake", "survival_times", "censored",
                             "jam_onsets", "shakes_per_jam", "empty_time", "discharge_rate"})
        member(name);
    // The engine reports 0 kg/s when it has no rate; say "no value" the same way as the rate.
    j["discharge_rate_kg_s"] = r.discharge_rate ? as_json(r.discharge_rate_mass) : Json(nullptr);
    for (const char* name : {"steps", "wall_seconds", "ns_per_particle_step"})
        member.diagnostic(name);
    member("diagnostics");
    Json curve = Json::object();
    Members{curve, r}("curve_time", "time");
    Members{curve, r}("curve_count", "in_hopper");
    j["discharge_curve"] = std::move(curve);
    member("exit_times");
    member("events");
    member("fields");  // only when the scene samples fields: otherwise the output is unchanged
    return j;
}

std::string result_json(const RunRequest& req, const engine::RealizationResult& r) {
    std::string out;
    write_block(out, result_object(req, r), 0);
    return out;
}

void write_summary(std::ostream& os, const RunRequest& req, const engine::RealizationResult& r) {
    const auto& d = r.diagnostics;
    auto row = [&](std::string_view label, const std::string& text) {
        os << "  " << label << std::string(label.size() < 22 ? 22 - label.size() : 1, ' ') << text
           << '\n';
    };
    os << "campaign simulate: " << req.sweep << "  D = " << num(req.D_cm)
       << " cm  theta = " << num(req.theta_deg) << " deg  seed = " << r.seed << '\n';
    row("status", engine::to_string(r.status));
    if (!r.message.empty()) row("message", r.message);
    row("particles", std::to_string(r.particles) + " (+ " + std::to_string(r.wall_particles) +
                         " wall), " + std::to_string(r.discharged) + " discharged");
    row("jams", std::to_string(r.n_jams));
    row("shakes", std::to_string(r.n_shakes) + " (" + std::to_string(r.n_jams_multi_shake) +
                      " jams needed more than one)");

    // Survival times: the first few in full, then how many more.
    constexpr std::size_t shown = 8;
    std::string st;
    for (std::size_t i = 0; i < r.survival_times.size() && i < shown; ++i) {
        if (i > 0) st += ", ";
        st += num(r.survival_times[i], 4);
        if (i < r.censored.size() && r.censored[i]) st += " (censored)";
    }
    if (r.survival_times.size() > shown)
        st += ", ... (" + std::to_string(r.survival_times.size() - shown) + " more)";
    if (r.survival_times.empty()) st = "none";
    row("survival times (s)", st);

    row("empty time", r.empty_time ? num(*r.empty_time) + " s" : "not emptied");
    row("discharge rate", r.discharge_rate ? num(*r.discharge_rate) + " particles/s (" +
                                                 num(r.discharge_rate_mass) + " kg/s)"
                                           : "n/a");
    row("steps", std::to_string(d.steps) + " (" + std::to_string(d.settle_steps) +
                     " settling), dt = " + num(d.dt) + " s");
    row("simulated time",
        "settle " + num(d.settle_time, 4) + " s, shaking " + num(d.shake_time, 4) + " s");
    row("max overlap", num(d.max_overlap_ratio, 3) + " d_small");
    row("wall time", num(d.wall_seconds, 4) + " s");
    row("ns per particle-step", num(d.ns_per_particle_step, 4));
}

}  // namespace hopper::cli
