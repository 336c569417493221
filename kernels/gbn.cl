/* Gaussian blue noise (Ahmed, Ren, Wonka 2022): the pair pass of one gradient step, an
 * n-body sum over the neighbours within the kernel's cutoff found through a grid of cells
 * (kernels/cells.h). NumPy twin: pair_pass_reference in clsamp/samplers/gbn.py, the same
 * bits: exactly rounded double operations in the same order, no contraction, and the
 * exponential gbn_exp_neg below (range reduction, a table and a Horner polynomial) instead of the
 * device's exp, whose last bits differ between devices.
 *
 * The points of the sets being optimized come sorted by (set, cell) of a G^D grid in pts
 * (total, D) (each point's cell found again here from its coordinates), and start
 * (sets G^D + 1) holds the first sorted index of each (set, cell); G >= 3 (the 3^D cells around a cell distinct,
 * each at least the cutoff wide) or G == 1 (every pair). For every sorted point i the
 * partners j != i in its 3^D neighbouring cells, in stencil order then sorted order, with
 * squared distance r2 < R2 (wrapped on the torus when PERIODIC) add
 *     e = exp(-r2 inv2s2),  energy += e - gR,  force[k] += (x_i - x_j)[k] e,
 * gR = exp(-R2 inv2s2), so that the kernel cut at the cutoff stays continuous; row i of
 * out (total, D + 1) is (energy, force).
 * Each sum is four partial sums, partner j's term going to partial sum j mod 4 (in the
 * order above), and its value is (s0 + s1) + (s2 + s3): so 4 consecutive partners go to
 * 4 vector lanes that add independently (gbn_range16).
 * ADAPTIVE (adaptive sampling): t (total) holds each sorted point's variance relative to
 * s^2; a pair's is tau = (t_i + t_j) / 2, it interacts while r2 < R2 tau, and adds
 *     q = r2 inv2s2 / tau,  e = exp(-q),  energy += e - gR,  force[k] += (x_i - x_j)[k] (e / tau),
 *     width += q (e / tau),
 * with R2 = (cut s)^2 and gR = exp(-cut^2 / 2); row i of out (total, D + 2) is
 * (energy, force, width).
 *
 * Build options: D (dimensions), PERIODIC (1: the unit torus, differences wrapped into
 * [-1/2, 1/2]; 0: the unit cube), ADAPTIVE (1: per-point widths t, as above; 0: none),
 * RESIDENT (1: a flags argument before out, and the sets whose flags[3 set] is 0 skipped;
 * gbn_control below), LANES (16: the pass without widths takes 16 points at a time in
 * vector lanes, gbn_range16 below, from 4-D on the exponential on 4 queued partners at a
 * time, with the same partial sums in the same order, for CPUs' vector units; else 1, one
 * at a time),
 * GBN_EXP_BITS, GBN_EXP_INV, GBN_EXP_HI, GBN_EXP_LO, GBN_EXP_TABLE and GBN_C0 .. GBN_C6 (the
 * exponential's constants, from clsamp.samplers.gbn.EXP_DEFINES).
 * From 3-D on, a neighbouring cell whose box lies beyond skip2 (the squared reach the grid
 * was made for) is skipped whole: it holds no partner within the cutoff, so the sums,
 * their order and the bits are those of the full stencil.
 * Launch: one work-item per sorted point, grid (total,).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF
#include "cells.h"
#include "in_order.h"
#include "torus.h"

#ifndef GBN_EXP_TABLE
#error "gbn.cl needs the exponential's constants (clsamp.samplers.gbn.EXP_DEFINES)"
#endif

/* 2^(-j / 2^GBN_EXP_BITS), j = 0 .. 2^GBN_EXP_BITS - 1, correctly rounded */
__constant double gbn_exp2_table[1 << GBN_EXP_BITS] = {GBN_EXP_TABLE};
#define GBN_EXP_MASK ((1 << GBN_EXP_BITS) - 1)

/* the Horner steps of (e^r - 1) / r's polynomial below, for p and r of one type (double or
 * double4) */
#define GBN_HORNER(p, r) \
    p = p * r + GBN_C5; p = p * r + GBN_C4; p = p * r + GBN_C3; p = p * r + GBN_C2; \
    p = p * r + GBN_C1;

/* a sum's value from its four partial sums (by partner index mod 4) */
#define GBN_FOLD(a, b, c, d) (((a) + (b)) + ((c) + (d)))

