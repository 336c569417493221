/* Parallel dart throwing into tracked voids: the `poisson_disk` sampler.
 * NumPy reference: clsamp/samplers/poisson_disk/reference.py (NumpyDarts, same step names).
 *
 * Ebeida et al., "Efficient maximal Poisson-disk sampling" (SIGGRAPH 2011) and
 * "A simple algorithm for maximal Poisson-disk sampling in high dimensions"
 * (Eurographics 2012): a background grid of cells of side s < r / sqrt(DIM) holds at
 * most one point each; the uncovered area is a list of active cells (level-L
 * subcells of the grid cells) that is refined until no active cell remains, which
 * makes the set maximal. Conflicts between darts thrown in the same round are settled
 * by a few steps of the greedy independent set in the order of a random priority (Luby
 * 1986; dart_resolve), whose rules ask only "is there any", so the outcome depends on no
 * scheduling order and every device gives the same set.
 *
 * Layout: B realizations of `cells` = G^DIM grid cells each; grid cell `cell` of local
 * realization `rel` is slot rel * cells + cell of occ (uchar, 1 = holds a point) and pts
 * (DIM doubles). Active entry i is (rel[i], base[i], sub[i * DIM + k]); entries of one
 * grid cell are contiguous and first[i] is the index of the first of them.
 *
 * The grid of side r / sqrt(DIM) serves DIM <= 4 (its windows grow as (2 sqrt(DIM) + 3)^DIM
 * cells); for a fixed n in DIM 5..8, coarse_throw and coarse_resolve at the end throw darts
 * into the whole torus and find neighbours through cells at least r wide (kernels/cells.h).
 *
 * Exactly rounded double operations only, in the order of clsamp.geometry.torus.distance2
 * (kernels/torus.h), so the NumPy reference gives the same bits. Every double is held as its
 * IEEE-754 bit pattern (ulong) and computed by kernels/f64bits.h: by the hardware where the
 * device has fp64, by integer arithmetic with the same rounding where it has not, so every
 * device gives the same points. All the doubles here are non-negative, so a device without
 * fp64 compares their patterns as integers, exactly (f64_less, f64_max).
 * Build options: DIM, and D = DIM for cells.h. */
#pragma OPENCL FP_CONTRACT OFF
#include "torus.h"
#include "cells.h"

#ifndef DIM
#error "DIM must be defined"
#endif
#define NBLOCKS (DIM / 2 + 1)   /* Philox blocks per dart: DIM coordinates + a priority word */

/* A dart's DIM uniforms in [0, 1) and its priority word: Philox blocks block0 ..
 * block0 + NBLOCKS - 1 of (index, realization), coordinates two a block, the priority the
 * first word left over (clsamp.samplers.poisson_disk.reference.draw_darts). */
inline uint dart_draw(const uint2 key, const uint stream, const uint realization,
                      const uint index, const uint block0, ulong *u)
{
    uint priority = 0u;
    for (uint b = 0; b < NBLOCKS; ++b) {
        const uint4 w = clsamp_block(key, stream, realization, index, block0 + b);
        if (2 * b < DIM)
            u[2 * b] = clsamp_unit_bits(w.x, w.y);
        else
            priority = w.x;
        if (2 * b + 1 < DIM)
            u[2 * b + 1] = clsamp_unit_bits(w.z, w.w);
        else if (2 * b < DIM)
            priority = w.z;
    }
    return priority;
}

inline void cell_coords(uint flat, const uint G, int *bc)
{
    for (int k = DIM - 1; k >= 0; --k) {
        bc[k] = (int)(flat % G);
        flat /= G;
    }
}

/* Window tables (clsamp.samplers.poisson_disk.grid.window_offsets, cover_window) list the
 * offsets whose cells can matter, nearest first, so the loops that stop at the first
 * conflict or cover stop early; each row is DIM offsets and the flat-index difference
 * the offset makes when no coordinate wraps. */
#define ROW (DIM + 1)

