#pragma once
// The particle system: mobile disks and immobile wall disks, the neighbour list, the contact
// forces and the time integrator. It knows nothing of hoppers; scene building and the
// realization protocol live in scene.hpp and realization.hpp.
//
// Layout (style.md, hot loop): per-particle state in columns, mobile particles only (walls have
// their own columns and are never integrated). Particles are re-sorted by cell at neighbour
// rebuilds, so the index of a particle changes; its id (returned by add_*) never does.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hopper/core/vec.hpp"
#include "hopper/engine/contact.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::engine {

namespace detail {
struct ForceArgs;
}

// Which implementation of the force pass runs (issue 12). Every path gives the same bits:
// `reference` is the force pass of force_batch_impl.hpp with one lane (each contact evaluated
// where it is found); the batched paths, the same pass with several lanes, pack the touching
// pairs and evaluate the contact law in SIMD registers of the named instruction set; `automatic`
// takes the path measured fastest (force_batch.cpp: the reference on the machines measured).
// avx512_gather ("avx512-gather"): the AVX-512 pass built to load partners with the hardware's
// gather instructions, which pay on Intel's AVX-512 cores and not on AMD's (issue 41;
// docs/performance.md): automatic picks it on an Intel CPU with AVX-512. The same bits.
enum class KernelPath { automatic, reference, baseline, avx2, avx512, avx512_gather };
std::string to_string(KernelPath p);
KernelPath parse_kernel_path(const std::string& s);  // "auto", "reference", ...; ConfigError

// How the integrator's passes are arranged around the force pass (round 3, issue 25;
// docs/performance.md, "Round 3, second session"). Every form gives the same bits; the choice is
// speed only. `none`: predictor, force pass and corrector as passes of their own (the default:
// measured fastest on the scalar and AVX2 paths, even on AVX-512). `corrector`: the corrector
// inside the force pass, block by block. `step`: that, and the predictor too, a block ahead of
// the rows that read it, on steps that need no rebuild.
enum class StepFusion { none, corrector, step };
std::string to_string(StepFusion f);
StepFusion parse_step_fusion(const std::string& s);  // "none", "corrector", "step"; ConfigError

struct SystemConfig {
    double dt = 1e-5;  // s
    Scheme scheme = Scheme::verlet;
    ContactParams particle;  // particle-particle contacts
    ContactParams wall;      // particle-wall contacts
    Vec2 gravity{0.0, -core::standard_gravity};
    double skin = 1e-3;        // m, Verlet skin of the neighbour list
    double max_overlap = 0.0;  // m; > 0: a larger overlap stops the run (SimulationError)
    // Lever arm R - x/2 (to the middle of the overlap) instead of R, in the contact velocity
    // and the torque (LeverArm in params.hpp).
    bool contact_lever = false;
    // Contact corrections (bench/results/ACCURACY.md, proposals A, B, C): a new spring grows only
    // over the part of the step spent in contact; with verlet the dashpots and the Coulomb cap
    // use the velocity extrapolated to the end of the step; with gear4 the spring grows with the
    // mean of the last corrected and the predicted velocity. Both make the spin and restitution
    // biases of a collision smaller at a given time step (docs/accuracy.md).
    bool contact_corrections = false;
    KernelPath kernel = KernelPath::automatic;
    // The contact law, by its normal and tangential parts (params.hpp): System takes the law of
    // the registry (laws.hpp) that has both; hertz uses the hertz_* coefficients of the
    // ContactParams above. automatic: inferred from the coefficients (TangentialLaw).
    NormalLaw normal_law = NormalLaw::linear;
    TangentialLaw tangential_law = TangentialLaw::automatic;
    // Rolling resistance (ContactParams::mu_r > 0): the registry's WithRolling variant of the law;
    // with rolling_spring its WithRollingSpring variant (a spring with history, capped at the
    // constant torque; linear normal law only).
    bool rolling = false;
    bool rolling_spring = false;
    // Plate friction (MaterialParams::plate_friction): a force of m plate_decel against each
    // mobile disk's velocity v, times |v| / plate_speed below plate_speed; 0 = none (and not a
    // flop of the step is spent on it).
    double plate_decel = 0.0;   // m/s^2
    double plate_speed = 0.01;  // m/s
    // A load band (the steady state's lid, docs/model.md "The lid"): each mobile disk whose
    // centre lies in [load_y_lo, load_y_hi] feels a further m load_accel downward; 0 = none
    // (and not a flop of the step is spent on it). Set with System::set_load_band.
    double load_accel = 0.0;                  // m/s^2
    double load_y_lo = 0.0, load_y_hi = 0.0;  // m
};

