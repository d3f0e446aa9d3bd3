// The batched force pass (force_batch.hpp), compiled once per instruction set: the including
// translation unit defines HOPPER_FORCE_NS (a namespace of its own, so that no template
// instantiation is shared between differently compiled objects) and HOPPER_FORCE_TABLE (the
// name of its table getter). No include guard: one inclusion per translation unit.
//
// Only always-inlined code and builtins may be called from here: a function emitted out of line
// in an AVX-512 object and merged by the linker with the baseline one would run AVX-512
// instructions on any CPU.

#include "force_batch.hpp"
#include "pair_force.hpp"

namespace hopper::engine::detail::HOPPER_FORCE_NS {
namespace {

// Particles per block: their list entries' results (5 doubles each, about 3 entries per
// particle) stay in the first-level cache between the two passes.
constexpr int block_particles = 256;

// Pass 1 over the list entries [k0, k1) of one kind of partner (mobile or wall): the contact law
// for every entry, touching or not, branch-free and vectorized. Results go to the scratch at
// k - k0; springs are updated in place (reset where the pair does not touch). Returns the
// number of touching entries.
template <class Law, bool Corr, bool Wall>
int evaluate(const ForceArgs& a, int k0, int k1) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    const ContactParams p = Wall ? a.pw : a.pp;
    const double dt = a.dt, lever_half = a.lever_half;
    double* __restrict hx = Wall ? a.gx : a.hx;
    double* __restrict hy = Wall ? a.gy : a.hy;
    const int* __restrict own = Wall ? a.wo : a.po;
    const int* __restrict partner = Wall ? a.wj : a.pj;
    const double* __restrict mbar = Wall ? a.wmbar : a.pmbar;
    const double* __restrict x = a.x;
    const double* __restrict y = a.y;
    const double* __restrict r = a.r;
    const double* __restrict px = Wall ? a.wx : a.x;
    const double* __restrict py = Wall ? a.wy : a.y;
    const double* __restrict pr = Wall ? a.wr : a.r;
    const double* __restrict vx = a.vx;
    const double* __restrict vy = a.vy;
    const double* __restrict w = a.w;
    const double* __restrict svx = a.svx;
    const double* __restrict svy = a.svy;
    const double* __restrict sw = a.sw;
    double* __restrict ofx = a.scratch.fx - k0;
    double* __restrict ofy = a.scratch.fy - k0;
    double* __restrict oti = a.scratch.ti - k0;
    double* __restrict otj = a.scratch.tj - k0;
    double* __restrict oov = a.scratch.ov - k0;
    const double vwx = a.vwx, vwy = a.vwy, ox = a.ox, oy = a.oy;
    int touching = 0;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN) reduction(+ : touching)
    for (int k = k0; k < k1; ++k) {
        // The separation and the touch test exactly as the reference loop computes them.
        const int i = own[k], j = partner[k];
        PairInput q;
        q.dx = Wall ? x[i] - (px[j] + ox) : x[i] - px[j];
        q.dy = Wall ? y[i] - (py[j] + oy) : y[i] - py[j];
        q.ri = r[i];
        q.rj = pr[j];
        q.rs = q.ri + q.rj;
        q.d2 = q.dx * q.dx + q.dy * q.dy;
        const bool touch = !(q.d2 >= q.rs * q.rs);
        q.mbar = mbar[k];
        q.vix = vx[i];
        q.viy = vy[i];
        q.wi = rot ? w[i] : 0.0;
        q.vjx = Wall ? vwx : vx[j];
        q.vjy = Wall ? vwy : vy[j];
        q.wj = Wall || !rot ? 0.0 : w[j];
        if constexpr (Corr) {
            q.six = svx[i];
            q.siy = svy[i];
            q.swi = rot ? sw[i] : 0.0;
            q.sjx = Wall ? vwx : svx[j];
            q.sjy = Wall ? vwy : svy[j];
            q.swj = Wall || !rot ? 0.0 : sw[j];
        } else {
            q.six = q.siy = q.swi = q.sjx = q.sjy = q.swj = 0.0;
        }
        double sx = 0.0, sy = 0.0;
        if constexpr (hist) {
            sx = hx[k];
            sy = hy[k];
        }
        const PairOutput o = pair_force<Law, Corr, true>(p, dt, lever_half, q, sx, sy);
        // Not touching: no force, and the spring is forgotten (as in the reference loop).
        ofx[k] = touch ? o.fx : 0.0;
        ofy[k] = touch ? o.fy : 0.0;
        if constexpr (rot) {
            oti[k] = touch ? o.ti : 0.0;
            otj[k] = touch ? o.tj : 0.0;
        }
        if constexpr (hist) {
            hx[k] = touch ? sx : 0.0;
            hy[k] = touch ? sy : 0.0;
        }
        oov[k] = touch ? o.overlap : 0.0;
        touching += touch ? 1 : 0;
    }
    return touching;
}


