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
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace hopper::engine::detail::HOPPER_FORCE_NS {
namespace {

// Particles per block: their list entries' scratch (about 3 entries per particle) stays in the
// first-level cache between the passes.
constexpr int block_particles = 256;

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
            hx[k] = touch ? hx[k] : 0.0;  // not touching: the spring is forgotten
            hy[k] = touch ? hy[k] : 0.0;
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

#if defined(__AVX512F__)
// The x, y and r of 8 particles from their interleaved rows (x, y, r, unused) in xyr4: one
// 32-byte load per particle and 11 shuffles, where 24 single loads each need a shuffle of their
// own. (Copies of the columns' values: the bits are the columns'.)
HOPPER_HOT_INLINE void gather_xyr(const double* xyr4, const int* idx, __m512d& x, __m512d& y,
                                  __m512d& r) {
    const auto row = [&](int l) { return _mm256_loadu_pd(xyr4 + 4 * idx[l]); };
    const auto pair = [&](int l) {
        return _mm512_insertf64x4(_mm512_zextpd256_pd512(row(l)), row(l + 1), 1);
    };
    const __m512d p0 = pair(0), p1 = pair(2), p2 = pair(4), p3 = pair(6);
    // p0 = x0 y0 r0 . x1 y1 r1 .; lo = x0 x2 r0 r2 x1 x3 r1 r3; hi = y0 y2 . . y1 y3 . .
    const __m512d lo01 = _mm512_unpacklo_pd(p0, p1), hi01 = _mm512_unpackhi_pd(p0, p1);
    const __m512d lo23 = _mm512_unpacklo_pd(p2, p3), hi23 = _mm512_unpackhi_pd(p2, p3);
    const __m512i first = _mm512_setr_epi64(0, 4, 1, 5, 8, 12, 9, 13);
    const __m512i third = _mm512_setr_epi64(2, 6, 3, 7, 10, 14, 11, 15);
    x = _mm512_permutex2var_pd(lo01, first, lo23);
    y = _mm512_permutex2var_pd(hi01, first, hi23);
    r = _mm512_permutex2var_pd(lo01, third, lo23);
}

// Pass 1 for mobile partners on AVX-512: the same touch test (same operations, so the same
// decisions), on positions and radii gathered from interleaved rows, 8 entries at a time, the
// mask used directly for the springs' reset and the compaction.
template <class Law>
int touching_mobile_avx512(const ForceArgs& a, int k0, int k1) {
    const int* __restrict own = a.po;
    const int* __restrict partner = a.pj;
    const double* __restrict xyr4 = a.scratch.xyr4;
    double* __restrict hx = a.hx;
    double* __restrict hy = a.hy;
    int* __restrict entry = a.scratch.entry;
    int* __restrict owner = a.scratch.owner;
    int* __restrict other = a.scratch.partner;
    int m = 0;
    int k = k0;
    __m256i ks = _mm256_add_epi32(_mm256_set1_epi32(k0), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    for (; k + 8 <= k1; k += 8) {
        __m512d xi, yi, ri, xj, yj, rj;
        gather_xyr(xyr4, own + k, xi, yi, ri);
        gather_xyr(xyr4, partner + k, xj, yj, rj);
        const __m512d dx = _mm512_sub_pd(xi, xj), dy = _mm512_sub_pd(yi, yj);
        const __m512d rs = _mm512_add_pd(ri, rj);
        const __m512d d2 = _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy));
        // touch = !(d2 >= rs^2): "not greater or equal", true when unordered
        const __mmask8 t = _mm512_cmp_pd_mask(d2, _mm512_mul_pd(rs, rs), _CMP_NGE_UQ);
        if constexpr (Law::has_history) {
            _mm512_storeu_pd(hx + k, _mm512_maskz_mov_pd(t, _mm512_loadu_pd(hx + k)));
            _mm512_storeu_pd(hy + k, _mm512_maskz_mov_pd(t, _mm512_loadu_pd(hy + k)));
        }
        // (compressed in a register and stored whole; the columns have 16 entries of slack)
        const __m256i ko = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(own + k));
        const __m256i kp = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(partner + k));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(entry + m), _mm256_maskz_compress_epi32(t, ks));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(owner + m), _mm256_maskz_compress_epi32(t, ko));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(other + m), _mm256_maskz_compress_epi32(t, kp));
        m += __builtin_popcount(unsigned(t));
        ks = _mm256_add_epi32(ks, _mm256_set1_epi32(8));
    }
    for (; k < k1; ++k) {  // the last few entries, one at a time, the same operations
        const int i = own[k], j = partner[k];
        const double dx = xyr4[4 * i] - xyr4[4 * j], dy = xyr4[4 * i + 1] - xyr4[4 * j + 1];
        const double rs = xyr4[4 * i + 2] + xyr4[4 * j + 2];
        const bool touch = !(dx * dx + dy * dy >= rs * rs);
        if constexpr (Law::has_history) {
            hx[k] = touch ? hx[k] : 0.0;
            hy[k] = touch ? hy[k] : 0.0;
        }
        entry[m] = k;
        owner[m] = i;
        other[m] = j;
        m += touch ? 1 : 0;
    }
    return m;
}
#endif

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
    double* __restrict of4 = a.scratch.f4;
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
        // (-t_i: the particle's own torque then adds it, and s + (-t) is exactly s - t)
        of4[4 * t] = o.fx;
        of4[4 * t + 1] = o.fy;
        of4[4 * t + 2] = rot ? o.tj : 0.0;
        of4[4 * t + 3] = rot ? -o.ti : 0.0;
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

