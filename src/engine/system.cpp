#include "hopper/engine/system.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>

#include "columns.hpp"
#include "force_batch.hpp"
#include "hopper/core/error.hpp"
#include "kernel.hpp"
#include "laws.hpp"

namespace hopper::engine {

using Clock = std::chrono::steady_clock;

namespace {

double seconds_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

}  // namespace

System::System(const SystemConfig& config) : config_(config) {
    if (!(config_.dt > 0.0) || !std::isfinite(config_.dt))
        throw core::ConfigError("System: time step dt must be positive and finite");
    if (!(config_.skin > 0.0) || !std::isfinite(config_.skin))
        throw core::ConfigError("System: neighbour skin must be positive and finite");
    const bool friction = config_.particle.mu > 0.0 || config_.wall.mu > 0.0;
    const bool spring = config_.particle.k_t > 0.0 || config_.wall.k_t > 0.0;
    // One law serves both kinds of contact, so they must agree on having a spring: a spring law
    // with k_t = 0 would divide by zero when it shortens the spring. (One kt_over_kn in the
    // sweep file sets both, so a scene never hits this.)
    if (friction && (config_.particle.k_t > 0.0) != (config_.wall.k_t > 0.0))
        throw core::ConfigError(
            "System: particle-particle and particle-wall contacts must both have k_t > 0 or both "
            "k_t = 0");
    // One-time dispatch (style.md): the law is the registered one with the scene's normal and
    // tangential parts (laws.hpp). Frictionless contacts exert no torque, so rotation is not
    // integrated at all; a law without a spring keeps no history.
    const bool hertz = config_.normal_law == NormalLaw::hertz;
    TangentialLaw tangential = config_.tangential_law;
    if (tangential == TangentialLaw::automatic) {
        // Inferred as before the setting existed: the cheapest law that is exact for the
        // coefficients (no friction: no torque to integrate; k_t = 0: no spring); the Hertz law
        // and rolling resistance take the spring.
        if (config_.rolling && !hertz && !(friction && spring))
            throw core::ConfigError(
                "System: rolling resistance needs tangential springs (k_t > 0 and mu > 0)");
        tangential = hertz || config_.rolling ? TangentialLaw::spring
                     : !friction              ? TangentialLaw::frictionless
                     : !spring                ? TangentialLaw::viscous
                                              : TangentialLaw::spring;
    }
    if (tangential == TangentialLaw::spring && !hertz && !spring)
        throw core::ConfigError(
            "System: material.tangential_law = spring needs a tangential spring: k_t > 0 "
            "(material.kt_over_kn > 0; it is 0)");
    if (config_.rolling_spring && !config_.rolling)
        throw core::ConfigError("System: a rolling spring needs rolling resistance (mu_r > 0)");
    const int law =
        detail::law_for(config_.normal_law, tangential, config_.rolling, config_.rolling_spring);
    if (law < 0) {
        const auto rolling_text = [](bool rolling, bool spring) {
            return spring ? " and a rolling spring" : rolling ? " and rolling resistance" : "";
        };
        std::string have;
        for (const auto& t : detail::law_traits)
            have += std::string(have.empty() ? "" : "; ") + to_string(t.normal) + " with " +
                    to_string(t.tangential) + rolling_text(t.rolling, t.rolling_spring);
        throw core::ConfigError(
            "System: no contact law has the normal law '" + to_string(config_.normal_law) +
            "' with the tangential law '" + to_string(tangential) + "'" +
            rolling_text(config_.rolling, config_.rolling_spring) + "; the laws are: " + have);
    }
    history_ = detail::law_traits[static_cast<std::size_t>(law)].has_history;
    rolling_history_ = detail::law_traits[static_cast<std::size_t>(law)].rolling_spring;
    kernel_ = detail::make_kernel(law, config_.scheme);
    kernel_path_ = config_.kernel == KernelPath::reference ? KernelPath::reference
                                                           : detail::resolve_kernel(config_.kernel);
}

System::~System() = default;

void System::set_time_step(double dt, bool rescale) {
    if (!(dt > 0.0) || !std::isfinite(dt))
        throw core::ConfigError("System: the time step must be positive and finite");
    if (dt == config_.dt) return;
    if (ready_ && rescale) {
        const double q = dt / config_.dt;
        const double scale[3] = {q * q, q * q * q, q * q * q * q};  // r_2, r_3, r_4
        const auto h = history_columns(*this);
        for (std::size_t c = 0; c < h.size(); ++c)
            for (double& v : *h[c])
                v *= scale[c % 3];
    }
    config_.dt = dt;
    ahead_ = false;  // the fused predictor's look-ahead was for the old step
}

void System::set_kernel(KernelPath p) {
    kernel_path_ = p == KernelPath::reference ? p : detail::resolve_kernel(p);
}

std::string to_string(StepFusion f) {
    switch (f) {
        case StepFusion::none:
            return "none";
        case StepFusion::corrector:
            return "corrector";
        case StepFusion::step:
            return "step";
    }
    return "?";
}

StepFusion parse_step_fusion(const std::string& s) {
    for (StepFusion f : {StepFusion::none, StepFusion::corrector, StepFusion::step})
        if (s == to_string(f)) return f;
    throw core::ConfigError("unknown step fusion '" + s + "': none, corrector or step");
}

void System::set_step_fusion(StepFusion f) {
    fusion_ = f;
    ahead_ = false;  // the look-ahead is computed only by the step form's corrector
}

int System::add_particle(const Vec2& pos, double diameter, double mass, double inertia,
                         const Vec2& vel, double omega) {
    if (!(diameter > 0.0 && mass > 0.0 && inertia > 0.0) || !pos.allFinite() || !vel.allFinite())
        throw core::ConfigError(
            "System::add_particle: diameter, mass and inertia must be positive "
            "and position and velocity finite");
    x_.push_back(pos.x());
    y_.push_back(pos.y());
    vx_.push_back(vel.x());
    vy_.push_back(vel.y());
    w_.push_back(omega);  // without friction nothing exerts torque: omega stays as given
    fx_.push_back(0.0);
    fy_.push_back(0.0);
    tq_.push_back(0.0);
    r_.push_back(0.5 * diameter);
    m_.push_back(mass);
    inv_m_.push_back(1.0 / mass);
    inv_I_.push_back(1.0 / inertia);
    id_.push_back(next_id_);
    ready_ = false;  // the integrator's history is (re)initialised at the next step
    ahead_ = false;
    need_rebuild_ = true;
    return next_id_++;
}

int System::add_wall(const Vec2& pos, double diameter) {
    if (!(diameter > 0.0) || !pos.allFinite())
        throw core::ConfigError("System::add_wall: diameter must be positive, position finite");
    wx_.push_back(pos.x() - wall_offset_.x());
    wy_.push_back(pos.y() - wall_offset_.y());
    wr_.push_back(0.5 * diameter);
    wid_.push_back(next_id_);
    walls_changed_ = true;
    need_rebuild_ = true;
    return next_id_++;
}

void System::remove_walls(std::span<const int> ids) {
    if (ids.empty()) return;
    save_history();  // wall indices change: the springs are carried by the walls' old indices
    history_saved_ = true;
    std::vector<int> keep;
    keep.reserve(wid_.size());
    for (std::size_t k = 0; k < wid_.size(); ++k)
        if (std::find(ids.begin(), ids.end(), wid_[k]) == ids.end()) keep.push_back(int(k));
    if (carry_) wall_old_ = keep;  // new wall index -> old one
    detail::compact(wx_, keep);
    detail::compact(wy_, keep);
    detail::compact(wr_, keep);
    detail::compact(wid_, keep);
    walls_changed_ = true;
    rebuild();
}

void System::set_wall_motion(const Vec2& offset, const Vec2& velocity) {
    wall_offset_ = offset;
    wall_velocity_ = velocity;
}

void System::set_load_band(double y_lo, double y_hi, double accel) {
    config_.load_y_lo = y_lo;
    config_.load_y_hi = y_hi;
    config_.load_accel = accel;
}

void System::set_removal_floor(double y) {
    removal_floor_ = y;
}

void System::flush_removals() {
    if (!ready_) return;
    rebuild();
}

void System::discard_particles(std::span<const int> ids) {
    discard_.assign(ids.begin(), ids.end());
    // The neighbour list and the springs are rebuilt without them (as at a flush); before the
    // first step there is no list yet and the columns are compacted directly.
    if (ready_)
        rebuild();
    else
        remove_below_floor();
    discard_.clear();
}

std::vector<Removal> System::take_removals() {
    std::vector<Removal> out;
    out.swap(removals_);
    return out;
}

void System::set_velocity(int index, const Vec2& v, double omega) {
    vx_[index] = v.x();
    vy_[index] = v.y();
    w_[index] = omega;
    ahead_ = false;  // the next displacement was computed from the old velocity
}

int System::index_of(int id) const {
    for (std::size_t k = 0; k < id_.size(); ++k)
        if (id_[k] == id) return int(k);
    return -1;
}

void System::ensure_ready() {
    if (ready_) return;
    // The integrator's history is rebuilt by prime() below.
    for (auto* col : history_columns(*this))
        col->clear();
    rebuild();
    // The second velocity set (contact corrections) starts as the velocities themselves.
    if (config_.contact_corrections) {
        avx_ = vx_;
        avy_ = vy_;
        aw_ = w_;
    }
    // The priming evaluation only provides accelerations: it must not advance the springs
    // (the first real step grows them by v_t dt), so they are put back afterwards.
    const auto ps = pair_springs(*this), ws = wall_springs(*this);
    std::array<std::vector<double>, 3> keep_p, keep_w;
    for (std::size_t c = 0; c < ps.size(); ++c) {
        keep_p[c] = *ps[c];
        keep_w[c] = *ws[c];
    }
    const double ov = kernel_->forces(*this, false, false).max_overlap;
    for (std::size_t c = 0; c < ps.size(); ++c) {
        *ps[c] = std::move(keep_p[c]);
        *ws[c] = std::move(keep_w[c]);
    }
    check_overlap(ov);
    kernel_->prime(*this);
    ready_ = true;
}

void System::step() {
    ensure_ready();
    const double wall_d = (wall_offset_ - wall_offset_ref_).norm();
    const auto t0 = Clock::now();
    detail::ForceSums sums;
    auto t1 = t0, t2 = t0, t3 = t0;  // the predictor, the rebuild, the force pass done
    // StepFusion::step (round 3, docs/performance.md): when the last step's corrector says that
    // the predicted positions need no rebuild (the test below, on the same numbers), the
    // predictor runs inside the force pass, a block ahead of the rows that read it; else the
    // separate predictor, the rebuild if needed, then the pass. The same bits either way.
    const bool look_ahead = fusion_ == StepFusion::step && ahead_ && !need_rebuild_ &&
                            ahead_d2_ <= std::numeric_limits<double>::max() &&
                            !(2.0 * std::max(std::sqrt(ahead_d2_), wall_d) > config_.skin);
    if (look_ahead) {
        sums = kernel_->forces(*this, true, true);  // the predictor's time counts as forces
        t3 = Clock::now();
    } else {
        const double maxd2 = kernel_->predict(*this);
        t1 = Clock::now();
        if (!(maxd2 <= std::numeric_limits<double>::max())) fail_nonfinite();
        const double dmax = std::max(std::sqrt(maxd2), wall_d);
        if (need_rebuild_ || 2.0 * dmax > config_.skin) rebuild();
        t2 = Clock::now();
        // With a fused form the corrector runs inside the force pass (its time counts as the
        // force pass's); with none (the default) as a pass of its own.
        const bool fused = fusion_ != StepFusion::none;
        sums = kernel_->forces(*this, fused, false);
        t3 = Clock::now();
        if (!fused) {
            kernel_->correct(*this);
            phase_.integration += seconds_between(t3, Clock::now());
        }
    }
    ahead_ = fusion_ == StepFusion::step;
    ahead_d2_ = sums.next_displacement2;
    time_ += config_.dt;
    check_overlap(sums.max_overlap);
    phase_.integration += seconds_between(t0, t1);
    phase_.neighbors += seconds_between(t1, t2);
    phase_.forces += seconds_between(t2, t3);
}

void System::run(std::int64_t steps) {
    for (std::int64_t k = 0; k < steps; ++k)
        step();
}

void System::check_overlap(double step_max_overlap) {
    max_overlap_seen_ = std::max(max_overlap_seen_, step_max_overlap);
    if (config_.max_overlap > 0.0 && step_max_overlap > config_.max_overlap) {
        std::ostringstream msg;
        msg << "overlap of " << step_max_overlap << " m exceeds the allowed " << config_.max_overlap
            << " m at t = " << time_ << " s (dt = " << config_.dt
            << " s): either the time step is too large for this stiffness and impact speed "
               "(use a smaller time step: raise integrator.steps_per_collision) or the contacts "
               "are too soft for the load of a tall packing (use stiffer contacts: a shorter "
               "material.collision_time_s, or allow more with protocol.max_overlap)";
        throw core::SimulationError(msg.str());
    }
}

void System::fail_nonfinite() const {
    std::ostringstream msg;
    msg << "particle state became non-finite (NaN or infinite) at t = " << time_
        << " s (dt = " << config_.dt
        << " s): the integration is unstable; use a smaller time step or check the material "
           "parameters";
    throw core::SimulationError(msg.str());
}

detail::ForceArgs System::force_args() {
    detail::ForceArgs a;
    a.n = int(x_.size());
    a.x = x_.data();
    a.y = y_.data();
    a.r = r_.data();
    a.vx = a.svx = vx_.data();
    a.vy = a.svy = vy_.data();
    a.w = a.sw = w_.data();
    a.fx = fx_.data();
    a.fy = fy_.data();
    a.tq = tq_.data();
    a.ps = pstart_.data();
    a.pj = pj_.data();
    a.ws = wstart_.data();
    a.wj = wj_.data();
    a.hx = history_ ? pxi_x_.data() : nullptr;
    a.hy = history_ ? pxi_y_.data() : nullptr;
    a.gx = history_ ? wxi_x_.data() : nullptr;
    a.gy = history_ ? wxi_y_.data() : nullptr;
    a.hr = rolling_history_ ? pxi_r_.data() : nullptr;
    a.gr = rolling_history_ ? wxi_r_.data() : nullptr;
    a.wx = wx_.data();
    a.wy = wy_.data();
    a.wr = wr_.data();
    a.ox = wall_offset_.x();
    a.oy = wall_offset_.y();
    a.vwx = wall_velocity_.x();
    a.vwy = wall_velocity_.y();
    a.pp = config_.particle;
    a.pw = config_.wall;
    a.dt = config_.dt;
    a.lever_half = config_.contact_lever ? 0.5 : 0.0;
    a.pmbar = pmbar_.data();
    a.wmbar = wmbar_.data();
    a.prstar = prstar_.data();
    a.wrstar = wrstar_.data();
    a.pK = phk_.data();
    a.wK = whk_.data();
    a.peta = pheta_.data();
    a.weta = wheta_.data();
    a.po = pown_.data();
    a.wo = wown_.data();
    // Scratch of the force passes: columns with room for every entry of either list (a block
    // uses the part of its own entries). Every path lists its touching entries in the index
    // columns (force_batch_impl.hpp); the batched paths also keep the law's results per entry.
    const std::size_t len = std::max(pj_.size(), wj_.size()) + 16;  // 16: slack for the
                                                                    // 16-wide stores
    if (batch_index_.size() < 4 * len) batch_index_.resize(4 * len);
    int* ib = batch_index_.data();
    if (kernel_path_ != KernelPath::reference) {
        if (batch_scratch_.size() < 8 * len) batch_scratch_.resize(8 * len);
        double* db = batch_scratch_.data();
        a.scratch = {ib,           ib + len,     ib + 2 * len, ib + 3 * len,
                     db,           db + len,     db + 2 * len, db + 3 * len,
                     db + 4 * len, db + 5 * len, db + 6 * len, db + 7 * len};
    } else {
        a.scratch = {ib,      ib + len, ib + 2 * len, ib + 3 * len, nullptr, nullptr,
                     nullptr, nullptr,  nullptr,      nullptr,      nullptr, nullptr};
    }
    return a;
}

// ----- observables ---------------------------------------------------------------------------

double System::kinetic_energy() const {
    double e = 0.0;
    for (std::size_t i = 0; i < x_.size(); ++i) {
        e += 0.5 * m_[i] * (vx_[i] * vx_[i] + vy_[i] * vy_[i]);
        e += 0.5 * w_[i] * w_[i] / inv_I_[i];
    }
    return e;
}

double System::potential_energy() const {
    double e = 0.0;
    for (std::size_t i = 0; i < x_.size(); ++i)
        e -= m_[i] * (config_.gravity.x() * x_[i] + config_.gravity.y() * y_[i]);
    return e;
}

template <class Pair, class Wall>
void System::for_each_touching(Pair&& pair, Wall&& wall) const {
    for (std::size_t i = 0; i < x_.size(); ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            const int j = pj_[k];
            const double dx = x_[i] - x_[j], dy = y_[i] - y_[j], rs = r_[i] + r_[j];
            const double d2 = dx * dx + dy * dy;
            if (d2 < rs * rs) pair(i, j, k, dx, dy, d2);
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k) {
            const int j = wj_[k];
            const double dx = x_[i] - wx_[j] - wall_offset_.x();
            const double dy = y_[i] - wy_[j] - wall_offset_.y();
            const double rs = r_[i] + wr_[j];
            const double d2 = dx * dx + dy * dy;
            if (d2 < rs * rs) wall(i, j, k, dx, dy, d2);
        }
    }
}

