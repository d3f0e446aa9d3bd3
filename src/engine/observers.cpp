// The parts of the realization protocol (observers.hpp).
#include "observers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "hopper/core/error.hpp"
#include "hopper/core/units.hpp"
#include "hopper/engine/scene.hpp"

namespace hopper::engine::detail {

namespace {

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

std::int64_t every(double seconds, double dt) {
    return std::max<std::int64_t>(1, std::llround(seconds / dt));
}

void IdTable::remember(int id, double m, double d, double I) {
    if (int(mass.size()) <= id) {
        mass.resize(std::size_t(id) + 1, 0.0);
        diameter.resize(std::size_t(id) + 1, 0.0);
        inertia.resize(std::size_t(id) + 1, 0.0);
    }
    mass[id] = m;
    diameter[id] = d;
    inertia[id] = I;
}

// ----- jam detector --------------------------------------------------------------------------

JamDetector::JamDetector(const SceneParams& p)
    : y_outlet(edge_disk_centre(p.hopper).y()),
      half_gap(outlet_free_gap(p.hopper) / 2),
      y_region(y_outlet - p.protocol.jam_region_height * p.particles.d_large),
      min_speed2(p.protocol.jam_min_speed * p.protocol.jam_min_speed * p.gravity *
                 p.particles.d_large) {}

bool JamDetector::occupied(const System& s) const {
    const auto x = s.x(), y = s.y(), vx = s.vx(), vy = s.vy();
    for (std::size_t i = 0; i < x.size(); ++i)
        if (y[i] < y_outlet && y[i] > y_region && std::abs(x[i]) < half_gap &&
            vx[i] * vx[i] + vy[i] * vy[i] >= min_speed2)
            return true;
    return false;
}

JamDetector::Look JamDetector::look(const System& s, double td, double t_check) {
    const bool occ = occupied(s);
    switch (flow) {
        case Flow::flowing:
            if (occ) {
                last_occupied = td;
            } else if (td - last_occupied >= t_check) {
                jammed.emplace_back(last_occupied, td);
                return Look::jammed;
            }
            break;
        case Flow::checking:
            if (occ) {
                flow = Flow::flowing;
                last_occupied = td;
                jammed.back().second = check_start;
                flow_start = check_start;
                return Look::restarted;
            }
            if (td - check_start >= t_check) return Look::still_jammed;
            break;
        case Flow::shaking:
        case Flow::ended:
            break;
    }
    return Look::nothing;
}

// ----- shaker --------------------------------------------------------------------------------

Shaker::Shaker(const SceneParams& p, double dt)
    : period_(p.protocol.shake_period),
      amplitude_(p.protocol.shake_amplitude * p.particles.d_large),
      growth_(p.protocol.shake_growth),
      amplitude_max_(std::max(p.protocol.shake_amplitude, p.protocol.shake_amplitude_max) *
                     p.particles.d_large),
      direction_(p.protocol.shake_direction),
      dt_(dt) {}

double Shaker::amplitude() const {
    // The k-th shake of a jam: A g^(k-1), capped (docs/model.md, step 5). At g = 1 this is
    // A exactly (pow(1, n) = 1), as before the escalation existed.
    if (growth_ == 1.0) return amplitude_;
    return std::min(amplitude_ * std::pow(growth_, std::max(0, shakes_this_jam - 1)),
                    amplitude_max_);
}

void Shaker::start(double sim_time) {
    ++shakes_this_jam;
    shake_start = sim_time;
}

void Shaker::drive(System& s) const {
    const double tau = s.time() + dt_ - shake_start;
    if (tau >= period_) {
        s.set_wall_motion(Vec2::Zero(), Vec2::Zero());
        return;
    }
    const double om = 2.0 * core::pi / period_;
    const Vec2 e(std::cos(direction_), std::sin(direction_));
    const double a = amplitude();
    s.set_wall_motion(a * std::sin(om * tau) * e, a * om * std::cos(om * tau) * e);
}

bool Shaker::done(double sim_time) const {
    return sim_time - shake_start >= period_ - 0.5 * dt_;
}

// ----- discharge log -------------------------------------------------------------------------

void DischargeLog::record(System& s, double td, const IdTable& ids, RealizationResult& res,
                          const std::function<void(int)>& on_exit) {
    for (const Removal& r : s.take_removals()) {
        res.exit_times.push_back(td);
        exit_mass.push_back(ids.mass[r.id]);
        ++res.discharged;
        if (on_exit) on_exit(r.id);
    }
}

void DischargeLog::sample(double td, int in_hopper, RealizationResult& res) const {
    res.curve_time.push_back(td);
    res.curve_count.push_back(in_hopper);
}

void DischargeLog::fit_rate(const std::vector<std::pair<double, double>>& jammed,
                            RealizationResult& res) const {
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

double DischargeLog::removed_mass() const {
    double m = 0.0;
    for (double x : exit_mass)
        m += x;
    return m;
}

// ----- fields --------------------------------------------------------------------------------

void FieldsObserver::start(const SceneParams& p, double dt, double wall_top,
                           const std::vector<Vec2>& outline) {
    const FieldParams& f = p.fields;
    FieldGrid g;
    g.cell = f.cell * p.particles.d_large;
    g.nx = std::max(2, 2 * int(std::ceil(0.5 * p.hopper.width / g.cell - 1e-9)));
    g.x0 = -0.5 * g.nx * g.cell;
    const int below =
        std::max(1, int(std::ceil(p.protocol.exit_depth * p.particles.d_large / g.cell - 1e-9)));
    g.y0 = -below * g.cell;
    g.ny = below + std::max(1, int(std::ceil(wall_top / g.cell - 1e-9)));
    g.kernel = f.kernel;
    g.kernel_width = f.kernel == FieldKernel::gaussian ? f.kernel_width * p.particles.d_large : 0.0;
    if (double(g.nx) * double(g.ny) > 2.0e7) {
        std::ostringstream msg;
        msg << "the field grid would have " << g.nx << " x " << g.ny
            << " cells; raise fields.cell_dlarge (now " << f.cell << ")";
        throw core::ConfigError(msg.str());
    }
    acc = std::make_unique<FieldAccumulator>(g, f.window, f.start);
    auto& m = acc->moments();
    m.wall_diameter = p.hopper.wall_diameter;
    for (const Vec2& q : outline) {
        m.outline_x.push_back(q.x());
        m.outline_y.push_back(q.y());
    }
    period = f.sample_interval > 0.0 ? every(f.sample_interval, dt) : 1;
}

void FieldsObserver::sample(const SceneParams& p, System& s, double td) {
    const FieldParams& f = p.fields;
    if (td < f.start || (f.end && td >= *f.end)) return;
    const int n = s.mobile_count();
    pressure_.resize(std::size_t(n));
    s.normal_force_sums(pressure_, {});
    const auto m = s.m();
    for (int i = 0; i < n; ++i)
        pressure_[i] /= m[i] * p.gravity;
    acc->sample(td, s.x(), s.y(), s.vx(), s.vy(), pressure_);
}

void FieldsObserver::finish(RealizationResult& res) {
    if (!acc) return;
    acc->close_window();
    res.fields = std::move(acc->moments());
    acc.reset();
}

// ----- steady state --------------------------------------------------------------------------

void Reinserter::set_base(const System& s, double y_outlet) {
    insert_base = y_outlet;
    const auto y = s.y(), r = s.r();
    for (std::size_t i = 0; i < y.size(); ++i)
        insert_base = std::max(insert_base, y[i] + r[i]);
}

void Reinserter::reinsert(int id, const SceneParams& p, System& s, IdTable& ids,
                          core::Rng& rng) const {
    const double d = ids.diameter[id], rad = 0.5 * d;
    const double top = insert_base;
    const double half_w = 0.5 * p.hopper.width - 1.01 * rad;
    // A disk dropped here falls straight down onto the packing, so it must clear the walls at
    // the packing's top, where the container is narrowest below it: with a small head the top
    // lies in the funnel, narrower than the hopper's width (issue 23). Draws outside are drawn
    // again; where the top is above the funnel nothing is refused, so the draws (and the bits
    // of every steady state with a full hopper) are those of before.
    const double inside = inner_half_width(p.hopper, std::max(0.0, top)) - 1.01 * rad;
    const Vec2 off = s.wall_offset();
    const auto overlaps = [&](const Vec2& q) {
        const auto x = s.x(), y = s.y(), r = s.r();
        for (std::size_t i = 0; i < x.size(); ++i) {
            const double dx = x[i] - q.x(), dy = y[i] - q.y(), sr = r[i] + rad;
            if (dx * dx + dy * dy < sr * sr) return true;
        }
        const auto wx = s.wall_x(), wy = s.wall_y(), wr = s.wall_r();
        for (std::size_t i = 0; i < wx.size(); ++i) {
            const double dx = wx[i] + off.x() - q.x(), dy = wy[i] + off.y() - q.y();
            const double sr = wr[i] + rad;
            if (dx * dx + dy * dy < sr * sr) return true;
        }
        return false;
    };
    // The band widens by a large diameter for every 200 failed draws. A wide outlet lets
    // particles out faster than the first 2000 draws' band (12 large diameters) clears by
    // falling: the band then goes on widening, up to about 100 diameters above the packing
    // (issue 29, item 6; the draws of a realization that found room in 2000 are unchanged).
    constexpr int max_attempts = 20000;
    for (int attempt = 0; attempt < max_attempts; ++attempt) {
        const double band = 2.5 + attempt / 200;
        const double lift = rng.uniform(0.5, 0.5 + band) * p.particles.d_large;
        const Vec2 q(rng.uniform(-half_w, half_w), top + rad + lift);
        if (std::abs(q.x()) > inside || overlaps(q)) continue;
        const double m = ids.mass[id], I = ids.inertia[id];
        const int nid = s.add_particle(q, d, m, I, Vec2::Zero(), 0.0);
        ids.remember(nid, m, d, I);
        return;
    }
    std::ostringstream msg;
    msg << "steady state: no free place found to re-insert a particle within "
        << 2.5 + max_attempts / 200 << " large diameters above the packing in " << max_attempts
        << " draws: particles leave faster than they can be re-inserted (outlet D = "
        << p.hopper.outlet * 100 << " cm, hopper " << p.hopper.width * 100
        << " cm wide); use a smaller outlet, a wider hopper or fewer particles";
    throw core::SimulationError(msg.str());
}

}  // namespace hopper::engine::detail
