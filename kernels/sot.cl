/* Sliced optimal transport sampling (Paulin et al. 2020): the passes of one batch.
 * NumPy twins in clsamp/samplers/sot.py (quantiles_reference, project_reference,
 * displacements_reference, move_reference), the same bits: exactly rounded double
 * operations in the same order, no contraction, no library function but sqrt (correctly
 * rounded in double, as NumPy's).
 *
 * sot_quantiles: for each direction r of the launch (slice row first + r) the n targets of
 * the 1-D transport, the quantiles q_i = F^-1((i + 1/2) / n) of <theta, U>, U uniform in
 * [0, 1)^D. The direction comes as the CDF of a sum of m scaled uniforms t = sum a_j U_j
 * (clsamp.samplers.sot.Slice):
 *     F(t) = norm sum_v sign_v (t - c_v)_+^m,   v over the 2^m vertices,
 * c (2^D per direction, the first 2^m used) the vertex sums, sign = (-1)^|v|,
 * norm = 1 / (m! prod a_j), total = sum a_j; the quantile is base + t. Only i < n/2 is solved
 * (t in [0, total / 2], where no cancellation beyond the one Slice bounds occurs) and mirrored:
 * q_(n-1-i) = base + (total - t_i); an odd n's middle is base + total / 2. Where m <= 2 the
 * CDF is a trapezoid's (a1 = c_1 >= a2 = c_2, a2 = 0 where m = 1): t = sqrt(2 a1 a2 p) where
 * 2 a1 p <= a2, else a1 p + a2 / 2, 4 quantiles at a time in vector lanes. Otherwise the
 * solver is Newton's step kept inside a bisection bracket (Numerical Recipes' rtsafe),
 * stopped when Newton's step (taken) or the step made is at most QTOL total, or after QMAX
 * steps. The half's quantiles come in chunks of CHUNK consecutive ones, solved in turn: a
 * chunk's first from the bracket's middle total / 4, the second from the first's root t1,
 * the third from 2 t1 - t2, the others from 3 t1 - 3 t2 + t3 (the last roots extrapolated),
 * each start kept in [t1, total / 2]. A work-item solves LANES consecutive chunks of one
 * direction, one a vector lane.
 * Launch: directions * ceil(ceil(((n + 1) / 2) / CHUNK) / LANES) work-items.
 *
 * sot_project: proj[set, k, i] = sum_j theta[set, k, j] x[set, i, j], j in order.
 * Launch: one work-item per (set, k, i).
 *
 * The displacements disp[set, k, i] = q[set, k, rank] - proj[set, k, i], rank the place of
 * point i's projection in its row sorted with ties by index (the order of a stable sort,
 * NumPy's argsort(kind="stable")); lexicographic order on distinct (key, index) pairs is
 * total, so the sorted order is unique. Two ways:
 * - on GPUs a bitonic sort of rows of P = 2^e >= n (key, index) pairs in global memory:
 *   sot_sort_init pads each row with (+inf, index) (projections are finite, so the padding
 *   sorts last); each sot_bitonic launch is one compare-exchange stage (k, j) over
 *   rows * P / 2 work-items, ascending by (key, index) where bit k of the lower position is
 *   clear; sot_bitonic_local runs the stages with j < L, L = 2 get_local_size(0) (a power of
 *   two dividing P), in local memory, a work-group per L consecutive pairs of a row: for k
 *   from kmin to kmax, j from jtop (k == kmin) or k / 2 down to 1; sot_displace matches
 *   the sorted row to q. Launch: rows * n work-items.
 * - where the device's cores are the host's, sot_project_displace (below): one row a
 *   work-item, the projections with it, by buckets; sot_row (below) solves the row's
 *   quantiles first, in the same work-item.
 *
 * sot_move: point i of a set moves by scale sum_k disp[set, k, i] theta_k (theta_k the row
 * first + set K + k, scale = step / K), clamped into [0, 1 - 2^-53]; cost[set, i] =
 * sum_k disp^2, the point's transport cost over the batch before the move.
 * Launch: one work-item per (set, i). sot_move4 (below) moves 4 points a work-item in
 * vector lanes, for CPUs.
 *
 * Build options: D (dimensions), QTOL, QMAX, CHUNK, LANES (sot_quantiles; 1, 4, 8 or 16).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

#include "cells.h"
#include "heap.h"
#include "in_order.h"

#define VERTS (1 << D)

/* LANES quantiles of one direction a work-item, in vector lanes (1, 4, 8 or 16): each lane
 * runs the scalar solver's operations on its own quantile (a comparison a mask of -1 or 0,
 * a branch a select), and stops changing once its own test stops it. Operators only (no
 * built-in function takes a vector: PoCL warns where a call passes double8 without
 * AVX-512); |x| compared is x or -x, which compares as fabs(x) does. */
