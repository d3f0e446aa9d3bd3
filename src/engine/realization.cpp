#include "hopper/engine/realization.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "hopper/core/error.hpp"
#include "hopper/core/random.hpp"
#include "hopper/engine/arch.hpp"
#include "hopper/engine/checkpoint.hpp"
#include "hopper/engine/fields.hpp"
#include "hopper/engine/scene.hpp"
#include "hopper/engine/system.hpp"

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

namespace {

using Clock = std::chrono::steady_clock;

// Steps between two looks of an observer that wants to run every `seconds`.
std::int64_t every(double seconds, double dt) {
    return std::max<std::int64_t>(1, std::llround(seconds / dt));
}

SystemConfig system_config(const SceneParams& p, const DerivedConstants& c, KernelPath kernel) {
    SystemConfig sc;
    sc.kernel = kernel;
    sc.dt = c.dt;
    sc.scheme = p.integrator.scheme;
    sc.gravity = Vec2(0.0, -p.gravity);
    sc.skin = p.integrator.skin * p.particles.d_small;
    sc.max_overlap = p.protocol.max_overlap * p.particles.d_small;
    // k_t = kt_over_kn k_n, gamma_t = gamma_n / 2   (spec/physics.md, tangential force)
    // k_t = kt_over_kn k_n, gamma_t = gamma_n / 2   (spec/physics.md, tangential force; the
    // ratio is material.gamma_t_over_gamma_n, 0.5 by default)
    const double gt = p.material.gamma_t_over_gamma_n;
    const bool spring_only = p.material.slip_rule == SlipRule::spring_only;
    sc.particle = {c.k_n,      c.gamma_n_system, c.k_t, c.gamma_n_system * gt, p.material.system.mu,
                   spring_only};
    sc.wall = {c.k_n, c.gamma_n_wall, c.k_t, c.gamma_n_wall * gt, p.material.wall.mu, spring_only};
    sc.contact_lever = p.material.lever_arm == LeverArm::contact;
    sc.contact_corrections = p.integrator.contact_corrections;
    return sc;
}

// Least-squares slope of y against x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
    const double n = double(x.size());
    double sx = 0, sy = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
        sx += x[k];
        sy += y[k];
    }
    const double mx = sx / n, my = sy / n;
    double sxx = 0, sxy = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
        sxx += (x[k] - mx) * (x[k] - mx);
        sxy += (x[k] - mx) * (y[k] - my);
    }
    return sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

struct Realization::Impl {
    enum class Flow { flowing, shaking, checking, ended };

    SceneParams p;
    DerivedConstants c;
    RunHooks hooks;
    RealizationResult res;
    std::unique_ptr<System> sys;
    std::vector<int> gate_ids;
    std::vector<double> mass_of_id;  // by particle id (walls: 0)
    // The realization's generator: the fill, then (steady state) the re-inserted positions.
    core::Rng rng;
    std::vector<double> diameter_of_id, inertia_of_id;  // by particle id (walls: 0)
    // Particles that had left (crossed the outlet plane) when the current avalanche began: at
    // the opening, then at each jam's detection.
    int interval_base = 0;
    double insert_base = 0.0;  // steady state: the settled packing's top at the opening
    Phase phase = Phase::settle;
    Flow flow = Flow::flowing;
    Clock::time_point wall_start;
    double particle_steps = 0.0;

    // Discharge clocks and detector state (discharge time td excludes shaking).
    double td = 0.0;
    double flow_start = 0.0;     // td at which the current survival interval began
    double last_occupied = 0.0;  // td at which the region last held a particle
    double check_start = 0.0;    // td at which the post-shake check began
    double shake_start = 0.0;    // sim time at which the current shake began
    int shakes_this_jam = 0;
    std::vector<std::pair<double, double>> jammed;  // [onset, restart) in td
    std::vector<double> exit_mass;
    // Observer schedule.
    std::int64_t step_count = 0;
    std::int64_t k_detect = 1, k_sample = 1, k_settle = 1;
    double next_snapshot = 0.0, next_progress = 0.0;
    double ke_limit = 0.0;  // mean KE per particle beyond which we call it a blow-up
    // Coarse-grained fields (only when p.fields.enabled; nothing allocated otherwise).
    std::unique_ptr<FieldAccumulator> fields;
    std::vector<double> field_pressure;  // per mobile particle, units of m g
    std::int64_t k_field = 1;
    double wall_top = 0.0;
    std::vector<Vec2> outline;
    // The detector region is |x| < half_gap, y_region < y < y_outlet: below the edge disks
    // (y_outlet = 0 and half_gap = D/2 in the default geometry).
    double y_region = 0.0, y_outlet = 0.0, half_gap = 0.0;
    // Settling: simulated time since which the kinetic energy has stayed below the threshold
    // (-1: it is above). A member, not a local, so that a checkpoint carries it.
    double below_since = -1.0;

