#include "hopper/engine/system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>

#include "force_batch.hpp"
#include "hopper/core/error.hpp"
#include "pair_force.hpp"

namespace hopper::engine {

using Clock = std::chrono::steady_clock;

namespace {

double seconds_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

// Gear 5-value predictor-corrector for second-order equations (Allen & Tildesley, appendix E):
// corrector coefficients for r, dt v, dt^2/2 a, dt^3/6 b, dt^4/24 c.
constexpr double gear_c0 = 19.0 / 120.0;
constexpr double gear_c1 = 3.0 / 4.0;
constexpr double gear_c3 = 1.0 / 2.0;
constexpr double gear_c4 = 1.0 / 12.0;

template <class T>
void permute(std::vector<T>& col, const std::vector<int>& order, std::vector<T>& scratch) {
    if (col.empty()) return;
    scratch.resize(col.size());
    for (std::size_t k = 0; k < order.size(); ++k)
        scratch[k] = col[order[k]];
    col.swap(scratch);
}

template <class T>
void compact(std::vector<T>& col, const std::vector<int>& keep) {
    if (col.empty()) return;
    for (std::size_t k = 0; k < keep.size(); ++k)
        col[k] = col[keep[k]];
    col.resize(keep.size());
}

// Gear predictor on one coordinate (Pascal triangle on the scaled derivatives
// r_k = dt^k/k! d^k r/dt^k; velocity kept unscaled). Free functions over raw columns so that
// the compiler sees no aliasing and vectorizes them.
void gear_predict_axis(std::size_t n, double dt, double* __restrict x, double* __restrict v,
                       double* __restrict x2, double* __restrict x3, const double* __restrict x4) {
    const double inv_dt = 1.0 / dt;
    for (std::size_t i = 0; i < n; ++i) {
        x[i] += dt * v[i] + x2[i] + x3[i] + x4[i];
        v[i] += (2.0 * x2[i] + 3.0 * x3[i] + 4.0 * x4[i]) * inv_dt;
        x2[i] += 3.0 * x3[i] + 6.0 * x4[i];
        x3[i] += 4.0 * x4[i];
    }
}

// Gear corrector on one coordinate: e = dt^2/2 a(t+dt) - predicted r_2, with
// a = force * inv_mass + g. x may be null (rotation: the angle itself is not tracked).
void gear_correct_axis(std::size_t n, double dt, double g, const double* __restrict force,
                       const double* __restrict inv_mass, double* __restrict x,
                       double* __restrict v, double* __restrict x2, double* __restrict x3,
                       double* __restrict x4) {
    const double h = 0.5 * dt * dt, inv_dt = 1.0 / dt;
    if (x)
        for (std::size_t i = 0; i < n; ++i)
            x[i] += gear_c0 * (h * (force[i] * inv_mass[i] + g) - x2[i]);
    for (std::size_t i = 0; i < n; ++i) {
        const double e = h * (force[i] * inv_mass[i] + g) - x2[i];
        v[i] += gear_c1 * e * inv_dt;
        x2[i] += e;
        x3[i] += gear_c3 * e;
        x4[i] += gear_c4 * e;
    }
}

// Counting sort of points into an nx x ny grid of cells of size cs with origin (x0, y0);
// points outside are clamped into the border cells (which keeps a neighbour search correct).
// Afterwards the points of cell c are items[start[c]] .. items[start[c + 1] - 1], in input
// order, and cell_of[k] is the cell of point k.
void bin_points(std::span<const double> xs, std::span<const double> ys, double x0, double y0,
                double cs, int nx, int ny, std::vector<int>& start, std::vector<int>& items,
                std::vector<int>& cell_of) {
    const std::size_t n = xs.size();
    const int ncell = nx * ny;
    cell_of.resize(n);
    start.assign(ncell + 1, 0);
    for (std::size_t k = 0; k < n; ++k) {
        const int cx = std::clamp(int((xs[k] - x0) / cs), 0, nx - 1);
        const int cy = std::clamp(int((ys[k] - y0) / cs), 0, ny - 1);
        cell_of[k] = cx + cy * nx;
        ++start[cell_of[k] + 1];
    }
    for (int c = 0; c < ncell; ++c)
        start[c + 1] += start[c];
    items.resize(n);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < n; ++k)
        items[fill[cell_of[k]]++] = int(k);
}

// Velocity Verlet on one coordinate: the half kick v += dt/2 (force inv_mass + g), then, when
// x is given, the drift x += dt v (x is null for the closing half kick and for rotation).
void verlet_axis(std::size_t n, double dt, double g, const double* __restrict force,
                 const double* __restrict inv_mass, double* __restrict v, double* __restrict x) {
    const double hdt = 0.5 * dt;
    if (x) {
        for (std::size_t i = 0; i < n; ++i) {
            v[i] += hdt * (force[i] * inv_mass[i] + g);
            x[i] += dt * v[i];
        }
    } else {
        for (std::size_t i = 0; i < n; ++i)
            v[i] += hdt * (force[i] * inv_mass[i] + g);
    }
}

// Largest squared displacement since the last rebuild; NaN if any position is not finite.
double max_displacement2(std::size_t n, const double* __restrict x, const double* __restrict y,
                         const double* __restrict xr, const double* __restrict yr) {
    double maxd2 = 0.0, sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double dx = x[i] - xr[i], dy = y[i] - yr[i];
        const double d2 = dx * dx + dy * dy;
        maxd2 = std::max(maxd2, d2);
        sum += d2;  // NaN or inf anywhere makes the sum non-finite
    }
    return std::isfinite(sum) ? maxd2 : std::numeric_limits<double>::quiet_NaN();
}

