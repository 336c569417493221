/* Capacity-constrained Voronoi tessellation (Balzer, Schloemer, Deussen 2009) on the
 * integer torus of voronoi.h. NumPy reference: clsamp/samplers/ccvt.py (ccvt_reference).
 *
 * Every site owns exactly p density points: slots [r][i][0..p) hold their point indices (ids)
 * and their coordinates (xy, so the scans stream through memory instead of gathering), and the
 * only change ever made to them is an exchange of one point of site i for one of site j,
 * so the capacities are exact at every moment by construction. One iteration is
 *   voronoi_build_grid -> ccvt_swap for each of the 9 phases -> ccvt_centroids.
 * The phases pair grid cells so that no cell, hence no site, is in two pairs of one
 * launch: phase 0 takes the site pairs inside each cell, then for each offset (1,0),
 * (0,1), (1,1), (1,-1) and parity 0, 1 the cells whose x (for (0,1): y) has that parity
 * are paired with the cell at that offset (G is even, so the partners have the other
 * parity). That is a deterministic matching of the neighbour graph: every pair of sites
 * in the same or adjacent cells meets once per iteration, independent pairs run in
 * parallel, and the result does not depend on the device or the scheduling. */
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#include "voronoi.h"
#include "philox.h"

#define CCVT_TOP 16   /* candidates per site and round (clsamp.samplers.ccvt.CCVT_TOP) */

/* Order of the candidates: larger gain first, then the smaller point index. */
inline int ccvt_before(const long g, const uint idx, const long g2, const uint idx2)
{
    return g > g2 || (g == g2 && idx < idx2);
}

/* The CCVT_TOP points of a site at (ax, ay) that gain most by moving to the site at offset
 * D = (dx, dy) from it, among those with gain > floor, sorted by ccvt_before. Returns how
 * many (<= CCVT_TOP). The gain of x, with u its offset from a, is
 *     |u|^2 - |u - D|^2 = 2 u.D - |D|^2  (dd = |D|^2),
 * the exact change of its squared distance when the other site's image at a + D is the
 * nearest, and never more than the true change otherwise (the torus can only bring the
 * other site nearer): an exchange accepted on these gains lowers the energy at least as
 * much as they say, and costs two products a point instead of two distances. */
inline void ccvt_insert(const long g, const uint k, const uint j, const long floor, uint *c,
                        long *gain, uint *slot, uint *index)
{
    if (g <= floor)
        return;
    if (*c == CCVT_TOP && !ccvt_before(g, j, gain[CCVT_TOP - 1], index[CCVT_TOP - 1]))
        return;
    uint q = *c < CCVT_TOP ? (*c)++ : CCVT_TOP - 1;
    while (q > 0 && ccvt_before(g, j, gain[q - 1], index[q - 1])) {
        gain[q] = gain[q - 1];
        slot[q] = slot[q - 1];
        index[q] = index[q - 1];
        --q;
    }
    gain[q] = g;
    slot[q] = k;
    index[q] = j;
}

inline uint ccvt_top(__global const uint *ids, __global const uint2 *xy, const uint p,
                     const uint ax, const uint ay, const long dx, const long dy, const long dd,
                     const long floor, long *gain, uint *slot, uint *index)
{
    uint c = 0, k = 0;
    /* Four points at a time in double4 (PoCL vectorizes explicit vectors only): every
     * value is an integer below 2^53, so the doubles are exact and equal the long gains.
     * The vector test only pre-selects; ccvt_insert decides exactly. */
    const double fx = (double)dx, fy = (double)dy, fd = (double)dd;
    __global const uint *raw = (__global const uint *)xy;
    for (; k + 4 <= p; k += 4) {
        const uint8 v = vload8(0, raw + 2 * (size_t)k);
        int4 ux = as_int4((v.s0246 - (uint4)ax) & (uint4)VOR_MASK);
        int4 uy = as_int4((v.s1357 - (uint4)ay) & (uint4)VOR_MASK);
        ux = select(ux, ux - (int4)VOR_SIZE, ux >= (int4)VOR_HALF);
        uy = select(uy, uy - (int4)VOR_SIZE, uy >= (int4)VOR_HALF);
        const double4 g = 2.0 * (convert_double4(ux) * fx + convert_double4(uy) * fy) - fd;
        const long low = c == CCVT_TOP ? max(floor, gain[CCVT_TOP - 1] - 1) : floor;
        const long4 pass = isgreater(g, (double4)((double)low));
        if (any(pass)) {
            double gg[4];
            vstore4(g, 0, gg);
            const long pp[4] = {pass.s0, pass.s1, pass.s2, pass.s3};
            for (uint lane = 0; lane < 4; ++lane)
                if (pp[lane])
                    ccvt_insert((long)gg[lane], k + lane, ids[k + lane], floor, &c, gain, slot,
                                index);
        }
    }
    for (; k < p; ++k) {
        const uint2 q2 = xy[k];
        const long g = 2 * (vor_delta(q2.x, ax) * dx + vor_delta(q2.y, ay) * dy) - dd;
        if (g > floor)
            ccvt_insert(g, k, ids[k], floor, &c, gain, slot, index);
    }
    return c;
}