/* e^-t for 0 <= t < 700: t = k ln 2 / 32 - r with |r| <= ln 2 / 64 (GBN_EXP_BITS 5),
 * e^-t = 2^-(k >> 5) T (1 + r P(r)), T = 2^(-(k mod 32) / 32) from the table and 1 + r P(r)
 * e^r's Taylor polynomial of degree 6 (truncation below 4e-18 relative), summed as
 * T + T (r P(r)) so that the small part's rounding barely shows; the power of two exactly */
inline double gbn_exp_neg(const double t)
{
    const int k = (int)(t * GBN_EXP_INV + 0.5);
    const double kd = (double)k;
    const double r = (kd * GBN_EXP_HI - t) + kd * GBN_EXP_LO;
    double p = GBN_C6;
    GBN_HORNER(p, r)
    const double table = gbn_exp2_table[k & GBN_EXP_MASK];
    return (table + table * (r * p)) * as_double((ulong)(1023 - (k >> GBN_EXP_BITS)) << 52);
}

#if LANES == 16
#if ADAPTIVE
#error "gbn.cl: LANES 16 is for the pass without widths"
#endif
/* gbn_exp_neg in 4 lanes, each the same operations (a float to int conversion rounds
 * toward zero, as the cast does) */
inline double4 gbn_exp_neg4(const double4 t)
{
    const int4 k = convert_int4(t * GBN_EXP_INV + 0.5);
    const double4 kd = convert_double4(k);
    const double4 r = (kd * GBN_EXP_HI - t) + kd * GBN_EXP_LO;
    double4 p = (double4)(GBN_C6);
    GBN_HORNER(p, r)
    const int4 j = k & GBN_EXP_MASK;
    const double4 table = (double4)(gbn_exp2_table[j.x], gbn_exp2_table[j.y],
                                    gbn_exp2_table[j.z], gbn_exp2_table[j.w]);
    return (table + table * (r * p)) * as_double4(convert_ulong4(1023 - (k >> GBN_EXP_BITS)) << 52);
}

/* The partners of a point are summed into gbn_acc: part[0] holds the energy's four partial
 * sums, part[1 + k] the force's along axis k, [m] partial sum m. Up to 3-D the terms are
 * added in vector lanes as they come (gbn_range16 below, a lane that is not a partner
 * adding +0.0). From 4-D on most candidates are not partners (a one-cell grid takes every
 * pair), so the partners are queued first and the exponential runs on 4 partners at a
 * time (GBN_QUEUED); their terms are then added in queue order, each to its partial sum. */
#define GBN_QUEUED (D >= 4)

typedef struct {
#if GBN_QUEUED
    double part[D + 1][4];
    double r2[4];               /* the queue: up to 4 partners' squared distances, */
    double w[D][4];             /* wrapped differences */
    uint m[4];                  /* and partial sums (partner index mod 4), in order */
    uint count;
#else
    double4 part[D + 1];
#endif
} gbn_acc;

inline void gbn_acc_init(gbn_acc *acc)
{
#if GBN_QUEUED
    for (int k = 0; k <= D; ++k)
        for (int m = 0; m < 4; ++m)
            acc->part[k][m] = 0.0;
    for (int m = 0; m < 4; ++m)
        acc->r2[m] = 0.0;
    acc->count = 0;
#else
    for (int k = 0; k <= D; ++k)
        acc->part[k] = (double4)(0.0);
#endif
}

#if GBN_QUEUED
/* the queued partners' terms added to their partial sums in queue order; the exponential
 * runs in 4 lanes, those past count on earlier (finite) values, unused */
inline void gbn_flush(gbn_acc *acc, const double inv2s2, const double gR)
{
    double e[4];
    vstore4(gbn_exp_neg4(vload4(0, acc->r2) * inv2s2), 0, e);
    for (uint s = 0; s < acc->count; ++s) {
        const uint m = acc->m[s];
        acc->part[0][m] = acc->part[0][m] + (e[s] - gR);
        _Pragma("unroll")
        for (int k = 0; k < D; ++k)
            acc->part[1 + k][m] = acc->part[1 + k][m] + acc->w[k][s] * e[s];
    }
    acc->count = 0;
}
#endif

/* the partners still queued added (nothing to do without the queue): after the last
 * range, before gbn_acc_sum */
inline void gbn_acc_finish(gbn_acc *acc, const double inv2s2, const double gR)
{
#if GBN_QUEUED
    if (acc->count)
        gbn_flush(acc, inv2s2, gR);
#endif
}