// Corrections, gear4: mean = 0.5 (v + saved), written over saved.
void mean_into(std::size_t n, const double* __restrict v, double* __restrict saved) {
    for (std::size_t i = 0; i < n; ++i)
        saved[i] = 0.5 * (v[i] + saved[i]);
}

// Corrections, verlet: out = v + dt/2 (force inv_mass + g).
void extrapolate(std::size_t n, double dt, double g, const double* __restrict force,
                 const double* __restrict inv_mass, const double* __restrict v,
                 double* __restrict out) {
    const double hdt = 0.5 * dt;
    for (std::size_t i = 0; i < n; ++i)
        out[i] = v[i] + hdt * (force[i] * inv_mass[i] + g);
}

}  // namespace

// The kernel chosen at setup: one contact law and one integrator, so that the hot loops contain
// no configuration branches and no per-contact virtual calls (one virtual call per phase).
struct System::Kernel {
    virtual ~Kernel() = default;
    // Advances positions; returns the largest squared displacement since the last rebuild
    // (NaN when the state is not finite). Loops use __restrict pointers (the columns never
    // alias) so that the compiler vectorizes them.
    virtual double predict(System& s) = 0;
    // Computes forces and torques; returns the largest overlap of this evaluation.
    virtual double forces(System& s) = 0;
    virtual void correct(System& s) = 0;
    // Initialises the integrator's history from the current forces.
    virtual void prime(System& s) = 0;
};

template <class Law, Scheme S>
struct KernelImpl final : System::Kernel {
    static constexpr bool rot = Law::has_tangential;
    static constexpr bool hist = Law::has_history;

