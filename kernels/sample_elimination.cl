/* Weighted sample elimination (Yuksel 2015): the neighbour search and the weights, the
 * O(M k) part of eliminating M candidates down to n. NumPy twin: neighbour_weights_reference
 * in clsamp/samplers/sample_elimination.py, the same bits: exactly rounded double
 * operations (the square root and the division included) in the same order, no
 * contraction, the power by squaring. The elimination itself, a tournament tree walked
 * one removal at a time, is se_eliminate, one work-item a set; its twin is eliminate()
 * there (a heap, the same order of removals).
 *
 * The candidates of every set come sorted by (set, cell) of a G^D grid in pts (total, D)
 * (each point's cell found again here from its coordinates), and start (sets G^D + 1)
 * holds the first sorted index of each (set, cell); G >= 3 (the 3^D cells around a cell
 * distinct, each at least d_max wide) or G == 1 (every pair). The neighbours of sorted
 * point i are the j != i of its set in its 3^D neighbouring cells with squared distance
 * r2 < R2 = d_max^2 (wrapped on the torus when PERIODIC), in stencil order then sorted
 * order (from 3-D on the cells wholly beyond d_max skipped, cells.h's cell_beyond: the
 * same pairs in the same order); the weight of a pair is
 *     w_ij = (1 - max(sqrt(r2), d_min) / d_max)^ALPHA,
 * which is symmetric to the bit (the wrapped differences of i - j and j - i have one
 * magnitude).
 *
 * se_count: count[i] = the neighbours of i (with LANES 16 by se_range16 without lists).
 * se_pairs: writes the neighbours (their sorted indices) and their weights to
 *     nbr[offset[i] ..] and w[offset[i] ..], offset the exclusive prefix sum of the counts
 *     (host), and the sum of the weights in that order to weight[i]. With cap > 0 it
 *     needs no count pass: i's list goes to the cap slots from i cap on, and count[i]
 *     gets the neighbours found (more than cap: the host runs the passes with offsets).
 * se_eliminate: per set, removes the candidate of the largest weight (the lowest index
 *     among equal ones), subtracts its pair weights (count[i] of them from first[i] in nbr
 *     and w, or with cap > 0 from i cap, as se_pairs wrote them: a set with a list longer
 *     than cap gets overflow[s] = 1 and nothing else) from its neighbours' weights, and
 *     again, `removals` times; writes the removed candidates (indices within the set) in
 *     order to gone, overflow[s] = 0, and leaves the final weights in weight; key and idx
 *     are its scratch, sample_elimination._tree_slots(m) doubles and uints a set (its
 *     tree, below).
 *
 * Build options: D (dimensions), PERIODIC (1: the unit torus; 0: the unit cube), ALPHA
 * (the weight's exponent, a positive integer), LANES (16: se_pairs takes the stencil's
 * rows 16 points at a time in vector lanes, se_range16 below, the same lists and sums,
 * for CPUs' vector units; else 1, one at a time).
 * Launch: se_count and se_pairs one work-item per sorted point, grid (total,);
 * se_eliminate one work-item per set, grid (sets,).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF
#include "cells.h"
#include "torus.h"

inline double se_r2(const double *x, __global const double *y)
{
    double r2 = 0.0;
    for (int k = 0; k < D; ++k) {
        double v = x[k] - y[k];
#if PERIODIC
        v = v > 0.5 ? v - 1.0 : v;
        v = v < -0.5 ? v + 1.0 : v;
#endif
        r2 = k == 0 ? v * v : r2 + v * v;
    }
    return r2;
}

/* t^ALPHA by squaring, low bits of ALPHA first, for T double or double4 */
#define SE_POWER(name, T)                               \
    inline T name(T t)                                  \
    {                                                   \
        T p = (T)(1.0);                                 \
        for (uint e = ALPHA; e != 0; e >>= 1) {         \
            if (e & 1)                                  \
                p = p * t;                              \
            t = t * t;                                  \
        }                                               \
        return p;                                       \
    }
SE_POWER(se_power, double)

#if LANES == 16
SE_POWER(se_power4, double4)

