// The force pass (force_batch.hpp), compiled once per build: the including translation unit
// defines HOPPER_FORCE_NS (a namespace of its own, so that no template instantiation is shared
// between differently compiled objects), HOPPER_FORCE_TABLE (the name of its table getter) and
// HOPPER_FORCE_SIMDLEN, the lanes of the law's loop: 1 for the reference pass (scalar code,
// force_batch_reference.cpp), 2, 4 and 8 for the batched passes of the baseline, AVX2 and
// AVX-512 builds (16 in the one with hardware gathers). No include guard: one inclusion per
// translation unit.
//
// One pass for every build (round 3, third session; issue 42): block by block of block_rows
// particles, per kind of partner (mobile, then wall),
//   1. `touching`: the touch test of the block's list entries, the springs of those that do not
//      touch reset by a mask on their bits, the touching entries listed in order (entry,
//      particle, partner), branch-free;
//   2. `evaluate`: the contact law over the touching entries, each result added in list order
//      to the block's sums: per particle the shares from earlier rows as they come, its own
//      mobile entries summed from 0, its wall entries likewise (the torque continuing from the
//      mobile sum), then fx += (mobile + wall) once the block is done (no later row names a
//      particle of the block).
// The width changes only how the loops are written. With one lane the listing is done in the
// touch test's own loop, each contact is added as its law is evaluated, and the Coulomb cap is
// a branch (pair_force<..., Select = false>: sliding contacts are few, and the select would add
// a square root and a division to every contact). With several, the flags are stored and then
// compacted (AVX-512: 16 at a time, in registers), the law runs under `#pragma omp simd` with
// the cap as a select (Select = true) into per-entry scratch, and a scalar loop (`accumulate`)
// adds the results in the same order. Every build computes an entry from the same expressions
// (PairColumns) and sums in the same order: the same bits (test_kernel_paths).
//
// Only always-inlined code, builtins and ordinary functions defined in other translation units
// (correct_block, predict_block) may be called from here: a function emitted out of line
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

constexpr bool one_lane = HOPPER_FORCE_SIMDLEN == 1;

// The reference pass's two loops are inlined into the block loop (as the reference loop always
// was); the batched builds leave it to the compiler (GCC keeps their touch and sum passes out
// of line).
#if HOPPER_FORCE_SIMDLEN == 1
#define HOPPER_FORCE_PASS [[gnu::always_inline]] inline
#else
#define HOPPER_FORCE_PASS
#endif

// The columns of one kind of partner (mobile or wall) and the pass's constants, held by value
// (no reloads after a store; ContactParams copied): the separation, touch test, law input and
// sums of a list entry k (particle i, partner j), written once for every build.
template <class Law, bool Wall>
struct PairColumns {
    static constexpr bool rot = Law::has_tangential;
    static constexpr bool hist = Law::has_history;
    static constexpr bool rhist = law_has_rolling_spring<Law>;
    const int* __restrict own;    // the particle of each list entry
    const int* __restrict other;  // its partner (a mobile index, or a wall's)
    const double* __restrict x, * __restrict y, * __restrict r;
    const double* __restrict px, * __restrict py, * __restrict pr;    // the partners
    const double* __restrict vx, * __restrict vy, * __restrict w;     // the dashpots' velocities
    const double* __restrict svx, * __restrict svy, * __restrict sw;  // the springs' velocities
    double* __restrict fx, * __restrict fy, * __restrict tq;
    double* __restrict hx, * __restrict hy;  // the springs (null without history)
    double* __restrict hr;                   // the rolling springs (null without them)
    const double* __restrict mbar;           // m_i m_j / (m_i + m_j), set at the rebuild
    const double* __restrict rstar, * __restrict hK, * __restrict heta;  // pair constants
    ContactParams p;
    double dt, lever_half, ox, oy, vwx, vwy;

