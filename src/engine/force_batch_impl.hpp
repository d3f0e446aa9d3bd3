// The batched force pass (force_batch.hpp), compiled once per instruction set: the including
// translation unit defines HOPPER_FORCE_NS (a namespace of its own, so that no template
// instantiation is shared between differently compiled objects) and HOPPER_FORCE_TABLE (the
// name of its table getter). No include guard: one inclusion per translation unit.
//
// Only always-inlined code, builtins and ordinary functions defined in other translation units
// (correct_block) may be called from here: a function emitted out of line
// in an AVX-512 object and merged by the linker with the baseline one would run AVX-512
// instructions on any CPU.

#include <bit>
#include <cstdint>

#include "force_batch.hpp"
#include "pair_force.hpp"
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace hopper::engine::detail::HOPPER_FORCE_NS {
namespace {

// Particles per block: their list entries' scratch (about 3 entries per particle) stays in the
// first-level cache between the passes. The fused integrator's block (integrate.hpp).
constexpr int block_particles = block_rows;

// Pass 1 over the list entries [k0, k1) of one kind of partner (mobile or wall): the touch test
// (vectorized), exactly as the reference loop computes it; the springs of the entries that do
// not touch are reset. Then the touching entries are listed in order (branch-free): their list
// entry and particle. Returns how many touch.
template <class Law, bool Wall>
int touching(const ForceArgs& a, int k0, int k1) {
    const int* __restrict own = Wall ? a.wo : a.po;
    const int* __restrict partner = Wall ? a.wj : a.pj;
    const double* __restrict x = a.x;
    const double* __restrict y = a.y;
    const double* __restrict r = a.r;
    const double* __restrict px = Wall ? a.wx : a.x;
    const double* __restrict py = Wall ? a.wy : a.y;
    const double* __restrict pr = Wall ? a.wr : a.r;
    double* __restrict hx = Wall ? a.gx : a.hx;
    double* __restrict hy = Wall ? a.gy : a.hy;
    int* __restrict flag = a.scratch.flag - k0;
    const double ox = a.ox, oy = a.oy;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN)
    for (int k = k0; k < k1; ++k) {
        const int i = own[k], j = partner[k];
        const double dx = Wall ? x[i] - (px[j] + ox) : x[i] - px[j];
        const double dy = Wall ? y[i] - (py[j] + oy) : y[i] - py[j];
        const double rs = r[i] + pr[j];
        const bool touch = !(dx * dx + dy * dy >= rs * rs);
        flag[k] = touch ? 1 : 0;
        if constexpr (Law::has_history) {
            // Not touching: the spring is forgotten (+0.0 exactly, as a select gives), by a
            // mask on the bits: where GCC does not vectorize the loop (the baseline build) it
            // turns a select of a stored value into an unpredictable branch.
            const std::uint64_t keep = std::uint64_t(0) - std::uint64_t(touch);
            hx[k] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(hx[k]) & keep);
            hy[k] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(hy[k]) & keep);
        }
    }
    int* __restrict entry = a.scratch.entry;
    int* __restrict owner = a.scratch.owner;
    int* __restrict other = a.scratch.partner;
    int m = 0;
    int k = k0;
#if defined(__AVX512F__)
    // 16 entries at a time: the flags as a mask, the touching ones' indices compressed
    // (integers only: the bits of the forces do not depend on this).
    const __m512i step = _mm512_set1_epi32(16);
    __m512i ks =
        _mm512_add_epi32(_mm512_set1_epi32(k0),
                         _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
    for (; k + 16 <= k1; k += 16) {
        const __mmask16 t =
            _mm512_test_epi32_mask(_mm512_loadu_si512(flag + k), _mm512_set1_epi32(1));
        // (compressed in a register and stored whole: a compressing store to memory is slow
        // on Zen 4; the columns have 16 entries of slack)
        _mm512_storeu_si512(entry + m, _mm512_maskz_compress_epi32(t, ks));
        _mm512_storeu_si512(owner + m, _mm512_maskz_compress_epi32(t, _mm512_loadu_si512(own + k)));
        _mm512_storeu_si512(other + m,
                            _mm512_maskz_compress_epi32(t, _mm512_loadu_si512(partner + k)));
        m += __builtin_popcount(unsigned(t));
        ks = _mm512_add_epi32(ks, step);
    }
#endif
    for (; k < k1; ++k) {
        entry[m] = k;
        owner[m] = own[k];
        other[m] = partner[k];
        m += flag[k];
    }
    return m;
}

