/* The pair sums of the L2-type discrepancies in float-float (clsamp/metrics/l2.py with
 * precision="float-float"; the double kernels are discrepancy.cl, whose formulas these are):
 *     sum_i sum_j prod_k g(x_ik, x_jk)
 * for devices without fp64. The host computes each point's row and column numbers (XR, UR,
 * XC, VC of discrepancy.cl) in float64 and splits them into float-float pairs (float2: hi,
 * lo); here every g and every product is float-float (float_float.h), each pair once (twice
 * the upper part plus the diagonal), summed in blocks of BLOCK terms; the host adds the
 * partial sums exactly. The bound is derived in clsamp.metrics.l2.float_float_bound.
 *
 * Build options: METHOD (0 CD, 1 WD, 2 MD, 3 L2-star, 4 symmetric, 5 L2 unanchored), D (the
 * dimension), COLS (columns a work-item sums: a grid axis of column chunks keeps every
 * work-item's loops short, for llvmpipe), BLOCK. FP_CONTRACT OFF: the error-free
 * transformations need every operation rounded as written.
 * Grid (items, chunks, realizations): work-item w takes rows w and n - 1 - w against the
 * columns of its chunk; out (r, chunks, items) float2. */
#include "float_float.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef BLOCK
#error "BLOCK comes from clsamp/metrics/l2.py"
#endif

inline float2 ffa(const float2 a, const float2 b)
{
    float h, l;
    FF_ADD(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

inline float2 ffm(const float2 a, const float2 b)
{
    float h, l;
    FF_MUL(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

/* comparisons of normalized pairs (|lo| <= ulp(hi) / 2): by hi, then lo; exact */
inline int ff_less(const float2 a, const float2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
inline float2 ff_min(const float2 a, const float2 b) { return ff_less(b, a) ? b : a; }
inline float2 ff_max(const float2 a, const float2 b) { return ff_less(a, b) ? b : a; }
inline float2 ff_abs(const float2 a) { return a.x < 0.0f ? -a : a; }

#if METHOD == 0          /* 1 + min(a_i, a_j) on one side of 1/2, else 1 (u: the row's side) */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    const float2 c = as_uint(ui.x) >> 31 ? -xj : xj;
    return ff_max((float2)(1.0f, 0.0f), ff_min(xi, c));
}
#elif METHOD == 1        /* 3/2 - t + t^2, t = |x_i - x_j| */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    const float2 t = ff_abs(ffa(xi, -xj));
    return ffa(ffm(t, ffa(t, (float2)(-1.0f, 0.0f))), (float2)(1.5f, 0.0f));
}
#elif METHOD == 2        /* (u_i - v_j) + t (t / 2 - 3/4) */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    const float2 t = ff_abs(ffa(xi, -xj));
    return ffa(ffm(t, ffa(0.5f * t, (float2)(-0.75f, 0.0f))), ffa(ui, -vj));
}
#elif METHOD == 3        /* min(1 - x_i, 1 - x_j) */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    return ff_min(xi, xj);
}
#elif METHOD == 4        /* (1 - x_i - x_j) + 2 min(x_i, x_j) */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    return ffa(ffa(ui, -vj), 2.0f * ff_min(xi, xj));
}
#elif METHOD == 5        /* min(x_i, x_j) min(1 - x_i, 1 - x_j) */
inline float2 g(const float2 xi, const float2 ui, const float2 xj, const float2 vj)
{
    return ffm(ff_min(xi, xj), ff_min(ui, vj));
}
#else
#error "METHOD must be 0..5"
#endif

inline float2 term(__global const float2 *xr, __global const float2 *ur,
                   __global const float2 *xc, __global const float2 *vc)
{
    float2 p = g(xr[0], ur[0], xc[0], vc[0]);
    for (int k = 1; k < D; ++k)
        p = ffm(p, g(xr[k], ur[k], xc[k], vc[k]));
    return p;
}

/* 2 sum_{j > i, j in [c0, c1)} term(i, j) + term(i, i) where i is in [c0, c1) */
inline float2 row_sum(const uint i, const uint c0, const uint c1,
                      __global const float2 *xr, __global const float2 *ur,
                      __global const float2 *xc, __global const float2 *vc)
{
    __global const float2 *ri = xr + (size_t)i * D, *si = ur + (size_t)i * D;
    float2 total = (float2)(0.0f);
    for (uint j0 = max(c0, i + 1); j0 < c1; j0 += BLOCK) {
        const uint j1 = min(c1, j0 + BLOCK);
        float2 acc = (float2)(0.0f);
        for (uint j = j0; j < j1; ++j)
            acc = ffa(acc, term(ri, si, xc + (size_t)j * D, vc + (size_t)j * D));
        total = ffa(total, acc);
    }
    total = 2.0f * total;
    if (c0 <= i && i < c1)
        total = ffa(total, term(ri, si, xc + (size_t)i * D, vc + (size_t)i * D));
    return total;
}

__kernel void discrepancy_ff_pairs(__global const float2 *xr, __global const float2 *ur,
                                   __global const float2 *xc, __global const float2 *vc,
                                   const uint n, const uint items, __global float2 *out)
{
    const uint w = get_global_id(0), chunk = get_global_id(1), r = get_global_id(2);
    if (w >= items)
        return;
    const size_t set = (size_t)r * n * D;
    const uint c0 = chunk * COLS, c1 = min(n, c0 + COLS);
    float2 s = row_sum(w, c0, c1, xr + set, ur + set, xc + set, vc + set);
    if (n - 1 - w != w)
        s = ffa(s, row_sum(n - 1 - w, c0, c1, xr + set, ur + set, xc + set, vc + set));
    out[((size_t)r * get_global_size(1) + chunk) * items + w] = s;
}
