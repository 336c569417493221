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

/* The ten rounds of Philox4x32-10 on the counter words c0..c3 (in place), for lanes of
 * any type T: uint, a uint vector, or ulong vectors carrying the words in their low halves.
 * MUL(a, m, &hi) returns the low 32 bits of the 64-bit product a * m (as T) and stores
 * the high 32 bits in hi; ulong lanes may leave garbage in the high halves of what MUL
 * returns and of c1, c3, which the next MUL and the caller mask off. Every form gives the
 * words of philox4x32_10 below, the twin of clsamp.philox. */
#define CLSAMP_PHILOX_ROUNDS(T, MUL, c0, c1, c2, c3, key) do {                    \
        uint kx_ = (key).x, ky_ = (key).y;                                        \
        _Pragma("unroll")                                                         \
        for (int round_ = 0; round_ < 10; ++round_) {                             \
            if (round_) {                                                         \
                kx_ += CLSAMP_PHILOX_W0;                                          \
                ky_ += CLSAMP_PHILOX_W1;                                          \
            }                                                                     \
            T h0_, h1_;                                                           \
            const T l0_ = MUL(c0, CLSAMP_PHILOX_M0, &h0_);                        \
            const T l1_ = MUL(c2, CLSAMP_PHILOX_M1, &h1_);                        \
            c0 = h1_ ^ c1 ^ kx_;                                                  \
            c2 = h0_ ^ c3 ^ ky_;                                                  \
            c1 = l1_;                                                             \
            c3 = l0_;                                                             \
        }                                                                         \
    } while (0)

/* The 32x32->64 products are taken as ulong multiplies, not mul_hi(): PoCL (LLVM 14,
 * x86-64) compiles the widening multiply to far better code (docs/performance.md); GPUs
 * compile both to the same wide multiply. */
CLSAMP_ALWAYS_INLINE uint clsamp_mul_wide(const uint a, const uint m, uint *hi)
{
    const ulong p = (ulong)m * a;
    *hi = (uint)(p >> 32);
    return (uint)p;
}

/* The same for four words riding in the low halves of 64-bit lanes: no shuffles between
 * uint4 and ulong4 (the high halves of a are masked off here, those of the results are
 * garbage). */
CLSAMP_ALWAYS_INLINE ulong4 clsamp_mul_wide4l(const ulong4 a, const uint m, ulong4 *hi)
{
    const ulong4 p = (a & 0xFFFFFFFFul) * (ulong)m;
    *hi = p >> 32;
    return p;
}

inline uint4 philox4x32_10(uint4 ctr, uint2 key)
{
    uint c0 = ctr.x, c1 = ctr.y, c2 = ctr.z, c3 = ctr.w;
    CLSAMP_PHILOX_ROUNDS(uint, clsamp_mul_wide, c0, c1, c2, c3, key);
    return (uint4)(c0, c1, c2, c3);
}

/* Four random words of (key, stream, realization, index, block). */
inline uint4 clsamp_block(uint2 key, uint stream, uint realization, uint index, uint block)
{
    return philox4x32_10((uint4)(index, realization, block, stream), key);
}

/* Lane `lane` (0..3) of b, chosen by its two bits. The equivalent chain
 * `lane == 0u ? b.x : lane == 1u ? b.y : lane == 2u ? b.z : b.w` is what Oclgrind 21.10
 * simulates wrongly (lanes 0 and 1 read as b.w from the second quad of work-items on, with
 * no report: the permutations of fisher_yates_inline and Faure's base-5 LMS came out wrong
 * there; tests/test_oclgrind.py). */
inline uint clsamp_lane(const uint4 b, const uint lane)
{
    return (lane & 2u) ? ((lane & 1u) ? b.w : b.z) : ((lane & 1u) ? b.y : b.x);
}

/* Word w of (key, stream, realization, index): block w/4, lane w%4. */
inline uint clsamp_bits(uint2 key, uint stream, uint realization, uint index, uint word)
{
    return clsamp_lane(clsamp_block(key, stream, realization, index, word >> 2), word & 3u);
}

/* The double in [0, 1) of 53 random bits (genrand_res53) from the words hi and lo,
 * scalar or vector: TO_DOUBLE converts their type to double. Two 32-bit conversions are
 * cheaper than one of 53 bits where the CPU lacks it; every step is exact. */
#if CLSAMP_FP64
#define CLSAMP_UNIT53(TO_DOUBLE, hi, lo) \
    ((TO_DOUBLE((hi) >> 5) * 67108864.0 + TO_DOUBLE((lo) >> 6)) * (1.0 / 9007199254740992.0))
#define CLSAMP_TO_DOUBLE(x) ((double)(x))
#endif

/* The bits of clsamp_unit(hi, lo). */
inline ulong clsamp_unit_bits(uint hi, uint lo)
{
#if CLSAMP_FP64
    return as_ulong(CLSAMP_UNIT53(CLSAMP_TO_DOUBLE, hi, lo));
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
    ulong4 a = convert_ulong4(c0), b = convert_ulong4(c1), c = convert_ulong4(c2),
           e = convert_ulong4(c3);
    CLSAMP_PHILOX_ROUNDS(ulong4, clsamp_mul_wide4l, a, b, c, e, key);
    *w0 = convert_uint4(a & 0xFFFFFFFFul);
    *w1 = convert_uint4(b & 0xFFFFFFFFul);
    *w2 = convert_uint4(c & 0xFFFFFFFFul);
    *w3 = convert_uint4(e & 0xFFFFFFFFul);
}

/* clsamp_unit_bits lane by lane. */
inline ulong4 clsamp_unit4_bits(uint4 hi, uint4 lo)
{
#if CLSAMP_FP64
    return as_ulong4(CLSAMP_UNIT53(convert_double4, hi, lo));
#else
    return (ulong4)(clsamp_unit_bits(hi.x, lo.x), clsamp_unit_bits(hi.y, lo.y),
                    clsamp_unit_bits(hi.z, lo.z), clsamp_unit_bits(hi.w, lo.w));
#endif
}

#endif