/* The neighbours of sorted point i (at x) among sorted points lo .. hi - 1, in order,
 * counted in *found; with lists, each also written to slot *at while *at < end (then *at
 * advances) and its weight added to *sum: 16 points at a time from a multiple of 4, the
 * distances and weights as four vectors of 4 lanes (no wider: tests/test_runtime.py), the
 * same operations as the scalar search, then the neighbours' lanes in order. */
inline void se_range16(__global const double *pts, const uint total, const uint lo,
                       const uint hi, const uint i, const double *x, const double R2,
                       const int lists, const double d_min, const double d_max,
                       __global uint *nbr, __global double *w, ulong *at, const ulong end,
                       uint *found, double *sum)
{
    for (uint j0 = lo & ~3u; j0 < hi; j0 += 16) {
        double4 r2[4];
        long4 on[4];
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            const uint jq = j0 + 4 * (uint)q;
            double4 v[D];
            cells_load4(pts, total, jq, v);
            _Pragma("unroll")
            for (int k = 0; k < D; ++k) {
#if PERIODIC
                const double4 t = torus_wrapped4((double4)(x[k]), v[k]);
#else
                const double4 t = x[k] - v[k];
#endif
                r2[q] = k == 0 ? t * t : r2[q] + t * t;
            }
            const long4 j = (long4)(long)jq + (long4)(0, 1, 2, 3);
            on[q] = (j >= (long)lo) & (j < (long)hi) & (j != (long)i) & (r2[q] < R2);
        }
        /* bit l set where lane l holds a neighbour (select reads a mask's sign bit, as a
         * mask is defined) */
        uint bits = 0;
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            const long4 lane = (long4)(0, 1, 2, 3) + (long4)(4 * q);
            const long4 b = select((long4)(0), (long4)(1), on[q]) << lane;
            bits |= (uint)((b.x | b.y) | (b.z | b.w));
        }
        if (!lists) {
            *found += popcount(bits);
            continue;
        }
        if (bits == 0)
            continue;
        double e[16];
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            const double4 dist = sqrt(r2[q]);
            const double4 t = select((double4)(d_min), dist, dist > d_min);
            vstore4(se_power4(1.0 - t / d_max), q, e);
        }
        /* the neighbours' lanes in order, the lowest set bit first */
        while (bits != 0) {
            const uint l = 31u - clz(bits & (0u - bits));
            bits &= bits - 1u;
            if (*at < end) {
                nbr[*at] = j0 + l;
                w[*at] = e[l];
            }
            *at += 1;
            *found += 1;
            *sum = *sum + e[l];
        }
    }
}

/* se_range16 over the stencil of sorted point gi (at x, in cell c) by rows along the last
 * axis (cells_row_ranges): the same cells in the same order as one at a time */
inline void se_search16(__global const double *pts, __global const uint *st, const uint total,
                        const uint gi, const double *x, const int *c, const int G,
                        const uint noff, const double R2, const int lists, const double d_min,
                        const double d_max, __global uint *nbr, __global double *w,
                        ulong *at, const ulong end, uint *found, double *sum)
{
    for (uint o = 0; o < cells_rows(G, noff); ++o) {
        uint lo[2], hi[2];
        const uint ranges = cells_row_ranges(st, c, x, G, o, R2, lo, hi);
        for (uint k = 0; k < ranges; ++k)
            se_range16(pts, total, lo[k], hi[k], gi, x, R2, lists, d_min, d_max, nbr, w, at,
                       end, found, sum);
    }
}
#endif

__kernel void se_count(__global const double *pts, __global const uint *start, const uint n,
                       const uint total, const int G, const uint noff, const double R2,
                       __global uint *count)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint total_cells = cells_count(G);
    double x[D];
    for (int k = 0; k < D; ++k)
        x[k] = pts[(size_t)gi * D + k];
    int c[D];
    cell_of(x, G, c);
    uint found = 0;
#if LANES == 16
    ulong at = 0;
    double sum = 0.0;
    se_search16(pts, start + (size_t)(gi / n) * total_cells, total, gi, x, c, G, noff, R2, 0,
                0.0, 1.0, 0, 0, &at, 0, &found, &sum);