// The largest overlap of [k0, k1), in a loop of its own (a floating-point max reduction would
// keep the loop above from vectorizing).
double largest(const ForceArgs& a, int n, double max_ov) {
    const double* ov = a.scratch.ov;
    for (int t = 0; t < n; ++t)
        max_ov = ov[t] > max_ov ? ov[t] : max_ov;
    return max_ov;
}

// Pass 2 for the particles [i0, i1): sums in the reference loop's order (per particle: its
// mobile partners, then its walls; partners' shares as they come). Entries that do not touch
// add +0.
template <class Law, bool Wall>
void accumulate_mobile(const ForceArgs& a, int i0, int i1, double* fxi, double* fyi,
                       double* tqi) {
    constexpr bool rot = Law::has_tangential;
    const int* start = Wall ? a.ws : a.ps;
    const int k0 = start[i0];
    const double* sfx = a.scratch.fx - k0;
    const double* sfy = a.scratch.fy - k0;
    const double* sti = a.scratch.ti - k0;
    const double* stj = a.scratch.tj - k0;
    for (int i = i0; i < i1; ++i) {
        double fx = 0.0, fy = 0.0, tq = tqi[i - i0];
        for (int k = start[i]; k < start[i + 1]; ++k) {
            fx += sfx[k];
            fy += sfy[k];
            if constexpr (!Wall) {
                const int j = a.pj[k];
                a.fx[j] -= sfx[k];
                a.fy[j] -= sfy[k];
            }
            if constexpr (rot) {
                tq -= sti[k];
                if constexpr (!Wall) a.tq[a.pj[k]] -= stj[k];
            }
        }
        fxi[i - i0] = fx;
        fyi[i - i0] = fy;
        tqi[i - i0] = tq;
    }
}

template <class Law, bool Corr>
ForceSums forces(const ForceArgs& a) {
    constexpr bool rot = Law::has_tangential;
    for (int i = 0; i < a.n; ++i) {
        a.fx[i] = 0.0;
        a.fy[i] = 0.0;
    }
    if constexpr (rot)
        for (int i = 0; i < a.n; ++i)
            a.tq[i] = 0.0;
    ForceSums sums;
    double max_ov = 0.0, wfx = 0.0, wfy = 0.0;
    int contacts = 0;
    double fxm[block_particles], fym[block_particles], tqm[block_particles];
    double fxw[block_particles], fyw[block_particles], tqw[block_particles];
    for (int i0 = 0; i0 < a.n; i0 += block_particles) {
        const int i1 = i0 + block_particles < a.n ? i0 + block_particles : a.n;
        const int bi = i1 - i0;
        // Mobile partners: evaluate, then sum (the torques from mobile partners start at 0).
        contacts += evaluate<Law, Corr, false>(a, a.ps[i0], a.ps[i1]);
        max_ov = largest(a, a.ps[i1] - a.ps[i0], max_ov);
        for (int t = 0; t < bi; ++t)
            tqm[t] = 0.0;
        accumulate_mobile<Law, false>(a, i0, i1, fxm, fym, tqm);
        // Wall partners: the torque continues from the mobile partners', as in the reference.
        contacts += evaluate<Law, Corr, true>(a, a.ws[i0], a.ws[i1]);
        max_ov = largest(a, a.ws[i1] - a.ws[i0], max_ov);
        for (int t = 0; t < bi; ++t)
            tqw[t] = tqm[t];
        accumulate_mobile<Law, true>(a, i0, i1, fxw, fyw, tqw);
        for (int i = i0; i < i1; ++i) {
            const int t = i - i0;
            a.fx[i] += fxm[t] + fxw[t];
            a.fy[i] += fym[t] + fyw[t];
            wfx -= fxw[t];
            wfy -= fyw[t];
            if constexpr (rot) a.tq[i] += tqw[t];
        }
    }
    sums.max_overlap = max_ov;
    sums.wall_fx = wfx;
    sums.wall_fy = wfy;
    sums.contacts = contacts;
    return sums;
}

const ForceTable table = {{
    {&forces<FrictionlessLaw, false>, &forces<FrictionlessLaw, true>},
    {&forces<ViscousFrictionLaw, false>, &forces<ViscousFrictionLaw, true>},
    {&forces<SpringFrictionLaw, false>, &forces<SpringFrictionLaw, true>},
}};

}  // namespace
}  // namespace hopper::engine::detail::HOPPER_FORCE_NS

namespace hopper::engine::detail {
const ForceTable& HOPPER_FORCE_TABLE() {
    return HOPPER_FORCE_NS::table;
}
}  // namespace hopper::engine::detail
