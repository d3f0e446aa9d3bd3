#pragma once
// What one realization reports (docs/model.md, "What each realization reports").
// Times are seconds of discharge time (shaking excluded) unless stated otherwise.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hopper/engine/arch.hpp"
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
    // The force pass that ran (to_string(KernelPath): reference, baseline, avx2, avx512). Every
    // path gives the same bits; this says which one a node used (issue 12). Set when the
    // realization ends (not kept in checkpoints: a resumed piece reports its own node's).
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

}  // namespace hopper::engine