#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#define SEL(a, b, c) ((c) ? (b) : (a))
#define ABS(x) ((x) < 0.0 ? -(x) : (x))
#define OR2(x) ((x).lo | (x).hi)
#if LANES == 1
typedef double real_v;
typedef long mask_v;
#define MASK(c) ((c) ? -1L : 0L)
#define ANY(live) ((live) != 0)
#define LANE_INDEX 0.0
#else
typedef CAT(double, LANES) real_v;
typedef CAT(long, LANES) mask_v;
#define MASK(c) (c)
#if LANES == 4
#define LANE_INDEX ((real_v)(0.0, 1.0, 2.0, 3.0))
#define ANY(live) (OR2(OR2(live)) != 0)
#elif LANES == 8
#define LANE_INDEX ((real_v)(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0))
#define ANY(live) (OR2(OR2(OR2(live))) != 0)
#else
#define LANE_INDEX ((real_v)(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, \
                             12.0, 13.0, 14.0, 15.0))
#define ANY(live) (OR2(OR2(OR2(OR2(live)))) != 0)
#endif
#endif

/* quantile j < (n + 1) / 2 of a row from its root t, and its mirror image: q_j = base + t,
 * q_(n-1-j) = base + (total - t); an odd n's middle base + total / 2 */
static inline void sot_store_quantile(__global double *row, const uint n, const uint j,
                                      const double base, const double total, const double t)
{
    if (2 * j + 1 == n) {
        row[j] = base + total * 0.5;
    } else {
        row[j] = base + t;
        row[n - 1 - j] = base + (total - t);
    }
}

/* the quantile groups of a direction's row: ceil(ceil(((n + 1) / 2) / CHUNK) / LANES) */
static inline uint sot_quantile_groups(const uint n)
{
    const uint chunks = ((n + 1) / 2 + CHUNK - 1) / CHUNK;
    return (chunks + LANES - 1) / LANES;
}