    HOPPER_HOT_INLINE explicit PairColumns(const ForceArgs& a)
        : own(Wall ? a.wo : a.po),
          other(Wall ? a.wj : a.pj),
          x(a.x),
          y(a.y),
          r(a.r),
          px(Wall ? a.wx : a.x),
          py(Wall ? a.wy : a.y),
          pr(Wall ? a.wr : a.r),
          vx(a.vx),
          vy(a.vy),
          w(a.w),
          svx(a.svx),
          svy(a.svy),
          sw(a.sw),
          fx(a.fx),
          fy(a.fy),
          tq(a.tq),
          hx(Wall ? a.gx : a.hx),
          hy(Wall ? a.gy : a.hy),
          hr(Wall ? a.gr : a.hr),
          mbar(Wall ? a.wmbar : a.pmbar),
          rstar(Wall ? a.wrstar : a.prstar),
          hK(Wall ? a.wK : a.pK),
          heta(Wall ? a.weta : a.peta),
          p(Wall ? a.pw : a.pp),
          dt(a.dt),
          lever_half(a.lever_half),
          ox(a.ox),
          oy(a.oy),
          vwx(a.vwx),
          vwy(a.vwy) {}

    // r_i - r_j (a wall at its base position moved by the walls' offset).
    HOPPER_HOT_INLINE double dx(int i, int j) const {
        return Wall ? x[i] - (px[j] + ox) : x[i] - px[j];
    }
    HOPPER_HOT_INLINE double dy(int i, int j) const {
        return Wall ? y[i] - (py[j] + oy) : y[i] - py[j];
    }

    // d^2 < (r_i + r_j)^2 (false for a NaN separation).
    HOPPER_HOT_INLINE bool touches(int i, int j) const {
        const double sx = dx(i, j), sy = dy(i, j);
        const double rs = r[i] + pr[j];
        return !(sx * sx + sy * sy >= rs * rs);
    }

    // Not touching: the spring is forgotten (+0.0 exactly, as a select gives), by a mask on the
    // bits: GCC turns a select of a stored value into a branch where it does not vectorize the
    // loop (the reference and the baseline build), unpredictable on the touch test.
    HOPPER_HOT_INLINE void reset_spring(int k, bool touch) const {
        const std::uint64_t keep = std::uint64_t(0) - std::uint64_t(touch);
        if constexpr (hist) {
            hx[k] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(hx[k]) & keep);
            hy[k] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(hy[k]) & keep);
        }
        if constexpr (rhist)
            hr[k] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(hr[k]) & keep);
    }

    // The law's input for a touching entry: the separation and radii recomputed exactly as the
    // touch test did them.
    template <bool Corr>
    HOPPER_HOT_INLINE PairInput input(int k, int i, int j) const {
        PairInput q;
        q.dx = dx(i, j);
        q.dy = dy(i, j);
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
        if constexpr (Corr) {  // the springs' own velocities: only with the corrections
            q.six = svx[i];
            q.siy = svy[i];
            q.swi = rot ? sw[i] : 0.0;
            q.sjx = Wall ? vwx : svx[j];
            q.sjy = Wall ? vwy : svy[j];
            q.swj = Wall || !rot ? 0.0 : sw[j];
        } else {
            q.six = q.siy = q.swi = q.sjx = q.sjy = q.swj = 0.0;
        }
        return q;
    }

    // One contact's results added to the sums: the particle's own (fxi, fyi, tqi at
    // b = particle - i0) and, for a mobile partner j, its share as it comes (Newton's third law).
    HOPPER_HOT_INLINE void add(int b, int j, double f_x, double f_y, double t_i, double t_j,
                               double* __restrict fxi, double* __restrict fyi,
                               double* __restrict tqi) const {
        fxi[b] += f_x;
        fyi[b] += f_y;
        if constexpr (!Wall) {
            fx[j] -= f_x;
            fy[j] -= f_y;
        }
        if constexpr (rot) {
            tqi[b] -= t_i;                      // -l_i (n x F_t)
            if constexpr (!Wall) tq[j] -= t_j;  // -l_j (n x F_t): the same form
        }
    }
};

