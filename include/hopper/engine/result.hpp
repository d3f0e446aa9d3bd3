#pragma once
// What one realization reports (docs/model.md, "What each realization reports").
// Times are seconds of discharge time (shaking excluded) unless stated otherwise.

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "hopper/engine/arch.hpp"
#include "hopper/engine/field_def.hpp"
#include "hopper/engine/fields.hpp"

namespace hopper::engine {

enum class Status {
    complete,    // the hopper emptied
    arrested,    // a jam could not be cleared by max_shakes shakes
    time_limit,  // max_time of discharge reached
    failed,      // numerical failure; message says why and what to change
};

std::string to_string(Status s);

// One entry of a realization's event log.
struct Event {
    enum class Kind { settled, opened, jam, shake_start, shake_end, flow_restart, empty, stop };
    Kind kind;
    double time;      // discharge time (shaking excluded)
    double sim_time;  // total simulated time since the fill (settling and shaking included)
    int in_hopper;    // particles left in the hopper at that moment
};

std::string to_string(Event::Kind k);

// The numbers of the diagnostics: a plain block of numbers (a checkpoint copies it as bytes).
struct DiagnosticNumbers {
    std::int64_t steps = 0;  // all steps (settle + discharge + shaking)
    std::int64_t settle_steps = 0;
    std::int64_t neighbor_rebuilds = 0;
    double particle_steps = 0.0;  // sum over steps of the mobile particles integrated
    double settle_time = 0.0;     // simulated seconds of settling
    double shake_time = 0.0;      // simulated seconds spent shaking
    double wall_seconds = 0.0;    // wall-clock time of the whole realization
    double ns_per_particle_step = 0.0;
    double max_overlap_ratio = 0.0;          // largest overlap seen / d_small
    double settled_kinetic_energy = 0.0;     // J, mean per particle when settled
    double potential_energy_released = 0.0;  // J, m g dy of all particles, fill to end
    double dt = 0.0;
    double tau_c = 0.0;
    double k_n = 0.0;
    // Wall-clock split by phase (seconds).
    double seconds_forces = 0.0;
    double seconds_integration = 0.0;
    double seconds_neighbors = 0.0;
    double seconds_observers = 0.0;
};

struct Diagnostics : DiagnosticNumbers {
    // The force pass that ran (to_string(KernelPath): reference, baseline, avx2, avx512,
    // avx512-gather). Every path gives the same bits; this says which one a node used (issue
    // 12). Set when the realization ends (not kept in checkpoints: a resumed piece reports its
    // own node's).
    std::string force_path;
};

struct RealizationResult {
    Status status = Status::failed;
    std::string message;
    std::uint64_t seed = 0;
    int particles = 0;       // N at the fill
    int wall_particles = 0;  // immobile particles (after the outlet opened)
    // Survival intervals in order; the last one is right-censored when the hopper emptied,
    // or when the realization stopped for another reason while flowing.
    std::vector<double> survival_times;
    std::vector<bool> censored;
    std::vector<double> jam_onsets;   // discharge time of each jam's onset
    std::vector<int> shakes_per_jam;  // shakes used on each jam (same length as jam_onsets)
    // Avalanche size of each survival interval: the particles that crossed the outlet plane
    // during it (same length as survival_times; the censored last one counts those until the
    // end). Empty in results stored before avalanche sizes existed (issue 13).
    std::vector<int> avalanche_sizes;
    // The arch that blocked the outlet at each jam (same length as jam_onsets; an arch that
    // was not found has no disks). Empty in results stored before arches existed.
    std::vector<Arch> arches;
    // The height of each jam's arch: its highest disk centre above the outlet plane (m; 0: no
    // arch found). Same length as jam_onsets; empty in results stored before it existed.
    std::vector<double> arch_heights;
    int n_jams = 0;
    int n_shakes = 0;
    int n_jams_multi_shake = 0;            // jams that needed more than one shake
    std::optional<double> empty_time;      // set only when the hopper emptied
    std::optional<double> discharge_rate;  // particles/s over the steady part
    double discharge_rate_mass = 0.0;      // kg/s over the steady part (0 when no rate)
    int discharged = 0;
    std::vector<double> exit_times;  // discharge time at which each particle left
    // Discharge curve: particles in the hopper sampled every sample_interval of discharge time.
    std::vector<double> curve_time;
    std::vector<int> curve_count;
    std::vector<Event> events;
    Diagnostics diagnostics;
    // Coarse-grained fields of the discharge; present only when SceneParams::fields.enabled.
    std::optional<FieldMoments> fields;
};

// ---------------------------------------------------------------------------------------------
// The result described once (field_def.hpp): every member of RealizationResult, its Diagnostics
// and Event with its name, units and description, in the journal's byte order, which must not
// change: a member added later goes at the end with `since` the next result format version
// (result_version below says which version a result needs). A new per-jam observable is a
// member above, one line here, and the protocol that fills it.

// Calls v(def) for every member of Diagnostics, in declaration order.
template <class V>
constexpr void for_each_diagnostic(V&& v) {
    using D = Diagnostics;
    v(field("steps", &D::steps, "1", "time steps (settle + discharge + shaking)"));
    v(field("settle_steps", &D::settle_steps, "1", "time steps while settling"));
    v(field("neighbor_rebuilds", &D::neighbor_rebuilds, "1", "neighbour list rebuilds"));
    v(placed(field("particle_steps", &D::particle_steps, "1",
                   "sum over steps of the mobile particles integrated"),
             Placement::nowhere));
    v(field("settle_time", &D::settle_time, "s", "simulated time spent settling"));
    v(field("shake_time", &D::shake_time, "s", "simulated time spent shaking"));
    v(timed(field("wall_seconds", &D::wall_seconds, "s",
                  "wall-clock time of the realization (not reproducible)")));
    v(timed(field("ns_per_particle_step", &D::ns_per_particle_step, "ns",
                  "wall-clock cost per particle and step")));
    v(field("max_overlap_ratio", &D::max_overlap_ratio, "d_small",
            "largest overlap seen / d_small"));
    v(field("settled_kinetic_energy", &D::settled_kinetic_energy, "J",
            "mean kinetic energy per particle when settled"));
    v(field("potential_energy_released", &D::potential_energy_released, "J",
            "m g dy of all particles, fill to end"));
    v(field("dt", &D::dt, "s", "time step"));
    v(field("tau_c", &D::tau_c, "s", "contact duration used"));
    v(field("k_n", &D::k_n, "N/m", "normal spring constant"));
    v(timed(field("seconds_forces", &D::seconds_forces, "s", "wall-clock time in force loops")));
    v(timed(
        field("seconds_integration", &D::seconds_integration, "s", "wall-clock time integrating")));
    v(timed(field("seconds_neighbors", &D::seconds_neighbors, "s",
                  "wall-clock time in neighbour search")));
    v(timed(
        field("seconds_observers", &D::seconds_observers, "s", "wall-clock time in observers")));
    // Issue 12: which machine-dependent code ran, like the timings above (the bits do not depend
    // on it), so it is left out of the physics digest.
    v(timed(since(
        field(
            "force_path", &D::force_path, "",
            "force pass that ran: reference, baseline, avx2, avx512 or avx512-gather (same bits)"),
        4)));
}

// Calls v(def) for every member of an Event, in declaration order (the store's columns are
// event_<name>).
template <class V>
constexpr void for_each_event_field(V&& v) {
    using E = Event;
    v(field("kind", &E::kind, "1", "event log: what happened"));
    v(field("time", &E::time, "s", "event log: discharge time (shaking excluded)"));
    v(field("sim_time", &E::sim_time, "s", "event log: simulated time since the fill"));
    v(field("in_hopper", &E::in_hopper, "1", "event log: particles left in the hopper"));
}

// Calls v(def) for every member of RealizationResult, in the journal's order.
template <class V>
constexpr void for_each_result_field(V&& v) {
    using R = RealizationResult;
    v(field("status", &R::status, "1", "how the realization ended"));
    v(field("message", &R::message, "", "the engine's message (the reason when failed)"));
    v(placed(field("seed", &R::seed, "1", "random seed of the realization"), Placement::record));
    v(field("particles", &R::particles, "1", "N at the fill"));
    v(field("wall_particles", &R::wall_particles, "1", "immobile wall particles"));
    v(in(field("survival_times", &R::survival_times, "s",
               "survival intervals in order (discharge time)"),
         Family::survival));
    v(in(field("censored", &R::censored, "1", "whether each survival interval is right-censored"),
         Family::survival));
    v(in(field("jam_onsets", &R::jam_onsets, "s", "discharge time of each jam's onset"),
         Family::jam));
    v(in(field("shakes_per_jam", &R::shakes_per_jam, "1", "shakes used on each jam"), Family::jam));
    v(field("n_jams", &R::n_jams, "1", "jams"));
    v(field("n_shakes", &R::n_shakes, "1", "shakes"));
    v(field("n_jams_multi_shake", &R::n_jams_multi_shake, "1",
            "jams that needed more than one shake"));
    v(field("empty_time", &R::empty_time, "s",
            "discharge time until the hopper was empty (shaking excluded); 0 when "
            "has_empty_time is false"));
    v(field("discharge_rate", &R::discharge_rate, "1/s",
            "particles per second over the steady part; 0 when has_discharge_rate is false"));
    v(field("discharge_rate_mass", &R::discharge_rate_mass, "kg/s",
            "mass discharge rate over the steady part (0: none)"));
    v(field("discharged", &R::discharged, "1", "particles that left the hopper"));
    v(in(field("exit_times", &R::exit_times, "s", "discharge time at which each particle left"),
         Family::exit));
    v(in(field("curve_time", &R::curve_time, "s", "discharge curve: sample times (discharge time)"),
         Family::curve));
    v(in(field("curve_count", &R::curve_count, "1", "discharge curve: particles in the hopper"),
         Family::curve, "curve_in_hopper"));
    v(in(field("events", &R::events, "1", "event log"), Family::event));
    v(field("diagnostics", &R::diagnostics, "", "engine diagnostics"));
    // Issue 7: journaled from version 2 on, when present; the store file has /fields/<row>.
    v(placed(since(field("fields", &R::fields, "", "coarse-grained fields of the discharge"), 2),
             Placement::own));
    // Issue 13: absent in results stored before (read with none).
    v(since(in(field("avalanche_sizes", &R::avalanche_sizes, "1",
                     "particles that crossed the outlet plane during each survival interval (0 "
                     "when has_avalanche_sizes is false)"),
               Family::survival, "avalanche_size"),
            3));
    v(placed(
        since(field("arches", &R::arches, "", "the arch that blocked the outlet at each jam"), 3),
        Placement::own));
    // Issue 42: the first member added through the description alone (format 5).
    v(since(in(field("arch_heights", &R::arch_heights, "m",
                     "height of each jam's arch: its highest disk centre above the outlet plane "
                     "(0: no arch found)"),
               Family::jam),
            5));
}

// The result format version a result needs: the largest `since` of the members it holds (a
// vector or string not empty, an optional set, a struct holding one). Results that hold no
// later member keep the bytes of the version they would have had before it existed.
template <class T>
constexpr bool holds_value(const T& v) {
    if constexpr (requires { v.empty(); })
        return !v.empty();
    else if constexpr (requires { v.has_value(); })
        return v.has_value();
    else
        return true;
}
inline std::uint16_t result_version(const RealizationResult& r) {
    std::uint16_t v = 1;
    for_each_result_field([&](const auto& f) {
        if (f.placement == Placement::nowhere) return;
        if constexpr (std::is_same_v<std::remove_cvref_t<decltype(r.*f.member)>, Diagnostics>) {
            for_each_diagnostic([&](const auto& d) {
                if (d.placement != Placement::nowhere && holds_value(r.diagnostics.*d.member))
                    v = std::max(v, d.since);
            });
        } else if (holds_value(r.*f.member)) {
            v = std::max(v, f.since);
        }
    });
    return v;
}
// The number of elements of a ragged family in a result: the length of its first array (every
// array of the family has one value per element); none for the families kept otherwise.
inline std::optional<std::size_t> family_length(const RealizationResult& r, Family f) {
    switch (f) {
        case Family::survival:
            return r.survival_times.size();
        case Family::jam:
            return r.jam_onsets.size();
        case Family::exit:
            return r.exit_times.size();
        case Family::curve:
            return r.curve_time.size();
        default:
            return std::nullopt;
    }
}

// A realization resumed from a state written before a member existed has no values of it for
// the elements before the state: such an array (of a later member, not as long as its family)
// is left out, and the result reads as one stored before the member existed.
inline void drop_incomplete_arrays(RealizationResult& r) {
    for_each_result_field([&](const auto& f) {
        using M = std::remove_cvref_t<decltype(r.*f.member)>;
        if constexpr (requires(M & v) {
                          v.clear();
                          v.size();
                      } &&
                      !std::is_same_v<M, std::string>) {
            const auto n = family_length(r, f.family);
            if (f.since > 1 && n && (r.*f.member).size() != *n) (r.*f.member).clear();
        }
    });
}

// The newest result format version (the largest `since` of any member).
inline constexpr std::uint16_t result_format_version = [] {
    std::uint16_t v = 1;
    for_each_result_field([&](const auto& f) { v = std::max(v, f.since); });
    for_each_diagnostic([&](const auto& f) { v = std::max(v, f.since); });
    return v;
}();

}  // namespace hopper::engine