/* the quantiles of chunks g0 .. g0 + LANES - 1 of slice k, into its row */
static inline void sot_quantile_lanes(__global const double *c, __global const double *sign,
                                      __global const int *m_of, __global const double *norm_of,
                                      __global const double *total_of,
                                      __global const double *base_of, const uint k,
                                      const uint n, const uint g0, __global double *row)
{
    const uint nh = (n + 1) / 2;
    const double total = total_of[k], base = base_of[k], norm = norm_of[k];
    const int m = m_of[k];
    const uint nv = 1u << m;
    __global const double *ck = c + (size_t)k * VERTS;
    __global const double *sk = sign + (size_t)k * VERTS;
    const double tol = QTOL * total, mid = total * 0.5;
    if (m <= 2) {
        /* the trapezoid's closed form, 4 quantiles at a time */
        const double a1 = ck[1], a2 = m == 2 ? ck[2] : 0.0;
        const uint j1 = min((g0 + LANES) * CHUNK, nh);
        for (uint j = g0 * CHUNK; j < j1; j += 4) {
            const double4 i = convert_double4((uint4)(j) + (uint4)(0, 1, 2, 3));
            const double4 p = (i + 0.5) / (double)n;
            double t[4];
            vstore4(select(a1 * p + 0.5 * a2, sqrt(2.0 * a1 * a2 * p), 2.0 * a1 * p <= a2), 0, t);
            for (uint l = 0; l < 4 && j + l < j1; ++l)
                sot_store_quantile(row, n, j + l, base, total, t[l]);
        }
        return;
    }
    real_v t1 = 0.0, t2 = 0.0, t3 = 0.0;           /* the lane's last three roots */
    for (uint cc = 0; cc < CHUNK; ++cc) {
        const real_v i = ((double)g0 + LANE_INDEX) * (double)CHUNK + (double)cc;
        const real_v p = (i + 0.5) / (double)n;
        real_v lo = 0.0, hi = mid, dx_old = hi;
        /* a chunk's first quantile from the bracket's middle, the next ones from the
         * last roots extrapolated (linearly, then quadratically), kept in [t1, total / 2] */
        real_v t = cc == 0 ? (real_v)(mid * 0.5) : cc == 1 ? t1
                 : cc == 2 ? 2.0 * t1 - t2 : 3.0 * t1 - 3.0 * t2 + t3;
        t = SEL(t, t1, MASK(t < t1));
        t = SEL(t, hi, MASK(t > hi));
        /* the lanes past the half and an odd n's middle solve nothing */
        mask_v live = MASK(i < (double)nh) & MASK(2.0 * i + 1.0 != (double)n);
        for (int it = 0; it < QMAX && ANY(live); ++it) {
            real_v F = 0.0, dF = 0.0;
            IN_ORDER
            for (uint v = 0; v < nv; ++v) {
                const real_v u = t - ck[v];
                real_v w = 1.0;
                IN_ORDER
                for (int j = 1; j < m; ++j)
                    w = w * u;
                const mask_v on = MASK(u > 0.0);
                F = SEL(F, F + sk[v] * (w * u), on);
                dF = SEL(dF, dF + sk[v] * w, on);
            }
            const real_v f = F * norm - p;
            const real_v df = dF * norm * (double)m;
            const mask_v below = MASK(f < 0.0);
            const real_v lo_t = SEL(lo, t, below), hi_t = SEL(t, hi, below);
            const real_v tn = t - f / df, step = tn - t;
            const mask_v done = MASK(df > 0.0) & MASK(ABS(step) <= tol);
            const mask_v newton = MASK(df > 0.0) & MASK(tn > lo_t) & MASK(tn < hi_t)
                                  & MASK(ABS(step) < 0.5 * ABS(dx_old));
            const real_v next = SEL(lo_t + (hi_t - lo_t) * 0.5, tn, newton);
            const real_v dx = next - t;
            t = SEL(t, SEL(next, tn, done), live);
            lo = SEL(lo, lo_t, live);
            hi = SEL(hi, hi_t, live);
            dx_old = SEL(dx_old, dx, live);
            live = live & ~done & ~MASK(ABS(dx) <= tol);
        }
        const double *tl = (const double *)&t;
        for (uint l = 0; l < LANES; ++l) {
            const uint j = (g0 + l) * CHUNK + cc;
            if (j >= nh)
                break;
            sot_store_quantile(row, n, j, base, total, tl[l]);
        }
        t3 = t2;
        t2 = t1;
        t1 = t;
    }
}

__kernel void sot_quantiles(__global const double *c, __global const double *sign,
                            __global const int *m_of, __global const double *norm_of,
                            __global const double *total_of, __global const double *base_of,
                            const uint first, const uint n, const uint dirs, __global double *q)
{
    const uint groups = sot_quantile_groups(n);
    const uint gid = get_global_id(0);
    if (gid >= dirs * groups)
        return;
    const uint r = gid / groups;
    sot_quantile_lanes(c, sign, m_of, norm_of, total_of, base_of, first + r, n,
                       (gid % groups) * LANES, q + (size_t)r * n);
}

