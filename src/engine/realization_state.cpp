// The realization's checkpoint: its whole state to bytes and back (checkpoint.hpp): the
// fingerprint, the protocol's state (protocol_state.hpp), the result so far, the System and the
// fields, each walked by its description; the order is the state format (state_format_version).
#include <algorithm>
#include <sstream>

#include "hopper/core/error.hpp"
#include "realization_impl.hpp"

namespace hopper::engine {

// What a state must agree on with the realization it is restored into.
void Realization::Impl::put_fingerprint(StateWriter& w) const {
    w.put(res.seed);
    w.put(p.particles.count);
    w.put(static_cast<std::int32_t>(p.integrator.scheme));
    w.put(c.dt);
    w.put(c.k_n);
    w.put<std::uint8_t>(p.fields.enabled);
}

void Realization::Impl::check_fingerprint(StateReader& r) const {
    std::ostringstream why;
    const auto seed = r.get<std::uint64_t>();
    const auto count = r.get<int>();
    const auto scheme = r.get<std::int32_t>();
    const auto dt = r.get<double>();
    const auto k_n = r.get<double>();
    const bool fields_on = r.get<std::uint8_t>() != 0;
    if (seed != res.seed) why << " seed " << seed << " (this realization: " << res.seed << ")";
    if (count != p.particles.count)
        why << " particles " << count << " (this realization: " << p.particles.count << ")";
    if (scheme != static_cast<std::int32_t>(p.integrator.scheme)) why << " another integrator";
    if (dt != c.dt) why << " dt " << dt << " s (this realization: " << c.dt << " s)";
    if (k_n != c.k_n) why << " k_n " << k_n << " N/m (this realization: " << c.k_n << " N/m)";
    if (fields_on != p.fields.enabled)
        why << " fields " << (fields_on ? "on" : "off")
            << " (this realization: " << (p.fields.enabled ? "on" : "off") << ")";
    if (!why.str().empty())
        throw core::ConfigError("the checkpoint belongs to another realization:" + why.str());
}

// The id table is built with the fill and not saved: particles re-inserted by the steady state
// before the checkpoint have ids beyond it. Each is a copy of a fill particle (same mass and
// diameter, reinsert in observers.cpp), so its inertia is that fill particle's.
void Realization::Impl::remember_reinserted() {
    struct Kind {
        double m, d, inertia;
    };
    std::vector<Kind> kinds;
    for (std::size_t id = 0; id < ids.mass.size(); ++id) {
        if (!(ids.mass[id] > 0.0)) continue;
        const Kind k{ids.mass[id], ids.diameter[id], ids.inertia[id]};
        if (std::none_of(kinds.begin(), kinds.end(), [&](const Kind& o) {
                return o.m == k.m && o.d == k.d && o.inertia == k.inertia;
            }))
            kinds.push_back(k);
    }
    const auto idv = sys->ids();
    const auto m = sys->m();
    const auto rad = sys->r();
    for (std::size_t i = 0; i < idv.size(); ++i) {
        const auto id = std::size_t(idv[i]);
        if (id < ids.mass.size() && ids.mass[id] > 0.0) continue;
        const double d = 2.0 * rad[i];
        const auto k = std::find_if(kinds.begin(), kinds.end(),
                                    [&](const Kind& o) { return o.m == m[i] && o.d == d; });
        if (k == kinds.end())
            throw core::ConfigError(
                "the checkpoint's state is inconsistent (a particle of a mass and diameter no "
                "particle of the fill has); it cannot be continued");
        ids.remember(int(id), k->m, k->d, k->inertia);
    }
}

std::vector<std::uint8_t> Realization::Impl::save_state() const {
    StateWriter w;
    w.put_string("HOPPERRS");
    w.put(state_format_version);
    put_fingerprint(w);
    StatePut io(w);
    detail::describe(io, static_cast<const detail::ProtocolState&>(*this));
    save_result(res, w);
    CheckpointAccess::save(*sys, w);
    w.put<std::uint8_t>(fields.active());
    if (fields.active()) CheckpointAccess::save(*fields.acc, w);
    return w.take();
}

void Realization::Impl::restore_state(std::span<const std::uint8_t> bytes) {
    static const std::uint8_t magic[16] = {8,   0,   0,   0,   0,   0,   0,   0,
                                           'H', 'O', 'P', 'P', 'E', 'R', 'R', 'S'};
    if (bytes.size() < 16 || !std::equal(magic, magic + 16, bytes.begin()))
        throw core::ConfigError("the checkpoint is not a hopper realization state");
    StateReader r(bytes);
    r.get_string();
    const auto version = r.get<std::uint32_t>();
    if (version < oldest_state_format_read || version > state_format_version)
        throw core::ConfigError("the checkpoint has state format " + std::to_string(version) +
                                "; this engine reads formats " +
                                std::to_string(oldest_state_format_read) + " to " +
                                std::to_string(state_format_version));
    check_fingerprint(r);
    StateGet io(r);
    detail::describe(io, static_cast<detail::ProtocolState&>(*this));
    restore_result(res, r, version);
    CheckpointAccess::restore(*sys, r);
    // The saved derivatives are scaled to the phase's own step (integrator.settle_steps_per_
    // collision while settling): taken as they are.
    sys->set_time_step(phase == Phase::settle ? c.settle_dt : c.dt, false);
    remember_reinserted();
    if (phase != Phase::settle) put_lid();
    fields.acc.reset();
    if (r.get<std::uint8_t>()) {
        if (!p.fields.enabled) StateReader::fail();
        fields.start(p, c.dt, wall_top, outline);  // the grid and period; the state below
        CheckpointAccess::restore(*fields.acc, r);
    }
    if (!r.at_end()) StateReader::fail();
}

}  // namespace hopper::engine