    Impl(const SceneParams& params, std::uint64_t seed, RunHooks h)
        : p(params), hooks(std::move(h)), rng(seed), wall_start(Clock::now()) {
        validate_scene(p);
        c = derive_constants(p);
        res.seed = seed;
        res.particles = p.particles.count;
        res.diagnostics.dt = c.dt;
        res.diagnostics.tau_c = c.tau_c;
        res.diagnostics.k_n = c.k_n;
        const SceneLayout layout = build_scene(p, rng);
        sys = std::make_unique<System>(system_config(p, c, hooks.kernel));
        for (const auto& w : layout.walls)
            sys->add_wall(w.pos, w.diameter);
        for (const auto& w : layout.gate)
            gate_ids.push_back(sys->add_wall(w.pos, w.diameter));
        for (const auto& f : layout.fill) {
            const double m = f.large ? c.m_large : c.m_small;
            const double I = f.large ? c.I_large : c.I_small;
            const int id = sys->add_particle(f.pos, f.diameter, m, I, f.vel, 0.0);
            remember(id, m, f.diameter, I);
        }
        res.wall_particles = sys->wall_count() - int(gate_ids.size());
        k_detect = every(p.protocol.detector_interval, c.dt);
        k_sample = every(p.protocol.sample_interval, c.dt);
        k_settle = every(1e-3, c.dt);
        y_outlet = edge_disk_centre(p.hopper).y();
        half_gap = outlet_free_gap(p.hopper) / 2;
        y_region = y_outlet - p.protocol.jam_region_height * p.particles.d_large;
        // Mean kinetic energy per particle can never exceed the potential energy of a fall from
        // the top of the walls to the removal floor (plus shaking); 100x that is a blow-up.
        const double drop =
            layout.wall_top - y_outlet + p.protocol.exit_depth * p.particles.d_large;
        ke_limit = 100.0 * c.m_large * p.gravity * drop;
        wall_top = layout.wall_top;
        outline = layout.outline;
        res.diagnostics.potential_energy_released = sys->potential_energy();
    }

    bool ended() const { return flow == Flow::ended; }

    void remember(int id, double m, double diameter, double inertia) {
        if (int(mass_of_id.size()) <= id) {
            mass_of_id.resize(std::size_t(id) + 1, 0.0);
            diameter_of_id.resize(std::size_t(id) + 1, 0.0);
            inertia_of_id.resize(std::size_t(id) + 1, 0.0);
        }
        mass_of_id[id] = m;
        diameter_of_id[id] = diameter;
        inertia_of_id[id] = inertia;
    }

    // Particles that have crossed the outlet plane: those removed plus those still falling.
    int left_count() const {
        int n = res.discharged;
        for (double y : sys->y())
            n += y < y_outlet ? 1 : 0;
        return n;
    }

    // The arch over the outlet now (arch.hpp), from the disks near the outlet.
    Arch current_arch() const {
        const double reach = 2.0 * half_gap + 6.0 * p.particles.d_large;
        const auto near = [&](double x, double y) {
            return x * x + (y - y_outlet) * (y - y_outlet) < reach * reach;
        };
        std::vector<ArchDisk> disks;
        const auto x = sys->x(), y = sys->y(), r = sys->r();
        const auto ids = sys->ids();
        for (std::size_t i = 0; i < x.size(); ++i)
            if (near(x[i], y[i])) disks.push_back({ids[i], x[i], y[i], r[i], false});
        const auto wx = sys->wall_x(), wy = sys->wall_y(), wr = sys->wall_r();
        const auto wid = sys->wall_ids();
        const Vec2 off = sys->wall_offset();
        for (std::size_t i = 0; i < wx.size(); ++i)
            if (near(wx[i] + off.x(), wy[i] + off.y()))
                disks.push_back({wid[i], wx[i] + off.x(), wy[i] + off.y(), wr[i], true});
        return find_arch(disks, y_region);
    }