/* A site to the rounded periodic mean of its members, unwrapped relative to it (never
 * raises its energy: vor_round_mean), and its reach (squared distance of the farthest
 * member) from there. ccvt_pair calls it for both sites of a pair that exchanged. */
inline void ccvt_move(__global uint *s, __global const uint2 *q, const uint p,
                      __global long *reach2)
{
    const uint x0 = s[0], y0 = s[1];
    long sx = 0, sy = 0;
    for (uint k = 0; k < p; ++k) {
        sx += vor_delta(q[k].x, x0);
        sy += vor_delta(q[k].y, y0);
    }
    const uint x = (uint)((long)x0 + vor_round_mean(sx, (long)p)) & VOR_MASK;
    const uint y = (uint)((long)y0 + vor_round_mean(sy, (long)p)) & VOR_MASK;
    long reach = 0;
    for (uint k = 0; k < p; ++k)
        reach = max(reach, vor_d2(q[k].x, q[k].y, x, y));
    s[0] = x;
    s[1] = y;
    *reach2 = reach;
}

/* Balzer's pairwise swap for sites i and j: their best candidates toward each other,
 * sorted, are exchanged in order while the two gains sum to more than zero (each exchange
 * lowers the energy by exactly that sum). A round looks at CCVT_TOP candidates a side;
 * when all of them were exchanged another round starts from the new memberships. */
inline uint ccvt_pair(const uint i, const uint j, __global uint *ids, __global uint2 *xy,
                      const uint p, __global uint *s,
                      __global long *reach2, __global const uint *dirty,
                      __global uint *touched, const long near2)
{
    /* Skipping is exact, never a change of result: a pair where neither site moved nor
     * changed members since it last met found nothing then and finds nothing now; and with
     * R_i, R_j the reaches (farthest members, kept current by ccvt_move) the two gains sum
     * to at most 2 |D| (R_i + R_j - |D|), so sites farther apart than R_i + R_j cannot
     * swap (the test is in doubles with a margin that covers their rounding). */
    const int fresh = touched[i] || touched[j];
    if (!fresh && !dirty[i] && !dirty[j])
        return 0;
    const uint ix = s[2 * i], iy = s[2 * i + 1], jx = s[2 * j], jy = s[2 * j + 1];
    const long dist2 = vor_d2(ix, iy, jx, jy);
    if (dist2 >= near2)
        return 0;   /* not neighbours: the pair graph joins sites closer than ccvt_near */
    const double ri = (double)reach2[i], rj = (double)reach2[j];
    if ((double)dist2 > ri + rj + 2.0 * sqrt(ri * rj) * (1.0 + 1e-9) + 4.0)
        return 0;
    /* offsets of each site from the other: delta is antisymmetric but at exactly half the
     * torus, so each direction is computed, not negated */
    const long dijx = vor_delta(jx, ix), dijy = vor_delta(jy, iy);
    const long djix = vor_delta(ix, jx), djiy = vor_delta(iy, jy);
    const long dd = dijx * dijx + dijy * dijy;
    __global uint *mi = ids + (size_t)i * p;
    __global uint *mj = ids + (size_t)j * p;
    __global uint2 *pi = xy + (size_t)i * p;
    __global uint2 *pj = xy + (size_t)j * p;
    long gi[CCVT_TOP], gj[CCVT_TOP];
    uint si[CCVT_TOP], sj[CCVT_TOP], xi[CCVT_TOP], xj[CCVT_TOP];
    uint total = 0;
    for (;;) {
        /* a point of j can only be exchanged if its gain beats minus i's best, gi[0] */
        const uint ci = ccvt_top(mi, pi, p, ix, iy, dijx, dijy, dd, LONG_MIN, gi, si, xi);
        const uint cj = ccvt_top(mj, pj, p, jx, jy, djix, djiy, dd, -gi[0], gj, sj, xj);
        const uint k = min(ci, cj);
        uint done = 0;
        while (done < k && gi[done] + gj[done] > 0) {
            const uint t = mi[si[done]];
            mi[si[done]] = mj[sj[done]];
            mj[sj[done]] = t;
            const uint2 u = pi[si[done]];
            pi[si[done]] = pj[sj[done]];
            pj[sj[done]] = u;
            ++done;
        }
        total += done;
        if (done < CCVT_TOP)
            break;
    }
    if (total) {
        touched[i] = 1;
        touched[j] = 1;
        ccvt_move(s + 2 * i, pi, p, reach2 + i);
        ccvt_move(s + 2 * j, pj, p, reach2 + j);
    }
    return total;
}