// Pass 1 over the list entries [k0, k1) of one kind of partner: the touch test, the springs of
// the entries that do not touch reset, the touching entries listed in order (entry, particle,
// partner). Returns how many touch.
template <class Law, bool Wall>
HOPPER_FORCE_PASS int touching(const ForceArgs& a, int k0, int k1) {
    const PairColumns<Law, Wall> c(a);
    int* __restrict entry = a.scratch.entry;
    int* __restrict owner = a.scratch.owner;
    int* __restrict partner = a.scratch.partner;
    int m = 0;
    if constexpr (one_lane) {
        // In the same loop, by unconditional stores and a count incremented by the outcome (the
        // scratch has room for one more than the entries).
        for (int k = k0; k < k1; ++k) {
            const int i = c.own[k], j = c.other[k];
            const bool touch = c.touches(i, j);
            c.reset_spring(k, touch);
            entry[m] = k;
            owner[m] = i;
            partner[m] = j;
            m += int(touch);
        }
        return m;
    } else {
        // The test vectorized, its outcome stored as a flag per entry, then the listing.
        int* __restrict flag = a.scratch.flag - k0;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN)
        for (int k = k0; k < k1; ++k) {
            const bool touch = c.touches(c.own[k], c.other[k]);
            flag[k] = touch ? 1 : 0;
            c.reset_spring(k, touch);
        }
        int k = k0;
#if defined(__AVX512F__)
        // 16 entries at a time: the flags as a mask, the touching ones' indices compressed
        // (integers only: the bits of the forces do not depend on this).
        const __m512i step = _mm512_set1_epi32(16);
        __m512i ks = _mm512_add_epi32(
            _mm512_set1_epi32(k0),
            _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
        for (; k + 16 <= k1; k += 16) {
            const __mmask16 t =
                _mm512_test_epi32_mask(_mm512_loadu_si512(flag + k), _mm512_set1_epi32(1));
            // (compressed in a register and stored whole: a compressing store to memory is slow
            // on Zen 4; the columns have 16 entries of slack)
            _mm512_storeu_si512(entry + m, _mm512_maskz_compress_epi32(t, ks));
            _mm512_storeu_si512(owner + m,
                                _mm512_maskz_compress_epi32(t, _mm512_loadu_si512(c.own + k)));
            _mm512_storeu_si512(partner + m,
                                _mm512_maskz_compress_epi32(t, _mm512_loadu_si512(c.other + k)));
            m += __builtin_popcount(unsigned(t));
            ks = _mm512_add_epi32(ks, step);
        }
#endif
        for (; k < k1; ++k) {
            entry[m] = k;
            owner[m] = c.own[k];
            partner[m] = c.other[k];
            m += flag[k];
        }
        return m;
    }
}

// The batched builds' pass 3 for the block starting at i0: the m results of the law (in the
// scratch) added in list order to the block's sums (fxi, fyi, tqi: indexed by particle - i0),
// the new springs written back to the list. One flat loop, no branch per particle (round 3,
// third session: the row-by-row form's loop exits were as unpredictable as the touch test).
template <class Law, bool Wall>
void accumulate(const ForceArgs& a, int i0, int m, double* __restrict fxi, double* __restrict fyi,
                double* __restrict tqi) {
    const PairColumns<Law, Wall> c(a);
    const int* __restrict entry = a.scratch.entry;
    const int* __restrict owner = a.scratch.owner;
    const int* __restrict partner = a.scratch.partner;
    const double* __restrict sfx = a.scratch.fx;
    const double* __restrict sfy = a.scratch.fy;
    const double* __restrict sti = a.scratch.ti;
    const double* __restrict stj = a.scratch.tj;
    const double* __restrict ssx = a.scratch.sx;
    const double* __restrict ssy = a.scratch.sy;
    const double* __restrict ssr = a.scratch.sr;
    constexpr bool rhist = law_has_rolling_spring<Law>;
    for (int t = 0; t < m; ++t) {
        c.add(owner[t] - i0, partner[t], sfx[t], sfy[t], sti[t], stj[t], fxi, fyi, tqi);
        if constexpr (Law::has_history) {
            c.hx[entry[t]] = ssx[t];
            c.hy[entry[t]] = ssy[t];
        }
        if constexpr (rhist) c.hr[entry[t]] = ssr[t];
    }
}