// A particle that left through the removal floor.
struct Removal {
    int id;
    double time;  // System::time() when it was removed
};

struct PhaseSeconds {
    double forces = 0.0, integration = 0.0, neighbors = 0.0;
};

class System {
  public:
    explicit System(const SystemConfig& config);
    ~System();
    System(const System&) = delete;
    System& operator=(const System&) = delete;

    // --- building -------------------------------------------------------------------------
    // Returns the particle's id (ids are shared by mobile and wall particles and never reused).
    int add_particle(const Vec2& pos, double diameter, double mass, double inertia,
                     const Vec2& vel = Vec2::Zero(), double omega = 0.0);
    int add_wall(const Vec2& pos, double diameter);
    // Removes wall particles by id (e.g. the gate that closes the outlet while settling).
    void remove_walls(std::span<const int> ids);
    // The load band of SystemConfig (load_accel, load_y_lo, load_y_hi) from the next step on;
    // accel 0 takes it off.
    void set_load_band(double y_lo, double y_hi, double accel);
    // Rigid translation of all walls: positions are base + offset, velocity is shared.
    void set_wall_motion(const Vec2& offset, const Vec2& velocity);
    // Mobile particles whose centre falls below this height are removed at the next neighbour
    // rebuild (or at flush_removals()) and reported by take_removals().
    void set_removal_floor(double y);
    void flush_removals();
    std::vector<Removal> take_removals();
    // Takes these mobile particles (ids) out at once, without reporting them as removals: they
    // did not leave through the outlet (the arch removal of protocol.unjam, docs/model.md).
    // Unknown ids are ignored.
    void discard_particles(std::span<const int> ids);

    // --- stepping -------------------------------------------------------------------------
    // One time step. Throws core::SimulationError on a non-finite state or an overlap beyond
    // max_overlap; the message names the cause and the remedy.
    void step();
    void run(std::int64_t steps);

    // --- state ----------------------------------------------------------------------------
    double time() const { return time_; }
    double dt() const { return config_.dt; }
    const SystemConfig& config() const { return config_; }
    int mobile_count() const { return static_cast<int>(x_.size()); }
    int wall_count() const { return static_cast<int>(wx_.size()); }
    // Index of a mobile particle id, or -1 if there is no such (remaining) particle.
    int index_of(int id) const;
    Vec2 position(int index) const { return {x_[index], y_[index]}; }
    Vec2 velocity(int index) const { return {vx_[index], vy_[index]}; }
    double omega(int index) const { return w_[index]; }
    double radius(int index) const { return r_[index]; }
    double mass(int index) const { return m_[index]; }
    int id(int index) const { return id_[index]; }
    void set_velocity(int index, const Vec2& v, double omega);
    // Columns, for observers and snapshots.
    std::span<const double> x() const { return x_; }
    std::span<const double> y() const { return y_; }
    std::span<const double> vx() const { return vx_; }
    std::span<const double> vy() const { return vy_; }
    std::span<const double> w() const { return w_; }
    std::span<const double> r() const { return r_; }
    std::span<const double> m() const { return m_; }
    std::span<const int> ids() const { return id_; }
    std::span<const double> wall_x() const { return wx_; }  // base positions (add offset)
    std::span<const double> wall_y() const { return wy_; }
    std::span<const double> wall_r() const { return wr_; }
    std::span<const int> wall_ids() const { return wid_; }
    Vec2 wall_offset() const { return wall_offset_; }
    Vec2 wall_velocity() const { return wall_velocity_; }