/* Flat index of the grid cell at row `off` of a window from grid cell bi (coordinates
 * bc): the flat difference inside the grid (`inner`: no coordinate of the window wraps,
 * the common case), else each coordinate wrapped on the torus. */
inline uint neighbour_cell(const int *bc, const uint bi, const bool inner,
                           __global const int *off, const uint G)
{
    if (inner)
        return (uint)((int)bi + off[DIM]);
    uint flat = 0;
    for (int k = 0; k < DIM; ++k) {
        /* |off| <= G (the host checks), so one correction wraps; an integer modulo
         * here cost more than the distance test it feeds */
        int c = bc[k] + off[k];
        c = c < 0 ? c + (int)G : c >= (int)G ? c - (int)G : c;
        flat = flat * G + (uint)c;
    }
    return flat;
}

/* Whether a window reaching `reach` cells along each axis stays inside the grid. */
inline bool inside(const int *bc, const int reach, const uint G)
{
    bool in = true;
    for (int k = 0; k < DIM; ++k)
        in = in && bc[k] >= reach && bc[k] + reach < (int)G;
    return in;
}

/* First entries of every realization: all G^DIM grid cells at level 0 (one per grid
 * slot, so the empty grid is set up here too). */
__kernel void dart_init(__global uint *rel, __global uint *base, __global uint *sub,
                        __global uint *first, __global uchar *occ, __global uint *cand_round,
                        const uint cells, const uint m)
{
    const uint i = get_global_id(0);
    if (i >= m)
        return;
    occ[i] = 0;
    cand_round[i] = 0xFFFFFFFFu;
    rel[i] = i / cells;
    base[i] = i % cells;
    first[i] = i;
    for (int k = 0; k < DIM; ++k)
        sub[i * DIM + k] = 0u;
}

/* One dart per active entry, uniform in its cell; valid when no accepted point is
 * closer than r. The first entry of each grid cell registers the cell's run of
 * entries (tagged with the round) for dart_resolve. valid[i] is DART_OPEN or DART_OUT. */
__kernel void dart_throw(__global const uint *rel, __global const uint *base,
                         __global const uint *sub, __global const uint *first,
                         __global const uchar *occ, __global const ulong *pts,
                         __global ulong *cand, __global uint *prio, __global uchar *valid,
                         __global uint *cand_round, __global uint *cand_first,
                         __global uint *overflow, const uint m, const uint G,
                         __global const int *window, const uint nwindow, const int reach,
                         const uint cells, const uint level, const uint round, const ulong r2,
                         __global const uint *ids, const uint attempt, const uint key_lo,
                         const uint key_hi, const uint stream)
{
    const uint i = get_global_id(0);
    if (i >= m)
        return;
    const uint ri = rel[i], bi = base[i], fi = first[i];
    const size_t slot = (size_t)ri * cells + bi;
    if (fi == i) {
        cand_round[slot] = round;
        cand_first[slot] = i;
    }
    int bc[DIM];
    cell_coords(bi, G, bc);
    const bool inner = inside(bc, reach, G);
    /* Philox counter (grid cell | attempt << 26, realization, dart tag, stream): the tag
     * numbers the round and the entry's rank among its grid cell's entries, so a dart
     * depends only on its own realization's state. */
    if (i - fi >= (1u << 20))
        overflow[0] = 1u;   /* the host raises: the tag would repeat */
    const uint tag = (round << 20) | (i - fi);
    const uint index = bi | (attempt << 26);
    const uint2 key = (uint2)(key_lo, key_hi);
    ulong u[DIM];
    const uint priority = dart_draw(key, stream, ids[ri], index, tag * NBLOCKS, u);
    const ulong M = (ulong)G << level;
    ulong x[DIM];
    for (int k = 0; k < DIM; ++k) {     /* (c + u) / M */
        const ulong c = ((ulong)bc[k] << level) | (ulong)sub[i * DIM + k];
        x[k] = f64_div_int(f64_add(f64_from_int(c), u[k]), M);
        if (!f64_less(x[k], F64_ONE))   /* rounded up to the far edge: the same torus point */
            x[k] = 0;
    }
    uchar ok = occ[slot] ? 0 : 1;
    for (uint o = 0; ok && o < nwindow; ++o) {
        const size_t nslot = (size_t)ri * cells
                             + neighbour_cell(bc, bi, inner, window + o * ROW, G);
        if (occ[nslot] && torus_closer_bits(x, pts + nslot * DIM, DIM, r2))
            ok = 0;
    }
    for (int k = 0; k < DIM; ++k)
        cand[(size_t)i * DIM + k] = x[k];
    prio[i] = priority;
    valid[i] = ok;
}

