/* Capacity-constrained Voronoi tessellation (Balzer, Schloemer, Deussen 2009) on the
 * integer torus of voronoi.h. NumPy reference: clsamp/samplers/ccvt/reference.py.
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
#include "ccvt.h"

/* Grid (G, G, r) for phase 0 (pairs inside a cell), (G/2, G, r) for a cell offset
 * (ox, oy) and a parity. swaps[r] counts the exchanges of the iteration. */
__kernel void ccvt_swap(__global uint *ids, __global uint2 *xy, __global uint *tids,
                        __global uint2 *txy, const uint n, const uint p,
                        __global uint *sites, __global long *meta, __global uint *bstart,
                        __global const uint *cell_start, __global const uint *cell_sites,
                        const uint G, const int ox, const int oy, const uint parity,
                        __global const uint *active, __global const uint *dirty,
                        __global uint *touched, __global uint *swaps, const long near2)
{
    const uint a = get_global_id(0), b = get_global_id(1), r = get_global_id(2);
    const int internal = ox == 0 && oy == 0;
    if (a >= (internal ? G : G / 2) || b >= G || !active[r])
        return;
    const size_t rn = (size_t)r * n, rnp = rn * p;
    const ccvt_t c = ccvt_state(n, p, ids + rnp, xy + rnp, tids + rnp, txy + rnp,
                                sites + 2 * rn, meta + rn * CCVT_META,
                                bstart + rn * (CCVT_BUCKETS + 1), dirty + rn, touched + rn);
    const uint total = ccvt_cell_pairs(&c, a, b, ox, oy, parity, G,
                                       cell_start + (size_t)r * (G * G + 1), cell_sites + rn,
                                       near2);
    if (total)
        atomic_add(swaps + r, total);
}

/* The end of an iteration for site i (of every site when `all`, the first time): a
 * touched site already sits at its centroid and its energy is kept; a wide one, or one that
 * drifted from its base by more than a tenth of the spacing (and
 * every site the first time: to the centroid of the start) is moved and rebuilt from
 * scratch. Then whether it changed (dirty). Returns the change of the site's energy,
 * which site_energy keeps, as (low 32 bits, high bits). */
inline long2 ccvt_centroid_site(const ccvt_t *c, const uint i, __global uint *dirty,
                                __global long *site_energy, const uint all)
{
    if (!all && !c->touched[i]) {
        dirty[i] = 0;
        return (long2)(0, 0);
    }
    __global long *m = c->meta + (size_t)i * CCVT_META;
    __global uint *s = c->s + 2 * i;
    const uint x0 = s[0], y0 = s[1];
    int rebuild = all || m[CCVT_WIDE];
    if (!rebuild) {
        const long2 q = ccvt_drift(c, i);
        rebuild = (long)abs(q.x) + (long)abs(q.y) >= c->drift;
    }
    if (rebuild) {
        ccvt_recenter(c, i);
        ccvt_rebuild(c, i);
    }
    const long e = m[CCVT_ENERGY];
    dirty[i] = c->touched[i] || s[0] != x0 || s[1] != y0;
    c->touched[i] = 0;
    const long old = all ? 0 : site_energy[i];
    site_energy[i] = e;
    return (long2)((e & 0xFFFFFFFFL) - (old & 0xFFFFFFFFL), (e >> 32) - (old >> 32));
}

/* Grid (n, r): the end of an iteration for every site of the active realizations;
 * status[r] = (low, high, swaps): their total energy as (low, high) sums, updated by the
 * differences, and the exchanges of the iteration, moved there from swaps[r] (which starts
 * the next iteration at 0), so that one read tells the host both. */
