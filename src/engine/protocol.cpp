// The realization's protocol (docs/model.md, realization steps 2-9), in the order it runs:
// the fill (the constructor), settle, open, and advance, the discharge loop, whose triggers
// watch the flow and whose events (a jam, a shake, the end) follow it. Its state between steps
// is the System, the result so far and the ProtocolState (protocol_state.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "hopper/core/error.hpp"
#include "hopper/engine/scene.hpp"
#include "realization_impl.hpp"

namespace hopper::engine {

// ----- the fill (step 1) ------------------------------------------------------------------
Realization::Impl::Impl(const SceneParams& params, std::uint64_t seed, RunHooks h)
    : Setup(params), ProtocolState(p, c.dt, seed), hooks(std::move(h)) {
    res.seed = seed;
    res.particles = p.particles.count;
    res.diagnostics.dt = c.dt;
    res.diagnostics.tau_c = c.tau_c;
    res.diagnostics.k_n = c.k_n;
    const SceneLayout layout = build_scene(p, rng);
    sys = std::make_unique<System>(detail::system_config(p, c, hooks.kernel));
    for (const auto& w : layout.walls)
        sys->add_wall(w.pos, w.diameter);
    for (const auto& w : layout.gate)
        gate_ids.push_back(sys->add_wall(w.pos, w.diameter));
    for (const auto& f : layout.fill) {
        double m = f.large ? c.m_large : c.m_small;
        double I = f.large ? c.I_large : c.I_small;
        if (p.particles.size_spread > 0.0) {  // m ~ d^2, I ~ m d^2 (hopper.size_spread)
            const double s = f.diameter / (f.large ? p.particles.d_large : p.particles.d_small);
            m *= s * s;
            I *= s * s * s * s;
        }
        const int id = sys->add_particle(f.pos, f.diameter, m, I, f.vel, 0.0);
        ids.remember(id, m, f.diameter, I);
    }
    res.wall_particles = sys->wall_count() - int(gate_ids.size());
    k_detect = detail::every(p.protocol.detector_interval, c.dt);
    k_sample = detail::every(p.protocol.sample_interval, c.dt);
    k_settle = detail::every(1e-3, c.settle_dt);
    // The settle's own time step (integrator.settle_steps_per_collision), set before the first
    // step: the priming scales Gear's derivatives to it. open() goes back to dt.
    sys->set_time_step(c.settle_dt);
    // Mean kinetic energy per particle can never exceed the potential energy of a fall from
    // the top of the walls to the removal floor (plus shaking); 100x that is a blow-up.
    const double drop =
        layout.wall_top - det.y_outlet + p.protocol.exit_depth * p.particles.d_large;
    ke_limit = 100.0 * c.m_large * p.gravity * drop;
    wall_top = layout.wall_top;
    outline = layout.outline;
    res.diagnostics.potential_energy_released = sys->potential_energy();
    if (p.protocol.mode == ProtocolMode::steady_state)
        on_exit = [this](int id) { reinserter.reinsert(id, p, *sys, ids, rng); };
}

// ----- settle (step 2) --------------------------------------------------------------------
void Realization::Impl::settle() {
    const double threshold = p.protocol.settle_ke * c.m_large * p.gravity * p.particles.d_large;
    while (true) {
        maybe_checkpoint();
        step();
        ++res.diagnostics.settle_steps;
        if (step_count % k_settle != 0) continue;
        if (stop_requested()) return fail("interrupted while settling (stop requested)");
        check_energy();
        const double ke = mean_ke();
        if (ke < threshold) {
            if (below_since < 0) below_since = sys->time();
            if (sys->time() - below_since >= p.protocol.settle_hold) break;
        } else {
            below_since = -1.0;
        }
        if (sys->time() > p.protocol.settle_max_time) {
            std::ostringstream msg;
            msg << "the packing did not come to rest within protocol.settle_max_time_s = "
                << p.protocol.settle_max_time << " s (mean kinetic energy " << ke
                << " J per particle, threshold " << threshold
                << " J); raise settle_max_time_s or settle_ke";
            return fail(msg.str());
        }
    }
    res.diagnostics.settle_time = sys->time();
    res.diagnostics.settled_kinetic_energy = mean_ke();
    log(Event::Kind::settled);
}

// ----- open (step 3) ----------------------------------------------------------------------
void Realization::Impl::open() {
    sys->set_time_step(c.dt);  // from the settle's own step, Gear's derivatives carried over
    sys->remove_walls(gate_ids);
    sys->set_removal_floor(det.y_outlet - p.protocol.exit_depth * p.particles.d_large);
    phase = Phase::discharge;
    det.flow = Flow::flowing;
    td = det.flow_start = det.last_occupied = 0.0;
    interval_base = left_count();
    reinserter.set_base(*sys, det.y_outlet);
    put_lid();
    log(Event::Kind::opened);
    sample_curve();
    if (p.fields.enabled) fields.start(p, c.dt, wall_top, outline);
}

// The lid (docs/model.md, "The lid"; steady state only, validate_scene): the disks between 1 and
// 1 + lid_depth large diameters below the insertion height weigh 1 + lid_gravity times as much.
// The band follows from insert_base, so a restored state puts it back (restore_state).
void Realization::Impl::put_lid() {
    if (!(p.protocol.lid_gravity > 0.0)) return;
    const double d = p.particles.d_large, top = reinserter.insert_base;
    sys->set_load_band(top - (1.0 + p.protocol.lid_depth) * d, top - d,
                       p.protocol.lid_gravity * p.gravity);
}

// ----- the discharge (steps 3-9) ----------------------------------------------------------
// One time step (the walls driven while a shake lasts), the discharge clock, the triggers in
// order (removals -> detector -> fields -> curve and guards), then the end conditions.
bool Realization::Impl::advance(double seconds) {
    if (ended()) return false;
    const double until = td + seconds;
    const std::array<Trigger, 4> triggers{{{1, &Impl::record_removals},
                                           {k_detect, &Impl::look},
                                           {fields.period, &Impl::sample_fields},
                                           {k_sample, &Impl::sample}}};
    while (!ended() && td < until) {
        maybe_checkpoint();
        if (det.flow == Flow::shaking) shaker.drive(*sys);
        step();
        if (det.flow == Flow::shaking) {
            res.diagnostics.shake_time += c.dt;
            if (shaker.done(sys->time())) finish_shake();
        } else {
            td += c.dt;
        }
        for (const Trigger& t : triggers)
            if (step_count % t.period == 0 && !(this->*t.run)()) return false;
        if (!ended()) check_end();
    }
    return !ended();
}

// ----- the triggers -----------------------------------------------------------------------
bool Realization::Impl::record_removals() {
    log_.record(*sys, td, ids, res, on_exit);
    return true;
}

bool Realization::Impl::look() {
    if (stop_requested()) {
        fail("interrupted (stop requested)");
        return false;
    }
    switch (det.look(*sys, td, c.t_check)) {
        case detail::JamDetector::Look::jammed:
            on_jam();
            break;
        case detail::JamDetector::Look::restarted:
            // The shake cleared the jam: a new survival interval starts at its end.
            log(Event::Kind::flow_restart);
            break;
        case detail::JamDetector::Look::still_jammed:
            if (shaker.shakes_this_jam >= p.protocol.max_shakes) {
                arrest();
            } else {
                unjam();
            }
            break;
        case detail::JamDetector::Look::nothing:
            break;
    }
    return true;
}

bool Realization::Impl::sample_fields() {
    if (fields.active() && det.flow != Flow::shaking && !ended()) fields.sample(p, *sys, td);
    return true;
}

bool Realization::Impl::sample() {
    check_energy();
    sys->flush_removals();
    record_removals();
    if (det.flow != Flow::shaking) sample_curve();
    return true;
}

// ----- the events -------------------------------------------------------------------------
// Jammed (steps 4, 6): the onset is the last moment the region held a particle. What a jam
// records per jam (the result's jam family, result.hpp) is appended here.
void Realization::Impl::on_jam() {
    const double onset = det.last_occupied;
    res.jam_onsets.push_back(onset);
    res.survival_times.push_back(onset - det.flow_start);
    res.censored.push_back(false);
    res.shakes_per_jam.push_back(0);
    ++res.n_jams;
    res.events.push_back({Event::Kind::jam, onset, sys->time(), sys->mobile_count()});
    // The next interval's avalanche starts here: particles that fall while shaking belong
    // to the flow the shake restarts.
    const int left = left_count();
    res.avalanche_sizes.push_back(left - interval_base);
    interval_base = left;
    res.arches.push_back(current_arch());
    const std::vector<double>& ay = res.arches.back().y;
    res.arch_heights.push_back(ay.empty() ? 0.0
                                          : *std::max_element(ay.begin(), ay.end()) - det.y_outlet);
    shaker.shakes_this_jam = 0;
    if (p.protocol.mode == ProtocolMode::steady_state && p.protocol.jams_per_realization > 0 &&
        res.n_jams >= p.protocol.jams_per_realization)
        return enough_jams();
    if (p.protocol.unjam == UnjamMode::refill) return refill();
    if (p.protocol.max_shakes == 0) return arrest();
    unjam();
}

// One try at clearing the jam (docs/model.md, step 5): a shake, or the arch's removal.
void Realization::Impl::unjam() {
    if (p.protocol.unjam == UnjamMode::remove_arch)
        remove_arch();
    else
        start_shake();
}

// protocol.unjam = remove_arch: the arch over the outlet (arch_removal, arch.hpp) leaves the
// hopper and its disks are re-inserted at the top as in the steady state; the detector then
// checks for t_check whether the flow restarted. Counted as one unjamming action
// (shakes_per_jam, n_shakes).
void Realization::Impl::remove_arch() {
    const std::vector<int> gone =
        arch_removal(near_outlet(), det.y_region, det.y_outlet, det.half_gap + p.particles.d_large);
    ++res.n_shakes;
    ++shaker.shakes_this_jam;
    res.shakes_per_jam.back() = shaker.shakes_this_jam;
    sys->discard_particles(gone);
    for (int id : gone)
        reinserter.reinsert(id, p, *sys, ids, rng);
    det.flow = Flow::checking;
    det.check_start = td;
}

// protocol.unjam = refill: the avalanche ended by this jam is the realization's last; the
// next one starts from a new fill (the next realization).
void Realization::Impl::refill() {
    res.status = Status::complete;
    std::ostringstream msg;
    msg << "refill: the avalanche ended by the jam at t = " << res.jam_onsets.back()
        << " s (protocol.unjam = refill: the next avalanche is the next realization's)";
    res.message = msg.str();
    det.jammed.back().second = td;
    end_run(Event::Kind::stop);
}

void Realization::Impl::start_shake() {
    ++res.n_shakes;
    shaker.start(sys->time());
    phase = Phase::shake;
    det.flow = Flow::shaking;
    log(Event::Kind::shake_start);
}

void Realization::Impl::finish_shake() {
    sys->set_wall_motion(Vec2::Zero(), Vec2::Zero());
    res.shakes_per_jam.back() = shaker.shakes_this_jam;
    phase = Phase::discharge;
    det.flow = Flow::checking;
    det.check_start = td;
    log(Event::Kind::shake_end);
}

void Realization::Impl::arrest() {
    res.shakes_per_jam.back() = shaker.shakes_this_jam;
    res.status = Status::arrested;
    std::ostringstream msg;
    msg << "jam at t = " << res.jam_onsets.back() << " s not cleared after "
        << shaker.shakes_this_jam << " shake(s) (protocol.max_shakes = " << p.protocol.max_shakes
        << "); " << sys->mobile_count() << " particles left";
    res.message = msg.str();
    det.jammed.back().second = td;
    end_run(Event::Kind::stop);
}

// Steady state: the realization asked for this many jams and has them.
void Realization::Impl::enough_jams() {
    res.status = Status::complete;
    std::ostringstream msg;
    msg << "steady state: " << res.n_jams << " jams (protocol.jams_per_realization) observed";
    res.message = msg.str();
    det.jammed.back().second = td;
    end_run(Event::Kind::stop);
}

// The end of a discharge (steps 7-9): the hopper emptied, or protocol.max_time_s.
void Realization::Impl::check_end() {
    if (sys->mobile_count() <= p.protocol.empty_threshold) {
        sys->flush_removals();
        record_removals();
        const double t_empty = res.exit_times.empty() ? td : res.exit_times.back();
        res.empty_time = t_empty;
        censor_final_interval(t_empty);
        res.status = Status::complete;
        res.message = "the hopper emptied";
        sample_curve();
        end_run(Event::Kind::empty);
    } else if (td >= p.protocol.max_time) {
        censor_final_interval(td);
        res.status = Status::time_limit;
        std::ostringstream msg;
        msg << "stopped at protocol.max_time_s = " << p.protocol.max_time << " s with "
            << sys->mobile_count() << " particles left";
        res.message = msg.str();
        sample_curve();
        end_run(Event::Kind::stop);
    }
}

// Ends the current survival interval as right-censored (the run stopped while flowing).
void Realization::Impl::censor_final_interval(double t_end) {
    if (det.flow != Flow::flowing) return;
    res.survival_times.push_back(std::max(0.0, t_end - det.flow_start));
    res.censored.push_back(true);
    res.avalanche_sizes.push_back(left_count() - interval_base);
}

void Realization::Impl::fail(const std::string& why) {
    res.status = Status::failed;
    res.message = why;
    end_run(Event::Kind::stop);
}

void Realization::Impl::end_run(Event::Kind kind) {
    if (ended()) return;
    det.flow = Flow::ended;
    log(kind);
    fields.finish(res);
    // The rate is a property of the whole discharge: computed once, at the end.
    if (res.status != Status::failed) log_.fit_rate(det.jammed, res);
}

// ----- the result ---------------------------------------------------------------------------
RealizationResult Realization::Impl::result() const {
    RealizationResult out = res;
    drop_incomplete_arrays(out);
    out.n_jams_multi_shake = int(std::count_if(out.shakes_per_jam.begin(), out.shakes_per_jam.end(),
                                               [](int n) { return n > 1; }));
    auto& d = out.diagnostics;
    d.steps = step_count;
    d.neighbor_rebuilds = sys->neighbor_rebuilds();
    d.particle_steps = particle_steps;
    d.wall_seconds = std::chrono::duration<double>(Clock::now() - wall_start).count();
    d.ns_per_particle_step = particle_steps > 0 ? d.wall_seconds * 1e9 / particle_steps : 0.0;
    d.max_overlap_ratio = sys->max_overlap() / p.particles.d_small;
    d.seconds_forces = sys->phase_seconds().forces;
    d.seconds_integration = sys->phase_seconds().integration;
    d.seconds_neighbors = sys->phase_seconds().neighbors;
    // (of the last piece, when the realization was resumed from a checkpoint elsewhere)
    d.force_path = to_string(sys->kernel_path());
    d.seconds_observers = std::max(
        0.0, d.wall_seconds - d.seconds_forces - d.seconds_integration - d.seconds_neighbors);
    // Potential energy released: from the fill to now, removed particles counted at the
    // removal floor.
    d.potential_energy_released =
        res.diagnostics.potential_energy_released -
        (sys->potential_energy() +
         log_.removed_mass() * p.gravity *
             (det.y_outlet - p.protocol.exit_depth * p.particles.d_large));
    return out;
}

// ----- one step and what it reports ---------------------------------------------------------
void Realization::Impl::step() {
    sys->step();
    ++step_count;
    particle_steps += sys->mobile_count();
    if (hooks.on_snapshot && hooks.snapshot_interval > 0 && sys->time() >= next_snapshot) {
        snapshot();
        next_snapshot += hooks.snapshot_interval;
    }
    if (hooks.on_progress && hooks.progress_interval > 0 && sys->time() >= next_progress) {
        hooks.on_progress({phase, sys->time(), td, sys->mobile_count(), res.n_jams});
        next_progress += hooks.progress_interval;
    }
}

void Realization::Impl::snapshot() {
    std::vector<double> wx(sys->wall_x().begin(), sys->wall_x().end());
    std::vector<double> wy(sys->wall_y().begin(), sys->wall_y().end());
    for (auto& v : wx)
        v += sys->wall_offset().x();
    for (auto& v : wy)
        v += sys->wall_offset().y();
    // Contact forces for viewers: read-only (the same evaluation the fields use).
    std::vector<double> fn(std::size_t(sys->mobile_count())), wfn(wx.size());
    sys->normal_force_sums(fn, wfn);
    hooks.on_snapshot({phase, sys->time(), td, sys->ids(), sys->x(), sys->y(), sys->vx(), sys->vy(),
                       sys->w(), sys->r(), wx, wy, sys->wall_r(), fn, wfn});
}

void Realization::Impl::maybe_checkpoint() {
    if (!hooks.checkpoint_request || !hooks.on_checkpoint) return;
    if (!hooks.checkpoint_request->load(std::memory_order_relaxed)) return;
    hooks.checkpoint_request->store(false);
    hooks.on_checkpoint(save_state());
}

void Realization::Impl::log(Event::Kind kind) {
    res.events.push_back({kind, td, sys->time(), sys->mobile_count()});
}

void Realization::Impl::sample_curve() {
    log_.sample(td, sys->mobile_count(), res);
}

double Realization::Impl::mean_ke() const {
    const int n = sys->mobile_count();
    return n > 0 ? sys->kinetic_energy() / n : 0.0;
}

void Realization::Impl::check_energy() {
    const double ke = mean_ke();
    if (!(ke <= ke_limit)) {
        std::ostringstream msg;
        msg << "kinetic energy blow-up: mean kinetic energy per particle " << ke << " J exceeds "
            << ke_limit << " J at t = " << sys->time()
            << " s; the integration is unstable: raise integrator.steps_per_collision (now "
            << p.integrator.steps_per_collision << ")";
        throw core::SimulationError(msg.str());
    }
}

int Realization::Impl::left_count() const {
    int n = res.discharged;
    for (double y : sys->y())
        n += y < det.y_outlet ? 1 : 0;
    return n;
}

Arch Realization::Impl::current_arch() const {
    return find_arch(near_outlet(), det.y_region);
}

// The mobile and wall disks near the outlet, for the arch finder.
std::vector<ArchDisk> Realization::Impl::near_outlet() const {
    const double reach = 2.0 * det.half_gap + 6.0 * p.particles.d_large;
    const double y_outlet = det.y_outlet;
    const auto near = [&](double x, double y) {
        return x * x + (y - y_outlet) * (y - y_outlet) < reach * reach;
    };
    std::vector<ArchDisk> disks;
    const auto x = sys->x(), y = sys->y(), r = sys->r();
    const auto pid = sys->ids();
    for (std::size_t i = 0; i < x.size(); ++i)
        if (near(x[i], y[i])) disks.push_back({pid[i], x[i], y[i], r[i], false});
    const auto wx = sys->wall_x(), wy = sys->wall_y(), wr = sys->wall_r();
    const auto wid = sys->wall_ids();
    const Vec2 off = sys->wall_offset();
    for (std::size_t i = 0; i < wx.size(); ++i)
        if (near(wx[i] + off.x(), wy[i] + off.y()))
            disks.push_back({wid[i], wx[i] + off.x(), wy[i] + off.y(), wr[i], true});
    return disks;
}

}  // namespace hopper::engine