/* Darts' states in dart_resolve: */
#define DART_OUT 0          /* invalid, or conflicts with an accepted dart */
#define DART_OPEN 1         /* valid, undecided */
#define DART_IN 2           /* accepted */

/* Whether dart i is still open in this step of dart_resolve, its position then in x; a
 * decided dart keeps its state. */
inline bool dart_open(const uint i, __global const uchar *in, __global uchar *out,
                      __global const ulong *cand, ulong *x)
{
    const uchar state = in[i];
    if (state != DART_OPEN) {
        out[i] = state;
        return false;
    }
    for (int k = 0; k < DIM; ++k)
        x[k] = cand[(size_t)i * DIM + k];
    return true;
}

/* The rule of dart_resolve for dart j seen from open dart i (priority pi, at x): only a
 * higher dart (random priority, then lower index) still in play and closer than r counts;
 * an accepted one beats i, an open one blocks it. True when the scan may stop: i is beaten,
 * or blocked at step 0 (no dart is in yet, so the first blocker decides, exactly). */
inline bool dart_rival(const ulong *x, const uint i, const uint pi, const uint j,
                       __global const uint *prio, __global const uchar *in,
                       __global const ulong *cand, const ulong r2, const uint step,
                       bool *beaten, bool *blocked)
{
    const uint pj = prio[j];
    if (!(pj > pi || (pj == pi && j < i)))
        return false;           /* not higher (this also skips j == i) */
    const uchar sj = in[j];
    if (sj == DART_OUT || !torus_closer_bits(x, cand + (size_t)j * DIM, DIM, r2))
        return false;
    if (sj == DART_IN) {
        *beaten = true;
        return true;
    }
    *blocked = true;
    return step == 0;
}

/* One step of the greedy independent set among this round's valid darts (Luby 1986 with
 * fixed priorities): dart i goes out when a conflicting (closer than r) dart of a higher
 * key (random priority, then lower index) is in, waits while such a dart is open, and goes
 * in when there is neither. Only higher darts matter: a dart goes in only once every
 * higher conflicting dart is out, so a lower one is never in while i is open. A step
 * reads `in` and writes `out` and its rule asks only "is there any", so no result depends
 * on the order in which work-items run or neighbours are scanned. Run to the end, the
 * steps accept the set that throwing the darts one by one in priority order would; the
 * host stops after a few steps (resolve_steps), and darts still open stay out this round (their
 * cells stay active). Two darts in one grid cell always conflict (the cell diagonal is
 * shorter than r), so each grid cell gains at most one point. Points are written to the
 * grid as they are accepted (no step reads the grid). */
__kernel void dart_resolve(__global const uint *rel, __global const uint *base,
                           __global const ulong *cand, __global const uint *prio,
                           __global const uchar *in, __global uchar *out,
                           __global const uint *cand_round, __global const uint *cand_first,
                           __global uchar *occ, __global ulong *pts, __global uint *accepted,
                           const uint m, const uint G, __global const int *window,
                           const uint nwindow, const int reach, const uint cells,
                           const uint round, const uint step, const ulong r2)
{
    const uint i = get_global_id(0);
    ulong x[DIM];
    if (i >= m || !dart_open(i, in, out, cand, x))
        return;
    const uint ri = rel[i], bi = base[i], pi = prio[i];
    int bc[DIM];
    cell_coords(bi, G, bc);
    const bool inner = inside(bc, reach, G);
    bool blocked = false, beaten = false;
    for (uint o = 0; !beaten && !(blocked && step == 0) && o < nwindow; ++o) {
        const uint nb = neighbour_cell(bc, bi, inner, window + o * ROW, G);
        const size_t nslot = (size_t)ri * cells + nb;
        if (cand_round[nslot] != round)
            continue;
        for (uint j = cand_first[nslot]; j < m && rel[j] == ri && base[j] == nb; ++j)
            if (dart_rival(x, i, pi, j, prio, in, cand, r2, step, &beaten, &blocked))
                break;
    }
    const uchar next = beaten ? DART_OUT : blocked ? DART_OPEN : DART_IN;
    out[i] = next;
    if (next == DART_IN) {
        const size_t slot = (size_t)ri * cells + bi;
        occ[slot] = 1;
        for (int k = 0; k < DIM; ++k)
            pts[slot * DIM + k] = x[k];
        atomic_inc(accepted + ri);  /* counts: their values do not depend on order */
    }
}