    // Energies (J): kinetic (translation + rotation), gravitational (-m g.r summed, zero at the
    // origin), elastic (normal and tangential springs of the current contacts; computed on
    // demand from the neighbour list, never in the hot loop).
    double kinetic_energy() const;
    double potential_energy() const;
    double elastic_energy() const;
    // Sum over each particle's current contacts of |F_n| = |k_n x - gamma_n mbar v_n| (N),
    // evaluated now from the neighbour list (not in the hot loop: costs about one force pass).
    // `mobile` gets one entry per mobile particle (index order) and `wall` one per wall
    // particle (wall order); either may be empty to skip it.
    void normal_force_sums(std::span<double> mobile, std::span<double> wall);
    // Total force exerted by the particles on all walls in the last force evaluation.
    Vec2 wall_force() const { return wall_force_; }
    // Largest overlap seen since the last reset (m).
    double max_overlap() const { return max_overlap_seen_; }
    void reset_max_overlap() { max_overlap_seen_ = 0.0; }
    // Number of active contacts (overlap > 0) in the last force evaluation.
    int contact_count() const { return contacts_; }
    std::int64_t neighbor_rebuilds() const { return rebuilds_; }
    const PhaseSeconds& phase_seconds() const { return phase_; }
    // The force pass that runs (never automatic): recorded in each realization's diagnostics.
    KernelPath kernel_path() const { return kernel_path_; }
    // Switches the force pass (bench_engine --paths compares them on one trajectory; the bits
    // do not change). ConfigError if this CPU cannot run it.
    void set_kernel(KernelPath p);
    // A new time step from the next step on (the settle's own, docs/model.md, "Realization
    // protocol"). With `rescale`, Gear's scaled derivatives r_k = dt^k/k! d^k r/dt^k are carried
    // over to it (times (dt_new/dt_old)^k), so that the trajectory continues smoothly; without,
    // they are taken as already scaled to dt_new (a restored checkpoint). Before the first step
    // it only sets dt (the priming uses it); the same dt changes nothing. ConfigError for a dt
    // that is not positive and finite.
    void set_time_step(double dt, bool rescale = true);
    // The arrangement of the integrator's passes (StepFusion; none by default). The bits do
    // not change (test_kernel_paths); for tests and bench_engine --fusion.
    void set_step_fusion(StepFusion f);
    StepFusion step_fusion() const { return fusion_; }
    // Candidate pairs in the neighbour list (mobile-mobile, mobile-wall).
    std::int64_t pair_count() const { return static_cast<std::int64_t>(pj_.size()); }
    std::int64_t wall_pair_count() const { return static_cast<std::int64_t>(wj_.size()); }
    // Every (id, id) pair within contact distance, from the neighbour list (for tests).
    std::vector<std::pair<int, int>> contacts_from_list();

    // Implementation detail: the kernel chosen at setup (law x integrator).
    struct Kernel;

  private:
    template <class Law, Scheme S>
    friend struct KernelImpl;
    friend struct CheckpointAccess;  // checkpoint.cpp: the whole state to bytes and back