#else
    for (uint o = 0; o < noff; ++o) {
#if D >= 3
        if (G > 1 && cell_beyond(x, c, o, G, R2))
            continue;
#endif
        const size_t slot = (size_t)(gi / n) * total_cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint j = start[slot]; j < s1; ++j)
            found += (j != gi && se_r2(x, pts + (size_t)j * D) < R2) ? 1u : 0u;
    }
#endif
    count[gi] = found;
}

__kernel void se_pairs(__global const double *pts, __global const uint *start, const uint n,
                       const uint total, const int G, const uint noff, const double R2,
                       const double d_min, const double d_max,
                       __global const ulong *offset, const uint cap, __global uint *nbr,
                       __global double *w, __global double *weight, __global uint *count)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint total_cells = cells_count(G);
    double x[D];
    for (int k = 0; k < D; ++k)
        x[k] = pts[(size_t)gi * D + k];
    int c[D];
    cell_of(x, G, c);
    /* the slots of gi's list: offset[gi] .. offset[gi + 1], or with cap > 0 cap slots
     * from gi cap on (the neighbours past them counted, not written) */
    ulong at = cap > 0 ? (ulong)gi * cap : offset[gi];
    const ulong end = cap > 0 ? at + cap : offset[gi + 1];
    uint found = 0;
    double sum = 0.0;
#if LANES == 16
    se_search16(pts, start + (size_t)(gi / n) * total_cells, total, gi, x, c, G, noff, R2, 1,
                d_min, d_max, nbr, w, &at, end, &found, &sum);
#else
    for (uint o = 0; o < noff; ++o) {
#if D >= 3
        if (G > 1 && cell_beyond(x, c, o, G, R2))
            continue;
#endif
        const size_t slot = (size_t)(gi / n) * total_cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint j = start[slot]; j < s1; ++j) {
            if (j == gi)
                continue;
            const double r2 = se_r2(x, pts + (size_t)j * D);
            if (r2 >= R2)
                continue;
            const double dist = sqrt(r2);
            const double e = se_power(1.0 - (dist > d_min ? dist : d_min) / d_max);
            if (at < end) {
                nbr[at] = j;
                w[at] = e;
                at += 1;
            }
            found += 1;
            sum = sum + e;
        }
    }
#endif
    weight[gi] = sum;
    if (cap > 0)
        count[gi] = found;
}

/* The elimination keeps each set's candidates in an 8-ary tournament tree. Level 0 holds
 * the leaves, candidate i's key the weight of i while it remains and -inf once removed
 * (padded with -inf to a multiple of 8); node p of level l + 1 decides among nodes 8 p ..
 * 8 p + 7 of level l, holding their winner (the leaf of the largest key, the lowest index
 * among equal keys) and its key; each level above the leaves is padded to a multiple of 8
 * (-inf) until one node, the root, is left. The levels lie one after another in key and
 * idx (SE_LEVELS at most; sample_elimination._tree_slots gives their length, a set's
 * scratch). Leaves are in index order, so of two equal keys the left one wins. The root's
 * winner is the next to go, as an eagerly updated heap gives it. A fallen leaf's key
 * reaches a node above it only where it won the node below; with 8 children a node, it
 * mostly did not, and a removal decides log_8 m nodes, not log_2 m. */
#define SE_LEVELS 12

/* the levels' first slots of a set of m candidates into off; returns the root's level */
inline uint se_levels(const uint m, uint *off)
{
    uint size = (m + 7u) & ~7u, top = 0;
    off[0] = 0;
    while (size > 1) {
        off[top + 1] = off[top] + size;
        size = (size + 7u) >> 3;
        size = size > 1 ? (size + 7u) & ~7u : 1u;
        top += 1;
    }
    return top;
}

/* the child (0 .. 7) of the largest of the 8 keys at k, the first among equal ones */
inline uint se_best8(__global const double *k)
{
    const uint c01 = k[1] > k[0], c23 = 2u + (k[3] > k[2]);
    const uint c45 = 4u + (k[5] > k[4]), c67 = 6u + (k[7] > k[6]);
    const uint c03 = k[c23] > k[c01] ? c23 : c01;
    const uint c47 = k[c67] > k[c45] ? c67 : c45;
    return k[c47] > k[c03] ? c47 : c03;
}

