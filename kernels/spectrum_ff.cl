/* Power spectra in float-float: the direct sum without double precision.
 *
 * The same sum as spectrum.cl, S_r(u, v) = sum_k a_k(u) b_k(v) with a_k(u) = e^{-2 pi i u x_k},
 * for devices without fp64 (and wherever precision="float-float" is asked for). Points
 * arrive as float64 bit patterns (ulong), so no double reaches the compiler:
 *  - each coordinate becomes the 64-bit fixed-point fraction X = floor(x 2^64) by integer
 *    shifts of its significand (exactly clsamp.spectrum.fixed_point's integer);
 *  - the phase f X mod 2^64 is an exact integer product (ulong wraparound), for any f;
 *  - e(theta) = T1[theta >> 54] T2[(theta >> 44) & 1023] e(delta): two tables of 1024
 *    float-float cos/sin pairs (e(i / 2^10) and e(j / 2^20), made on the host in float64 by
 *    clsamp.spectrum_ff.sincos_tables) and delta = 2 pi (theta mod 2^44) 2^-64 < 6.0e-6, for
 *    which cos = 1 - delta^2 / 2 and sin = delta leave less than 4e-17;
 *  - the products and the sums are float-float (float_float.h), in blocks of BLOCK terms
 *    whose sums are added to S in place (a launch per chunk of points), eight frequencies
 *    v a work-item in float8 lanes (PoCL does not vectorize across work-items that loop).
 * The host squares S in float64 (O(R^2) work; the O(N R^2) sum is here). The error bound
 * is derived in clsamp.spectrum_ff's docstring; tests/test_float_float.py holds
 * the result to the float64 reference (clsamp.spectrum.direct_reference) within it.
 * Built without -cl-mad-enable, FP_CONTRACT OFF: the error-free transformations need every
 * operation rounded as written. */
#include "float_float.h"

#pragma OPENCL FP_CONTRACT OFF

/* floor(x 2^64) for a float64 x in [0, 1) given as its bits: x = M 2^(e - 1075) with the
 * 53-bit significand M, so x 2^64 = M 2^(e - 1011); zero and subnormals give 0. */
inline ulong fixed64_from_bits(const ulong bits)
{
    const int e = (int)(bits >> 52) & 0x7FF;
    if (e == 0)
        return 0;
    const ulong m = (bits & 0x000FFFFFFFFFFFFFUL) | 0x0010000000000000UL;
    const int shift = e - 1011;
    if (shift >= 0)
        return m << shift;          /* x < 1: e <= 1022, so shift <= 11 and nothing is lost */
    return -shift >= 64 ? 0 : m >> -shift;
}

/* e^{-2 pi i theta / 2^64}: the conjugate of T1 T2 e(delta), as (re h, re l, im h, im l). */
inline float4 twiddle_ff(const ulong theta, __global const float4 *coarse, __global const float4 *fine)
{
    const float4 a = coarse[theta >> 54], b = fine[(theta >> 44) & 1023];
    float4 t;
    CFF_MUL(float, a.s0, a.s1, a.s2, a.s3, b.s0, b.s1, b.s2, b.s3, t.s0, t.s1, t.s2, t.s3);
    /* theta mod 2^44 = rh 2^20 + rl: (rh 2^-24 + rl 2^-44) is exact in float-float, times
     * 2 pi 2^-20 (DELTA_HI + DELTA_LO, the host's split of that constant) */
    const ulong rest = theta & 0xFFFFFFFFFFFUL;
    float fh, fl, dh, dl;
    FF_FAST_TWO_SUM(float, (float)(uint)(rest >> 20) * 0x1p-24f, (float)(uint)(rest & 0xFFFFF) * 0x1p-44f,
                    fh, fl);
    FF_MUL(float, fh, fl, DELTA_HI, DELTA_LO, dh, dl);
    float4 w;
    CFF_MUL(float, t.s0, t.s1, t.s2, t.s3, 1.0f, -0.5f * dh * dh, dh, dl, w.s0, w.s1, w.s2, w.s3);
    return (float4)(w.s01, -w.s23);
}