/* the sum of quantity k (0 the energy, 1 + k the force along axis k) */
inline double gbn_acc_sum(gbn_acc *acc, const int k)
{
#if GBN_QUEUED
    return GBN_FOLD(acc->part[k][0], acc->part[k][1], acc->part[k][2], acc->part[k][3]);
#else
    return GBN_FOLD(acc->part[k].x, acc->part[k].y, acc->part[k].z, acc->part[k].w);
#endif
}

/* the partners of sorted point i (at x) among sorted points lo .. hi - 1, in order, added
 * to acc: 16 points at a time from a multiple of 4, as four vectors of 4 lanes (no wider:
 * PoCL's built-ins and kernels disagree on how a 512-bit vector is passed on some AVX-512
 * hosts, tests/test_runtime.py), so that lane l is always a point of index l mod 4. The
 * loops are unrolled (PoCL keeps them rolled, the vectors in memory). Without the queue a
 * lane that is not a partner adds +0.0, which leaves a partial sum unchanged: it starts at
 * +0.0 and x + y is -0.0 only where both are, so none is ever -0.0; 16 points without a
 * partner add nothing. With it the partners' lanes are queued lowest first. */
inline void gbn_range16(__global const double *pts, const uint total, const uint lo,
                        const uint hi, const uint i, const double *x, const double R2,
                        const double inv2s2, const double gR, gbn_acc *acc)
{
    const double4 zero = (double4)(0.0);
    for (uint j0 = lo & ~3u; j0 < hi; j0 += 16) {
        double4 v[4][D], r2[4];
        long4 on[4];
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            const uint jq = j0 + 4 * (uint)q;
            cells_load4(pts, total, jq, v[q]);
            r2[q] = zero;
            _Pragma("unroll")
            for (int k = 0; k < D; ++k) {
#if PERIODIC
                const double4 w = torus_wrapped4((double4)(x[k]), v[q][k]);
#else
                const double4 w = x[k] - v[q][k];
#endif
                v[q][k] = w;
                r2[q] = k == 0 ? w * w : r2[q] + w * w;
            }
            const long4 j = (long4)(long)jq + (long4)(0, 1, 2, 3);
            on[q] = (j >= (long)lo) & (j < (long)hi) & (j != (long)i) & (r2[q] < R2);
        }
#if GBN_QUEUED
        /* bit l set where lane l holds a partner (select reads a mask's sign bit, as a
         * mask is defined), the lanes kept in arrays to be queued by index */
        uint bits = 0;
        double r2l[16], wl[D][16];
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            const long4 lane = (long4)(0, 1, 2, 3) + (long4)(4 * q);
            const long4 b = select((long4)(0), (long4)(1), on[q]) << lane;
            bits |= (uint)((b.x | b.y) | (b.z | b.w));
            vstore4(r2[q], q, r2l);
            _Pragma("unroll")
            for (int k = 0; k < D; ++k)
                vstore4(v[q][k], q, wl[k]);
        }
        while (bits != 0) {
            const uint l = 31u - clz(bits & (0u - bits));
            bits &= bits - 1u;
            const uint s = acc->count;
            acc->r2[s] = r2l[l];
            _Pragma("unroll")
            for (int k = 0; k < D; ++k)
                acc->w[k][s] = wl[k][l];
            acc->m[s] = l & 3u;
            acc->count = s + 1;
            if (s == 3)
                gbn_flush(acc, inv2s2, gR);
        }
#else
        if (!any(on[0] | on[1] | on[2] | on[3]))
            continue;
        _Pragma("unroll")
        for (int q = 0; q < 4; ++q) {
            /* in 1-D and 2-D a vector without a partner is skipped (from 3-D on the
             * branch cost what it saved) */
            if (D <= 2 && !any(on[q]))
                continue;
            const double4 e = gbn_exp_neg4(select(zero, r2[q] * inv2s2, on[q]));
            acc->part[0] = acc->part[0] + select(zero, e - gR, on[q]);
            _Pragma("unroll")
            for (int k = 0; k < D; ++k)
                acc->part[1 + k] = acc->part[1 + k] + select(zero, v[q][k] * e, on[q]);
        }
#endif
    }
}
#endif

__kernel void gbn_pairs(__global const double *pts,
#if ADAPTIVE
                        __global const double *t,
#endif
                        __global const uint *start, const uint n,
                        const uint total, const int G, const uint noff, const double R2,
                        const double inv2s2, const double gR, const double skip2,
#if RESIDENT
                        __global const int *flags,
#endif
                        __global double *out)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint r = gi / n;
#if RESIDENT
    if (!flags[3 * r])                              /* a set that has stopped (gbn_control) */
        return;
