#pragma once
// The protocol's state (private to the engine; docs/model.md, realization steps 2-9): what a
// realization carries from one time step to the next besides the System and the result so far.
// It is described once (describe, below), and the checkpoint walks that description both ways
// (realization_state.cpp), so a member added here and to describe() is saved and restored.

#include <array>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <type_traits>

#include "hopper/core/random.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/engine/realization.hpp"
#include "observers.hpp"

namespace hopper::engine::detail {

// What the realization was asked for, checked (validate_scene), and the constants derived from
// it. A base of Realization::Impl so that it exists before the protocol's state is built.
struct Setup {
    explicit Setup(const SceneParams& params) : p(checked(params)), c(derive_constants(p)) {}
    static const SceneParams& checked(const SceneParams& params) {
        validate_scene(params);
        return params;
    }
    SceneParams p;
    DerivedConstants c;
};

struct ProtocolState {
    using Clock = std::chrono::steady_clock;
    using Flow = JamDetector::Flow;

    ProtocolState(const SceneParams& p, double dt, std::uint64_t seed)
        : rng(seed), det(p), shaker(p, dt), wall_start(Clock::now()) {}

    // The realization's generator: the fill, then (steady state) the re-inserted positions.
    core::Rng rng;
    JamDetector det;
    Shaker shaker;
    DischargeLog log_;
    Reinserter reinserter;
    Phase phase = Phase::settle;
    Clock::time_point wall_start;
    double particle_steps = 0.0;
    double td = 0.0;  // discharge time: since the opening, shaking excluded
    std::int64_t step_count = 0;
    double next_snapshot = 0.0, next_progress = 0.0;  // sim times of the next hook calls
    // Settling: simulated time since which the kinetic energy has stayed below the threshold
    // (-1: it is above).
    double below_since = -1.0;
    // Particles that had left (crossed the outlet plane) when the current avalanche began: at
    // the opening, then at each jam's detection.
    int interval_base = 0;
};

// The description, in the state format's byte order (formats 2 and 3 alike): the phase and the
// detector's clocks, the shake, the discharge log's exits, the observers' schedules, the
// settling clock, the avalanche base, the steady state's insertion height and its generator.
// Io is StatePut (S const) or StateGet (checkpoint.hpp).
template <class Io, class S>
requires std::same_as<std::remove_const_t<S>, ProtocolState>
void describe(Io& io, S& s) {
    using Clock = ProtocolState::Clock;
    io.enumeration(s.phase, Phase::shake);
    io.enumeration(s.det.flow, ProtocolState::Flow::ended);
    io.template as<double>(  // the wall time so far (a resumed run's clock continues from it)
        s.wall_start,
        [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); },
        [](double elapsed) {
            return Clock::now() - std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(elapsed));
        });
    io(s.particle_steps);
    io(s.td);
    io(s.det.flow_start);
    io(s.det.last_occupied);
    io(s.det.check_start);
    io(s.shaker.shake_start);
    io(s.shaker.shakes_this_jam);
    io.list(s.det.jammed, 16, [&](auto& on_off) {
        io(on_off.first);
        io(on_off.second);
    });
    io(s.log_.exit_mass);
    io(s.step_count);
    io(s.next_snapshot);
    io(s.next_progress);
    io(s.below_since);
    io(s.interval_base);  // issue 13
    io(s.reinserter.insert_base);
    using Words = std::array<std::uint64_t, 4>;
    io.template as<Words>(
        s.rng,
        [](const core::Rng& g) {
            Words w{};
            g.state(w.data());
            return w;
        },
        [&](const Words& w) {
            core::Rng g = s.rng;
            g.set_state(w.data());
            return g;
        });
}

}  // namespace hopper::engine::detail
