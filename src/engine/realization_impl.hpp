#pragma once
// The realization's protocol (private to the engine): Realization::Impl, whose steps are
// protocol.cpp's, its checkpoint realization_state.cpp's, its public face realization.cpp's.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hopper/engine/arch.hpp"
#include "hopper/engine/checkpoint.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"
#include "observers.hpp"
#include "protocol_state.hpp"

namespace hopper::engine {

namespace detail {
// The System's configuration for a scene: time step, scheme, skin, the contact laws' constants.
SystemConfig system_config(const SceneParams& p, const DerivedConstants& c, KernelPath kernel);
}  // namespace detail

// The protocol (docs/model.md, realization steps 2-9): settle, open, then advance the
// discharge, whose observers (observers.hpp) run from one trigger list after every time step.
// What changes from step to step is the System, the result so far and the ProtocolState (its
// base); what is fixed is the Setup (its other base) and the members below.
struct Realization::Impl : detail::Setup, detail::ProtocolState {
    Impl(const SceneParams& params, std::uint64_t seed, RunHooks h);

    // ----- the protocol's phases (protocol.cpp) -------------------------------------------
    void settle();                 // step 2: until the packing is at rest
    void open();                   // step 3: the gate goes
    bool advance(double seconds);  // steps 3-9: the discharge, `seconds` of it at most
    RealizationResult result() const;
    void fail(const std::string& why);
    bool ended() const { return det.flow == Flow::ended; }

    // ----- checkpoints (checkpoint.hpp; realization_state.cpp) ---------------------------
    std::vector<std::uint8_t> save_state() const;
    void restore_state(std::span<const std::uint8_t> bytes);

    RunHooks hooks;
    RealizationResult res;
    std::unique_ptr<System> sys;
    std::vector<int> gate_ids;
    detail::IdTable ids;
    detail::FieldsObserver fields;
    // What happens to a particle that leaves, chosen once: re-insertion in the steady state,
    // nothing otherwise (empty).
    std::function<void(int)> on_exit;
    // Observer schedule (steps between looks).
    std::int64_t k_detect = 1, k_sample = 1, k_settle = 1;
    double ke_limit = 0.0;  // mean KE per particle beyond which we call it a blow-up
    double wall_top = 0.0;
    std::vector<Vec2> outline;

  private:
    // After every discharge step, each trigger whose period divides the step count runs, in
    // advance()'s order; one that returns false ends advance() at once (a requested stop).
    struct Trigger {
        std::int64_t period;
        bool (Impl::*run)();
    };
    bool record_removals();
    bool look();
    bool sample_fields();
    bool sample();

    // The discharge's events (steps 4-9).
    void on_jam();
    void unjam();
    void remove_arch();
    void refill();
    void start_shake();
    void finish_shake();
    void arrest();
    void enough_jams();
    void check_end();
    void censor_final_interval(double t_end);
    void end_run(Event::Kind kind);

    // One time step, with the hooks' snapshots and progress.
    void step();
    void snapshot();
    void maybe_checkpoint();
    bool stop_requested() const { return hooks.stop && hooks.stop->load(); }
    void log(Event::Kind kind);
    void sample_curve();
    double mean_ke() const;
    void check_energy();
    // Particles that have crossed the outlet plane: those removed plus those still falling.
    int left_count() const;
    // The arch over the outlet now (arch.hpp), from the disks near the outlet.
    Arch current_arch() const;
    std::vector<ArchDisk> near_outlet() const;

    void put_fingerprint(StateWriter& w) const;
    void check_fingerprint(StateReader& r) const;
    void remember_reinserted();
    void put_lid();  // the lid's load band, from the insertion height (protocol.cpp)
};

}  // namespace hopper::engine