#endif
    const uint total_cells = cells_count(G);
    double x[D], f[D], e_sum;
    for (int k = 0; k < D; ++k)
        x[k] = pts[(size_t)gi * D + k];
#if ADAPTIVE
    const double ti = t[gi];
    double width;
#endif
    int c[D];
    cell_of(x, G, c);
#if LANES == 16
    /* the stencil by rows along the last axis (cells_row_ranges): the same cells in the
     * same order as one at a time, into gbn_acc's partial sums */
    gbn_acc acc;
    gbn_acc_init(&acc);
    __global const uint *st = start + (size_t)r * total_cells;
    for (uint o = 0; o < cells_rows(G, noff); ++o) {
        uint lo[2], hi[2];
        const uint ranges = cells_row_ranges(st, c, x, G, o, skip2, lo, hi);
        for (uint k = 0; k < ranges; ++k)
            gbn_range16(pts, total, lo[k], hi[k], gi, x, R2, inv2s2, gR, &acc);
    }
    gbn_acc_finish(&acc, inv2s2, gR);
    e_sum = gbn_acc_sum(&acc, 0);
    for (int k = 0; k < D; ++k)
        f[k] = gbn_acc_sum(&acc, 1 + k);
#else
    /* the partial sums, [j mod 4]: the energy's, the force's (D a partner) and the width's */
    double w[D], pe[4], pf[4][D];
#if ADAPTIVE
    double pw[4];
#endif
    for (int m = 0; m < 4; ++m) {
        pe[m] = 0.0;
        for (int k = 0; k < D; ++k)
            pf[m][k] = 0.0;
#if ADAPTIVE
        pw[m] = 0.0;
#endif
    }
    IN_ORDER
    for (uint o = 0; o < noff; ++o) {
#if D >= 3
        /* a neighbouring cell wholly beyond the reach holds no partner */
        if (G > 1 && cell_beyond(x, c, o, G, skip2))
            continue;
#endif
        const size_t slot = (size_t)r * total_cells + neighbour(c, o, G);
        const uint s1 = start[slot + 1];
        IN_ORDER
        for (uint j = start[slot]; j < s1; ++j) {
            if (j == gi)
                continue;
            __global const double *y = pts + (size_t)j * D;
            double r2 = 0.0;
            IN_ORDER
            for (int k = 0; k < D; ++k) {
                double v = x[k] - y[k];
#if PERIODIC
                v = v > 0.5 ? v - 1.0 : v;
                v = v < -0.5 ? v + 1.0 : v;
#endif
                w[k] = v;
                r2 = k == 0 ? v * v : r2 + v * v;
            }
#if ADAPTIVE
            const double tau = (ti + t[j]) * 0.5;
            if (r2 >= R2 * tau)
                continue;
            const double q = r2 * inv2s2 / tau;
            const double e = gbn_exp_neg(q);
            const double ce = e / tau;
            pw[j & 3u] = pw[j & 3u] + q * ce;
#else
            if (r2 >= R2)
                continue;
            const double e = gbn_exp_neg(r2 * inv2s2);
            const double ce = e;
#endif
            const uint m = j & 3u;
            pe[m] = pe[m] + (e - gR);
            for (int k = 0; k < D; ++k)
                pf[m][k] = pf[m][k] + w[k] * ce;
        }
    }
    e_sum = GBN_FOLD(pe[0], pe[1], pe[2], pe[3]);
    for (int k = 0; k < D; ++k)
        f[k] = GBN_FOLD(pf[0][k], pf[1][k], pf[2][k], pf[3][k]);
#if ADAPTIVE
    width = GBN_FOLD(pw[0], pw[1], pw[2], pw[3]);
#endif
#endif
    __global double *row = out + (size_t)gi * (D + 1 + ADAPTIVE);
    row[0] = e_sum;
    for (int k = 0; k < D; ++k)
        row[1 + k] = f[k];
#if ADAPTIVE
    row[D + 1] = width;
#endif
}