    // Steady state: each particle that left comes back at the top of the packing, at a
    // position drawn from the realization's generator where it overlaps nothing: x across the
    // container, y in a band from half a large diameter to three above the settled packing's
    // top (measured at the opening; the head stays there as the count is constant). Measuring
    // the top anew would follow particles still falling from earlier insertions upward.
    void reinsert(int id) {
        const double d = diameter_of_id[id], rad = 0.5 * d;
        const double top = insert_base;
        const double half_w = 0.5 * p.hopper.width - 1.01 * rad;
        const Vec2 off = sys->wall_offset();
        const auto overlaps = [&](const Vec2& q) {
            const auto x = sys->x(), y = sys->y(), r = sys->r();
            for (std::size_t i = 0; i < x.size(); ++i) {
                const double dx = x[i] - q.x(), dy = y[i] - q.y(), s = r[i] + rad;
                if (dx * dx + dy * dy < s * s) return true;
            }
            const auto wx = sys->wall_x(), wy = sys->wall_y(), wr = sys->wall_r();
            for (std::size_t i = 0; i < wx.size(); ++i) {
                const double dx = wx[i] + off.x() - q.x(), dy = wy[i] + off.y() - q.y();
                const double s = wr[i] + rad;
                if (dx * dx + dy * dy < s * s) return true;
            }
            return false;
        };
        for (int attempt = 0; attempt < 2000; ++attempt) {
            // The band widens by a large diameter for every 200 failed draws.
            const double band = 2.5 + attempt / 200;
            const double lift = rng.uniform(0.5, 0.5 + band) * p.particles.d_large;
            const Vec2 q(rng.uniform(-half_w, half_w), top + rad + lift);
            if (overlaps(q)) continue;
            const int nid =
                sys->add_particle(q, d, mass_of_id[id], inertia_of_id[id], Vec2::Zero(), 0.0);
            remember(nid, mass_of_id[id], d, inertia_of_id[id]);
            return;
        }
        throw core::SimulationError(
            "steady state: no free place found above the packing to re-insert a particle in "
            "2000 draws; widen the hopper or lower hopper.particles");
    }

    void fail(const std::string& why) {
        res.status = Status::failed;
        res.message = why;
        end_run(Event::Kind::stop);
    }

    void end_run(Event::Kind kind) {
        if (flow == Flow::ended) return;
        flow = Flow::ended;
        log(kind);
        finish_fields();
        // The rate is a property of the whole discharge: computed once, at the end.
        if (res.status != Status::failed) discharge_rate();
    }

    void log(Event::Kind kind) {
        res.events.push_back({kind, td, sys->time(), sys->mobile_count()});
    }

    double mean_ke() const {
        const int n = sys->mobile_count();
        return n > 0 ? sys->kinetic_energy() / n : 0.0;
    }

    void check_energy() {
        const double ke = mean_ke();
        if (!(ke <= ke_limit)) {
            std::ostringstream msg;
            msg << "kinetic energy blow-up: mean kinetic energy per particle " << ke
                << " J exceeds " << ke_limit << " J at t = " << sys->time()
                << " s; the integration is unstable: raise integrator.steps_per_collision (now "
                << p.integrator.steps_per_collision << ")";
            throw core::SimulationError(msg.str());
        }
    }

