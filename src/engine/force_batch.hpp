#pragma once
// The force pass (issues 12 and 42), one source for every path: block by block (256 particles
// at a time, so that the scratch stays in the first-level cache), per kind of partner (mobile,
// then wall), the touch test over the block's list entries (the springs of the entries that do
// not touch reset, the touching ones listed in order: entry, particle, partner), then the
// contact law over the touching entries (pair_force.hpp), their forces and torques summed in
// list order. force_batch_impl.hpp holds the pass as a template over its lanes:
//   - one lane (force_batch_reference.cpp): the reference pass, scalar code, each contact added
//     to the sums as its law is evaluated;
//   - several (force_batch_{baseline,avx2,avx512}.cpp, the batched paths): the touch test and
//     the law vectorized for the instruction set the translation unit is built for (the
//     touching entries compacted 16 at a time in registers on AVX-512), the law's results kept
//     per entry and then summed in the same order, so every path gives the reference's bits.
// Each build is compiled in its own namespace; force_batch.cpp picks one at run time.

#include <array>
#include <cstdint>
#include <string>

#include "hopper/engine/contact.hpp"
#include "hopper/engine/system.hpp"
#include "integrate.hpp"
#include "laws.hpp"

namespace hopper::engine::detail {

// Everything a force pass reads and writes: raw columns of the System (mobile particles,
// walls, neighbour list, springs) and scratch space for the passes.
struct ForceArgs {
    int n = 0;  // mobile particles
    const double *x, *y, *r;
    const double *vx, *vy, *w;     // velocities for the dashpots
    const double *svx, *svy, *sw;  // velocities for the springs (used with the corrections)
    double *fx, *fy, *tq;
    const int *ps, *pj, *ws, *wj;  // neighbour list (CSR by mobile index)
    double *hx, *hy, *gx, *gy;     // springs of mobile and wall pairs (null without history)
    double *hr, *gr;               // rolling springs of mobile and wall pairs (null without)
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
    // Scratch for one block: flags per list entry (batched paths), then per touching entry (the
    // indices on every path; the law's results on the batched paths, null on the reference).
    struct Scratch {
        int *flag, *entry, *owner, *partner;            // touch flags; touching entries, particles
        double *fx, *fy, *ti, *tj, *sx, *sy, *ov, *sr;  // per touching entry
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

// The force pass of one build, by law (its id in the registry, laws.hpp) and whether the
// contact corrections are on (see pair_force).
struct ForceTable {
    std::array<std::array<ForceFn, 2>, law_count> fn;
};

const ForceTable& force_table_reference();
const ForceTable& force_table_baseline();
const ForceTable& force_table_avx2();
const ForceTable& force_table_avx512();
const ForceTable& force_table_avx512_gather();

// The path to use for `wanted` on this CPU; throws core::ConfigError if it is not available.
KernelPath resolve_kernel(KernelPath wanted);
bool kernel_available(KernelPath p);
const ForceTable& force_table(KernelPath p);  // p is resolved (not automatic)

}  // namespace hopper::engine::detail
