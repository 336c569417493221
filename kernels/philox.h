/* Philox4x32-10 counter-based random numbers: the OpenCL twin of clsamp/philox.py.
 *
 * Salmon et al., "Parallel random numbers: as easy as 1, 2, 3" (SC 2011).
 * Key = the 64-bit seed as (low, high); counter = (index, realization, block, stream).
 * Integer-only arithmetic, so every device gives the same words; the conversion to
 * double is exact (53 bits, scaled by a power of two). The *_bits forms give the same
 * doubles as IEEE-754 bit patterns, on devices without fp64 too (f64bits.h).
 */
#ifndef CLSAMP_PHILOX_H
#define CLSAMP_PHILOX_H

#include "f64bits.h"

#define CLSAMP_PHILOX_M0 0xD2511F53u
#define CLSAMP_PHILOX_M1 0xCD9E8D57u
#define CLSAMP_PHILOX_W0 0x9E3779B9u
#define CLSAMP_PHILOX_W1 0xBB67AE85u

/* The 32x32->64 products are taken as ulong multiplies, not mul_hi(): PoCL (LLVM 14,
 * x86-64) compiles the widening multiply to far better code (docs/performance.md); GPUs
 * compile both to the same wide multiply. */
inline uint4 philox4x32_10(uint4 ctr, uint2 key)
{
#pragma unroll
    for (int round = 0; round < 10; ++round) {
        if (round) {
            key.x += CLSAMP_PHILOX_W0;
            key.y += CLSAMP_PHILOX_W1;
        }
        const ulong p0 = (ulong)CLSAMP_PHILOX_M0 * ctr.x;
        const ulong p1 = (ulong)CLSAMP_PHILOX_M1 * ctr.z;
        ctr = (uint4)((uint)(p1 >> 32) ^ ctr.y ^ key.x, (uint)p1,
                      (uint)(p0 >> 32) ^ ctr.w ^ key.y, (uint)p0);
    }
    return ctr;
}

/* Four random words of (key, stream, realization, index, block). */
inline uint4 clsamp_block(uint2 key, uint stream, uint realization, uint index, uint block)
{
    return philox4x32_10((uint4)(index, realization, block, stream), key);
}

/* Word w of (key, stream, realization, index): block w/4, lane w%4. */
inline uint clsamp_bits(uint2 key, uint stream, uint realization, uint index, uint word)
{
    const uint4 b = clsamp_block(key, stream, realization, index, word >> 2);
    const uint lane = word & 3u;
    return lane == 0u ? b.x : lane == 1u ? b.y : lane == 2u ? b.z : b.w;
}

/* The bits of clsamp_unit(hi, lo). */
inline ulong clsamp_unit_bits(uint hi, uint lo)
{
#if CLSAMP_FP64
    /* two 32-bit conversions: cheaper than one of 53 bits where the CPU lacks it */
    return as_ulong(((double)(hi >> 5) * 67108864.0 + (double)(lo >> 6)) * (1.0 / 9007199254740992.0));
#else
    return f64_scaled(((ulong)(hi >> 5) << 26) | (lo >> 6), -53);
#endif
}

/* The bits of clsamp_uniform2 and clsamp_uniform. */
inline ulong2 clsamp_uniform2_bits(uint2 key, uint stream, uint realization, uint index, uint pair)
{
    const uint4 b = clsamp_block(key, stream, realization, index, pair);
    return (ulong2)(clsamp_unit_bits(b.x, b.y), clsamp_unit_bits(b.z, b.w));
}

inline ulong clsamp_uniform_bits(uint2 key, uint stream, uint realization, uint index, uint dim)
{
    const ulong2 u = clsamp_uniform2_bits(key, stream, realization, index, dim >> 1);
    return (dim & 1u) ? u.y : u.x;
}

#if CLSAMP_FP64
/* A double in [0, 1) with 53 random bits (genrand_res53). */
inline double clsamp_unit(uint hi, uint lo) { return as_double(clsamp_unit_bits(hi, lo)); }

/* Both coordinates of dimension pair b: (2b, 2b+1). */
inline double2 clsamp_uniform2(uint2 key, uint stream, uint realization, uint index, uint pair)
{
    return as_double2(clsamp_uniform2_bits(key, stream, realization, index, pair));
}

/* Coordinate `dim` of point `index`: the same number as clsamp.philox.uniform. */
inline double clsamp_uniform(uint2 key, uint stream, uint realization, uint index, uint dim)
{
    return as_double(clsamp_uniform_bits(key, stream, realization, index, dim));
}
#endif

/* philox4x32_10 on four counters at once, lane l holding the counter (c0.l, c1.l, c2.l,
 * c3.l): the same words as four calls, computed in vector lanes (PoCL does not vectorize
 * across work-items when a kernel has a loop). The words ride in the low halves of 64-bit
 * lanes, so the 32x32->64 products need no shuffles between uint4 and ulong4; the high
 * halves hold garbage that the masks before each multiply and at the end drop. 256-bit
 * vectors only (docs/design.md, "Kernels and the runtime"). */
CLSAMP_ALWAYS_INLINE void philox4x32_10_x4(uint4 c0, uint4 c1, uint4 c2, uint4 c3, uint2 key,
                             uint4 *w0, uint4 *w1, uint4 *w2, uint4 *w3)
{
    const ulong4 low = (ulong4)(0xFFFFFFFFul);
    ulong4 a = convert_ulong4(c0), b = convert_ulong4(c1), c = convert_ulong4(c2),
           e = convert_ulong4(c3);
    ulong kx = key.x, ky = key.y;
#pragma unroll
    for (int round = 0; round < 10; ++round) {
        if (round) {
            kx = (kx + CLSAMP_PHILOX_W0) & 0xFFFFFFFFul;
            ky = (ky + CLSAMP_PHILOX_W1) & 0xFFFFFFFFul;
        }
        const ulong4 p0 = (a & low) * (ulong)CLSAMP_PHILOX_M0;
        const ulong4 p1 = (c & low) * (ulong)CLSAMP_PHILOX_M1;
        a = (p1 >> 32) ^ b ^ kx;
        c = (p0 >> 32) ^ e ^ ky;
        b = p1;
        e = p0;
    }
    *w0 = convert_uint4(a & low);
    *w1 = convert_uint4(b & low);
    *w2 = convert_uint4(c & low);
    *w3 = convert_uint4(e & low);
}

/* clsamp_unit_bits lane by lane. */
inline ulong4 clsamp_unit4_bits(uint4 hi, uint4 lo)
{
#if CLSAMP_FP64
    return as_ulong4((convert_double4(hi >> 5) * 67108864.0 + convert_double4(lo >> 6))
                     * (1.0 / 9007199254740992.0));
#else
    return (ulong4)(clsamp_unit_bits(hi.x, lo.x), clsamp_unit_bits(hi.y, lo.y),
                    clsamp_unit_bits(hi.z, lo.z), clsamp_unit_bits(hi.w, lo.w));
#endif
}

#endif
