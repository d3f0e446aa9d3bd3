#pragma once
// One realization of the hopper: fill, settle, discharge, jam detection, shaking, survival and
// empty times (docs/model.md, realization protocol). This is the engine's main entry point.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "hopper/engine/params.hpp"
#include "hopper/engine/result.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine {

enum class Phase { settle, discharge, shake };
std::string_view to_string(Phase p);

// A read-only view of the particles, handed to snapshot callbacks (valid during the call only).
struct Snapshot {
    Phase phase;
    double sim_time;        // s since the fill
    double discharge_time;  // s since the opening, shaking excluded (0 while settling)
    std::span<const int> id;
    std::span<const double> x, y, vx, vy, omega, radius;
    std::span<const double> wall_x, wall_y, wall_radius;  // current wall positions
    // Sum of |F_n| over each particle's current contacts (N; System::normal_force_sums), per
    // mobile particle and per wall particle.
    std::span<const double> contact_force, wall_contact_force;
};

struct Progress {
    Phase phase;
    double sim_time;
    double discharge_time;
    int in_hopper;
    int n_jams;
};

struct RunHooks {
    // Snapshots every snapshot_interval seconds of simulated time (0 = never).
    double snapshot_interval = 0.0;
    std::function<void(const Snapshot&)> on_snapshot;
    // Progress every progress_interval seconds of simulated time (0 = never).
    double progress_interval = 0.0;
    std::function<void(const Progress&)> on_progress;
    // Cooperative stop: when set, the realization ends with status failed and a message saying
    // it was interrupted (callers treat it as not done).
    const std::atomic<bool>* stop = nullptr;
    // The force pass (system.hpp). How to run, not what: every path gives the same bits.
    KernelPath kernel = KernelPath::automatic;
    // Checkpoints (checkpoint.hpp): when *checkpoint_request is true at the start of a time step
    // (every step is looked at; a relaxed atomic load), the realization clears it, saves its
    // whole state and hands the bytes to on_checkpoint. The callback may throw to end the
    // realization there (the worker does, to stop right after the checkpoint of a drain).
    std::atomic<bool>* checkpoint_request = nullptr;
    std::function<void(std::vector<std::uint8_t>&&)> on_checkpoint;
};

// One realization, phase by phase (for benchmarks and tests; run_realization() composes them).
// Construction builds the scene and the fill. Numerical failures (core::SimulationError) are
// recorded, not thrown: after one, every further call does nothing and result() says failed.
class Realization {
  public:
    Realization(const SceneParams& params, std::uint64_t seed, RunHooks hooks = {});
    ~Realization();
    Realization(const Realization&) = delete;
    Realization& operator=(const Realization&) = delete;

    // Settles the packing with the outlet closed until it is at rest (realization step 2).
    void settle();
    // Removes the gate: discharge starts, t = 0 (step 3).
    void open();
    // Runs the discharge protocol (steps 3-7) for up to `discharge_seconds` of discharge time
    // (shaking excluded). Returns false once the realization has ended.
    bool advance(double discharge_seconds);
    bool finished() const;
    // The result so far (final once finished()).
    RealizationResult result() const;
    System& system();
    Phase phase() const;

    // The whole state as bytes (checkpoint.hpp), taken between two time steps. restore_state
    // replaces the state of a realization constructed with the same parameters and seed; it
    // throws core::ConfigError when the bytes belong to another realization, another engine
    // format or are damaged (the realization is then unchanged only in the first two cases).
    std::vector<std::uint8_t> save_state() const;
    void restore_state(std::span<const std::uint8_t> bytes);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Runs one realization. Never throws for numerical trouble: that ends with Status::failed and a
// message naming the cause and the remedy. Throws core::ConfigError for invalid parameters.
RealizationResult run_realization(const SceneParams& params, std::uint64_t seed,
                                  const RunHooks& hooks = {});
// The same realization continued from a state saved by save_state (a checkpoint): the result is
// bit-identical to that of run_realization. Throws core::ConfigError when the state does not
// belong to this realization (restore_state).
RealizationResult resume_realization(const SceneParams& params, std::uint64_t seed,
                                     std::span<const std::uint8_t> state,
                                     const RunHooks& hooks = {});

}  // namespace hopper::engine