/* The exchanges of one cell pair of a phase: (a, b) numbers the pair, (ox, oy) = (0, 0)
 * is phase 0 (the pairs inside cell (a, b)). Returns the number of exchanges. */
inline uint ccvt_cell_pairs(const uint a, const uint b, const int ox, const int oy,
                            const uint parity, const uint G, __global const uint *start,
                            __global const uint *list, __global uint *rid, __global uint2 *rxy,
                            const uint p, __global uint *s, __global long *rr,
                            __global const uint *dd, __global uint *tt, const long near2)
{
    uint total = 0;
    if (ox == 0 && oy == 0) {
        const uint c = b * G + a;
        for (uint qa = start[c]; qa < start[c + 1]; ++qa)
            for (uint qb = qa + 1; qb < start[c + 1]; ++qb)
                total += ccvt_pair(list[qa], list[qb], rid, rxy, p, s, rr, dd, tt, near2);
    } else {
        const uint ax = ox != 0 ? 2 * a + parity : b;
        const uint ay = ox != 0 ? b : 2 * a + parity;
        const uint bx = (uint)(((int)ax + ox + (int)G) % (int)G);
        const uint by = (uint)(((int)ay + oy + (int)G) % (int)G);
        const uint ca = ay * G + ax, cb = by * G + bx;
        for (uint qa = start[ca]; qa < start[ca + 1]; ++qa)
            for (uint qb = start[cb]; qb < start[cb + 1]; ++qb)
                total += ccvt_pair(list[qa], list[qb], rid, rxy, p, s, rr, dd, tt, near2);
    }
    return total;
}

/* Grid (G, G, r) for phase 0 (pairs inside a cell), (G/2, G, r) for a cell offset
 * (ox, oy) and a parity. swaps[r] counts the exchanges of the iteration. */
__kernel void ccvt_swap(__global uint *ids, __global uint2 *xy, const uint n, const uint p,
                        __global uint *sites,
                        __global const uint *cell_start, __global const uint *cell_sites,
                        const uint G, const int ox, const int oy, const uint parity,
                        __global const uint *active, __global long *reach2,
                        __global const uint *dirty, __global uint *touched,
                        __global uint *swaps, const long near2)
{
    const uint a = get_global_id(0), b = get_global_id(1), r = get_global_id(2);
    const int internal = ox == 0 && oy == 0;
    if (a >= (internal ? G : G / 2) || b >= G || !active[r])
        return;
    const uint total = ccvt_cell_pairs(
        a, b, ox, oy, parity, G, cell_start + (size_t)r * (G * G + 1), cell_sites + (size_t)r * n,
        ids + (size_t)r * n * p, xy + (size_t)r * n * p, p, sites + (size_t)r * n * 2,
        reach2 + (size_t)r * n, dirty + (size_t)r * n, touched + (size_t)r * n, near2);
    if (total)
        atomic_add(swaps + r, total);
}