    double predict(System& s) override {
        const std::size_t n = s.x_.size();
        const double dt = s.config_.dt;
        const bool corr = s.config_.contact_corrections;
        if constexpr (S == Scheme::gear4) {
            // Corrections: the springs grow with the mean of the last corrected velocity
            // (saved here) and the predicted one.
            if (corr && hist) {
                s.avx_ = s.vx_;
                s.avy_ = s.vy_;
                s.aw_ = s.w_;
            }
            gear_predict_axis(n, dt, s.x_.data(), s.vx_.data(), s.x2_.data(), s.x3_.data(),
                              s.x4_.data());
            gear_predict_axis(n, dt, s.y_.data(), s.vy_.data(), s.y2_.data(), s.y3_.data(),
                              s.y4_.data());
            if constexpr (rot) {
                // The angle is not tracked: predict omega and its derivatives only.
                double* __restrict w = s.w_.data();
                double* __restrict w2 = s.w2_.data();
                double* __restrict w3 = s.w3_.data();
                const double* __restrict w4 = s.w4_.data();
                const double inv_dt = 1.0 / dt;
                for (std::size_t i = 0; i < n; ++i) {
                    w[i] += (2.0 * w2[i] + 3.0 * w3[i] + 4.0 * w4[i]) * inv_dt;
                    w2[i] += 3.0 * w3[i] + 6.0 * w4[i];
                    w3[i] += 4.0 * w4[i];
                }
            }
            if (corr && hist) {
                mean_into(n, s.vx_.data(), s.avx_.data());
                mean_into(n, s.vy_.data(), s.avy_.data());
                mean_into(n, s.w_.data(), s.aw_.data());
            }
        } else {
            // Velocity Verlet: half kick with the last forces, then drift.
            const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
            verlet_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.vx_.data(), s.x_.data());
            verlet_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.vy_.data(), s.y_.data());
            if constexpr (rot)
                verlet_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), s.w_.data(), nullptr);
            // Corrections: the dashpots see the velocity extrapolated to the end of the step
            // with the last forces, v + dt/2 (F/m + g).
            if (corr) {
                s.avx_.resize(n);
                s.avy_.resize(n);
                s.aw_.resize(n);
                extrapolate(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.vx_.data(), s.avx_.data());
                extrapolate(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.vy_.data(), s.avy_.data());
                if constexpr (rot)
                    extrapolate(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), s.w_.data(),
                                s.aw_.data());
            }
        }
        return max_displacement2(n, s.x_.data(), s.y_.data(), s.xref_.data(), s.yref_.data());
    }

    void correct(System& s) override {
        const std::size_t n = s.x_.size();
        const double dt = s.config_.dt;
        const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
        if constexpr (S == Scheme::gear4) {
            gear_correct_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.x_.data(), s.vx_.data(),
                              s.x2_.data(), s.x3_.data(), s.x4_.data());
            gear_correct_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.y_.data(), s.vy_.data(),
                              s.y2_.data(), s.y3_.data(), s.y4_.data());
            if constexpr (rot)
                gear_correct_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), nullptr, s.w_.data(),
                                  s.w2_.data(), s.w3_.data(), s.w4_.data());
        } else {
            // Velocity Verlet: the closing half kick with the new forces.
            verlet_axis(n, dt, gx, s.fx_.data(), s.inv_m_.data(), s.vx_.data(), nullptr);
            verlet_axis(n, dt, gy, s.fy_.data(), s.inv_m_.data(), s.vy_.data(), nullptr);
            if constexpr (rot)
                verlet_axis(n, dt, 0.0, s.tq_.data(), s.inv_I_.data(), s.w_.data(), nullptr);
        }
    }

    void prime(System& s) override {
        if constexpr (S == Scheme::gear4) {
            const std::size_t n = s.x_.size();
            const double h = 0.5 * s.config_.dt * s.config_.dt;
            const double gx = s.config_.gravity.x(), gy = s.config_.gravity.y();
            for (auto* col :
                 {&s.x2_, &s.x3_, &s.x4_, &s.y2_, &s.y3_, &s.y4_, &s.w2_, &s.w3_, &s.w4_})
                col->assign(n, 0.0);
            for (std::size_t i = 0; i < n; ++i) {
                s.x2_[i] = h * (s.fx_[i] * s.inv_m_[i] + gx);
                s.y2_[i] = h * (s.fy_[i] * s.inv_m_[i] + gy);
                if constexpr (rot) s.w2_[i] = h * s.tq_[i] * s.inv_I_[i];
            }
        }
    }

    // The velocity sets of the force pass: without corrections the particles' velocities for
    // both; with them, verlet's dashpots use the extrapolated set and gear4's springs the mean.
    void velocity_sets(System& s, detail::ForceArgs& a, bool& two) const {
        const bool corr = s.config_.contact_corrections;
        const bool verlet_corr = corr && S == Scheme::verlet;
        a.vx = verlet_corr ? s.avx_.data() : s.vx_.data();
        a.vy = verlet_corr ? s.avy_.data() : s.vy_.data();
        a.w = verlet_corr ? s.aw_.data() : s.w_.data();
        two = corr && hist;
        const bool gear_corr = two && S == Scheme::gear4;
        a.svx = two ? (gear_corr ? s.avx_.data() : s.vx_.data()) : a.vx;
        a.svy = two ? (gear_corr ? s.avy_.data() : s.vy_.data()) : a.vy;
        a.sw = two ? (gear_corr ? s.aw_.data() : s.w_.data()) : a.w;
    }

    double forces(System& s) override {
        detail::ForceArgs a = s.force_args();
        bool two = false;
        velocity_sets(s, a, two);
        detail::ForceSums sums;
        if (s.kernel_path_ == KernelPath::reference) {
            sums = two ? reference<true>(a) : reference<false>(a);
        } else {
            constexpr int law = !Law::has_tangential ? 0 : (!Law::has_history ? 1 : 2);
            sums = detail::force_table(s.kernel_path_).fn[law][two ? 1 : 0](a);
        }
        s.wall_force_ = Vec2(sums.wall_fx, sums.wall_fy);
        s.contacts_ = sums.contacts;
        return sums.max_overlap;
    }

    // The reference force pass: one loop over the neighbour list, each touching pair evaluated
    // where it is found. The batched paths must give exactly its bits (test_kernel_paths).
    template <bool Corr>
    static detail::ForceSums reference(const detail::ForceArgs& a) {
        using detail::PairInput;
        using detail::PairOutput;
        std::fill(a.fx, a.fx + a.n, 0.0);
        std::fill(a.fy, a.fy + a.n, 0.0);
        if constexpr (rot) std::fill(a.tq, a.tq + a.n, 0.0);
        double no_spring_x = 0.0, no_spring_y = 0.0;  // stands in when there is no history
        double max_ov = 0.0, wfx = 0.0, wfy = 0.0;
        int contacts = 0;
        PairInput q{};
        for (int i = 0; i < a.n; ++i) {
            const double xi = a.x[i], yi = a.y[i], ri = a.r[i];
            q.vix = a.vx[i];
            q.viy = a.vy[i];
            q.wi = rot ? a.w[i] : 0.0;
            if constexpr (Corr) {  // the springs' own velocities: only with the corrections
                q.six = a.svx[i];
                q.siy = a.svy[i];
                q.swi = rot ? a.sw[i] : 0.0;
            }
            q.ri = ri;
            double fxi = 0.0, fyi = 0.0, tqi = 0.0;
            // Mobile partners: each pair once, Newton's third law.
            for (int k = a.ps[i]; k < a.ps[i + 1]; ++k) {
                const int j = a.pj[k];
                double& sx = hist ? a.hx[k] : no_spring_x;
                double& sy = hist ? a.hy[k] : no_spring_y;
                q.dx = xi - a.x[j];
                q.dy = yi - a.y[j];
                q.rj = a.r[j];
                q.rs = ri + q.rj;
                q.d2 = q.dx * q.dx + q.dy * q.dy;
                if (q.d2 >= q.rs * q.rs) {
                    sx = sy = 0.0;  // not touching: the spring is forgotten
                    continue;
                }
                q.mbar = a.pmbar[k];  // m_i m_j / (m_i + m_j), set at the rebuild
                q.vjx = a.vx[j];
                q.vjy = a.vy[j];
                q.wj = rot ? a.w[j] : 0.0;
                if constexpr (Corr) {
                    q.sjx = a.svx[j];
                    q.sjy = a.svy[j];
                    q.swj = rot ? a.sw[j] : 0.0;
                }
                const PairOutput o =
                    detail::pair_force<Law, Corr, false>(a.pp, a.dt, a.lever_half, q, sx, sy);
                fxi += o.fx;
                fyi += o.fy;
                a.fx[j] -= o.fx;
                a.fy[j] -= o.fy;
                if constexpr (rot) {
                    tqi -= o.ti;      // -l_i (n x F_t)
                    a.tq[j] -= o.tj;  // -l_j (n x F_t): the same form for the partner
                }
                max_ov = std::max(max_ov, o.overlap);
                ++contacts;
            }
            // Wall partners: immobile (or moving rigidly while shaking), inverse mass 0.
            double wfxi = 0.0, wfyi = 0.0;
            q.vjx = q.sjx = a.vwx;
            q.vjy = q.sjy = a.vwy;
            q.wj = q.swj = 0.0;
            for (int k = a.ws[i]; k < a.ws[i + 1]; ++k) {
                const int j = a.wj[k];
                double& sx = hist ? a.gx[k] : no_spring_x;
                double& sy = hist ? a.gy[k] : no_spring_y;
                q.dx = xi - (a.wx[j] + a.ox);
                q.dy = yi - (a.wy[j] + a.oy);
                q.rj = a.wr[j];
                q.rs = ri + q.rj;
                q.d2 = q.dx * q.dx + q.dy * q.dy;
                if (q.d2 >= q.rs * q.rs) {
                    sx = sy = 0.0;
                    continue;
                }
                q.mbar = a.wmbar[k];
                const PairOutput o =
                    detail::pair_force<Law, Corr, false>(a.pw, a.dt, a.lever_half, q, sx, sy);
                wfxi += o.fx;
                wfyi += o.fy;
                if constexpr (rot) tqi -= o.ti;
                max_ov = std::max(max_ov, o.overlap);
                ++contacts;
            }
            a.fx[i] += fxi + wfxi;
            a.fy[i] += fyi + wfyi;
            wfx -= wfxi;
            wfy -= wfyi;
            if constexpr (rot) a.tq[i] += tqi;
        }
        return {max_ov, wfx, wfy, contacts};
    }
};