/* gbn_control: a resident run's step control (clsamp/samplers/gbn_device.py), one work-item
 * a set, on the torus without a density: what gbn_optimize does on the host between pair
 * passes, so that a run's iterations are launches with no wait. Its twin is gbn_optimize
 * itself (the same bits).
 *
 * A set's state: its points x and their force f (sets, n, D), and its proposal y (the
 * points the last pair pass saw, in index order); energy, tau and initial in real
 * (sets, 3), live, converged and ran in flags (sets, 3); history (sets, iterations). The
 * pair pass reads sorted (sets n, D) and start (sets G^D + 1), which gbn_control writes
 * by a counting sort of y (stable: the order sorted_by_cell gives), with order (sets n,
 * sorted index -> index in the set), and writes out (sets n, D + 1) in sorted order.
 * mode 0: sort y (the start, which the host put in x and y);
 * mode 1: the start's pass: its energy (exact_sum of the pass's energies / n, math.fsum's
 *         value) into energy and initial, its force into f;
 * mode 2: iteration it of a live set: ran + 1; the proposal accepted where its energy is
 *         no higher (x = y, f, energy; converged once the drop is at most tol |energy|,
 *         never where tol is 0),
 *         else tau halved (converged below tau_min); history[it] = energy.
 * Then, where the set is live and propose is 1, the next proposal y = x + tau f wrapped
 * into [0, 1) and sorted. gbn_pairs built with RESIDENT 1 skips the sets whose live flag
 * is 0, so the passes that follow a set's end, until the host sees it, cost it nothing. */
#include "counting_sort.h"
#include "exact_sum.h"

/* the flat cell of point i of p (sorted_by_cell's) */
inline uint gbn_item_cell(__global const double *p, const uint i, const uint G)
{
    double x[D];
    int c[D];
    for (int k = 0; k < D; ++k)
        x[k] = p[(size_t)i * D + k];
    cell_of(x, (int)G, c);
    uint flat = 0;
    for (int k = 0; k < D; ++k)
        flat = flat * G + (uint)c[k];
    return flat;
}

COUNTING_SORT(gbn_sort_by_cell, double, gbn_item_cell)

__kernel void gbn_control(__global double *x, __global double *f, __global double *y,
                          __global const double *out, __global double *sorted,
                          __global uint *start, __global uint *order, __global double *real,
                          __global int *flags, __global double *history, const uint n,
                          const uint sets, const int G, const int mode, const uint it,
                          const uint iterations, const double tol, const double tau_min,
                          const int propose)
{
    const uint s = get_global_id(0);
    if (s >= sets)
        return;
    const uint cells = cells_count(G);
    const size_t base = (size_t)s * n;
    __global double *xs = x + base * D, *fs = f + base * D, *ys = y + base * D;
    __global const double *os = out + base * (D + 1);
    __global double *rs = real + (size_t)s * 3;
    __global int *fl = flags + (size_t)s * 3;
    if (mode > 0) {
        if (mode == 2 && !fl[0])
            return;
        long acc[EXACT_DIGITS];
        exact_clear(acc);
        for (uint g = 0; g < n; ++g)
            exact_add(acc, os[(size_t)g * (D + 1)]);
        const double e = exact_round(acc) / (double)n;
        bool take = mode == 1, done = false;
        if (mode == 2) {
            fl[2] += 1;
            take = e <= rs[0];
            if (take) {
                const double drop = rs[0] - e;
                done = tol > 0.0 && drop <= tol * fabs(e);      /* 0: every iteration */
                for (size_t i = 0; i < (size_t)n * D; ++i)
                    xs[i] = ys[i];
            } else {
                rs[1] = rs[1] * 0.5;
                done = rs[1] < tau_min;
            }
        }
        if (take) {
            rs[0] = e;
            if (mode == 1)
                rs[2] = e;
            for (uint g = 0; g < n; ++g) {
                const size_t i = order[base + g];
                for (int k = 0; k < D; ++k)
                    fs[i * D + k] = os[(size_t)g * (D + 1) + 1 + k];
            }
        }
        if (mode == 2) {
            history[(size_t)s * iterations + it] = rs[0];
            if (done) {
                fl[0] = 0;
                fl[1] = 1;
                return;
            }
        }
        if (!propose)
            return;
        const double tau = rs[1];
        for (size_t i = 0; i < (size_t)n * D; ++i) {
            double v = xs[i] + tau * fs[i];
            v = v - floor(v);
            ys[i] = v >= 1.0 ? 0.0 : v;
        }
    }
    /* the counting sort of y by cell, ties in index order, and the points in that order */
    __global uint *ord = order + base;
    gbn_sort_by_cell(ys, n, cells, (uint)G, (uint)base, start + (size_t)s * cells, ord);
    for (uint g = 0; g < n; ++g)
        for (int k = 0; k < D; ++k)
            sorted[(base + g) * D + k] = ys[(size_t)ord[g] * D + k];
    if (s == sets - 1)
        start[(size_t)sets * cells] = (uint)(base + n);
}