namespace {
// The energy M^2 / (2 k_r) held by a rolling spring of torque M (k_r = k_t R*^2).
double rolling_spring_energy(double k_t, double ri, double rj, double M) {
    const double rs = reduced_radius(ri, rj);
    return 0.5 * M * M / (k_t * rs * rs);
}
}  // namespace

double System::elastic_energy() const {
    if (pstart_.size() != x_.size() + 1) return 0.0;
    double e = 0.0;
    for_each_touching(
        [&](std::size_t i, int j, int k, double, double, double d2) {
            const double ov = r_[i] + r_[j] - std::sqrt(d2);
            e += 0.5 * config_.particle.k_n * ov * ov;
            if (history_)
                e += 0.5 * config_.particle.k_t * (pxi_x_[k] * pxi_x_[k] + pxi_y_[k] * pxi_y_[k]);
            if (rolling_history_)  // M^2 / (2 k_r), k_r = k_t R*^2
                e += rolling_spring_energy(config_.particle.k_t, r_[i], r_[j], pxi_r_[k]);
        },
        [&](std::size_t i, int j, int k, double, double, double d2) {
            const double ov = r_[i] + wr_[j] - std::sqrt(d2);
            e += 0.5 * config_.wall.k_n * ov * ov;
            if (history_)
                e += 0.5 * config_.wall.k_t * (wxi_x_[k] * wxi_x_[k] + wxi_y_[k] * wxi_y_[k]);
            if (rolling_history_)
                e += rolling_spring_energy(config_.wall.k_t, r_[i], wr_[j], wxi_r_[k]);
        });
    return e;
}