namespace {

template <class Law>
std::unique_ptr<System::Kernel> make_kernel_for(Scheme scheme) {
    if (scheme == Scheme::gear4) return std::make_unique<KernelImpl<Law, Scheme::gear4>>();
    return std::make_unique<KernelImpl<Law, Scheme::verlet>>();
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
    // One-time dispatch (style.md): frictionless contacts exert no torque, so rotation is not
    // integrated at all; k_t = 0 needs no spring history.
    history_ = friction && spring;
    if (!friction)
        kernel_ = make_kernel_for<FrictionlessLaw>(config_.scheme);
    else if (!spring)
        kernel_ = make_kernel_for<ViscousFrictionLaw>(config_.scheme);
    else
        kernel_ = make_kernel_for<SpringFrictionLaw>(config_.scheme);
    kernel_path_ = config_.kernel == KernelPath::reference ? KernelPath::reference
                                                           : detail::resolve_kernel(config_.kernel);
}

System::~System() = default;

void System::set_kernel(KernelPath p) {
    kernel_path_ = p == KernelPath::reference ? p : detail::resolve_kernel(p);
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
    save_history();  // wall indices change: carry springs over by id
    history_saved_ = true;
    std::vector<int> keep;
    keep.reserve(wid_.size());
    for (std::size_t k = 0; k < wid_.size(); ++k)
        if (std::find(ids.begin(), ids.end(), wid_[k]) == ids.end()) keep.push_back(int(k));
    compact(wx_, keep);
    compact(wy_, keep);
    compact(wr_, keep);
    compact(wid_, keep);
    walls_changed_ = true;
    rebuild();
}

void System::set_wall_motion(const Vec2& offset, const Vec2& velocity) {
    wall_offset_ = offset;
    wall_velocity_ = velocity;
}

void System::set_removal_floor(double y) {
    removal_floor_ = y;
}

void System::flush_removals() {
    if (!ready_) return;
    rebuild();
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
}

int System::index_of(int id) const {
    for (std::size_t k = 0; k < id_.size(); ++k)
        if (id_[k] == id) return int(k);
    return -1;
}

void System::ensure_ready() {
    if (ready_) return;
    // The integrator's history is rebuilt by prime() below.
    for (auto* col : {&x2_, &x3_, &x4_, &y2_, &y3_, &y4_, &w2_, &w3_, &w4_})
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
    const std::vector<double> px = pxi_x_, py = pxi_y_, wxs = wxi_x_, wys = wxi_y_;
    const double ov = kernel_->forces(*this);
    pxi_x_ = px;
    pxi_y_ = py;
    wxi_x_ = wxs;
    wxi_y_ = wys;
    check_overlap(ov);
    kernel_->prime(*this);
    ready_ = true;
}

void System::step() {
    ensure_ready();
    const auto t0 = Clock::now();
    const double maxd2 = kernel_->predict(*this);
    const auto t1 = Clock::now();
    if (!(maxd2 <= std::numeric_limits<double>::max())) fail_nonfinite();
    const double dmax = std::max(std::sqrt(maxd2), (wall_offset_ - wall_offset_ref_).norm());
    if (need_rebuild_ || 2.0 * dmax > config_.skin) rebuild();
    const auto t2 = Clock::now();
    const double ov = kernel_->forces(*this);
    const auto t3 = Clock::now();
    kernel_->correct(*this);
    const auto t4 = Clock::now();
    time_ += config_.dt;
    check_overlap(ov);
    phase_.integration += seconds_between(t0, t1) + seconds_between(t3, t4);
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
    a.im = inv_m_.data();
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
    if (kernel_path_ != KernelPath::reference) {
        // Packed-pair scratch: 3 index and 7 double columns, mobile pairs then walls.
        const std::size_t np = pj_.size(), nw = wj_.size(), len = np + nw;
        if (pack_i_.size() < 3 * len) pack_i_.resize(3 * len);
        if (pack_d_.size() < 7 * len) pack_d_.resize(7 * len);
        auto carve = [&](detail::ForceArgs::Packed& pk, std::size_t off) {
            double* db = pack_d_.data();
            pk.entry = pack_i_.data() + off;
            pk.own = pack_i_.data() + len + off;
            pk.partner = pack_i_.data() + 2 * len + off;
            double** cols[] = {&pk.fx, &pk.fy, &pk.ti, &pk.tj, &pk.sx, &pk.sy, &pk.ov};
            for (std::size_t c = 0; c < 7; ++c)
                *cols[c] = db + c * len + off;
        };
        carve(a.mob, 0);
        carve(a.wall, np);
    }
    return a;
}

// ----- neighbour list ------------------------------------------------------------------------

void System::rebuild() {
    if (!history_saved_) save_history();
    history_saved_ = false;
    remove_below_floor();
    r_max_ = 0.0;
    for (double r : r_)
        r_max_ = std::max(r_max_, r);
    wr_max_ = 0.0;
    for (double r : wr_)
        wr_max_ = std::max(wr_max_, r);
    const double cutoff = 2.0 * r_max_ + config_.skin;
    const double wcutoff = r_max_ + wr_max_ + config_.skin;
    if (walls_changed_ || wcutoff > wcell_size_) build_wall_grid(wcutoff);
    permute_by_cell(cutoff);
    build_pairs();
    restore_history();
    xref_ = x_;
    yref_ = y_;
    wall_offset_ref_ = wall_offset_;
    need_rebuild_ = false;
    ++rebuilds_;
}

void System::remove_below_floor() {
    std::vector<int>& keep = iscratch_;
    keep.clear();
    for (std::size_t i = 0; i < y_.size(); ++i) {
        if (y_[i] < removal_floor_)
            removals_.push_back({id_[i], time_});
        else
            keep.push_back(int(i));
    }
    if (keep.size() == y_.size()) return;
    for (auto* col : {&x_,  &y_,  &vx_, &vy_, &w_,  &fx_, &fy_, &tq_, &r_,  &m_,   &inv_m_, &inv_I_,
                      &x2_, &x3_, &x4_, &y2_, &y3_, &y4_, &w2_, &w3_, &w4_, &avx_, &avy_,   &aw_})
        compact(*col, keep);
    compact(id_, keep);
}

void System::build_wall_grid(double cutoff) {
    const std::size_t nw = wx_.size();
    wcell_size_ = cutoff;
    if (nw == 0) {
        wgrid_nx_ = wgrid_ny_ = 1;
        wgrid_x0_ = wgrid_y0_ = 0.0;
        wcell_start_.assign(2, 0);
        wcell_items_.clear();
        walls_changed_ = false;
        return;
    }
    double x0 = wx_[0], x1 = wx_[0], y0 = wy_[0], y1 = wy_[0];
    for (std::size_t k = 0; k < nw; ++k) {
        x0 = std::min(x0, wx_[k]);
        x1 = std::max(x1, wx_[k]);
        y0 = std::min(y0, wy_[k]);
        y1 = std::max(y1, wy_[k]);
    }
    wgrid_x0_ = x0 - cutoff;
    wgrid_y0_ = y0 - cutoff;
    wgrid_nx_ = std::max(1, int(std::ceil((x1 - x0 + 2 * cutoff) / cutoff)));
    wgrid_ny_ = std::max(1, int(std::ceil((y1 - y0 + 2 * cutoff) / cutoff)));
    std::vector<int> cell;
    bin_points(wx_, wy_, wgrid_x0_, wgrid_y0_, cutoff, wgrid_nx_, wgrid_ny_, wcell_start_,
               wcell_items_, cell);
    walls_changed_ = false;
}

void System::permute_by_cell(double cutoff) {
    const std::size_t n = x_.size();
    if (n == 0) {
        cell_start_.assign(2, 0);
        grid_nx_ = grid_ny_ = 1;
        return;
    }
    // Grid over the particles and walls; clamping outliers into the border cells keeps the
    // search correct (clamping never separates two cells' neighbours), only slower for them.
    double x0 = x_[0], x1 = x_[0], y0 = y_[0], y1 = y_[0];
    for (std::size_t i = 0; i < n; ++i) {
        x0 = std::min(x0, x_[i]);
        x1 = std::max(x1, x_[i]);
        y0 = std::min(y0, y_[i]);
        y1 = std::max(y1, y_[i]);
    }
    if (!wx_.empty()) {
        // Keep the grid to the hopper's extent (plus a margin) even if a particle flew away.
        const double m = 4.0 * cutoff;
        const double wx0 = wgrid_x0_ + wall_offset_.x() - m;
        const double wy0 = wgrid_y0_ + wall_offset_.y() - m;
        const double wx1 = wx0 + wgrid_nx_ * wcell_size_ + 2 * m;
        const double wy1 = wy0 + wgrid_ny_ * wcell_size_ + 2 * m;
        x0 = std::max(std::min(x0, wx0 + m), wx0);
        y0 = std::max(std::min(y0, wy0 + m), wy0);
        x1 = std::min(std::max(x1, wx1 - m), wx1);
        y1 = std::min(std::max(y1, wy1 - m), wy1);
    }
    double cs = cutoff;
    const double max_cells = 4.0 * double(n + wx_.size()) + 1024.0;
    while (((x1 - x0) / cs + 1) * ((y1 - y0) / cs + 1) > max_cells)
        cs *= 1.5;
    cell_size_ = cs;
    grid_x0_ = x0;
    grid_y0_ = y0;
    grid_nx_ = std::max(1, int((x1 - x0) / cs) + 1);
    grid_ny_ = std::max(1, int((y1 - y0) / cs) + 1);
    const int ncell = grid_nx_ * grid_ny_;
    // Counting sort: order_[new index] = old index.
    bin_points(x_, y_, x0, y0, cs, grid_nx_, grid_ny_, cell_start_, order_, cell_of_);
    for (auto* col : {&x_,  &y_,  &vx_, &vy_, &w_,  &fx_, &fy_, &tq_, &r_,  &m_,   &inv_m_, &inv_I_,
                      &x2_, &x3_, &x4_, &y2_, &y3_, &y4_, &w2_, &w3_, &w4_, &avx_, &avy_,   &aw_})
        permute(*col, order_, scratch_);
    permute(id_, order_, iscratch_);
    // cell_of_ in the new order is non-decreasing; rebuild it from the starts.
    for (int c = 0; c < ncell; ++c)
        for (int i = cell_start_[c]; i < cell_start_[c + 1]; ++i)
            cell_of_[i] = c;
}

void System::build_pairs() {
    const std::size_t n = x_.size();
    pstart_.resize(n + 1);
    wstart_.resize(n + 1);
    pj_.clear();
    wj_.clear();
    const double skin = config_.skin;
    // Half stencil: own cell (j > i) and four of the eight neighbours.
    static constexpr int sx[4] = {1, -1, 0, 1};
    static constexpr int sy[4] = {0, 1, 1, 1};
    for (std::size_t i = 0; i < n; ++i) {
        pstart_[i] = int(pj_.size());
        const double xi = x_[i], yi = y_[i], ri = r_[i];
        const int c = cell_of_[i];
        const int cx = c % grid_nx_, cy = c / grid_nx_;
        auto consider = [&](int j) {
            const double dx = xi - x_[j], dy = yi - y_[j];
            const double cut = ri + r_[j] + skin;
            if (dx * dx + dy * dy < cut * cut) pj_.push_back(j);
        };
        for (int j = int(i) + 1; j < cell_start_[c + 1]; ++j)
            consider(j);
        for (int s = 0; s < 4; ++s) {
            const int nx = cx + sx[s], ny = cy + sy[s];
            if (nx < 0 || nx >= grid_nx_ || ny >= grid_ny_) continue;
            const int nc = nx + ny * grid_nx_;
            for (int j = cell_start_[nc]; j < cell_start_[nc + 1]; ++j)
                consider(j);
        }
    }
    pstart_[n] = int(pj_.size());
    // Mobile-wall pairs from the wall grid (in the walls' base frame).
    const double ox = wall_offset_.x(), oy = wall_offset_.y();
    for (std::size_t i = 0; i < n; ++i) {
        wstart_[i] = int(wj_.size());
        if (wx_.empty()) continue;
        const double qx = x_[i] - ox, qy = y_[i] - oy, ri = r_[i];
        const int cx = std::clamp(int(std::floor((qx - wgrid_x0_) / wcell_size_)), -1, wgrid_nx_);
        const int cy = std::clamp(int(std::floor((qy - wgrid_y0_) / wcell_size_)), -1, wgrid_ny_);
        for (int ny = cy - 1; ny <= cy + 1; ++ny) {
            if (ny < 0 || ny >= wgrid_ny_) continue;
            for (int nx = cx - 1; nx <= cx + 1; ++nx) {
                if (nx < 0 || nx >= wgrid_nx_) continue;
                const int nc = nx + ny * wgrid_nx_;
                for (int k = wcell_start_[nc]; k < wcell_start_[nc + 1]; ++k) {
                    const int j = wcell_items_[k];
                    const double dx = qx - wx_[j], dy = qy - wy_[j];
                    const double cut = ri + wr_[j] + skin;
                    if (dx * dx + dy * dy < cut * cut) wj_.push_back(j);
                }
            }
        }
    }
    wstart_[n] = int(wj_.size());
    pair_constants();
}

void System::pair_constants() {
    const std::size_t n = x_.size();
    pmbar_.resize(pj_.size());
    wmbar_.resize(wj_.size());
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k)
            pmbar_[k] = 1.0 / (inv_m_[i] + inv_m_[pj_[k]]);
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k)
            wmbar_[k] = 1.0 / inv_m_[i];
    }
}