/* The centroid step of one site (index `site` over all realizations): to the rounded mean
 * of its members (unwrapped relative to the site, which never raises its energy:
 * vor_round_mean), then its energy, its reach (largest squared distance to a member) and
 * whether it changed (dirty). Only sites whose members changed in this iteration are
 * visited (all of them when `all`): the others already sit at their rounded mean. Returns
 * the change of the site's energy, which site_energy keeps. */
inline long2 ccvt_centroid_site(const size_t site, __global uint *sites, const uint p,
                                __global const uint2 *xy, __global long *reach2,
                                __global uint *dirty, __global uint *touched,
                                __global long *site_energy, const uint all)
{
    if (!all && !touched[site]) {
        dirty[site] = 0;
        return (long2)(0, 0);
    }
    __global uint *s = sites + site * 2;
    __global const uint2 *q = xy + site * p;
    const uint x0 = s[0], y0 = s[1];
    long sx = 0, sy = 0;
    for (uint k = 0; k < p; ++k) {
        sx += vor_delta(q[k].x, x0);
        sy += vor_delta(q[k].y, y0);
    }
    const uint x = (uint)((long)x0 + vor_round_mean(sx, (long)p)) & VOR_MASK;
    const uint y = (uint)((long)y0 + vor_round_mean(sy, (long)p)) & VOR_MASK;
    long e = 0, reach = 0;
    for (uint k = 0; k < p; ++k) {
        const long d2 = vor_d2(q[k].x, q[k].y, x, y);
        e += d2;
        reach = max(reach, d2);
    }
    s[0] = x;
    s[1] = y;
    reach2[site] = reach;
    dirty[site] = touched[site] || x != x0 || y != y0;
    touched[site] = 0;
    const long old = all ? 0 : site_energy[site];
    site_energy[site] = e;
    /* (low 32 bits, high bits) parts: the realization's total cannot overflow */
    return (long2)((e & 0xFFFFFFFFL) - (old & 0xFFFFFFFFL), (e >> 32) - (old >> 32));
}

/* Grid (n, r): the centroid step of every site of the active realizations; energy[r]
 * holds their total energy as (low, high) sums, updated by the differences. */
__kernel void ccvt_centroids(__global uint *sites, const uint n, const uint p,
                             __global const uint2 *xy, __global const uint *active,
                             __global long *reach2, __global uint *dirty,
                             __global uint *touched, __global long *site_energy,
                             __global long *energy, const uint all)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= n || !active[r])
        return;
    const long2 d = ccvt_centroid_site((size_t)r * n + i, sites, p, xy, reach2, dirty, touched,
                                       site_energy, all);
    if (d.x)
        atom_add(energy + 2 * r, d.x);
    if (d.y)
        atom_add(energy + 2 * r + 1, d.y);
}

/* The whole optimization of a realization in one work-group (group r = realization r):
 * the same steps as the launches above, in the same order, with barriers between them, so
 * the results are identical; many realizations then cost one launch instead of a dozen
 * per iteration. history[r][t] = the total energy after iteration t as (low, high);
 * state[r] = (iterations run, converged). */