// Four doubles: one 32-byte load, add or store (element by element, so each lane gets exactly
// the bits of the scalar operation). Moved with memcpy: the columns are 8-byte aligned.
typedef double Lanes4 __attribute__((vector_size(32)));

// Pass 3 for the particles [i0, i1): sums the m results in the reference loop's order (per
// particle: its mobile partners, then its walls; partners' shares as they come) into the
// block's per-particle sums, and writes the new springs back to the list. Each touching pair's
// (F_x, F_y, t_j, -t_i) is added to its particle's running sum (lanes 0, 1 and 3 are used) and
// subtracted from its partner's share in scratch.acc (lanes 0, 1 and 2 are used).
template <class Law, bool Wall>
void accumulate(const ForceArgs& a, int i0, int i1, int m, double* __restrict fxi,
                double* __restrict fyi, double* __restrict tqi) {
    constexpr bool hist = Law::has_history;
    const int* __restrict entry = a.scratch.entry;
    const int* __restrict owner = a.scratch.owner;
    const int* __restrict partner = a.scratch.partner;
    const double* __restrict f4 = a.scratch.f4;
    const double* __restrict ssx = a.scratch.sx;
    const double* __restrict ssy = a.scratch.sy;
    double* __restrict hx = Wall ? a.gx : a.hx;
    double* __restrict hy = Wall ? a.gy : a.hy;
    double* __restrict acc = a.scratch.acc;
    int t = 0;
    for (int i = i0; i < i1; ++i) {
        Lanes4 own = {0.0, 0.0, 0.0, tqi[i - i0]};
        for (; t < m && owner[t] == i; ++t) {
            Lanes4 c;
            __builtin_memcpy(&c, f4 + 4 * t, sizeof c);
            own += c;
            if constexpr (!Wall) {
                double* pj = acc + 4 * partner[t];
                Lanes4 share;
                __builtin_memcpy(&share, pj, sizeof share);
                share -= c;
                __builtin_memcpy(pj, &share, sizeof share);
            }
            if constexpr (hist) {
                hx[entry[t]] = ssx[t];
                hy[entry[t]] = ssy[t];
            }
        }
        fxi[i - i0] = own[0];
        fyi[i - i0] = own[1];
        tqi[i - i0] = own[3];
    }
}

template <class Law, bool Corr>
ForceSums forces(const ForceArgs& a) {
    constexpr bool rot = Law::has_tangential;
    double* __restrict acc = a.scratch.acc;
    for (int i = 0; i < 4 * a.n; ++i)
        acc[i] = 0.0;
#if defined(__AVX512F__)
    // The positions and radii as interleaved rows, for the touch test's gathers.
    double* __restrict xyr4 = a.scratch.xyr4;
    for (int i = 0; i < a.n; ++i) {
        xyr4[4 * i] = a.x[i];
        xyr4[4 * i + 1] = a.y[i];
        xyr4[4 * i + 2] = a.r[i];
        xyr4[4 * i + 3] = 0.0;
    }
#endif
    ForceSums sums;
    double max_ov = 0.0, wfx = 0.0, wfy = 0.0;
    int contacts = 0;
    double fxm[block_particles], fym[block_particles], tqm[block_particles];
    double fxw[block_particles], fyw[block_particles], tqw[block_particles];
    for (int i0 = 0; i0 < a.n; i0 += block_particles) {
        const int i1 = i0 + block_particles < a.n ? i0 + block_particles : a.n;
        const int bi = i1 - i0;
        // Mobile partners (the torques from mobile partners start at 0).
#if defined(__AVX512F__)
        int m = touching_mobile_avx512<Law>(a, a.ps[i0], a.ps[i1]);
#else
        int m = touching<Law, false>(a, a.ps[i0], a.ps[i1]);
#endif
        max_ov = evaluate<Law, Corr, false>(a, m, max_ov);
        for (int t = 0; t < bi; ++t)
            tqm[t] = 0.0;
        accumulate<Law, false>(a, i0, i1, m, fxm, fym, tqm);
        contacts += m;
        // Wall partners: the torque continues from the mobile partners', as in the reference.
        m = touching<Law, true>(a, a.ws[i0], a.ws[i1]);
        max_ov = evaluate<Law, Corr, true>(a, m, max_ov);
        for (int t = 0; t < bi; ++t)
            tqw[t] = tqm[t];
        accumulate<Law, true>(a, i0, i1, m, fxw, fyw, tqw);
        contacts += m;
        for (int i = i0; i < i1; ++i) {
            const int t = i - i0;
            // (every partner of i has a smaller index: its share in acc is complete)
            a.fx[i] = acc[4 * i] + (fxm[t] + fxw[t]);
            a.fy[i] = acc[4 * i + 1] + (fym[t] + fyw[t]);
            wfx -= fxw[t];
            wfy -= fyw[t];
            if constexpr (rot) a.tq[i] = acc[4 * i + 2] + tqw[t];
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
