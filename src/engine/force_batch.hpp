#pragma once
// The batched force pass (issue 12): the same forces as the reference loop in kernel.cpp,
// computed block by block (256 particles at a time, so that the scratch stays in the first-level
// cache) in three passes per kind of partner (mobile, then wall):
//   1. the touch test over the block's list entries, vectorized and computed exactly as the
//      reference loop does; springs of the entries that do not touch are reset; the touching
//      entries are then listed in order (entry, particle, partner): branch-free, and on AVX-512
//      16 entries at a time, compressed in registers;
//   2. the contact law over the touching entries, branch-free (pair_force.hpp, Select), in a
//      loop the compiler vectorizes for the instruction set the translation unit is built for;
//   3. accumulation (scalar, in list order): forces and torques summed in exactly the order of
//      the reference loop, springs written back, so every path gives the reference's bits.
// force_batch_impl.hpp holds the passes; force_batch_{baseline,avx2,avx512}.cpp compile it once
// per instruction set, each in its own namespace; force_batch.cpp picks one at run time.

#include <array>
#include <cstdint>
#include <string>

#include "hopper/engine/contact.hpp"
#include "hopper/engine/system.hpp"
#include "integrate.hpp"
#include "laws.hpp"

namespace hopper::engine::detail {

// Everything a force pass reads and writes: raw columns of the System (mobile particles,
// walls, neighbour list, springs) and scratch space for the batched passes.
struct ForceArgs {
    int n = 0;  // mobile particles
    const double *x, *y, *r;
    const double *vx, *vy, *w;     // velocities for the dashpots
    const double *svx, *svy, *sw;  // velocities for the springs (used with the corrections)
    double *fx, *fy, *tq;
    const int *ps, *pj, *ws, *wj;  // neighbour list (CSR by mobile index)
    double *hx, *hy, *gx, *gy;     // springs of mobile and wall pairs (null without history)
    const double *wx, *wy, *wr;    // walls (base positions)
    double ox, oy, vwx, vwy;       // wall offset and velocity
    ContactParams pp, pw;
    double dt, lever_half;
    const double *pmbar, *wmbar;  // reduced mass per list entry (set at each rebuild)
    // R* and the law's pair constants per list entry (set at each rebuild; null when the law
    // needs none): see System::pair_constants.
    const double *prstar, *wrstar, *pK, *wK, *peta, *weta;
    const int *po, *wo;  // the particle each list entry belongs to (set at each rebuild)
    // The corrector fused into the pass (integrate.hpp; scheme none: forces only).
    CorrectArgs correct;
    // Scratch of the batched passes, for one block: flags per list entry, then per touching entry.
    struct Scratch {
        int *flag, *entry, *owner, *partner;       // touch flags; touching entries, particles
        double *fx, *fy, *ti, *tj, *sx, *sy, *ov;  // per touching entry
    } scratch;
};

struct ForceSums {
    double max_overlap = 0.0, wall_fx = 0.0, wall_fy = 0.0;
    int contacts = 0;
    // With the corrector fused: the largest squared displacement the next step's predictor will
    // give (NaN if not finite; CorrectArgs::next_displacement).
    double next_displacement2 = 0.0;
};

using ForceFn = ForceSums (*)(const ForceArgs&);

// The batched pass of one instruction set, by law (its id in the registry, laws.hpp) and
// whether the contact corrections are on (see pair_force).
struct ForceTable {
    std::array<std::array<ForceFn, 2>, law_count> fn;
};

const ForceTable& force_table_baseline();
const ForceTable& force_table_avx2();
const ForceTable& force_table_avx512();

// The path to use for `wanted` on this CPU; throws core::ConfigError if it is not available.
KernelPath resolve_kernel(KernelPath wanted);
bool kernel_available(KernelPath p);
const ForceTable& force_table(KernelPath p);  // p is a batched path

}  // namespace hopper::engine::detail