/* Per axis, the distance from p to the farther end of [lo, hi] (tl, th: to each end), or
 * 0.5 when the interval comes within its width of the antipode, f > 0.5 - (hi - lo)
 * (conservative: a covered box may stay active one level longer, an uncovered one is never
 * dropped). `near` is 0.5 - (hi - lo), once per interval (near_bound). */
inline ulong far_end(const ulong tl, const ulong th, const ulong near)
{
    const ulong f = f64_max(tl, th);
    return f64_less(near, f) ? F64_HALF : f;
}

/* 0.5 - (hi - lo) for far_end; +0 for an interval wider than 1/2 (never: G >= 3), where the
 * difference is negative: f > 0 there, as one end of an interval narrower than 1 is away
 * from p. */
inline ulong near_bound(const ulong lo, const ulong hi)
{
    const ulong w = f64_sub(hi, lo);
    return f64_less(F64_HALF, w) ? 0 : f64_sub(F64_HALF, w);
}

/* Which children (split = 1: the 2^DIM halves, at most 16: DIM <= 4; split = 0: the cell
 * itself) of active
 * entry i are still uncovered. A box is covered when all its corners lie closer than r
 * to one point (a box lies in a disk iff its corners do; the farthest corner is, per axis,
 * the farther end); a child also counts as covered when its whole parent is, which is
 * what nearly always drops an entry. A child's ends are its parent's ends and midpoint,
 * computed once: (2c)/(2M) rounds as c/M, so these are the bits of the child's own ends.
 * `window` is the cover table of the children's level: only its cells can cover. */
