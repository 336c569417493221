/* The pair sums of the L2-type discrepancies in float-float (clsamp/metrics/l2.py with
 * precision="float-float"; the double kernels are discrepancy.cl, whose formulas these are):
 *     sum_i sum_j prod_k g(x_ik, x_jk)
 * for devices without fp64. The host computes each point's row and column numbers (XR, UR,
 * XC, VC of discrepancy.cl; for CD, VC is the factor's floor 1) in float64 and splits them
 * into float-float pairs (float2: hi, lo); here every g and every product is float-float
 * (float_float.h), each pair once (twice the upper part plus the diagonal), summed in blocks
 * of BLOCK terms; the host adds the partial sums exactly. The bound is derived in
 * clsamp.metrics.l2.float_float_bound.
 *
 * Build options: METHOD (0 CD, 1 WD, 2 MD, 3 L2-star, 4 symmetric, 5 L2 unanchored), D (the
 * dimension), COLS (columns a work-item sums: a grid axis of column chunks keeps every
 * work-item's loops short, for llvmpipe), BLOCK. FP_CONTRACT OFF: the error-free
 * transformations need every operation rounded as written.
 * Rows come eight a work-item in float8 lanes (PoCL does not vectorize across work-items that
 * loop), the columns one at a time, broadcast. Grid (items, chunks, realizations): work-item
 * w takes the row tiles w and tiles - 1 - w (tiles = ceil(n / 8), items = ceil(tiles / 2))
 * against the columns of its chunk; out (r, chunks, items, 8 lanes) float2, every lane's
 * sum apart (the host adds them exactly). */
#include "float_float.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef BLOCK
#error "BLOCK comes from clsamp/metrics/l2.py"
#endif

/* vector float-float comparisons, exact: by hi, then lo (pairs are normalized) */
#define FF_LESS8(ah, al, bh, bl) (((ah) < (bh)) | (((ah) == (bh)) & ((al) < (bl))))
#define FF_MIN8(ah, al, bh, bl, zh, zl) do {                       \
        const int8 m_ = FF_LESS8(bh, bl, ah, al);                   \
        zh = m_ ? (bh) : (ah);                                      \
        zl = m_ ? (bl) : (al);                                      \
    } while (0)
#define FF_ABS8(ah, al, zh, zl) do {                               \
        const int8 m_ = (ah) < 0.0f;                                \
        zh = m_ ? -(ah) : (ah);                                     \
        zl = m_ ? -(al) : (al);                                     \
    } while (0)

/* g of eight rows (xh, xl, uh, ul lanes) and one column (yh, yl, vh, vl broadcast), as the
 * double kernel's formulas */
inline void g8(const float8 xh, const float8 xl, const float8 uh, const float8 ul,
               const float8 yh, const float8 yl, const float8 vh, const float8 vl,
               float8 *gh, float8 *gl)
{
    float8 h, l;
#if METHOD == 0          /* 1 + min(a_i, a_j) on one side of 1/2, else 1 (u: the row's side) */
    /* v is the floor 1 (as the pair 1, 0), loaded rather than a constant: with constant
     * arms LLVM folds the selects below into `and` with `sext (xor (fcmp ...), true)` of
     * <8 x i1>, which Oclgrind (21.10) computes from a true lane stored as 0xFF, not 1
     * (scripts/oclgrind_narrow_ints.py); same values everywhere. */
    const uint8 sign = as_uint8(uh) & (uint8)(0x80000000u);
    const float8 ch = as_float8(as_uint8(yh) ^ sign), cl = as_float8(as_uint8(yl) ^ sign);
    FF_MIN8(xh, xl, ch, cl, h, l);
    const int8 below = FF_LESS8(h, l, vh, vl);
    h = below ? vh : h;
    l = below ? vl : l;
#elif METHOD == 1 || METHOD == 2    /* t = |x_i - x_j|; WD 3/2 - t + t^2, MD (u - v) + t (t/2 - 3/4) */
    float8 th, tl, sh, sl;
    FF_ADD(float8, xh, xl, -yh, -yl, th, tl);
    FF_ABS8(th, tl, th, tl);
#if METHOD == 1
    FF_ADD(float8, th, tl, (float8)(-1.0f), (float8)(0.0f), sh, sl);
    FF_MUL(float8, th, tl, sh, sl, sh, sl);
    FF_ADD(float8, sh, sl, (float8)(1.5f), (float8)(0.0f), h, l);
#else
    FF_ADD(float8, 0.5f * th, 0.5f * tl, (float8)(-0.75f), (float8)(0.0f), sh, sl);
    FF_MUL(float8, th, tl, sh, sl, sh, sl);
    FF_ADD(float8, uh, ul, -vh, -vl, h, l);
    FF_ADD(float8, sh, sl, h, l, h, l);
#endif
#elif METHOD == 3        /* min(1 - x_i, 1 - x_j) */
    FF_MIN8(xh, xl, yh, yl, h, l);
#elif METHOD == 4        /* (1 - x_i - x_j) + 2 min(x_i, x_j) */
    float8 mh, ml;
    FF_MIN8(xh, xl, yh, yl, mh, ml);
    FF_ADD(float8, uh, ul, -vh, -vl, h, l);
    FF_ADD(float8, h, l, 2.0f * mh, 2.0f * ml, h, l);
#elif METHOD == 5        /* min(x_i, x_j) min(1 - x_i, 1 - x_j) */
    float8 mh, ml;
    FF_MIN8(xh, xl, yh, yl, mh, ml);
    FF_MIN8(uh, ul, vh, vl, h, l);
    FF_MUL(float8, mh, ml, h, l, h, l);
#else
#error "METHOD must be 0..5"
#endif
    *gh = h;
    *gl = l;
}