/* <theta, x> summed over the coordinates in order: the projection both ways of sorting use */
static inline double sot_dot(__global const double *th, __global const double *xi)
{
    double p = th[0] * xi[0];
    IN_ORDER
    for (int j = 1; j < D; ++j)
        p = p + th[j] * xi[j];
    return p;
}

__kernel void sot_project(__global const double *x, __global const double *theta, const uint n,
                          const uint K, const uint sets, __global double *proj)
{
    const uint gid = get_global_id(0);
    if (gid >= sets * K * n)
        return;
    const uint i = gid % n, sk = gid / n, s = sk / K;
    __global const double *xi = x + ((size_t)s * n + i) * D;
    __global const double *th = theta + (size_t)sk * D;
    proj[gid] = sot_dot(th, xi);
}

/* point i of set s moved (sot_move's operations) */
static inline void sot_move_point(__global const double *x, __global const double *theta,
                                  const uint first, __global const double *disp, const uint n,
                                  const uint K, const uint s, const uint i, const double scale,
                                  __global double *out, __global double *cost)
{
    double shift[D];
    for (int j = 0; j < D; ++j)
        shift[j] = 0.0;
    double c = 0.0;
    IN_ORDER
    for (uint k = 0; k < K; ++k) {
        const size_t sk = (size_t)s * K + k;
        const double dk = disp[sk * n + i];
        c = c + dk * dk;
        for (int j = 0; j < D; ++j)
            shift[j] = shift[j] + dk * theta[(first + sk) * D + j];
    }
    const double top = 1.0 - 0x1.0p-53;
    const size_t at = (size_t)s * n + i;
    for (int j = 0; j < D; ++j) {
        double v = x[at * D + j] + shift[j] * scale;
        v = v < 0.0 ? 0.0 : v;
        out[at * D + j] = v > top ? top : v;
    }
    cost[at] = c;
}

__kernel void sot_move(__global const double *x, __global const double *theta, const uint first,
                       __global const double *disp, const uint n, const uint K, const uint sets,
                       const double scale, __global double *out, __global double *cost)
{
    const uint gid = get_global_id(0);
    if (gid >= sets * n)
        return;
    sot_move_point(x, theta, first, disp, n, K, gid / n, gid % n, scale, out, cost);
}

/* sot_move4: sot_move for points 4 g .. 4 g + 3 of a set a work-item, the same operations
 * in the lanes of double4 vectors; a set's last n mod 4 points one at a time. The costs go
 * to slot `slot` of costs (slot, set, i), so that a resident run sums a few batches' at
 * once (sot_cost).
 * Launch: sets * ceil(n / 4) work-items. */
__kernel void sot_move4(__global const double *x, __global const double *theta,
                        const uint first, __global const double *disp, const uint n,
                        const uint K, const uint sets, const double scale,
                        __global double *out, __global double *costs, const uint slot)
{
    const uint groups = (n + 3) / 4, gid = get_global_id(0);
    if (gid >= sets * groups)
        return;
    __global double *cost = costs + (size_t)slot * sets * n;
    const uint s = gid / groups, i = (gid % groups) * 4;
    if (i + 4 > n) {
        for (uint p = i; p < n; ++p)
            sot_move_point(x, theta, first, disp, n, K, s, p, scale, out, cost);
        return;
    }
    double4 shift[D];
    for (int j = 0; j < D; ++j)
        shift[j] = (double4)(0.0);
    double4 c = (double4)(0.0);
    IN_ORDER
    for (uint k = 0; k < K; ++k) {
        const size_t sk = (size_t)s * K + k;
        const double4 dk = vload4(0, disp + sk * n + i);
        c = c + dk * dk;
        _Pragma("unroll")
        for (int j = 0; j < D; ++j)
            shift[j] = shift[j] + dk * theta[(first + sk) * D + j];
    }
    const size_t at = (size_t)s * n + i;
    double4 y[D];
    cells_load4(x + (size_t)s * n * D, n, i, y);
    const double4 zero = (double4)(0.0), top = (double4)(1.0 - 0x1.0p-53);
    double v[D][4];
    _Pragma("unroll")
    for (int j = 0; j < D; ++j) {
        double4 w = y[j] + shift[j] * scale;
        w = select(w, zero, w < zero);
        vstore4(select(w, top, w > top), 0, v[j]);
    }
    for (uint l = 0; l < 4; ++l)
        for (int j = 0; j < D; ++j)
            out[(at + l) * D + j] = v[j][l];
    vstore4(c, 0, cost + at);
}