// Contact springs survive rebuilds keyed by the persistent ids of the pair: saved grouped by
// owner (the smaller id for two mobile particles, the mobile one against a wall), restored by a
// short scan of the owner's few entries. O(pairs), no sorting, no maps.
void System::save_history() {
    hist_start_.assign(next_id_ + 1, 0);
    hist_partner_.clear();
    hist_x_.clear();
    hist_y_.clear();
    if (!history_ || pstart_.size() != x_.size() + 1) return;
    const std::size_t n = x_.size();
    auto each_spring = [&](auto&& fn) {
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = pstart_[i]; k < pstart_[i + 1]; ++k)
                if (pxi_x_[k] != 0.0 || pxi_y_[k] != 0.0) {
                    const int a = id_[i], b = id_[pj_[k]];
                    fn(std::min(a, b), std::max(a, b), pxi_x_[k], pxi_y_[k]);
                }
            for (int k = wstart_[i]; k < wstart_[i + 1]; ++k)
                if (wxi_x_[k] != 0.0 || wxi_y_[k] != 0.0)
                    fn(id_[i], wid_[wj_[k]], wxi_x_[k], wxi_y_[k]);
        }
    };
    each_spring([&](int owner, int, double, double) { ++hist_start_[owner + 1]; });
    for (int k = 0; k < next_id_; ++k)
        hist_start_[k + 1] += hist_start_[k];
    const int total = hist_start_[next_id_];
    hist_partner_.resize(total);
    hist_x_.resize(total);
    hist_y_.resize(total);
    std::vector<int> fill(hist_start_.begin(), hist_start_.end() - 1);
    each_spring([&](int owner, int partner, double sx, double sy) {
        const int at = fill[owner]++;
        hist_partner_[at] = partner;
        hist_x_[at] = sx;
        hist_y_[at] = sy;
    });
}

