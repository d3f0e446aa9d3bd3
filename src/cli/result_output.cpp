#include "cli/result_output.hpp"

#include <cmath>
#include <cstdio>
#include <string_view>

#include "hopper/store/result_fields.hpp"

#ifndef HOPPER_VERSION
#define HOPPER_VERSION "unknown"
#endif

namespace hopper::cli {

namespace {

// A readable number for people: %.*g, or "n/a" when not finite.
std::string num(double v, int precision = 6) {
    if (!std::isfinite(v)) return "n/a";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

// One member as JSON, by its C++ type: numbers, texts and optionals (null when absent) as
// values, arrays on one line, the diagnostics as an object, the events as an array of one-line
// objects, the fields as their one-line summary.
struct JsonMember {
    JsonWriter& w;

    void operator()(std::string_view k, engine::Status v) { w.field(k, engine::to_string(v)); }
    void operator()(std::string_view k, engine::Event::Kind v) { w.field(k, engine::to_string(v)); }
    template <class T>
    void operator()(std::string_view k, const std::vector<T>& v) {
        w.field_array(k, v);
    }
    void operator()(std::string_view k, const engine::Diagnostics& d) {
        w.key(k).begin_object();
        store::for_each_diagnostic([&](const auto& f) { (*this)(f.name, d.*f.member); });
        w.end_object();
    }
    void operator()(std::string_view k, const std::vector<engine::Event>& events) {
        w.key(k).begin_array();
        for (const auto& e : events) {
            w.begin_object_inline();
            store::for_each_event_field([&](const auto& f) { (*this)(f.name, e.*f.member); });
            w.end_object();
        }
        w.end_array();
    }
    void operator()(std::string_view k, const std::optional<engine::FieldMoments>& m) {
        if (!m) return;
        w.key(k).begin_object_inline();
        write_fields_summary(w, *m);
        w.end_object();
    }
    void operator()(std::string_view, const std::vector<engine::Arch>&) {}  // not in this JSON
    template <class T>
    void operator()(std::string_view k, const T& v) {
        w.field(k, v);
    }
};

// The member `name` of the result (or of its diagnostics) under the key `key` (default: name).
struct Members {
    JsonWriter& w;
    const engine::RealizationResult& r;

    void operator()(std::string_view name, std::string_view key = {}) const {
        store::for_each_result_field([&](const auto& f) {
            if (f.name == name) JsonMember{w}(key.empty() ? name : key, r.*f.member);
        });
    }
    void diagnostic(std::string_view name) const {
        store::for_each_diagnostic([&](const auto& f) {
            if (f.name == name) JsonMember{w}(name, r.diagnostics.*f.member);
        });
    }
};

}  // namespace

bool is_wall_clock_key(std::string_view key) {
    bool wall_clock = false;
    store::for_each_diagnostic([&](const auto& f) { wall_clock |= f.wall_clock && f.name == key; });
    return wall_clock;
}

// The values come from the result's description (store/result_fields.hpp); what is written
// here is the JSON's layout: its keys in their documented order (result_output.hpp).
void write_result_json(JsonWriter& w, const RunRequest& req, const engine::RealizationResult& r) {
    const Members member{w, r};
    w.begin_object();
    member("status");
    member("message");
    w.field("version", HOPPER_VERSION);
    w.field("sweep", req.sweep);
    w.field("D_cm", req.D_cm);
    w.field("theta_deg", req.theta_deg);
    for (const char* name : {"seed", "particles", "wall_particles", "discharged", "n_jams",
                             "n_shakes", "n_jams_multi_shake", "survival_times", "censored",
                             "jam_onsets", "shakes_per_jam", "empty_time", "discharge_rate"})
        member(name);
    // The engine reports 0 kg/s when it has no rate; say "no value" the same way as the rate.
    w.key("discharge_rate_kg_s");
    if (r.discharge_rate)
        w.value(r.discharge_rate_mass);
    else
        w.null();
    for (const char* name : {"steps", "wall_seconds", "ns_per_particle_step"})
        member.diagnostic(name);
    member("diagnostics");
    w.key("discharge_curve").begin_object();
    member("curve_time", "time");
    member("curve_count", "in_hopper");
    w.end_object();
    member("exit_times");
    member("events");
    member("fields");  // only when the scene samples fields: otherwise the output is unchanged
    w.end_object();
}

std::string result_json(const RunRequest& req, const engine::RealizationResult& r) {
    JsonWriter w;
    write_result_json(w, req, r);
    return w.str();
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