    // The per-particle columns of doubles, listed once (issue 42). history_columns: the Gear
    // integrator's scaled derivatives. saved_columns: the state, the properties and that history,
    // in the checkpoint's order. particle_columns: those and the second velocity set of the
    // contact corrections (derived at the start, not saved): what a rebuild reorders and a
    // removal compacts (the ids go beside). S is System or const System.
    template <class S>
    static auto history_columns(S& s) {
        return std::array{&s.x2_, &s.x3_, &s.x4_, &s.y2_, &s.y3_, &s.y4_, &s.w2_, &s.w3_, &s.w4_};
    }
    template <class S>
    static auto saved_columns(S& s) {
        const auto h = history_columns(s);
        return std::array{&s.x_,  &s.y_, &s.vx_, &s.vy_,    &s.w_,     &s.fx_, &s.fy_,
                          &s.tq_, &s.r_, &s.m_,  &s.inv_m_, &s.inv_I_, h[0],   h[1],
                          h[2],   h[3],  h[4],   h[5],      h[6],      h[7],   h[8]};
    }
    template <class S>
    static auto particle_columns(S& s) {
        const auto c = saved_columns(s);
        std::array<typename decltype(c)::value_type, c.size() + 3> all{};
        std::copy(c.begin(), c.end(), all.begin());
        all[c.size()] = &s.avx_;
        all[c.size() + 1] = &s.avy_;
        all[c.size() + 2] = &s.aw_;
        return all;
    }

    // The contact history per list entry, listed once (issue 39): the tangential spring (x, y)
    // and the rolling spring's torque, of the mobile list (pair_springs) and of the wall list
    // (wall_springs). The first spring_count() of each are kept: none without history, the
    // tangential spring's two, or all three with the rolling spring.
    template <class S>
    static auto pair_springs(S& s) {
        return std::array{&s.pxi_x_, &s.pxi_y_, &s.pxi_r_};
    }
    template <class S>
    static auto wall_springs(S& s) {
        return std::array{&s.wxi_x_, &s.wxi_y_, &s.wxi_r_};
    }
    std::size_t spring_count() const { return !history_ ? 0 : rolling_history_ ? 3 : 2; }

    detail::ForceArgs force_args();  // the columns and scratch of a force pass
    void ensure_ready();
    // Calls pair(i, j, k, dx, dy, d2) for every touching mobile pair of the neighbour list and
    // wall(i, j, k, dx, dy, d2) for every touching particle-wall pair (k: list entry; dx, dy:
    // r_i - r_j, walls at their current offset). For the on-demand observables, not the hot loop.
    template <class Pair, class Wall>
    void for_each_touching(Pair&& pair, Wall&& wall) const;
    void rebuild();
    void save_history();
    void restore_history();
    void build_wall_grid(double cutoff);
    void remove_below_floor();
    void permute_by_cell(double cutoff);
    void build_pairs();
    void pair_constants();  // pmbar_, wmbar_ from the list (after a rebuild or a restore)
    [[noreturn]] void fail_nonfinite() const;
    void check_overlap(double step_max_overlap);

    SystemConfig config_;
    std::unique_ptr<Kernel> kernel_;
    double time_ = 0.0;
    bool ready_ = false;  // forces and integrator history initialised
    bool need_rebuild_ = true;
    bool walls_changed_ = true;
    bool history_saved_ = false;    // save_history() already ran for the coming rebuild
    bool history_ = false;          // keep tangential springs (k_t > 0 and mu > 0)
    bool rolling_history_ = false;  // and rolling springs (SystemConfig::rolling_spring)
    int next_id_ = 0;
    // StepFusion::step (docs/performance.md): the last step's corrector also computed the
    // largest squared displacement the next predictor will give (ahead_d2_); while nothing else
    // changed the state since (ahead_), a step that needs no rebuild predicts inside its force
    // pass instead of in a pass of its own. Not part of a checkpoint: a restored System takes
    // the separate predictor once (the same bits).
    StepFusion fusion_ = StepFusion::none;
    bool ahead_ = false;
    double ahead_d2_ = 0.0;

    // Mobile particle columns.
    std::vector<double> x_, y_, vx_, vy_, w_, fx_, fy_, tq_;
    std::vector<double> r_, m_, inv_m_, inv_I_;
    std::vector<int> id_;
    // Gear predictor-corrector: scaled derivatives r_k = dt^k/k! d^k r/dt^k, k = 2..4.
    std::vector<double> x2_, x3_, x4_, y2_, y3_, y4_, w2_, w3_, w4_;
    // Positions at the last rebuild (for the displacement criterion).
    std::vector<double> xref_, yref_;
    Vec2 wall_offset_ref_ = Vec2::Zero();

