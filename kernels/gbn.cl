/* Gaussian blue noise (Ahmed, Ren, Wonka 2022): the pair pass of one gradient step, an
 * n-body sum over the neighbours within the kernel's cutoff found through a grid of cells
 * (kernels/cells.h). NumPy twin: pair_pass_reference in clsamp/samplers/gbn.py, the same
 * bits: exactly rounded double operations in the same order, no contraction, and the
 * exponential gbn_exp_neg below (range reduction and a Horner polynomial) instead of the
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
 * ADAPTIVE (adaptive sampling): t (total) holds each sorted point's variance relative to
 * s^2; a pair's is tau = (t_i + t_j) / 2, it interacts while r2 < R2 tau, and adds
 *     q = r2 inv2s2 / tau,  e = exp(-q),  energy += e - gR,  force[k] += (x_i - x_j)[k] (e / tau),
 *     width += q (e / tau),
 * with R2 = (cut s)^2 and gR = exp(-cut^2 / 2); row i of out (total, D + 2) is
 * (energy, force, width).
 *
 * Build options: D (dimensions), PERIODIC (1: the unit torus, differences wrapped into
 * [-1/2, 1/2]; 0: the unit cube), ADAPTIVE (1: per-point widths t, as above; 0: none),
 * GBN_INV_LN2, GBN_LN2_HI, GBN_LN2_LO and GBN_C0 .. GBN_C13 (the exponential's constants,
 * from clsamp.samplers.gbn.EXP_DEFINES).
 * From 3-D on, a neighbouring cell whose box lies beyond skip2 (the squared reach the grid
 * was made for) is skipped whole: it holds no partner within the cutoff, so the sums,
 * their order and the bits are those of the full stencil.
 * Launch: one work-item per sorted point, grid (total,).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF
#include "cells.h"
#include "in_order.h"

#ifndef GBN_C13
#error "gbn.cl needs the exponential's constants (clsamp.samplers.gbn.EXP_DEFINES)"
#endif

/* e^-t for 0 <= t < 700: t = k ln 2 - r with |r| <= ln 2 / 2, e^r by its Taylor
 * polynomial of degree 13 (truncation below 5e-18 relative), times 2^-k exactly */
inline double gbn_exp_neg(const double t)
{
    const int k = (int)(t * GBN_INV_LN2 + 0.5);
    const double kd = (double)k;
    const double r = (kd * GBN_LN2_HI - t) + kd * GBN_LN2_LO;
    double p = GBN_C13;
    p = p * r + GBN_C12;
    p = p * r + GBN_C11;
    p = p * r + GBN_C10;
    p = p * r + GBN_C9;
    p = p * r + GBN_C8;
    p = p * r + GBN_C7;
    p = p * r + GBN_C6;
    p = p * r + GBN_C5;
    p = p * r + GBN_C4;
    p = p * r + GBN_C3;
    p = p * r + GBN_C2;
    p = p * r + GBN_C1;
    p = p * r + GBN_C0;
    return p * as_double((ulong)(1023 - k) << 52);
}

__kernel void gbn_pairs(__global const double *pts,
#if ADAPTIVE
                        __global const double *t,
#endif
                        __global const uint *start, const uint n,
                        const uint total, const int G, const uint noff, const double R2,
                        const double inv2s2, const double gR, const double skip2,
                        __global double *out)
{
    const uint gi = get_global_id(0);
    if (gi >= total)
        return;
    const uint r = gi / n;
    const uint total_cells = cells_count(G);
    double x[D], f[D], w[D];
    for (int k = 0; k < D; ++k) {
        x[k] = pts[(size_t)gi * D + k];
        f[k] = 0.0;
    }
    double e_sum = 0.0;
#if ADAPTIVE
    const double ti = t[gi];
    double width = 0.0;
#endif
    int c[D];
    cell_of(x, G, c);
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
            width = width + q * ce;
#else
            if (r2 >= R2)
                continue;
            const double e = gbn_exp_neg(r2 * inv2s2);
            const double ce = e;
#endif
            e_sum = e_sum + (e - gR);
            for (int k = 0; k < D; ++k)
                f[k] = f[k] + w[k] * ce;
        }
    }
    __global double *row = out + (size_t)gi * (D + 1 + ADAPTIVE);
    row[0] = e_sum;
    for (int k = 0; k < D; ++k)
        row[1 + k] = f[k];
#if ADAPTIVE
    row[D + 1] = width;
#endif
}