/* node p of level l (1 ..) decided again from its 8 children */
inline void se_decide(__global double *key, __global uint *idx, const uint *off, const uint l,
                      const uint p)
{
    __global const double *k = key + off[l - 1] + 8 * (size_t)p;
    const uint c = se_best8(k);
    key[off[l] + p] = k[c];
    idx[off[l] + p] = l == 1 ? 8 * p + c : idx[off[l - 1] + 8 * p + c];
}

/* leaf j's key set to v (never above the last): the nodes above it that it won, from the
 * bottom up, decided again (a node that j did not win keeps its winner, and so does every
 * node above it) */
inline void se_replay(__global double *key, __global uint *idx, const uint *off,
                      const uint top, const uint j, const double v)
{
    key[j] = v;
    uint p = j;
    for (uint l = 1; l <= top; ++l) {
        p >>= 3;
        if (idx[off[l] + p] != j)
            return;
        se_decide(key, idx, off, l, p);
    }
}

/* Up to 3-D a removal's neighbours are replayed at once (SE_EAGER); from 4-D on they are
 * many, so only their weights fall and a leaf's key is refreshed when it wins the root with
 * a key above its weight (weights only fall, so every key stays at least its weight, and a
 * root whose key is its weight is the heaviest candidate). */
#define SE_EAGER (D <= 3)

/* The elimination of set s (its m sorted candidates from s m on; nbr holds sorted indices
 * over all sets; key (doubles) and idx (uints) the set's tree, scratch, from s slots on).
 * The removed candidate's pair weights leave all its neighbours' weights (the removed ones'
 * too). The order of removals is that of eliminate() in Python's heapq, whose entries are
 * unique. */
__kernel void se_eliminate(__global const ulong *first, __global const uint *count,
                           const uint cap, __global const uint *nbr,
                           __global const double *w, __global double *weight, const uint m,
                           const uint sets, const uint removals, __global double *key,
                           __global uint *idx, __global uint *gone, __global uint *overflow)
{
    const uint s = get_global_id(0);
    if (s >= sets)
        return;
    uint off[SE_LEVELS];
    const uint top = se_levels(m, off);
    const size_t base = (size_t)s * m, slots = off[top] + 1;
    /* with cap > 0 list i is in the cap slots from i cap on, unless se_pairs found more
     * neighbours than that (count[i] > cap) in some list of the set: then overflow[s] = 1
     * and the set is left alone */
    uint over = 0;
    for (uint i = 0; cap > 0 && i < m; ++i)
        over |= count[base + i] > cap;
    overflow[s] = over;
    if (over)
        return;
    __global double *current = weight + base;
    __global double *tk = key + (size_t)s * slots;
    __global uint *ti = idx + (size_t)s * slots;
    for (uint i = 0; i < off[1]; ++i)
        tk[i] = i < m ? current[i] : -INFINITY;
    for (uint l = 1; l <= top; ++l) {
        const uint nodes = (l < top ? off[l + 1] : off[l] + 1) - off[l];
        const uint decided = (off[l] - off[l - 1]) >> 3;
        for (uint p = 0; p < nodes; ++p) {
            if (p < decided) {
                se_decide(tk, ti, off, l, p);
            } else {
                tk[off[l] + p] = -INFINITY;         /* padding: never a winner */
                ti[off[l] + p] = 0;
            }
        }
    }
    uint removed = 0;
    while (removed < removals) {
        const uint i = ti[off[top]];
        const double now = current[i];
        if (tk[i] != now) {                         /* a stale key (never with SE_EAGER) */
            se_replay(tk, ti, off, top, i, now);
            continue;
        }
        gone[(size_t)s * removals + removed] = i;
        removed += 1;
        se_replay(tk, ti, off, top, i, -INFINITY);
        const ulong a0 = cap > 0 ? (ulong)(base + i) * cap : first[base + i];
        const ulong stop = a0 + count[base + i];
        for (ulong a = a0; a < stop; ++a) {
            const uint j = nbr[a];
            const double fallen = weight[j] - w[a];
            weight[j] = fallen;
#if SE_EAGER
            const uint jl = j - (uint)base;
            if (tk[jl] != -INFINITY)
                se_replay(tk, ti, off, top, jl, fallen);
#endif
        }
    }
}