// Pass 2: the contact law over the m touching entries listed by pass 1, branch-free and
// vectorized (pair_force, Select). Results (force, torque parts, overlap, new spring) go to the
// scratch at the same place. Returns the largest overlap.
template <class Law, bool Corr, bool Wall>
double evaluate(const ForceArgs& a, int m, double max_ov) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    const ContactParams p = Wall ? a.pw : a.pp;
    const double dt = a.dt, lever_half = a.lever_half;
    const double* __restrict hx = Wall ? a.gx : a.hx;
    const double* __restrict hy = Wall ? a.gy : a.hy;
    const int* __restrict entry = a.scratch.entry;
    const int* __restrict owner = a.scratch.owner;
    const int* __restrict partner = a.scratch.partner;
    const double* __restrict mbar = Wall ? a.wmbar : a.pmbar;
    const double* __restrict rstar = Wall ? a.wrstar : a.prstar;
    const double* __restrict hK = Wall ? a.wK : a.pK;
    const double* __restrict heta = Wall ? a.weta : a.peta;
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
    double* __restrict ofx = a.scratch.fx;
    double* __restrict ofy = a.scratch.fy;
    double* __restrict oti = a.scratch.ti;
    double* __restrict otj = a.scratch.tj;
    double* __restrict osx = a.scratch.sx;
    double* __restrict osy = a.scratch.sy;
    double* __restrict oov = a.scratch.ov;
    const double vwx = a.vwx, vwy = a.vwy, ox = a.ox, oy = a.oy;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN)
    for (int t = 0; t < m; ++t) {
        // The separation and radii recomputed exactly as pass 1 (and the reference) did.
        const int k = entry[t], i = owner[t], j = partner[t];
        PairInput q;
        q.dx = Wall ? x[i] - (px[j] + ox) : x[i] - px[j];
        q.dy = Wall ? y[i] - (py[j] + oy) : y[i] - py[j];
        q.ri = r[i];
        q.rj = pr[j];
        q.rs = q.ri + q.rj;
        q.d2 = q.dx * q.dx + q.dy * q.dy;
        q.mbar = mbar[k];
        if constexpr (law_needs_rstar<Law>) q.rstar = rstar[k];
        if constexpr (law_needs_pair_constants<Law>) {
            q.hertz_K = hK[k];
            q.hertz_eta = heta[k];
        }
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
    for (int t = 0; t < m; ++t)
        max_ov = oov[t] > max_ov ? oov[t] : max_ov;
    return max_ov;
}

// Pass 3 for the block of particles starting at i0: adds the m results in the reference loop's
// order (per particle: its mobile partners, then its walls; partners' shares as they come) to
// the block's per-particle sums (fxi, fyi, tqi: indexed by particle - i0, continuing from what
// they hold), and writes the new springs back to the list. One flat loop over the results, no
// branch per particle (round 3, third session: the row-by-row form's loop exits were as
// unpredictable as the reference's touch test).
template <class Law, bool Wall>
void accumulate(const ForceArgs& a, int i0, int m, double* __restrict fxi, double* __restrict fyi,
                double* __restrict tqi) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    const int* __restrict entry = a.scratch.entry;
    const int* __restrict owner = a.scratch.owner;
    const int* __restrict partner = a.scratch.partner;
    const double* __restrict sfx = a.scratch.fx;
    const double* __restrict sfy = a.scratch.fy;
    const double* __restrict sti = a.scratch.ti;
    const double* __restrict stj = a.scratch.tj;
    const double* __restrict ssx = a.scratch.sx;
    const double* __restrict ssy = a.scratch.sy;
    double* __restrict hx = Wall ? a.gx : a.hx;
    double* __restrict hy = Wall ? a.gy : a.hy;
    double* __restrict fx = a.fx;
    double* __restrict fy = a.fy;
    double* __restrict tq = a.tq;
    for (int t = 0; t < m; ++t) {
        const int b = owner[t] - i0;
        fxi[b] += sfx[t];
        fyi[b] += sfy[t];
        if constexpr (!Wall) {
            const int j = partner[t];
            fx[j] -= sfx[t];
            fy[j] -= sfy[t];
            if constexpr (rot) tq[j] -= stj[t];
        }
        if constexpr (rot) tqi[b] -= sti[t];
        if constexpr (hist) {
            hx[entry[t]] = ssx[t];
            hy[entry[t]] = ssy[t];
        }
    }
}