/* sot_cost: sums[g] = the point costs of row g (n of them from g n) summed in index order
 * (from 0.0): a row is a set's costs after one batch.
 * Launch: one work-item a row. */
__kernel void sot_cost(__global const double *cost, const uint n, const uint rows,
                       __global double *sums)
{
    const uint g = get_global_id(0);
    if (g >= rows)
        return;
    __global const double *c = cost + (size_t)g * n;
    double t = 0.0;
    IN_ORDER
    for (uint i = 0; i < n; ++i)
        t = t + c[i];
    sums[g] = t;
}

__kernel void sot_sort_init(__global const double *proj, const uint n, const uint P,
                            const uint rows, __global double *key, __global uint *index)
{
    const uint g = get_global_id(0);
    if (g >= rows * P)
        return;
    const uint row = g / P, i = g % P;
    key[g] = i < n ? proj[(size_t)row * n + i] : INFINITY;
    index[g] = i;
}

__kernel void sot_bitonic(__global double *key, __global uint *index, const uint P,
                          const uint rows, const uint k, const uint j)
{
    const uint g = get_global_id(0);
    const uint hp = P >> 1;
    if (g >= rows * hp)
        return;
    const uint row = g / hp, t = g % hp;
    const uint low = t & (j - 1);
    const uint i = ((t - low) << 1) + low;
    const size_t a = (size_t)row * P + i, b = a + j;
    const double ka = key[a], kb = key[b];
    const uint ia = index[a], ib = index[b];
    const int greater = ka > kb || (ka == kb && ia > ib);
    const int up = (i & k) == 0;
    if (greater == up) {
        key[a] = kb;
        key[b] = ka;
        index[a] = ib;
        index[b] = ia;
    }
}