__kernel void ccvt_solve(__global uint *ids, __global uint2 *xy, const uint n, const uint p,
                         __global uint *sites, __global uint *cell_start,
                         __global uint *cell_sites, const uint G, __global long *reach2,
                         __global uint *dirty, __global uint *touched,
                         __global long *site_energy, const long near2, const uint iterations,
                         __global long *history, __global uint *state)
{
    const uint r = get_group_id(0), lid = get_local_id(0), L = get_local_size(0);
    __local long total[2];
    __local uint swaps;
    __global uint *start = cell_start + (size_t)r * (G * G + 1);
    __global uint *list = cell_sites + (size_t)r * n;
    __global uint *rid = ids + (size_t)r * n * p;
    __global uint2 *rxy = xy + (size_t)r * n * p;
    __global uint *s = sites + (size_t)r * n * 2;
    __global long *rr = reach2 + (size_t)r * n;
    __global uint *dd = dirty + (size_t)r * n;
    __global uint *tt = touched + (size_t)r * n;
    if (lid == 0)
        total[0] = total[1] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint i = lid; i < n; i += L) {
        const long2 d = ccvt_centroid_site((size_t)r * n + i, sites, p, xy, reach2, dirty,
                                           touched, site_energy, 1);
        atom_add(total, d.x);
        atom_add(total + 1, d.y);
        dd[i] = 1;   /* every pair meets in the first iteration */
    }
    uint done = 0, t = 0;
    for (; t < iterations && !done; ++t) {
        barrier(CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE);
        if (lid == 0) {
            vor_build_grid_one(s, n, G, start, list);
            swaps = 0;
        }
        barrier(CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE);
        uint made = 0;
        for (uint phase = 0; phase < 9; ++phase) {
            const int ox = phase == 0 ? 0 : (phase <= 2 ? 1 : phase <= 4 ? 0 : 1);
            const int oy = phase == 0 ? 0 : (phase <= 2 ? 0 : phase <= 6 ? 1 : -1);
            const uint parity = phase == 0 ? 0 : (phase - 1) & 1;
            const uint A = phase == 0 ? G : G / 2;
            for (uint w = lid; w < A * G; w += L)
                made += ccvt_cell_pairs(w % A, w / A, ox, oy, parity, G, start, list, rid, rxy,
                                        p, s, rr, dd, tt, near2);
            barrier(CLK_GLOBAL_MEM_FENCE);
        }
        atomic_add(&swaps, made);
        for (uint i = lid; i < n; i += L) {
            const long2 d = ccvt_centroid_site((size_t)r * n + i, sites, p, xy, reach2, dirty,
                                               touched, site_energy, 0);
            if (d.x)
                atom_add(total, d.x);
            if (d.y)
                atom_add(total + 1, d.y);
        }
        barrier(CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE);
        if (lid == 0) {
            history[((size_t)r * iterations + t) * 2] = total[0];
            history[((size_t)r * iterations + t) * 2 + 1] = total[1];
        }
        done = swaps == 0;
    }
    if (lid == 0) {
        state[2 * r] = t;
        state[2 * r + 1] = done;
    }
}

/* Grid (M, r): the density, point j of realization realization0 + r from words 4, 5 (Philox
 * block 1) of (key, stream, realization, j), top VOR_BITS bits each; the NumPy twin is
 * clsamp.samplers.ccvt.density_points. */
__kernel void ccvt_density(__global uint2 *out, const uint M, const uint realization0,
                           const uint key_lo, const uint key_hi, const uint stream)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const uint4 b = clsamp_block((uint2)(key_lo, key_hi), stream, realization0 + r, j, 1);
    out[(size_t)r * M + j] = (uint2)(b.x >> (32 - VOR_BITS), b.y >> (32 - VOR_BITS));
}

/* Grid (M, r): the jittered density of clsamp.samplers.ccvt.density_points. Point j lies
 * in its own cell of an equal-area partition into exactly M cells: `rows` rows, row i holding
 * points floor(i M / rows) .. floor((i+1) M / rows) - 1 (c of them, row height c / M, cells
 * 1 / c wide), uniform in the cell from words 4, 5 of (key, stream, realization, j); then the
 * whole set moves by the realization's toroidal shift, words 6, 7 of index 0. Integer
 * arithmetic (every product stays below 2^55), so it equals the NumPy twin bit for bit. */
__kernel void ccvt_density_jittered(__global uint2 *out, const uint M, const uint rows,
                                    const uint realization0, const uint key_lo,
                                    const uint key_hi, const uint stream)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint4 b = clsamp_block(key, stream, realization0 + r, j, 1);
    const uint4 t = clsamp_block(key, stream, realization0 + r, 0, 1);
    const ulong m = M, k = rows;
    const ulong row = (((ulong)j + 1) * k - 1) / m;
    const ulong start = row * m / k;
    const ulong c = (row + 1) * m / k - start;
    const ulong x = ((((ulong)j - start) << VOR_BITS) + (b.x >> (32 - VOR_BITS))) / c;
    const ulong y = ((start << VOR_BITS) + (ulong)(b.y >> (32 - VOR_BITS)) * c) / m;
    out[(size_t)r * M + j] = (uint2)(((uint)x + (t.z >> (32 - VOR_BITS))) & VOR_MASK,
                                     ((uint)y + (t.w >> (32 - VOR_BITS))) & VOR_MASK);
}
