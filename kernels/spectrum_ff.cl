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
 *    whose sums are added to S in place (a launch per chunk of points).
 * The host squares S in float64 (O(R^2) work; the O(N R^2) sum is here). The error bound
 * is derived in clsamp.spectrum_ff.direct_ff's docstring; tests/test_spectrum_ff.py holds
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

/* A complex float-float: (re hi, re lo, im hi, im lo). */
inline float4 cff_mul(const float4 a, const float4 b)
{
    const float2 re = ff_add(ff_mul(a.s01, b.s01), -ff_mul(a.s23, b.s23));
    const float2 im = ff_add(ff_mul(a.s01, b.s23), ff_mul(a.s23, b.s01));
    return (float4)(re, im);
}

inline float4 cff_add(const float4 a, const float4 b)
{
    return (float4)(ff_add(a.s01, b.s01), ff_add(a.s23, b.s23));
}

/* e^{-2 pi i theta / 2^64}: the conjugate of T1 T2 e(delta). */
inline float4 twiddle_ff(const ulong theta, __global const float4 *coarse, __global const float4 *fine)
{
    const float4 t = cff_mul(coarse[theta >> 54], fine[(theta >> 44) & 1023]);
    /* theta mod 2^44 = rh 2^20 + rl: (rh 2^-24 + rl 2^-44) is exact in float-float, times
     * 2 pi 2^-20 (DELTA_HI + DELTA_LO, the host's split of that constant) */
    const ulong rest = theta & 0xFFFFFFFFFFFUL;
    const float2 frac = ff_fast_two_sum((float)(uint)(rest >> 20) * 0x1p-24f,
                                        (float)(uint)(rest & 0xFFFFF) * 0x1p-44f);
    const float2 delta = ff_mul(frac, (float2)(DELTA_HI, DELTA_LO));
    const float4 e = (float4)(1.0f, -0.5f * delta.x * delta.x, delta);
    const float4 w = cff_mul(t, e);
    return (float4)(w.s01, -w.s23);
}

/* Twiddles e^{-2 pi i f x_k} of one coordinate (axis) for f = f0 + m, m in [0, count):
 *     out[(r * count + m) * n + k]
 * Grid (n, realizations). */
__kernel void spectrum_ff_twiddles(__global const ulong *points, __global float4 *out,
                                   __global const float4 *coarse, __global const float4 *fine,
                                   const uint n, const uint d, const uint axis, const long f0,
                                   const uint count)
{
    const uint k = get_global_id(0);
    const uint r = get_global_id(1);
    if (k >= n)
        return;
    const ulong X = fixed64_from_bits(points[((size_t)r * n + k) * d + axis]);
    __global float4 *o = out + (size_t)r * count * n + k;
    ulong theta = (ulong)f0 * X;             /* wraps modulo 2^64: exact phase reduction */
    for (uint m = 0; m < count; ++m) {
        o[(size_t)m * n] = twiddle_ff(theta, coarse, fine);
        theta += X;
    }
}

#ifndef BLOCK
#error "BLOCK (terms per partial sum) comes from clsamp/spectrum_ff.py"
#endif

/* S_r(u, v) += sum_k A_r[u, k] B_r[v, k] over this chunk's n points, in float-float.
 * S is (realizations, count_u, count_v) complex float-float. Grid (count_v, count_u,
 * realizations): work-items next to each other read the same a_k(u) and neighbouring panels
 * of b. */
__kernel void spectrum_ff_product(__global const float4 *A, __global const float4 *B,
                                  __global float4 *S, const uint n, const uint count_u,
                                  const uint count_v)
{
    const uint v = get_global_id(0);
    const uint u = get_global_id(1);
    const uint r = get_global_id(2);
    if (v >= count_v)
        return;
    __global const float4 *a = A + ((size_t)r * count_u + u) * n;
    __global const float4 *b = B + ((size_t)r * count_v + v) * n;
    __global float4 *s = S + ((size_t)r * count_u + u) * count_v + v;
    float4 total = *s;
    for (uint k0 = 0; k0 < n; k0 += BLOCK) {
        /* blocks of BLOCK terms summed apart: the rounding errors grow with the block's
         * partial sums, not the whole sum's (the bound in clsamp.spectrum_ff) */
        const uint k1 = min(n, k0 + BLOCK);
        float4 acc = (float4)(0.0f);
        for (uint k = k0; k < k1; ++k)
            acc = cff_add(acc, cff_mul(a[k], b[k]));
        total = cff_add(total, acc);
    }
    *s = total;
}
