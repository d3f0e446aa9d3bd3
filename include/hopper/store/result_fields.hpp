#pragma once
// The result record described once: every member of engine::RealizationResult (and of its
// Diagnostics and Event) with its name, units and description, in the order of the journal's
// encoding. The codec (codec.cpp), the HDF5 columns of /realizations and /ragged (columns.cpp)
// and the JSON of `campaign simulate` (cli/result_output.cpp) are all driven by these lists:
// each visits the fields and handles them by their C++ type, so a field added here reaches the
// journal, the store file and the JSON without another list to edit. What differs between the
// three is written beside the field (since: the codec version that added it; column: its HDF5
// name when that is not its name; family: the ragged family of an array in the store file).
//
// The order is the journal's byte order and must not change: a new field goes at the end with
// the codec version that adds it (codec.hpp).

#include <cstdint>
#include <string_view>

#include "hopper/engine/result.hpp"

namespace hopper::store {

// The ragged families of the store file (/realizations/<family>_start and _length): the arrays
// of one family have one value per element of its first array.
enum class Family : std::int8_t { none = -1, survival, jam, exit, curve, event, arch, arch_disk };

// Where a member goes in the store file.
enum class Placement : std::int8_t {
    column,   // /realizations (scalars), /realizations/diagnostics or /ragged (arrays)
    record,   // a column of the result's record (the seed: /realizations/seed)
    own,      // its own layout (the fields: /fields/<row>; the arches: the arch families)
    nowhere,  // reported by `campaign simulate` only, neither journaled nor stored
};

template <class Owner, class Member>
struct FieldDef {
    std::string_view name;  // JSON key; HDF5 column unless `column` is set
    Member Owner::*member;
    std::string_view units;
    std::string_view description;
    std::uint16_t since = 1;  // result codec version that added it
    Family family = Family::none;
    std::string_view column = {};
    Placement placement = Placement::column;
    bool wall_clock = false;  // a wall-clock measurement: differs between two runs of a realization

    std::string_view column_name() const { return column.empty() ? name : column; }
};

template <class Owner, class Member>
constexpr FieldDef<Owner, Member> field(std::string_view name, Member Owner::*member,
                                        std::string_view units, std::string_view description) {
    return {name, member, units, description};
}

// Copies of `f` with one property changed.
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> in(FieldDef<Owner, Member> f, Family family,
                                     std::string_view column = {}) {
    f.family = family;
    f.column = column;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> since(FieldDef<Owner, Member> f, std::uint16_t version) {
    f.since = version;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> timed(FieldDef<Owner, Member> f) {
    f.wall_clock = true;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> placed(FieldDef<Owner, Member> f, Placement p) {
    f.placement = p;
    return f;
}

// Calls v(def) for every member of Diagnostics, in declaration order.
template <class V>
constexpr void for_each_diagnostic(V&& v) {
    using D = engine::Diagnostics;
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
    v(timed(since(field("force_path", &D::force_path, "",
                        "force pass that ran: reference, baseline, avx2 or avx512 (same bits)"),
                  4)));
}

// Calls v(def) for every member of an Event, in declaration order (the store's columns are
// event_<name>).
template <class V>
constexpr void for_each_event_field(V&& v) {
    using E = engine::Event;
    v(field("kind", &E::kind, "1", "event log: what happened"));
    v(field("time", &E::time, "s", "event log: discharge time (shaking excluded)"));
    v(field("sim_time", &E::sim_time, "s", "event log: simulated time since the fill"));
    v(field("in_hopper", &E::in_hopper, "1", "event log: particles left in the hopper"));
}

// Calls v(def) for every member of RealizationResult, in the journal's order.
template <class V>
constexpr void for_each_result_field(V&& v) {
    using R = engine::RealizationResult;
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
}

}  // namespace hopper::store
