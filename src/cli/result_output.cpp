#include "cli/result_output.hpp"

#include <cmath>
#include <cstdio>
#include <string_view>

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

void write_diagnostics(JsonWriter& w, const engine::Diagnostics& d) {
    w.begin_object();
    w.field("steps", d.steps);
    w.field("settle_steps", d.settle_steps);
    w.field("neighbor_rebuilds", d.neighbor_rebuilds);
    w.field("particle_steps", d.particle_steps);
    w.field("settle_time", d.settle_time);
    w.field("shake_time", d.shake_time);
    w.field("wall_seconds", d.wall_seconds);
    w.field("ns_per_particle_step", d.ns_per_particle_step);
    w.field("max_overlap_ratio", d.max_overlap_ratio);
    w.field("settled_kinetic_energy", d.settled_kinetic_energy);
    w.field("potential_energy_released", d.potential_energy_released);
    w.field("dt", d.dt);
    w.field("tau_c", d.tau_c);
    w.field("k_n", d.k_n);
    w.field("seconds_forces", d.seconds_forces);
    w.field("seconds_integration", d.seconds_integration);
    w.field("seconds_neighbors", d.seconds_neighbors);
    w.field("seconds_observers", d.seconds_observers);
    w.end_object();
}

}  // namespace

bool is_wall_clock_key(std::string_view key) {
    return key == "wall_seconds" || key == "ns_per_particle_step" || key.starts_with("seconds_");
}

void write_result_json(JsonWriter& w, const RunRequest& req, const engine::RealizationResult& r) {
    w.begin_object();
    w.field("status", engine::to_string(r.status));
    w.field("message", r.message);
    w.field("version", HOPPER_VERSION);
    w.field("sweep", req.sweep);
    w.field("D_cm", req.D_cm);
    w.field("theta_deg", req.theta_deg);
    w.field("seed", r.seed);
    w.field("particles", r.particles);
    w.field("wall_particles", r.wall_particles);
    w.field("discharged", r.discharged);
    w.field("n_jams", r.n_jams);
    w.field("n_shakes", r.n_shakes);
    w.field("n_jams_multi_shake", r.n_jams_multi_shake);
    w.field_array("survival_times", r.survival_times);
    w.field_array("censored", r.censored);
    w.field_array("jam_onsets", r.jam_onsets);
    w.field_array("shakes_per_jam", r.shakes_per_jam);
    w.field("empty_time", r.empty_time);
    w.field("discharge_rate", r.discharge_rate);
    // The engine reports 0 kg/s when it has no rate; say "no value" the same way as the rate.
    w.key("discharge_rate_kg_s");
    if (r.discharge_rate)
        w.value(r.discharge_rate_mass);
    else
        w.null();
    w.field("steps", r.diagnostics.steps);
    w.field("wall_seconds", r.diagnostics.wall_seconds);
    w.field("ns_per_particle_step", r.diagnostics.ns_per_particle_step);
    w.key("diagnostics");
    write_diagnostics(w, r.diagnostics);
    w.key("discharge_curve").begin_object();
    w.field_array("time", r.curve_time);
    w.field_array("in_hopper", r.curve_count);
    w.end_object();
    w.field_array("exit_times", r.exit_times);
    w.key("events").begin_array();
    for (const auto& e : r.events) {
        w.begin_object_inline();
        w.field("kind", engine::to_string(e.kind));
        w.field("time", e.time);
        w.field("sim_time", e.sim_time);
        w.field("in_hopper", e.in_hopper);
        w.end_object();
    }
    w.end_array();
    if (r.fields) {  // only when the scene samples fields: otherwise the output is unchanged
        w.key("fields").begin_object_inline();
        write_fields_summary(w, *r.fields);
        w.end_object();
    }
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