__kernel void dart_refine(__global const uint *rel, __global const uint *base,
                          __global const uint *sub, __global const uchar *occ,
                          __global const ulong *pts, __global const uchar *done,
                          __global ushort *mask, __global uchar *count,
                          __global uint *remaining, const uint m, const uint G,
                          __global const int *window, const uint nwindow, const int reach,
                          const uint cells, const uint level, const uint split,
                          const ulong r2)
{
    const uint i = get_global_id(0);
    if (i >= m)
        return;
    const uint ri = rel[i], bi = base[i];
    const size_t slot = (size_t)ri * cells + bi;
    if (done[ri] || occ[slot]) {
        mask[i] = 0;
        count[i] = 0;
        return;
    }
    int bc[DIM];
    cell_coords(bi, G, bc);
    const bool inner = inside(bc, reach, G);
    const ulong Mp = (ulong)G << level;
    const ulong Mc = (ulong)G << (level + 1);
    ulong lo[DIM], mid[DIM], hi[DIM], near[DIM], near_lo[DIM], near_hi[DIM];
    for (int k = 0; k < DIM; ++k) {     /* c / Mp, (c + 1) / Mp, (2c + 1) / Mc */
        const ulong c = ((ulong)bc[k] << level) | (ulong)sub[i * DIM + k];
        lo[k] = f64_div(c, Mp, 0);
        hi[k] = f64_div(c + 1, Mp, 0);
        mid[k] = f64_div(2 * c + 1, Mc, 0);
        near[k] = near_bound(lo[k], hi[k]);
        near_lo[k] = near_bound(lo[k], mid[k]);
        near_hi[k] = near_bound(mid[k], hi[k]);
    }
    const uint children = split ? (1u << DIM) : 1u;
    uint open = (1u << children) - 1u;
    for (uint o = 0; open && o < nwindow; ++o) {
        const size_t nslot = (size_t)ri * cells
                             + neighbour_cell(bc, bi, inner, window + o * ROW, G);
        if (!occ[nslot])
            continue;
        __global const ulong *p = pts + nslot * DIM;
        ulong tl[DIM], tm[DIM], th[DIM];
        ulong far2 = 0;
        for (int k = 0; k < DIM; ++k) {
            tl[k] = torus_delta_bits(lo[k], p[k]);
            th[k] = torus_delta_bits(hi[k], p[k]);
            const ulong f = far_end(tl[k], th[k], near[k]);
            far2 = k ? f64_add(far2, f64_mul(f, f)) : f64_mul(f, f);
        }
        if (f64_less(far2, r2)) {
            open = 0;
            break;
        }
        if (!split)
            continue;
        for (int k = 0; k < DIM; ++k)
            tm[k] = torus_delta_bits(mid[k], p[k]);
        for (uint t = 0; t < children; ++t) {
            if (!(open & (1u << t)))
                continue;
            ulong c2 = 0;
            for (int k = 0; k < DIM; ++k) {
                const ulong f = ((t >> (DIM - 1 - k)) & 1u)
                                ? far_end(tm[k], th[k], near_hi[k])
                                : far_end(tl[k], tm[k], near_lo[k]);
                c2 = k ? f64_add(c2, f64_mul(f, f)) : f64_mul(f, f);
#if !CLSAMP_FP64
                if (!f64_less(c2, r2))  /* the sums only grow (torus_closer_bits) */
                    break;
#endif
            }
            if (f64_less(c2, r2))
                open &= ~(1u << t);
        }
    }
    mask[i] = (ushort)open;
    count[i] = (uchar)popcount(open);
    if (open)
        atomic_add(remaining + ri, (uint)popcount(open));
}

/* Write the uncovered children of entry i at offs[i] (exclusive scan of the counts);
 * their grid cell's run starts at offs[first[i]]. */
__kernel void dart_emit(__global const uint *rel, __global const uint *base,
                        __global const uint *sub, __global const uint *first,
                        __global const ushort *mask, __global const uint *offs,
                        __global uint *out_rel, __global uint *out_base, __global uint *out_sub,
                        __global uint *out_first, const uint m, const uint split)
{
    const uint i = get_global_id(0);
    if (i >= m)
        return;
    const uint open = mask[i];
    if (!open)
        return;
    uint o = offs[i];
    const uint f = offs[first[i]];
    const uint children = split ? (1u << DIM) : 1u;
    for (uint t = 0; t < children; ++t) {
        if (!(open & (1u << t)))
            continue;
        out_rel[o] = rel[i];
        out_base[o] = base[i];
        out_first[o] = f;
        for (int k = 0; k < DIM; ++k) {
            const uint bit = split ? (t >> (DIM - 1 - k)) & 1u : 0u;
            out_sub[o * DIM + k] = (sub[i * DIM + k] << split) | bit;
        }
        ++o;
    }
}

/* Drop the points of the listed grid slots (the lowest-priority darts of the round that
 * passed n, so that exactly n remain). */
__kernel void dart_clear(__global uchar *occ, __global const uint *slots, const uint count)
{
    const uint i = get_global_id(0);
    if (i < count)
        occ[slots[i]] = 0;
}

/* The points of each realization in grid-cell order, written from point dst[r] of out
 * (shape (total, DIM)); dst[r] = 0xFFFFFFFF skips realization r (it will be redrawn).
 * One work-item per realization. */