    // Wall columns (base positions).
    std::vector<double> wx_, wy_, wr_;
    std::vector<int> wid_;
    Vec2 wall_offset_ = Vec2::Zero();
    Vec2 wall_velocity_ = Vec2::Zero();

    // Neighbour list (half list, CSR by mobile index): mobile-mobile and mobile-wall.
    std::vector<int> pstart_, pj_, wstart_, wj_;
    std::vector<double> pxi_x_, pxi_y_, wxi_x_, wxi_y_;  // tangential springs (if history_)
    std::vector<double> pxi_r_, wxi_r_;  // rolling springs' torques (if rolling_history_)
    // Reduced mass per list entry, 1 / (1/m_i + 1/m_j) (walls: 1 / (1/m_i)): a per-pair constant
    // set at each rebuild, so that the force pass divides less.
    std::vector<double> pmbar_, wmbar_;
    // More per-entry constants, only for the laws that read them (round 3): R* (the Hertz law,
    // rolling resistance) and the Hertz law's K and alpha sqrt(mbar K) (HertzSpringLaw).
    std::vector<double> prstar_, wrstar_, phk_, whk_, pheta_, wheta_;
    // The mobile particle each list entry belongs to (the batched force pass loops over entries).
    std::vector<int> pown_, wown_;
    // Per block of detail::block_rows rows: one past the largest particle index its rows read
    // (its own and their partners'), for the fused step's predictor (integrate.hpp).
    std::vector<int> block_reach_;
    // Cell grid for mobile particles (rebuilt with the list) and for walls (when walls change).
    double cell_size_ = 0.0, grid_x0_ = 0.0, grid_y0_ = 0.0;
    int grid_nx_ = 0, grid_ny_ = 0;
    std::vector<int> cell_start_, cell_of_, order_;
    double wcell_size_ = 0.0, wgrid_x0_ = 0.0, wgrid_y0_ = 0.0;
    int wgrid_nx_ = 0, wgrid_ny_ = 0;
    std::vector<int> wcell_start_, wcell_items_;
    double r_max_ = 0.0, wr_max_ = 0.0;
    // The springs carried across a rebuild (round 3, docs/performance.md): the list before it,
    // moved aside (old_*), and for every particle of the new list its index in the old one
    // (carry_old_; walls: wall_old_, empty while the walls keep their indices). Transient: set
    // by save_history(), read by restore_history() in the same rebuild (carry_), never part of
    // a checkpoint.
    bool carry_ = false;
    std::vector<int> old_pstart_, old_pj_, old_wstart_, old_wj_, carry_old_, wall_old_;
    std::array<std::vector<double>, 3> old_springs_, old_wall_springs_;
    std::vector<double> scratch_;
    std::vector<int> iscratch_;
    // Second velocity set when contact_corrections is on: verlet, velocities extrapolated to the
    // end of the step (for the dashpots); gear4, the mean of the last corrected and the predicted
    // velocities (for the springs).
    std::vector<double> avx_, avy_, aw_;
    // Batched force pass: the chosen path and its scratch (force_batch.hpp).
    KernelPath kernel_path_ = KernelPath::reference;
    std::vector<double> batch_scratch_;
    std::vector<int> batch_index_;

    double removal_floor_ = -1e300;
    std::vector<Removal> removals_;
    std::vector<int> discard_;  // ids for remove_below_floor to drop unreported (transient)

    // Observables of the last force evaluation.
    Vec2 wall_force_ = Vec2::Zero();
    double max_overlap_seen_ = 0.0;
    int contacts_ = 0;
    std::int64_t rebuilds_ = 0;
    PhaseSeconds phase_;
};

}  // namespace hopper::engine