void System::restore_history() {
    if (!history_) {
        pxi_x_.clear();
        pxi_y_.clear();
        wxi_x_.clear();
        wxi_y_.clear();
        return;
    }
    pxi_x_.assign(pj_.size(), 0.0);
    pxi_y_.assign(pj_.size(), 0.0);
    wxi_x_.assign(wj_.size(), 0.0);
    wxi_y_.assign(wj_.size(), 0.0);
    if (hist_partner_.empty()) return;
    auto lookup = [&](int owner, int partner, double& sx, double& sy) {
        if (owner + 1 >= int(hist_start_.size())) return;
        for (int k = hist_start_[owner]; k < hist_start_[owner + 1]; ++k)
            if (hist_partner_[k] == partner) {
                sx = hist_x_[k];
                sy = hist_y_[k];
                return;
            }
    };
    const std::size_t n = x_.size();
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            const int a = id_[i], b = id_[pj_[k]];
            lookup(std::min(a, b), std::max(a, b), pxi_x_[k], pxi_y_[k]);
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k)
            lookup(id_[i], wid_[wj_[k]], wxi_x_[k], wxi_y_[k]);
    }
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

double System::elastic_energy() const {
    if (pstart_.size() != x_.size() + 1) return 0.0;
    double e = 0.0;
    for_each_touching(
        [&](std::size_t i, int j, int k, double, double, double d2) {
            const double ov = r_[i] + r_[j] - std::sqrt(d2);
            e += 0.5 * config_.particle.k_n * ov * ov;
            if (history_)
                e += 0.5 * config_.particle.k_t * (pxi_x_[k] * pxi_x_[k] + pxi_y_[k] * pxi_y_[k]);
        },
        [&](std::size_t i, int j, int k, double, double, double d2) {
            const double ov = r_[i] + wr_[j] - std::sqrt(d2);
            e += 0.5 * config_.wall.k_n * ov * ov;
            if (history_)
                e += 0.5 * config_.wall.k_t * (wxi_x_[k] * wxi_x_[k] + wxi_y_[k] * wxi_y_[k]);
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