void System::normal_force_sums(std::span<double> mobile, std::span<double> wall) {
    const std::size_t n = x_.size();
    if ((!mobile.empty() && mobile.size() != n) || (!wall.empty() && wall.size() != wx_.size()))
        throw std::invalid_argument("System::normal_force_sums: span sizes must be " +
                                    std::to_string(n) + " and " + std::to_string(wx_.size()));
    ensure_ready();
    std::fill(mobile.begin(), mobile.end(), 0.0);
    std::fill(wall.begin(), wall.end(), 0.0);
    const bool want_mobile = !mobile.empty(), want_wall = !wall.empty();
    for_each_touching(
        [&](std::size_t i, int j, int, double dx, double dy, double d2) {
            const double d = std::sqrt(d2);
            const double v_n = ((vx_[i] - vx_[j]) * dx + (vy_[i] - vy_[j]) * dy) / d;
            const double mbar = 1.0 / (inv_m_[i] + inv_m_[j]);
            const double f =
                std::abs(normal_magnitude(config_.particle, mbar, r_[i] + r_[j] - d, v_n));
            if (want_mobile) {
                mobile[i] += f;
                mobile[j] += f;
            }
        },
        [&](std::size_t i, int j, int, double dx, double dy, double d2) {
            const double d = std::sqrt(d2);
            const double v_n =
                ((vx_[i] - wall_velocity_.x()) * dx + (vy_[i] - wall_velocity_.y()) * dy) / d;
            const double f =
                std::abs(normal_magnitude(config_.wall, m_[i], r_[i] + wr_[j] - d, v_n));
            if (want_mobile) mobile[i] += f;
            if (want_wall) wall[j] += f;
        });
}

std::vector<std::pair<int, int>> System::contacts_from_list() {
    ensure_ready();
    std::vector<std::pair<int, int>> out;
    for_each_touching(
        [&](std::size_t i, int j, int, double, double, double) {
            out.emplace_back(std::min(id_[i], id_[j]), std::max(id_[i], id_[j]));
        },
        [&](std::size_t i, int j, int, double, double, double) {
            out.emplace_back(id_[i], wid_[j]);
        });
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace hopper::engine