__kernel void sot_bitonic_local(__global double *key, __global uint *index, const uint P,
                                const uint kmin, const uint kmax, const uint jtop,
                                __local double *lk, __local uint *li)
{
    const uint L2 = get_local_size(0), L = 2 * L2, lid = get_local_id(0);
    const uint blocks = P / L, grp = get_group_id(0);
    const uint base = (grp % blocks) * L;
    const size_t off = (size_t)(grp / blocks) * P + base;
    lk[lid] = key[off + lid];
    lk[lid + L2] = key[off + lid + L2];
    li[lid] = index[off + lid];
    li[lid + L2] = index[off + lid + L2];
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = kmin; k <= kmax; k <<= 1) {
        for (uint j = k == kmin ? jtop : k >> 1; j >= 1; j >>= 1) {
            const uint low = lid & (j - 1);
            const uint i = ((lid - low) << 1) + low;
            const double ka = lk[i], kb = lk[i + j];
            const uint ia = li[i], ib = li[i + j];
            const int greater = ka > kb || (ka == kb && ia > ib);
            const int up = ((base + i) & k) == 0;
            if (greater == up) {
                lk[i] = kb;
                lk[i + j] = ka;
                li[i] = ib;
                li[i + j] = ia;
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
    }
    key[off + lid] = lk[lid];
    key[off + lid + L2] = lk[lid + L2];
    index[off + lid] = li[lid];
    index[off + lid + L2] = li[lid + L2];
}

__kernel void sot_displace(__global const uint *index, __global const double *q,
                           __global const double *proj, const uint n, const uint P,
                           const uint rows, __global double *disp)
{
    const uint g = get_global_id(0);
    if (g >= rows * n)
        return;
    const uint row = g / n, j = g % n;
    const size_t i = (size_t)row * n + index[(size_t)row * P + j];
    disp[i] = q[g] - proj[i];
}

/* A long bucket's (key, index) pairs sorted in place by key then index (heapsort); the
 * short ones by insertion, stable on indices that come in increasing order. Distinct
 * pairs have one sorted order, so both give the stable sort's. */
#define LONG_RUN 16

/* whether (ka, ia) comes after (kb, ib) in sorted order: the heapsort's heap puts the
 * largest pair first */
static inline int sot_after(const double ka, const uint ia, const double kb, const uint ib)
{
    return ka > kb || (ka == kb && ia > ib);
}

HEAP_SIFT(sot_sift, sot_after)

static void sot_heapsort(__global double *key, __global uint *idx, const uint len)
{
    for (uint r = len / 2; r-- > 0;)
        sot_sift(key, idx, len, r);
    for (uint end = len - 1; end > 0; --end) {
        const double k = key[0];
        const uint v = idx[0];
        key[0] = key[end];
        idx[0] = idx[end];
        key[end] = k;
        idx[end] = v;
        sot_sift(key, idx, end, 0);
    }
}

/* sot_project_displace: one work-item a row (set s, direction k), on devices that share the
 * host's cores: the row's projections (sot_project's sums), sorted with ties by index by a
 * bucket sort, matched to the row's targets q: disp[i] = q[rank of i] - p_i, as
 * sot_project, a stable sort and sot_displace give. With B buckets (n, or 2n from
 * SOT_WIDE_FROM points on), a key's bucket, floor((p - lo) B / (hi - lo)) clamped to
 * B - 1 (all keys in bucket 0 where the row's range is 0 or B over it overflows), never
 * falls as the key rises, so the buckets in turn, each sorted, are the row in sorted
 * order; keys fill the buckets in index order. The projected cube's density is at most a
 * few times its mean, so a bucket holds a few keys. Scratch: key (doubles) and perm
 * (uints), n a row; count (uints), 2n a row.
 * Launch: sets * K work-items, the rows of directions theta[first..first + sets K). */

/* from this many points on a row takes 2n buckets: fewer keys share one, and the
 * insertion pass meets fewer inversions; below it the longer prefix sums cost as much */
#define SOT_WIDE_FROM 2048
static inline void sot_row_displace(__global const double *x, __global const double *theta,
                                    const uint first, __global const double *q, const uint n,
                                    const uint K, const uint row, __global double *disp,
                                    __global double *key, __global uint *count,
                                    __global uint *perm)
{
    __global const double *restrict xs = x + (size_t)(row / K) * n * D;
    __global const double *restrict th = theta + ((size_t)first + row) * D;
    __global const double *restrict qr = q + (size_t)row * n;
    __global double *restrict p = disp + (size_t)row * n;
    __global double *restrict ks = key + (size_t)row * n;
    const uint nb = n >= SOT_WIDE_FROM ? 2 * n : n;
    __global uint *restrict cnt = count + (size_t)row * 2 * n;
    __global uint *restrict pm = perm + (size_t)row * n;
    /* the projections 4 points at a time (sot_dot's operations in each lane), their
     * smallest and largest kept per lane: a minimum does not depend on the order in which
     * it is taken (but for the sign of a zero, which moves no key to another bucket) */
    double t[D];
    for (int k = 0; k < D; ++k)
        t[k] = th[k];
    double4 lo4 = (double4)(INFINITY), hi4 = (double4)(-INFINITY);
    const uint n4 = n & ~3u;
    for (uint i = 0; i < n4; i += 4) {
        double4 y[D];
        cells_load4(xs, n, i, y);
        double4 v = t[0] * y[0];
        _Pragma("unroll")
        for (int k = 1; k < D; ++k)
            v = v + t[k] * y[k];
        vstore4(v, 0, p + i);
        lo4 = select(lo4, v, v < lo4);
        hi4 = select(hi4, v, v > hi4);
    }
    double lo = INFINITY, hi = -INFINITY;
    for (uint i = n4; i < n; ++i) {
        const double v = sot_dot(th, xs + (size_t)i * D);
        p[i] = v;
        lo = v < lo ? v : lo;
        hi = v > hi ? v : hi;
    }
    const double *lo_l = (const double *)&lo4, *hi_l = (const double *)&hi4;
    for (int l = 0; l < 4; ++l) {
        lo = lo_l[l] < lo ? lo_l[l] : lo;
        hi = hi_l[l] > hi ? hi_l[l] : hi;
    }
    for (uint b = 0; b < nb; ++b)
        cnt[b] = 0;
    double scale = (double)nb / (hi - lo);
    scale = scale < INFINITY ? scale : 0.0;            /* a zero range (or its overflow) */
    const double last = (double)(nb - 1);
    for (uint i = 0; i < n; ++i) {
        const double f = (p[i] - lo) * scale;
        cnt[(uint)(f < last ? f : last)] += 1;
    }
    uint start = 0, longest = 0;
    for (uint b = 0; b < nb; ++b) {
        const uint c = cnt[b];
        cnt[b] = start;
        start += c;
        longest = c > longest ? c : longest;
    }
    for (uint i = 0; i < n; ++i) {                     /* cnt[b] ends as bucket b's end */
        const double f = (p[i] - lo) * scale;
        const uint at = cnt[(uint)(f < last ? f : last)]++;
        ks[at] = p[i];
        pm[at] = i;
    }
    /* long buckets by heapsort, then one insertion pass over the row: a key never moves
     * past its bucket's start (every key of an earlier bucket is smaller), so the pass
     * costs the short buckets' inversions and leaves the sorted ones alone */
    start = 0;
    for (uint b = 0; longest > LONG_RUN && b < nb; ++b) {
        const uint end = cnt[b];
        if (end - start > LONG_RUN)
            sot_heapsort(ks + start, pm + start, end - start);
        start = end;
    }
    for (uint a = 1; a < n; ++a) {
        const double k = ks[a];
        if (ks[a - 1] > k) {
            const uint v = pm[a];
            uint b = a;
            do {
                ks[b] = ks[b - 1];
                pm[b] = pm[b - 1];
                --b;
            } while (b > 0 && ks[b - 1] > k);
            ks[b] = k;
            pm[b] = v;
        }
    }
    for (uint j = 0; j < n; ++j)
        p[pm[j]] = qr[j] - ks[j];
}

__kernel void sot_project_displace(__global const double *x, __global const double *theta,
                                   const uint first, __global const double *q, const uint n,
                                   const uint K, const uint sets, __global double *disp,
                                   __global double *key, __global uint *count,
                                   __global uint *perm)
{
    const uint row = get_global_id(0);
    if (row < sets * K)
        sot_row_displace(x, theta, first, q, n, K, row, disp, key, count, perm);
}

/* sot_row: a resident run's row (set s, direction k) in one work-item: its quantiles
 * (sot_quantiles' groups in turn, slice first + row) into q's row, then
 * sot_project_displace's work.
 * Launch: sets * K work-items. */
__kernel void sot_row(__global const double *c, __global const double *sign,
                      __global const int *m_of, __global const double *norm_of,
                      __global const double *total_of, __global const double *base_of,
                      __global const double *x, __global const double *theta,
                      const uint first, __global double *q, const uint n, const uint K,
                      const uint sets, __global double *disp, __global double *key,
                      __global uint *count, __global uint *perm)
{
    const uint row = get_global_id(0);
    if (row >= sets * K)
        return;
    const uint groups = sot_quantile_groups(n);
    for (uint g = 0; g < groups; ++g)
        sot_quantile_lanes(c, sign, m_of, norm_of, total_of, base_of, first + row, n,
                           g * LANES, q + (size_t)row * n);
    sot_row_displace(x, theta, first, q, n, K, row, disp, key, count, perm);
}
