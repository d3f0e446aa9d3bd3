#pragma once
// The parts of the realization protocol (private to the engine), each a small class the
// realization (realization.cpp) schedules from one trigger list: the jam detector, the shaker,
// the discharge log, the coarse-grained fields and the steady state's re-insertion. Their state
// is public data: the realization's checkpoint writes it field by field (checkpoint.hpp), in an
// order that is part of the state format.

#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/core/vec.hpp"
#include "hopper/engine/fields.hpp"
#include "hopper/engine/params.hpp"
#include "hopper/engine/result.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine::detail {

// Steps between two looks of an observer that wants to run every `seconds`.
std::int64_t every(double seconds, double dt);

// Mass, diameter and moment of inertia by particle id (walls: 0), for particles that leave.
struct IdTable {
    std::vector<double> mass, diameter, inertia;
    void remember(int id, double m, double d, double I);
};

// The jam detector (docs/model.md, steps 4-6): the region below the outlet and the state of
// the flow. Times are discharge times (td: shaking excluded).
class JamDetector {
  public:
    // The order is part of the checkpoint format.
    enum class Flow { flowing, shaking, checking, ended };
    enum class Look { nothing, jammed, restarted, still_jammed };

    explicit JamDetector(const SceneParams& p);

    // A particle inside |x| < half_gap, y_region < y < y_outlet moving at least min_speed
    // (docs/model.md, step 4: one lodged there at rest is part of the clog, not of the flow).
    bool occupied(const System& s) const;
    // One look at the region: while flowing, `jammed` once it has been empty for t_check
    // (the jam's onset is last_occupied; [onset, td) is appended to `jammed`); after a
    // shake (checking), `restarted` when a particle is there again (the new survival interval
    // starts at check_start) or `still_jammed` after t_check without one.
    Look look(const System& s, double td, double t_check);

    // The region: below the edge disks (y_outlet = 0, half_gap = D/2 in the default geometry).
    double y_outlet = 0.0, half_gap = 0.0, y_region = 0.0;
    double min_speed2 = 0.0;  // (m/s)^2; 0: every particle in the region counts
    Flow flow = Flow::flowing;
    double flow_start = 0.0;     // td at which the current survival interval began
    double last_occupied = 0.0;  // td at which the region last held a particle
    double check_start = 0.0;    // td at which the post-shake check began
    std::vector<std::pair<double, double>> jammed;  // [onset, restart) in td
};

// The shake (docs/model.md, step 5): one sinusoidal oscillation of the walls,
// u(t) = A_k sin(2 pi t / T) e, the k-th shake of a jam with A_k = min(A g^(k-1), A_max).
class Shaker {
  public:
    Shaker(const SceneParams& p, double dt);
    void start(double sim_time);
    // A_k of the current shake (m): from shakes_this_jam, so a checkpoint needs nothing more.
    double amplitude() const;
    // Wall motion at the end of the coming step (at rest once the period is over).
    void drive(System& s) const;
    bool done(double sim_time) const;

    double shake_start = 0.0;  // sim time at which the current shake began
    int shakes_this_jam = 0;

  private:
    double period_, amplitude_, growth_, amplitude_max_, direction_, dt_;
};

// What left the hopper and when: exit times (in the result), their masses, the discharge
// curve, and the discharge rate fitted at the end.
class DischargeLog {
  public:
    // Takes the system's removals: exit time td and mass of each; then on_exit(id) (the steady
    // state re-inserts the particle there), removal by removal.
    void record(System& s, double td, const IdTable& ids, RealizationResult& res,
                const std::function<void(int)>& on_exit);
    void sample(double td, int in_hopper, RealizationResult& res) const;
    // The steady part's rate: exits between 20 % and 80 % of all discharged particles against
    // the flowing time (discharge time minus the jammed periods). Nothing below 20 exits.
    void fit_rate(const std::vector<std::pair<double, double>>& jammed,
                  RealizationResult& res) const;
    double removed_mass() const;

    std::vector<double> exit_mass;  // kg, in exit order
};

// The coarse-grained fields (fields.hpp) while they are on (p.fields.enabled, from the opening).
class FieldsObserver {
  public:
    // The grid covers the container's full width and from the removal floor to the top of the
    // walls; the outlet (y = 0) and the axis (x = 0) lie on cell boundaries.
    void start(const SceneParams& p, double dt, double wall_top, const std::vector<Vec2>& outline);
    bool active() const { return acc != nullptr; }
    void sample(const SceneParams& p, System& s, double td);
    void finish(RealizationResult& res);

    std::unique_ptr<FieldAccumulator> acc;
    std::int64_t period = 1;  // steps between samples

  private:
    std::vector<double> pressure_;  // per mobile particle, units of m g
};

// The steady state (protocol.mode = "steady_state"): each particle that leaves comes back at
// the top of the packing.
class Reinserter {
  public:
    // The settled packing's top (the head stays there as the count is constant).
    void set_base(const System& s, double y_outlet);
    // A position drawn from the realization's generator where the particle overlaps nothing:
    // x across the container, y in a band from half a large diameter to three above insert_base
    // (measuring the top anew would follow particles still falling from earlier insertions
    // upward). Throws core::SimulationError after 2000 draws.
    void reinsert(int id, const SceneParams& p, System& s, IdTable& ids, core::Rng& rng) const;

    double insert_base = 0.0;
};

}  // namespace hopper::engine::detail