    void step() {
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

    void snapshot() {
        std::vector<double> wx(sys->wall_x().begin(), sys->wall_x().end());
        std::vector<double> wy(sys->wall_y().begin(), sys->wall_y().end());
        for (auto& v : wx)
            v += sys->wall_offset().x();
        for (auto& v : wy)
            v += sys->wall_offset().y();
        // Contact forces for viewers: read-only (the same evaluation the fields use).
        std::vector<double> fn(std::size_t(sys->mobile_count())), wfn(wx.size());
        sys->normal_force_sums(fn, wfn);
        hooks.on_snapshot({phase, sys->time(), td, sys->ids(), sys->x(), sys->y(), sys->vx(),
                           sys->vy(), sys->w(), sys->r(), wx, wy, sys->wall_r(), fn, wfn});
    }

    bool stop_requested() const { return hooks.stop && hooks.stop->load(); }

    // ----- checkpoints (checkpoint.hpp) -------------------------------------------------
    // Called between two time steps, where the state is whole.
    void maybe_checkpoint() {
        if (!hooks.checkpoint_request || !hooks.on_checkpoint) return;
        if (!hooks.checkpoint_request->load(std::memory_order_relaxed)) return;
        hooks.checkpoint_request->store(false);
        hooks.on_checkpoint(save_state());
    }

    // What a state must agree on with the realization it is restored into.
    void put_fingerprint(StateWriter& w) const {
        w.put(res.seed);
        w.put(p.particles.count);
        w.put(static_cast<std::int32_t>(p.integrator.scheme));
        w.put(c.dt);
        w.put(c.k_n);
        w.put<std::uint8_t>(p.fields.enabled);
    }

    void check_fingerprint(StateReader& r) const {
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

    std::vector<std::uint8_t> save_state() const {
        StateWriter w;
        w.put_string("HOPPERRS");
        w.put(state_format_version);
        put_fingerprint(w);
        w.put(static_cast<std::int32_t>(phase));
        w.put(static_cast<std::int32_t>(flow));
        w.put(std::chrono::duration<double>(Clock::now() - wall_start).count());
        w.put(particle_steps);
        w.put(td);
        w.put(flow_start);
        w.put(last_occupied);
        w.put(check_start);
        w.put(shake_start);
        w.put(shakes_this_jam);
        w.put<std::uint64_t>(jammed.size());
        for (const auto& [on, off] : jammed) {
            w.put(on);
            w.put(off);
        }
        w.put_vector(exit_mass);
        w.put(step_count);
        w.put(next_snapshot);
        w.put(next_progress);
        w.put(below_since);
        // Issue 13: the avalanche count's base, the steady state's insertion height and its
        // generator (draws positions of re-inserted particles).
        w.put(interval_base);
        w.put(insert_base);
        std::uint64_t rs[4];
        rng.state(rs);
        for (std::uint64_t v : rs)
            w.put(v);
        save_result(res, w);
        CheckpointAccess::save(*sys, w);
        w.put<std::uint8_t>(fields != nullptr);
        if (fields) CheckpointAccess::save(*fields, w);
        return w.take();
    }

    void restore_state(std::span<const std::uint8_t> bytes) {
        static const std::uint8_t magic[16] = {8,   0,   0,   0,   0,   0,   0,   0,
                                               'H', 'O', 'P', 'P', 'E', 'R', 'R', 'S'};
        if (bytes.size() < 16 || !std::equal(magic, magic + 16, bytes.begin()))
            throw core::ConfigError("the checkpoint is not a hopper realization state");
        StateReader r(bytes);
        r.get_string();
        const auto version = r.get<std::uint32_t>();
        if (version != state_format_version)
            throw core::ConfigError("the checkpoint has state format " + std::to_string(version) +
                                    "; this engine reads format " +
                                    std::to_string(state_format_version));
        check_fingerprint(r);
        const auto ph = r.get<std::int32_t>();
        const auto fl = r.get<std::int32_t>();
        if (ph < 0 || ph > 2 || fl < 0 || fl > 3) StateReader::fail();
        phase = static_cast<Phase>(ph);
        flow = static_cast<Flow>(fl);
        const double elapsed = r.get<double>();
        wall_start = Clock::now() - std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(elapsed));
        particle_steps = r.get<double>();
        td = r.get<double>();
        flow_start = r.get<double>();
        last_occupied = r.get<double>();
        check_start = r.get<double>();
        shake_start = r.get<double>();
        shakes_this_jam = r.get<int>();
        const auto n_jammed = r.get<std::uint64_t>();
        if (n_jammed > (std::uint64_t(1) << 32)) StateReader::fail();
        jammed.clear();
        for (std::uint64_t k = 0; k < n_jammed; ++k) {
            const double on = r.get<double>();
            const double off = r.get<double>();
            jammed.emplace_back(on, off);
        }
        r.get_vector(exit_mass);
        step_count = r.get<std::int64_t>();
        next_snapshot = r.get<double>();
        next_progress = r.get<double>();
        below_since = r.get<double>();
        interval_base = r.get<int>();
        insert_base = r.get<double>();
        std::uint64_t rs[4];
        for (std::uint64_t& v : rs)
            v = r.get<std::uint64_t>();
        rng.set_state(rs);
        restore_result(res, r);
        CheckpointAccess::restore(*sys, r);
        fields.reset();
        if (r.get<std::uint8_t>()) {
            if (!p.fields.enabled) StateReader::fail();
            start_fields();  // the grid and k_field from the parameters; the state below
            CheckpointAccess::restore(*fields, r);
        }
        if (!r.at_end()) StateReader::fail();
    }

    // ----- settle (step 2) --------------------------------------------------------------
    void settle() {
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

    // ----- open (step 3) ----------------------------------------------------------------
    void open() {
        sys->remove_walls(gate_ids);
        sys->set_removal_floor(y_outlet - p.protocol.exit_depth * p.particles.d_large);
        phase = Phase::discharge;
        flow = Flow::flowing;
        td = flow_start = last_occupied = 0.0;
        interval_base = left_count();
        insert_base = y_outlet;
        {
            const auto y = sys->y(), r = sys->r();
            for (std::size_t i = 0; i < y.size(); ++i)
                insert_base = std::max(insert_base, y[i] + r[i]);
        }
        log(Event::Kind::opened);
        sample();
        if (p.fields.enabled) start_fields();
    }

    // ----- coarse-grained fields (fields.hpp) -------------------------------------------
    // The grid covers the container's full width and from the removal floor to the top of
    // the walls; the outlet (y = 0) and the axis (x = 0) lie on cell boundaries.
    void start_fields() {
        const FieldParams& f = p.fields;
        FieldGrid g;
        g.cell = f.cell * p.particles.d_large;
        g.nx = std::max(2, 2 * int(std::ceil(0.5 * p.hopper.width / g.cell - 1e-9)));
        g.x0 = -0.5 * g.nx * g.cell;
        const int below = std::max(
            1, int(std::ceil(p.protocol.exit_depth * p.particles.d_large / g.cell - 1e-9)));
        g.y0 = -below * g.cell;
        g.ny = below + std::max(1, int(std::ceil(wall_top / g.cell - 1e-9)));
        g.kernel = f.kernel;
        g.kernel_width =
            f.kernel == FieldKernel::gaussian ? f.kernel_width * p.particles.d_large : 0.0;
        if (double(g.nx) * double(g.ny) > 2.0e7) {
            std::ostringstream msg;
            msg << "the field grid would have " << g.nx << " x " << g.ny
                << " cells; raise fields.cell_dlarge (now " << f.cell << ")";
            throw core::ConfigError(msg.str());
        }
        fields = std::make_unique<FieldAccumulator>(g, f.window, f.start);
        auto& m = fields->moments();
        m.wall_diameter = p.hopper.wall_diameter;
        for (const Vec2& q : outline) {
            m.outline_x.push_back(q.x());
            m.outline_y.push_back(q.y());
        }
        k_field = f.sample_interval > 0.0 ? every(f.sample_interval, c.dt) : 1;
    }

    void sample_fields() {
        const FieldParams& f = p.fields;
        if (td < f.start || (f.end && td >= *f.end)) return;
        const int n = sys->mobile_count();
        field_pressure.resize(std::size_t(n));
        sys->normal_force_sums(field_pressure, {});
        const auto m = sys->m();
        for (int i = 0; i < n; ++i)
            field_pressure[i] /= m[i] * p.gravity;
        fields->sample(td, sys->x(), sys->y(), sys->vx(), sys->vy(), field_pressure);
    }

    void finish_fields() {
        if (!fields) return;
        fields->close_window();
        res.fields = std::move(fields->moments());
        fields.reset();
    }

    // ----- discharge (steps 3-7) --------------------------------------------------------
    bool region_occupied() const {
        const auto x = sys->x(), y = sys->y();
        for (std::size_t i = 0; i < x.size(); ++i)
            if (y[i] < y_outlet && y[i] > y_region && std::abs(x[i]) < half_gap) return true;
        return false;
    }

    void sample() {
        res.curve_time.push_back(td);
        res.curve_count.push_back(sys->mobile_count());
    }

    void start_shake() {
        ++shakes_this_jam;
        ++res.n_shakes;
        shake_start = sys->time();
        phase = Phase::shake;
        flow = Flow::shaking;
        log(Event::Kind::shake_start);
    }

    // Wall motion of the shake at the end of the coming step: one sinusoidal oscillation.
    void drive_walls() {
        const double T = p.protocol.shake_period;
        const double tau = sys->time() + c.dt - shake_start;
        if (tau >= T) {
            sys->set_wall_motion(Vec2::Zero(), Vec2::Zero());
            return;
        }
        const double A = p.protocol.shake_amplitude * p.particles.d_large;
        const double om = 2.0 * core::pi / T;
        const Vec2 e(std::cos(p.protocol.shake_direction), std::sin(p.protocol.shake_direction));
        sys->set_wall_motion(A * std::sin(om * tau) * e, A * om * std::cos(om * tau) * e);
    }

    void record_removals() {
        for (const Removal& r : sys->take_removals()) {
            res.exit_times.push_back(td);
            exit_mass.push_back(mass_of_id[r.id]);
            ++res.discharged;
            if (p.protocol.mode == ProtocolMode::steady_state) reinsert(r.id);
        }
    }

    void detect() {
        const bool occupied = region_occupied();
        switch (flow) {
            case Flow::flowing:
                if (occupied) {
                    last_occupied = td;
                } else if (td - last_occupied >= c.t_check) {
                    // Jammed: the onset is the last moment the region held a particle.
                    res.jam_onsets.push_back(last_occupied);
                    res.survival_times.push_back(last_occupied - flow_start);
                    res.censored.push_back(false);
                    res.shakes_per_jam.push_back(0);
                    ++res.n_jams;
                    res.events.push_back(
                        {Event::Kind::jam, last_occupied, sys->time(), sys->mobile_count()});
                    jammed.emplace_back(last_occupied, td);
                    {
                        // The next interval's avalanche starts here: particles that fall while
                        // shaking belong to the flow the shake restarts.
                        const int left = left_count();
                        res.avalanche_sizes.push_back(left - interval_base);
                        interval_base = left;
                    }
                    res.arches.push_back(current_arch());
                    shakes_this_jam = 0;
                    if (p.protocol.mode == ProtocolMode::steady_state &&
                        p.protocol.jams_per_realization > 0 &&
                        res.n_jams >= p.protocol.jams_per_realization)
                        return enough_jams();
                    if (p.protocol.max_shakes == 0) return arrest();
                    start_shake();
                }
                break;
            case Flow::checking:
                if (occupied) {
                    // The shake cleared the jam: a new survival interval starts at its end.
                    flow = Flow::flowing;
                    last_occupied = td;
                    jammed.back().second = check_start;
                    flow_start = check_start;
                    log(Event::Kind::flow_restart);
                } else if (td - check_start >= c.t_check) {
                    if (shakes_this_jam >= p.protocol.max_shakes) return arrest();
                    start_shake();
                }
                break;
            case Flow::shaking:
            case Flow::ended:
                break;
        }
    }

    void arrest() {
        res.shakes_per_jam.back() = shakes_this_jam;
        res.status = Status::arrested;
        std::ostringstream msg;
        msg << "jam at t = " << res.jam_onsets.back() << " s not cleared after " << shakes_this_jam
            << " shake(s) (protocol.max_shakes = " << p.protocol.max_shakes << "); "
            << sys->mobile_count() << " particles left";
        res.message = msg.str();
        jammed.back().second = td;
        end_run(Event::Kind::stop);
    }

    // Steady state: the realization asked for this many jams and has them.
    void enough_jams() {
        res.status = Status::complete;
        std::ostringstream msg;
        msg << "steady state: " << res.n_jams << " jams (protocol.jams_per_realization) observed";
        res.message = msg.str();
        jammed.back().second = td;
        end_run(Event::Kind::stop);
    }

    void finish_shake() {
        sys->set_wall_motion(Vec2::Zero(), Vec2::Zero());
        res.shakes_per_jam.back() = shakes_this_jam;
        phase = Phase::discharge;
        flow = Flow::checking;
        check_start = td;
        log(Event::Kind::shake_end);
    }

    // Ends the current survival interval as right-censored (the run stopped while flowing).
    void censor_final_interval(double t_end) {
        if (flow != Flow::flowing) return;
        res.survival_times.push_back(std::max(0.0, t_end - flow_start));
        res.censored.push_back(true);
        res.avalanche_sizes.push_back(left_count() - interval_base);
    }

    bool advance(double seconds) {
        if (ended()) return false;
        const double until = td + seconds;
        const int empty_at = p.protocol.empty_threshold;
        while (!ended() && td < until) {
            maybe_checkpoint();
            if (flow == Flow::shaking) drive_walls();
            step();
            if (flow == Flow::shaking) {
                res.diagnostics.shake_time += c.dt;
                if (sys->time() - shake_start >= p.protocol.shake_period - 0.5 * c.dt)
                    finish_shake();
            } else {
                td += c.dt;
            }
            record_removals();
            if (step_count % k_detect == 0) {
                if (stop_requested()) {
                    fail("interrupted (stop requested)");
                    return false;
                }
                detect();
            }
            if (fields && flow != Flow::shaking && !ended() && step_count % k_field == 0)
                sample_fields();
            if (step_count % k_sample == 0) {
                check_energy();
                sys->flush_removals();
                record_removals();
                if (flow != Flow::shaking) sample();
            }
            if (!ended() && sys->mobile_count() <= empty_at) {
                sys->flush_removals();
                record_removals();
                const double t_empty = res.exit_times.empty() ? td : res.exit_times.back();
                res.empty_time = t_empty;
                censor_final_interval(t_empty);
                res.status = Status::complete;
                res.message = "the hopper emptied";
                sample();
                end_run(Event::Kind::empty);
            } else if (!ended() && td >= p.protocol.max_time) {
                censor_final_interval(td);
                res.status = Status::time_limit;
                std::ostringstream msg;
                msg << "stopped at protocol.max_time_s = " << p.protocol.max_time << " s with "
                    << sys->mobile_count() << " particles left";
                res.message = msg.str();
                sample();
                end_run(Event::Kind::stop);
            }
        }
        return !ended();
    }

    void discharge_rate() {
        // Steady part: the exits between 20 % and 80 % of all discharged particles, against
        // the flowing time (discharge time minus the jammed periods).
        const std::size_t n = res.exit_times.size();
        if (n < 20) return;
        const std::size_t lo = n / 5, hi = (4 * n) / 5;
        std::vector<double> t, count, mass;
        double cum_mass = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
            cum_mass += exit_mass[k];
            if (k < lo || k >= hi) continue;
            double flowing = res.exit_times[k];
            for (const auto& [on, off] : jammed)
                if (on < res.exit_times[k]) flowing -= std::min(off, res.exit_times[k]) - on;
            t.push_back(flowing);
            count.push_back(double(k + 1));
            mass.push_back(cum_mass);
        }
        const double rate = slope(t, count);
        if (std::isfinite(rate) && rate > 0) {
            res.discharge_rate = rate;
            res.discharge_rate_mass = slope(t, mass);
        }
    }

    RealizationResult result() const {
        RealizationResult out = res;
        out.n_jams_multi_shake = int(std::count_if(
            out.shakes_per_jam.begin(), out.shakes_per_jam.end(), [](int n) { return n > 1; }));
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
        d.seconds_observers = std::max(
            0.0, d.wall_seconds - d.seconds_forces - d.seconds_integration - d.seconds_neighbors);
        // Potential energy released: from the fill to now, removed particles counted at the
        // removal floor.
        double removed_mass = 0.0;
        for (double m : exit_mass)
            removed_mass += m;
        d.potential_energy_released =
            res.diagnostics.potential_energy_released -
            (sys->potential_energy() +
             removed_mass * p.gravity * (y_outlet - p.protocol.exit_depth * p.particles.d_large));
        return out;
    }
};

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