// Pass 2 (and 3): the contact law over the m touching entries listed by pass 1, each result
// added to the block's sums (fxi, fyi, tqi: indexed by particle - i0, continuing from what they
// hold). Returns the largest overlap.
template <class Law, bool Corr, bool Wall>
HOPPER_FORCE_PASS double evaluate(const ForceArgs& a, int m, int i0, double max_ov,
                                  double* __restrict fxi, double* __restrict fyi,
                                  double* __restrict tqi) {
    constexpr bool rot = Law::has_tangential;
    constexpr bool hist = Law::has_history;
    constexpr bool rhist = law_has_rolling_spring<Law>;
    const PairColumns<Law, Wall> c(a);
    const int* __restrict entry = a.scratch.entry;
    const int* __restrict owner = a.scratch.owner;
    const int* __restrict partner = a.scratch.partner;
    if constexpr (one_lane) {
        // stand in when there is no history
        double no_spring_x = 0.0, no_spring_y = 0.0, no_spring_r = 0.0;
        for (int t = 0; t < m; ++t) {
            const int k = entry[t], i = owner[t], j = partner[t];
            const PairInput q = c.template input<Corr>(k, i, j);
            double& sx = hist ? c.hx[k] : no_spring_x;
            double& sy = hist ? c.hy[k] : no_spring_y;
            double& sr = rhist ? c.hr[k] : no_spring_r;
            const PairOutput o =
                pair_force<Law, Corr, false>(c.p, c.dt, c.lever_half, q, sx, sy, sr);
            c.add(i - i0, j, o.fx, o.fy, o.ti, o.tj, fxi, fyi, tqi);
            max_ov = o.overlap > max_ov ? o.overlap : max_ov;
        }
        return max_ov;
    } else {
        // Branch-free and vectorized: results (force, torque parts, overlap, new spring) to the
        // scratch at the same place.
        double* __restrict ofx = a.scratch.fx;
        double* __restrict ofy = a.scratch.fy;
        double* __restrict oti = a.scratch.ti;
        double* __restrict otj = a.scratch.tj;
        double* __restrict osx = a.scratch.sx;
        double* __restrict osy = a.scratch.sy;
        double* __restrict osr = a.scratch.sr;
        double* __restrict oov = a.scratch.ov;
#pragma omp simd simdlen(HOPPER_FORCE_SIMDLEN)
        for (int t = 0; t < m; ++t) {
            const int k = entry[t];
            const PairInput q = c.template input<Corr>(k, owner[t], partner[t]);
            double sx = 0.0, sy = 0.0, sr = 0.0;
            if constexpr (hist) {
                sx = c.hx[k];
                sy = c.hy[k];
            }
            if constexpr (rhist) sr = c.hr[k];
            const PairOutput o =
                pair_force<Law, Corr, true>(c.p, c.dt, c.lever_half, q, sx, sy, sr);
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
            if constexpr (rhist) osr[t] = sr;
            oov[t] = o.overlap;
        }
        // The largest overlap, in a loop of its own (a floating-point max reduction would keep
        // the loop above from vectorizing).
        for (int t = 0; t < m; ++t)
            max_ov = oov[t] > max_ov ? oov[t] : max_ov;
        accumulate<Law, Wall>(a, i0, m, fxi, fyi, tqi);
        return max_ov;
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
    double max_ov = 0.0, wfx = 0.0, wfy = 0.0, next_d2 = 0.0;
    int contacts = 0, predicted = 0;
    double fxm[block_particles], fym[block_particles], tqm[block_particles];
    double fxw[block_particles], fyw[block_particles];
    for (int i0 = 0; i0 < a.n; i0 += block_particles) {
        const int i1 = i0 + block_particles < a.n ? i0 + block_particles : a.n;
        const int bi = i1 - i0;
        // The fused step: this block's rows and their partners predicted (and their forces
        // zeroed) before any row reads them (integrate.hpp).
        predict_ahead(a.correct, a.fx, a.fy, a.tq, rot, i0 / block_particles, predicted);
        for (int t = 0; t < bi; ++t)
            fxm[t] = fym[t] = tqm[t] = fxw[t] = fyw[t] = 0.0;
        // Mobile partners: each pair once, Newton's third law.
        int m = touching<Law, false>(a, a.ps[i0], a.ps[i1]);
        max_ov = evaluate<Law, Corr, false>(a, m, i0, max_ov, fxm, fym, tqm);
        contacts += m;
        // Wall partners: immobile (or moving rigidly while shaking), inverse mass 0; the torque
        // continues from the mobile partners'.
        m = touching<Law, true>(a, a.ws[i0], a.ws[i1]);
        max_ov = evaluate<Law, Corr, true>(a, m, i0, max_ov, fxw, fyw, tqm);
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
    ForceSums sums;
    sums.next_displacement2 = next_d2;
    sums.max_overlap = max_ov;
    sums.wall_fx = wfx;
    sums.wall_fy = wfy;
    sums.contacts = contacts;
    return sums;
}

#undef HOPPER_FORCE_PASS

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