template <class Law, bool Corr>
ForceSums forces(const ForceArgs& a) {
    constexpr bool rot = Law::has_tangential;
    if (!a.correct.predict) {  // the fused step zeroes them block by block (predict_ahead)
        for (int i = 0; i < a.n; ++i) {
            a.fx[i] = 0.0;
            a.fy[i] = 0.0;
        }
        if constexpr (rot)
            for (int i = 0; i < a.n; ++i)
                a.tq[i] = 0.0;
    }
    ForceSums sums;
    double max_ov = 0.0, wfx = 0.0, wfy = 0.0, next_d2 = 0.0;
    int contacts = 0, predicted = 0;
    double fxm[block_particles], fym[block_particles], tqm[block_particles];
    double fxw[block_particles], fyw[block_particles];
    for (int i0 = 0; i0 < a.n; i0 += block_particles) {
        const int i1 = i0 + block_particles < a.n ? i0 + block_particles : a.n;
        const int bi = i1 - i0;
        // The fused step: the block's particles and their partners predicted first.
        predict_ahead(a.correct, a.fx, a.fy, a.tq, rot, i0 / block_particles, predicted);
        // Mobile partners (the torques from mobile partners start at 0).
        int m = touching<Law, false>(a, a.ps[i0], a.ps[i1]);
        max_ov = evaluate<Law, Corr, false>(a, m, max_ov);
        for (int t = 0; t < bi; ++t)
            fxm[t] = fym[t] = tqm[t] = fxw[t] = fyw[t] = 0.0;
        accumulate<Law, false>(a, i0, m, fxm, fym, tqm);
        contacts += m;
        // Wall partners: the torque continues from the mobile partners', as in the reference.
        m = touching<Law, true>(a, a.ws[i0], a.ws[i1]);
        max_ov = evaluate<Law, Corr, true>(a, m, max_ov);
        accumulate<Law, true>(a, i0, m, fxw, fyw, tqm);
        contacts += m;
        for (int i = i0; i < i1; ++i) {
            const int t = i - i0;
            a.fx[i] += fxm[t] + fxw[t];
            a.fy[i] += fym[t] + fyw[t];
            wfx -= fxw[t];
            wfy -= fyw[t];
            if constexpr (rot) a.tq[i] += tqm[t];
        }
        // The block's forces are final (later blocks' rows never name its particles) and
        // nothing later reads their state: the corrector, fused (integrate.hpp; an ordinary
        // call into kernel.cpp's multi-versioned loops, not code compiled here).
        next_d2 = max_or_nan(next_d2, correct_block(a.correct, a.fx, a.fy, a.tq, rot, i0, i1));
    }
    sums.next_displacement2 = next_d2;
    sums.max_overlap = max_ov;
    sums.wall_fx = wfx;
    sums.wall_fy = wfy;
    sums.contacts = contacts;
    return sums;
}

// Every registered law (laws.hpp), without and with the contact corrections.
const ForceTable table = {for_each_law([]<class L>() {
    return std::array<ForceFn, 2>{&forces<L, false>, &forces<L, true>};
})};

}  // namespace
}  // namespace hopper::engine::detail::HOPPER_FORCE_NS

namespace hopper::engine::detail {
const ForceTable& HOPPER_FORCE_TABLE() {
    return HOPPER_FORCE_NS::table;
}
}  // namespace hopper::engine::detail
