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

// Pass 1 over one kind of partner: packs the list entries that touch (entry, particle and
// partner indices, in list order) and resets the springs of the others; returns the number packed.
// Partner columns: mobile (x, y, r) or walls (wx + ox, wy + oy, wr).
template <bool Wall>
int pack(const ForceArgs& a, const ForceArgs::Packed& pk) {
    const int* start = Wall ? a.ws : a.ps;
    const int* list = Wall ? a.wj : a.pj;
    double* hx = Wall ? a.gx : a.hx;
    double* hy = Wall ? a.gy : a.hy;
    const double* px = Wall ? a.wx : a.x;
    const double* py = Wall ? a.wy : a.y;
    const double* pr = Wall ? a.wr : a.r;
    int m = 0;
    for (int i = 0; i < a.n; ++i) {
        const double xi = a.x[i], yi = a.y[i], ri = a.r[i];
        for (int k = start[i]; k < start[i + 1]; ++k) {
            const int j = list[k];
            const double dx = Wall ? xi - (px[j] + a.ox) : xi - px[j];
            const double dy = Wall ? yi - (py[j] + a.oy) : yi - py[j];
            const double rj = pr[j], rs = ri + rj;
            const double d2 = dx * dx + dy * dy;
            const bool touch = d2 < rs * rs;
            pk.entry[m] = k;
            pk.own[m] = i;
            pk.partner[m] = j;
            if (hx) {
                // Not touching: the spring is forgotten.
                hx[k] = touch ? hx[k] : 0.0;
                hy[k] = touch ? hy[k] : 0.0;
            }
            m += touch ? 1 : 0;
        }
    }
    return m;
}

// Pass 2: the contact law over m packed pairs (vectorized). Returns the largest overlap.
template <class Law, bool Corr, bool Wall>
double evaluate(const ForceArgs& a, const ForceArgs::Packed& pk, int m) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    const ContactParams p = Wall ? a.pw : a.pp;
    const double dt = a.dt, lever_half = a.lever_half;
    const double* __restrict hx = Wall ? a.gx : a.hx;
    const double* __restrict hy = Wall ? a.gy : a.hy;
    const std::int64_t* __restrict entry = pk.entry;
    const std::int64_t* __restrict own = pk.own;
    const std::int64_t* __restrict partner = pk.partner;
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
    double* __restrict ofx = pk.fx;
    double* __restrict ofy = pk.fy;
    double* __restrict oti = pk.ti;
    double* __restrict otj = pk.tj;
    double* __restrict osx = pk.sx;
    double* __restrict osy = pk.sy;
    double* __restrict oov = pk.ov;
    const double vwx = a.vwx, vwy = a.vwy, ox = a.ox, oy = a.oy;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN)
    for (int t = 0; t < m; ++t) {
        // Gathered from the columns; separation and radii recomputed exactly as pass 1 did.
        const std::int64_t k = entry[t], i = own[t], j = partner[t];
        PairInput q;
        q.dx = Wall ? x[i] - (px[j] + ox) : x[i] - px[j];
        q.dy = Wall ? y[i] - (py[j] + oy) : y[i] - py[j];
        q.ri = r[i];
        q.rj = pr[j];
        q.rs = q.ri + q.rj;
        q.d2 = q.dx * q.dx + q.dy * q.dy;
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
        ofx[t] = o.fx;
        ofy[t] = o.fy;
        if constexpr (rot) {
            oti[t] = o.ti;
            otj[t] = o.tj;
        }
        if constexpr (hist) {
            osx[t] = sx;
            osy[t] = sy;
        }
        oov[t] = o.overlap;
    }
    // The largest overlap, in a loop of its own (a floating-point max reduction would keep the
    // loop above from vectorizing).
    double max_ov = 0.0;
    for (int t = 0; t < m; ++t)
        max_ov = oov[t] > max_ov ? oov[t] : max_ov;
    return max_ov;
}

// Pass 3: sums in the reference loop's order (per particle: its mobile partners, then its
// walls; partners' shares as they come) and writes the new springs back to the list.
template <class Law>
void accumulate(const ForceArgs& a, int nm, int nw, ForceSums& sums) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    const ForceArgs::Packed& pm = a.mob;
    const ForceArgs::Packed& pw = a.wall;
    double wfx = 0.0, wfy = 0.0;
    int t = 0, u = 0;
    for (int i = 0; i < a.n; ++i) {
        double fxi = 0.0, fyi = 0.0, tqi = 0.0;
        for (; t < nm && pm.own[t] == i; ++t) {
            const std::int64_t j = pm.partner[t];
            fxi += pm.fx[t];
            fyi += pm.fy[t];
            a.fx[j] -= pm.fx[t];
            a.fy[j] -= pm.fy[t];
            if constexpr (rot) {
                tqi -= pm.ti[t];
                a.tq[j] -= pm.tj[t];
            }
            if constexpr (hist) {
                a.hx[pm.entry[t]] = pm.sx[t];
                a.hy[pm.entry[t]] = pm.sy[t];
            }
        }
        double wfxi = 0.0, wfyi = 0.0;
        for (; u < nw && pw.own[u] == i; ++u) {
            wfxi += pw.fx[u];
            wfyi += pw.fy[u];
            if constexpr (rot) tqi -= pw.ti[u];
            if constexpr (hist) {
                a.gx[pw.entry[u]] = pw.sx[u];
                a.gy[pw.entry[u]] = pw.sy[u];
            }
        }
        a.fx[i] += fxi + wfxi;
        a.fy[i] += fyi + wfyi;
        wfx -= wfxi;
        wfy -= wfyi;
        if constexpr (rot) a.tq[i] += tqi;
    }
    sums.wall_fx = wfx;
    sums.wall_fy = wfy;
}

template <class Law, bool Corr>
ForceSums forces(const ForceArgs& a) {
    for (int i = 0; i < a.n; ++i) {
        a.fx[i] = 0.0;
        a.fy[i] = 0.0;
    }
    if constexpr (Law::has_tangential)
        for (int i = 0; i < a.n; ++i)
            a.tq[i] = 0.0;
    const int nm = pack<false>(a, a.mob);
    const int nw = pack<true>(a, a.wall);
    const double om = evaluate<Law, Corr, false>(a, a.mob, nm);
    const double ow = evaluate<Law, Corr, true>(a, a.wall, nw);
    ForceSums sums;
    accumulate<Law>(a, nm, nw, sums);
    sums.max_overlap = om > ow ? om : ow;
    sums.contacts = nm + nw;
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