__kernel void ccvt_centroids(__global uint *ids, __global uint2 *xy, __global uint *tids,
                             __global uint2 *txy, __global uint *sites, const uint n,
                             const uint p, __global long *meta, __global uint *bstart,
                             __global const uint *active, __global uint *dirty,
                             __global uint *touched, __global long *site_energy,
                             __global long *status, __global uint *swaps, const uint all)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= n || !active[r])
        return;
    const size_t rn = (size_t)r * n, rnp = rn * p;
    const ccvt_t c = ccvt_state(n, p, ids + rnp, xy + rnp, tids + rnp, txy + rnp,
                                sites + 2 * rn, meta + rn * CCVT_META,
                                bstart + rn * (CCVT_BUCKETS + 1), dirty + rn, touched + rn);
    const long2 d = ccvt_centroid_site(&c, i, dirty + rn, site_energy + rn, all);
    if (d.x)
        atom_add(status + 3 * r, d.x);
    if (d.y)
        atom_add(status + 3 * r + 1, d.y);
    if (i == 0) {
        status[3 * r + 2] = swaps[r];
        swaps[r] = 0;
    }
}

/* The whole optimization of a realization in one work-group (group r = realization r):
 * the same steps as the launches above, in the same order, with barriers between them, so
 * the results are identical; many realizations then cost one launch instead of a dozen
 * per iteration. With `resume` it goes on from where those launches left the active
 * realizations (their status holds the energy; the others are left alone), without the
 * first move of the sites to their centroids: the tail of a run, where the few exchanges
 * left cost less than the launches. history[r][t] = the total energy after iteration t
 * as (low, high); state[r] = (iterations run, converged). */
__kernel void ccvt_solve(__global uint *ids, __global uint2 *xy, __global uint *tids,
                         __global uint2 *txy, const uint n, const uint p,
                         __global uint *sites, __global long *meta, __global uint *bstart,
                         __global uint *cell_start, __global uint *cell_sites, const uint G,
                         __global uint *dirty, __global uint *touched,
                         __global long *site_energy, const long near2, const uint iterations,
                         const uint resume, __global const uint *active,
                         __global long *status, __global long *history, __global uint *state)
{
    const uint r = get_group_id(0), lid = get_local_id(0), L = get_local_size(0);
    __local long total[2];
    __local uint swaps;
    if (!active[r])
        return;
    const size_t rn = (size_t)r * n, rnp = rn * p;
    __global uint *start = cell_start + (size_t)r * (G * G + 1);
    __global uint *list = cell_sites + rn;
    __global uint *s = sites + 2 * rn;
    __global uint *dd = dirty + rn;
    __global long *se = site_energy + rn;
    const ccvt_t c = ccvt_state(n, p, ids + rnp, xy + rnp, tids + rnp, txy + rnp, s,
                                meta + rn * CCVT_META, bstart + rn * (CCVT_BUCKETS + 1), dd,
                                touched + rn);
    if (lid == 0) {
        total[0] = resume ? status[3 * r] : 0;
        total[1] = resume ? status[3 * r + 1] : 0;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (!resume) {
        for (uint i = lid; i < n; i += L) {
            const long2 d = ccvt_centroid_site(&c, i, dd, se, 1);
            atom_add(total, d.x);
            atom_add(total + 1, d.y);
            dd[i] = 1;   /* every pair meets in the first iteration */
        }
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
                made += ccvt_cell_pairs(&c, w % A, w / A, ox, oy, parity, G, start, list,
                                        near2);
            barrier(CLK_GLOBAL_MEM_FENCE);
        }
        atomic_add(&swaps, made);
        for (uint i = lid; i < n; i += L) {
            const long2 d = ccvt_centroid_site(&c, i, dd, se, 0);
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
        status[3 * r] = total[0];
        status[3 * r + 1] = total[1];
    }
}

/* Grid (n * p, r): every slot gets its point's coordinates (xy[r][t] = points[r][ids[r][t]],
 * points M = n * p a realization), so the optimization streams instead of gathering. */
__kernel void ccvt_gather(__global const uint2 *points, __global const uint *ids,
                          __global uint2 *xy, const uint M)
{
    const uint t = get_global_id(0), r = get_global_id(1);
    if (t >= M)
        return;
    const size_t at = (size_t)r * M + t;
    xy[at] = points[(size_t)r * M + ids[at]];
}