/* Twiddles e^{-2 pi i f x_k} of one coordinate (axis) for f = f0 + m, m in [0, count), count
 * a multiple of `tile`, in panels of `tile` frequencies, the four parts of each point's
 * twiddles `tile` apart (re h, re l, im h, im l):
 *     out[(((r * (count / tile) + m / tile) * n + k) * 4 + part) * tile + m % tile]
 * Grid (n, realizations). */
__kernel void spectrum_ff_twiddles(__global const ulong *points, __global float *out,
                                   __global const float4 *coarse, __global const float4 *fine,
                                   const uint n, const uint d, const uint axis, const long f0,
                                   const uint count, const uint tile)
{
    const uint k = get_global_id(0);
    const uint r = get_global_id(1);
    if (k >= n)
        return;
    const ulong X = fixed64_from_bits(points[((size_t)r * n + k) * d + axis]);
    ulong theta = (ulong)f0 * X;             /* wraps modulo 2^64: exact phase reduction */
    for (uint m = 0; m < count; ++m) {
        const float4 w = twiddle_ff(theta, coarse, fine);
        __global float *o = out + (((size_t)r * (count / tile) + m / tile) * n + k) * 4 * tile + m % tile;
        o[0] = w.s0;
        o[tile] = w.s1;
        o[2 * tile] = w.s2;
        o[3 * tile] = w.s3;
        theta += X;
    }
}

/* S_r(u, v) += sum_k A_r[u, k] B_r[v, k] over this chunk's n points, in float-float, eight
 * v a work-item. A from spectrum_ff_twiddles with tile 1, B with tile 8; S is (realizations,
 * count_u, tiles_v, 4 parts, 8 lanes). Grid (tiles_v, count_u, realizations). */
__kernel void spectrum_ff_product(__global const float4 *A, __global const float8 *B,
                                  __global float8 *S, const uint n, const uint count_u,
                                  const uint tiles_v)
{
    const uint tv = get_global_id(0);
    const uint u = get_global_id(1);
    const uint r = get_global_id(2);
    if (tv >= tiles_v)
        return;
    __global const float4 *a = A + ((size_t)r * count_u + u) * n;
    __global const float8 *b = B + ((size_t)r * tiles_v + tv) * n * 4;
    __global float8 *s = S + (((size_t)r * count_u + u) * tiles_v + tv) * 4;
    float8 rh = s[0], rl = s[1], ih = s[2], il = s[3];
    for (uint k0 = 0; k0 < n; k0 += BLOCK) {
        /* blocks of BLOCK terms summed apart: the rounding errors grow with the block's
         * partial sums, not the whole sum's (the bound in clsamp.spectrum_ff) */
        const uint k1 = min(n, k0 + BLOCK);
        float8 brh = (float8)(0.0f), brl = brh, bih = brh, bil = brh;
        for (uint k = k0; k < k1; ++k) {
            const float4 x = a[k];
            __global const float8 *y = b + 4 * k;
            float8 ph, pl, qh, ql;
            CFF_MUL(float8, (float8)(x.s0), (float8)(x.s1), (float8)(x.s2), (float8)(x.s3),
                    y[0], y[1], y[2], y[3], ph, pl, qh, ql);
            FF_ADD(float8, brh, brl, ph, pl, brh, brl);
            FF_ADD(float8, bih, bil, qh, ql, bih, bil);
        }
        FF_ADD(float8, rh, rl, brh, brl, rh, rl);
        FF_ADD(float8, ih, il, bih, bil, ih, il);
    }
    s[0] = rh;
    s[1] = rl;
    s[2] = ih;
    s[3] = il;
}

#ifdef WIDTH
/* The NUFFT's spreading (nufft.cl's spectrum_spread) in float-float, for method="fast"
 * with precision="float-float". A coordinate's fixed-point fraction X times M gives its
 * node floor(x M) = mul_hi(X, M) and the fraction f of the way to the next exactly
 * (the low 64 bits), taken to float-float with an error below 2^-48; the weights
 * phi(z) = exp(-beta z^2 / (1 + sqrt(1 - z^2))) of the WIDTH nodes from i0 = ceil(x M -
 * WIDTH / 2) are float-float (float_float.h: ff2_sqrt, FF_DIV, ff2_exp), and
 * so are the grid's sums. Build options: DIM, WIDTH, DELTA_HI, DELTA_LO, BLOCK (unused). */