/* Adds, for the eight rows 8q .. 8q + 7 (lanes; rows >= n weigh 0), weight(i, j)
 * prod_k g(x_ik, x_jk) over the columns j in [max(c0, 8q), c1), weight 2 for i < j and 1
 * for i = j, in blocks of BLOCK columns, to (sh, sl). */
inline void tile_sum(const uint q, const uint n, const uint c0, const uint c1,
                     __global const float2 *xr, __global const float2 *ur,
                     __global const float2 *xc, __global const float2 *vc, float8 *sh, float8 *sl)
{
    float8 xh[D], xl[D], uh[D], ul[D];
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7) + (int)(8 * q);
    for (int k = 0; k < D; ++k) {
        float *pxh = (float *)&xh[k], *pxl = (float *)&xl[k], *puh = (float *)&uh[k], *pul = (float *)&ul[k];
        for (int l = 0; l < 8; ++l) {
            const uint i = min(8 * q + l, n - 1);
            const float2 x = xr[(size_t)i * D + k], u = ur[(size_t)i * D + k];
            pxh[l] = x.x; pxl[l] = x.y; puh[l] = u.x; pul[l] = u.y;
        }
    }
    for (uint j0 = max(c0, 8 * q); j0 < c1; j0 += BLOCK) {
        const uint j1 = min(c1, j0 + BLOCK);
        float8 bh = (float8)(0.0f), bl = bh;
        for (uint j = j0; j < j1; ++j) {
            __global const float2 *y = xc + (size_t)j * D, *v = vc + (size_t)j * D;
            float8 ph, pl;
            g8(xh[0], xl[0], uh[0], ul[0], (float8)(y[0].x), (float8)(y[0].y), (float8)(v[0].x),
               (float8)(v[0].y), &ph, &pl);
            for (int k = 1; k < D; ++k) {
                float8 gh, gl;
                g8(xh[k], xl[k], uh[k], ul[k], (float8)(y[k].x), (float8)(y[k].y), (float8)(v[k].x),
                   (float8)(v[k].y), &gh, &gl);
                FF_MUL(float8, ph, pl, gh, gl, ph, pl);
            }
            const int8 col = (int8)((int)j);
            const float8 weight = lane >= (int8)((int)n) ? (float8)(0.0f)
                                  : lane < col ? (float8)(2.0f) : lane == col ? (float8)(1.0f) : (float8)(0.0f);
            FF_ADD(float8, bh, bl, weight * ph, weight * pl, bh, bl);
        }
        FF_ADD(float8, *sh, *sl, bh, bl, *sh, *sl);
    }
}

__kernel void discrepancy_ff_pairs(__global const float2 *xr, __global const float2 *ur,
                                   __global const float2 *xc, __global const float2 *vc,
                                   const uint n, const uint items, __global float2 *out)
{
    const uint w = get_global_id(0), chunk = get_global_id(1), r = get_global_id(2);
    if (w >= items)
        return;
    const size_t set = (size_t)r * n * D;
    const uint tiles = (n + 7) / 8;
    const uint c0 = chunk * COLS, c1 = min(n, c0 + COLS);
    float8 sh = (float8)(0.0f), sl = sh;
    tile_sum(w, n, c0, c1, xr + set, ur + set, xc + set, vc + set, &sh, &sl);
    if (tiles - 1 - w != w)
        tile_sum(tiles - 1 - w, n, c0, c1, xr + set, ur + set, xc + set, vc + set, &sh, &sl);
    __global float2 *o = out + (((size_t)r * get_global_size(1) + chunk) * items + w) * 8;
    const float *ph = (const float *)&sh, *pl = (const float *)&sl;
    for (int l = 0; l < 8; ++l)
        o[l] = (float2)(ph[l], pl[l]);
}
