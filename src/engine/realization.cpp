#include "hopper/engine/realization.hpp"

#include <limits>

#include "hopper/core/error.hpp"
#include "realization_impl.hpp"

namespace hopper::engine {

std::string to_string(Status s) {
    switch (s) {
        case Status::complete:
            return "complete";
        case Status::arrested:
            return "arrested";
        case Status::time_limit:
            return "time_limit";
        case Status::failed:
            return "failed";
    }
    return "unknown";
}

std::string to_string(Event::Kind k) {
    switch (k) {
        case Event::Kind::settled:
            return "settled";
        case Event::Kind::opened:
            return "opened";
        case Event::Kind::jam:
            return "jam";
        case Event::Kind::shake_start:
            return "shake_start";
        case Event::Kind::shake_end:
            return "shake_end";
        case Event::Kind::flow_restart:
            return "flow_restart";
        case Event::Kind::empty:
            return "empty";
        case Event::Kind::stop:
            return "stop";
    }
    return "unknown";
}

std::string_view to_string(Phase p) {
    switch (p) {
        case Phase::settle:
            return "settle";
        case Phase::discharge:
            return "discharge";
        case Phase::shake:
            return "shake";
    }
    return "unknown";
}

SystemConfig detail::system_config(const SceneParams& p, const DerivedConstants& c,
                                   KernelPath kernel) {
    SystemConfig sc;
    sc.kernel = kernel;
    sc.dt = c.dt;
    sc.scheme = p.integrator.scheme;
    sc.gravity = Vec2(0.0, -p.gravity);
    sc.skin = p.integrator.skin * p.particles.d_small;
    sc.max_overlap = p.protocol.max_overlap * p.particles.d_small;
    // k_t = kt_over_kn k_n, gamma_t = gamma_n / 2   (docs/model.md, tangential force; the
    // ratio is material.gamma_t_over_gamma_n, 0.5 by default)
    const double gt = p.material.gamma_t_over_gamma_n;
    const bool spring_only = p.material.slip_rule == SlipRule::spring_only;
    sc.particle = {c.k_n,      c.gamma_n_system, c.k_t, c.gamma_n_system * gt, p.material.system.mu,
                   spring_only};
    sc.wall = {c.k_n, c.gamma_n_wall, c.k_t, c.gamma_n_wall * gt, p.material.wall.mu, spring_only};
    sc.normal_law = p.material.normal_law;
    sc.tangential_law = p.material.tangential_law;
    sc.rolling = p.material.mu_r > 0.0;
    sc.rolling_spring = sc.rolling && p.material.rolling_law == RollingLaw::spring;
    sc.particle.mu_r = sc.wall.mu_r = p.material.mu_r;
    sc.plate_decel = p.material.plate_friction * p.gravity;
    sc.plate_speed = p.material.plate_speed;
    for (auto [cp, alpha] :
         {std::pair{&sc.particle, c.hertz_alpha_system}, std::pair{&sc.wall, c.hertz_alpha_wall}}) {
        cp->hertz_k = c.hertz_k;
        cp->hertz_alpha = alpha;
        cp->hertz_kt_ratio = p.material.kt_over_kn;
        cp->hertz_gt_ratio = gt;
    }
    sc.contact_lever = p.material.lever_arm == LeverArm::contact;
    sc.contact_corrections = p.integrator.contact_corrections;
    return sc;
}

Realization::Realization(const SceneParams& params, std::uint64_t seed, RunHooks hooks)
    : impl_(std::make_unique<Impl>(params, seed, std::move(hooks))) {}

Realization::~Realization() = default;

void Realization::settle() {
    if (impl_->ended()) return;
    try {
        impl_->settle();
    } catch (const core::SimulationError& e) {
        impl_->fail(std::string("while settling: ") + e.what());
    }
}

void Realization::open() {
    if (impl_->ended()) return;
    try {
        impl_->open();
    } catch (const core::SimulationError& e) {
        impl_->fail(std::string("at opening: ") + e.what());
    }
}

bool Realization::advance(double discharge_seconds) {
    if (impl_->ended()) return false;
    try {
        return impl_->advance(discharge_seconds);
    } catch (const core::SimulationError& e) {
        impl_->fail(std::string("during discharge: ") + e.what());
        return false;
    }
}

bool Realization::finished() const {
    return impl_->ended();
}

RealizationResult Realization::result() const {
    return impl_->result();
}

System& Realization::system() {
    return *impl_->sys;
}

Phase Realization::phase() const {
    return impl_->phase;
}

std::vector<std::uint8_t> Realization::save_state() const {
    return impl_->save_state();
}

void Realization::restore_state(std::span<const std::uint8_t> bytes) {
    impl_->restore_state(bytes);
}

RealizationResult run_realization(const SceneParams& params, std::uint64_t seed,
                                  const RunHooks& hooks) {
    Realization r(params, seed, hooks);
    r.settle();
    r.open();
    while (r.advance(std::numeric_limits<double>::infinity())) {
    }
    return r.result();
}

RealizationResult resume_realization(const SceneParams& params, std::uint64_t seed,
                                     std::span<const std::uint8_t> state, const RunHooks& hooks) {
    Realization r(params, seed, hooks);
    r.restore_state(state);
    // A state saved while settling continues the settling; one saved later is past the opening.
    if (r.phase() == Phase::settle) {
        r.settle();
        r.open();
    }
    while (r.advance(std::numeric_limits<double>::infinity())) {
    }
    return r.result();
}

}  // namespace hopper::engine