__kernel void dart_gather(__global const uchar *occ, __global const ulong *pts,
                          __global const uint *dst, __global ulong *out,
                          const uint cells, const uint B)
{
    const uint r = get_global_id(0);
    if (r >= B || dst[r] == 0xFFFFFFFFu)
        return;
    size_t o = dst[r];
    for (uint c = 0; c < cells; ++c) {
        const size_t slot = (size_t)r * cells + c;
        if (occ[slot]) {
            for (int k = 0; k < DIM; ++k)
                out[o * DIM + k] = pts[slot * DIM + k];
            ++o;
        }
    }
}

/* -- DIM 5..8, a fixed n: darts into the whole torus (clsamp/samplers/poisson_disk/coarse.py;
 * NumPy twin NumpyCoarse in reference.py). No voids are tracked: every round throws
 * `darts` darts into each unfinished realization, a dart is valid when no accepted point
 * is closer than r, and valid darts are settled among themselves as dart_resolve settles
 * them. The accepted points and the darts are sorted by (set, cell) on the host
 * (cells of side 1/G >= r, G >= 3, or G == 1: the 3^DIM cells around a cell, or the one
 * cell, hold every neighbour closer than r); `start` is the first sorted index of each
 * (set, cell). Set a of the round holds darts a * darts .. (a + 1) * darts - 1. */

inline void coarse_cell(const ulong *x, const int G, int *c)
{
    for (int k = 0; k < DIM; ++k) {     /* (int)(x G), as clsamp.geometry.cells.sorted_by_cell */
        const int v = (int)f64_floor(f64_mul_int(x[k], (ulong)G));
        c[k] = v < G - 1 ? v : G - 1;
    }
}

/* Dart i = a * darts + j of set a (realization ids[a]): Philox counter (j | attempt << 26,
 * realization, round * NBLOCKS + block, stream); valid when no accepted point of its set in
 * the cells around it is closer than r. */
__kernel void coarse_throw(__global const uint *ids, const uint darts, const uint m,
                           __global const ulong *pts, __global const uint *start,
                           const int G, const uint stencil, const uint cells,
                           const ulong r2, const uint round, const uint attempt,
                           const uint key_lo, const uint key_hi, const uint stream,
                           __global ulong *cand, __global uint *prio, __global uchar *valid)
{
    const uint i = get_global_id(0);
    if (i >= m)
        return;
    const uint a = i / darts, j = i % darts;
    ulong x[DIM];
    const uint priority = dart_draw((uint2)(key_lo, key_hi), stream, ids[a],
                                    j | (attempt << 26), round * NBLOCKS, x);
    int c[DIM];
    coarse_cell(x, G, c);
    uchar ok = 1;
    for (uint o = 0; ok && o < stencil; ++o) {
        const size_t slot = (size_t)a * cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint q = start[slot]; q < s1; ++q)
            if (torus_closer_bits(x, pts + (size_t)q * DIM, DIM, r2)) {
                ok = 0;
                break;
            }
    }
    for (int k = 0; k < DIM; ++k)
        cand[(size_t)i * DIM + k] = x[k];
    prio[i] = priority;
    valid[i] = ok;
}

/* One step of dart_resolve's greedy independent set among the round's darts, sorted by
 * (set, cell): the same rule, the tie of equal priorities broken by the lower sorted index. */
__kernel void coarse_resolve(__global const ulong *cand, __global const uint *prio,
                             __global const uint *start, __global const uchar *in,
                             __global uchar *out, const uint darts, const uint m, const int G,
                             const uint stencil, const uint cells, const uint step,
                             const ulong r2)
{
    const uint i = get_global_id(0);
    ulong x[DIM];
    if (i >= m || !dart_open(i, in, out, cand, x))
        return;
    const uint a = i / darts, pi = prio[i];
    int c[DIM];
    coarse_cell(x, G, c);
    bool blocked = false, beaten = false;
    for (uint o = 0; !beaten && !(blocked && step == 0) && o < stencil; ++o) {
        const size_t slot = (size_t)a * cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        for (uint j = start[slot]; j < s1; ++j)
            if (dart_rival(x, i, pi, j, prio, in, cand, r2, step, &beaten, &blocked))
                break;
    }
    out[i] = beaten ? DART_OUT : blocked ? DART_OPEN : DART_IN;
}