inline int axis_weights_ff(const ulong bits, const uint M, const float2 beta, const float2 scale,
                           __global const float2 *coef, float2 *w)
{
    const ulong X = fixed64_from_bits(bits);
    const int node = (int)mul_hi(X, (ulong)M);
    const ulong frac = X * (ulong)M;
    const float2 f = (float2)((float)(uint)(frac >> 40) * 0x1p-24f,
                              (float)(uint)((frac >> 16) & 0xFFFFFF) * 0x1p-48f);
    /* i0 = ceil(node + f - WIDTH / 2) */
#if WIDTH % 2 == 0
    const int i0 = node - WIDTH / 2 + (frac != 0);
#else
    const int i0 = node - (WIDTH + 1) / 2 + (f.x > 0.5f || (f.x == 0.5f && f.y > 0.0f) ? 2 : 1);
#endif
    const float2 base = ff2_add((float2)((float)(i0 - node), 0.0f), -f);      /* i0 - x M */
    for (int l = 0; l < WIDTH; ++l) {
        const float2 z = ff2_mul(ff2_add(base, (float2)((float)l, 0.0f)), scale);
        const float2 z2 = ff2_mul(z, z);
        const float2 root = ff2_sqrt(ff2_add((float2)(1.0f, 0.0f), -z2));
        const float2 den = ff2_add((float2)(1.0f, 0.0f), root);
        float h, l2;
        FF_DIV(float, z2.x, z2.y, den.x, den.y, h, l2);
        const float2 arg = ff2_mul((float2)(h, l2), beta);
        w[l] = ff2_exp(-arg, coef);
    }
    return i0;
}

inline int wrap_ff(const int i, const int M) { return i < 0 ? i + M : (i >= M ? i - M : i); }

/* As spectrum_spread: every point of block c of realization r adds its tensor-product
 * kernel to the WIDTH^DIM nodes nearest to it, into the work-item's own grid copy, in
 * float-float. Grid (copies, realizations). */
__kernel void spectrum_spread_ff(__global const ulong *points, __global float2 *copies,
                                 const uint n, const uint M, const uint blocks, const float2 beta,
                                 const float2 scale, __global const float2 *coef)
{
    const uint c = get_global_id(0);
    const uint r = get_global_id(1);
    if (c >= blocks)
        return;
#if DIM == 1
    const size_t size = M;
#else
    const size_t size = (size_t)M * M;
#endif
    __global float2 *g = copies + ((size_t)r * blocks + c) * size;     /* zeroed by the host */
    const uint per = (n + blocks - 1) / blocks;
    const uint k0 = c * per, k1 = min(n, k0 + per);
    __global const ulong *p = points + (size_t)r * n * DIM;
    for (uint k = k0; k < k1; ++k) {
        float2 wx[WIDTH];
        const int i0 = axis_weights_ff(p[k * DIM], M, beta, scale, coef, wx);
#if DIM == 1
        for (int l = 0; l < WIDTH; ++l) {
            __global float2 *o = g + wrap_ff(i0 + l, M);
            *o = ff2_add(*o, wx[l]);
        }
#else
        float2 wy[WIDTH];
        const int j0 = axis_weights_ff(p[k * 2 + 1], M, beta, scale, coef, wy);
        for (int l = 0; l < WIDTH; ++l) {
            __global float2 *row = g + (size_t)wrap_ff(i0 + l, M) * M;
            for (int m = 0; m < WIDTH; ++m) {
                __global float2 *o = row + wrap_ff(j0 + m, M);
                *o = ff2_add(*o, ff2_mul(wx[l], wy[m]));
            }
        }
#endif
    }
}

/* out[r][i] = sum_c copies[r][c][i] in float-float, in order of c. Grid (size, realizations). */
__kernel void spectrum_sum_copies_ff(__global const float2 *copies, __global float2 *out,
                                     const uint size, const uint blocks)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= size)
        return;
    __global const float2 *src = copies + (size_t)r * blocks * size + i;
    float2 sum = (float2)(0.0f);
    for (uint c = 0; c < blocks; ++c)
        sum = ff2_add(sum, src[(size_t)c * size]);
    out[(size_t)r * size + i] = sum;
}
#endif
