#pragma once
// The System's kernel (private to the engine): one contact law and one integrator chosen at
// setup, so that the hot loops contain no configuration branches and no per-contact virtual
// calls (one virtual call per phase). kernel.cpp holds the integrators (Gear predictor-corrector,
// velocity Verlet, the contact corrections' second velocity set) and calls the force pass of
// the chosen path (force_batch.hpp).

#include <memory>

#include "force_batch.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine {

struct System::Kernel {
    virtual ~Kernel() = default;
    // Advances positions; returns the largest squared displacement since the last rebuild
    // (NaN when the state is not finite). Loops use __restrict pointers (the columns never
    // alias) so that the compiler vectorizes them.
    virtual double predict(System& s) = 0;
    // Computes forces and torques; returns the largest overlap of this evaluation and its other
    // sums. With `correct`, the integrator's correction (Gear corrector, verlet's closing half
    // kick) is fused into the pass (integrate.hpp): the same bits as forces, then correct();
    // the sums then also hold the next step's largest squared displacement. With `predict` as
    // well, the predictor too, a block ahead (the fused step): the same bits as predict(),
    // forces, correct().
    virtual detail::ForceSums forces(System& s, bool correct, bool predict) = 0;
    // The corrector as a separate pass (the fused form above gives the same bits; System::step
    // uses this one with StepFusion::none, the default).
    virtual void correct(System& s) = 0;
    // Initialises the integrator's history from the current forces.
    virtual void prime(System& s) = 0;
};

namespace detail {
// The kernel of the contact law with this id in the registry (laws.hpp) and this integrator.
std::unique_ptr<System::Kernel> make_kernel(int law, Scheme scheme);
}  // namespace detail

}  // namespace hopper::engine
