/* Random permutations on the device: the OpenCL twin of clsamp/permutation.py.
 *
 * clsamp_permute(i, length, p)
 *     Kensler's hash permutation with cycle walking ("Correlated Multi-Jittered
 *     Sampling", Pixar Technical Memo 13-01, 2013): element i of a pseudo-random
 *     permutation of [0, length) chosen by the 32-bit pattern p, computed alone
 *     (no table). A fast approximation of a random permutation, NOT an exactly
 *     uniform one: only 2^32 patterns exist and the hash is not a perfect mixer.
 *     (The final rotation is by p % length, so it stays a bijection where the
 *     listing's 32-bit (i + p) % length wraps; elsewhere the values are the listing's.)
 *
 * clsamp_bounded(key, stream, realization, step, perm, range)
 *     An exactly uniform integer in [0, range) (Lemire's multiply with rejection)
 *     from the Philox words reserved for (perm, step). clsamp_bounded_from(x, ...)
 *     is the same with the first word x already drawn (four steps share a Philox call).
 *
 * clsamp_fisher_yates(a, length, key, stream, realization, perm)
 *     Fills a[0 .. length) with an exactly uniform random permutation of [0, length):
 *     Fisher-Yates driven by Philox. Permutation `perm` of (seed, stream, realization)
 *     is the same on every device and in clsamp.permutation.random_permutations.
 *     Sequential in one work-item: for short permutations inside another kernel; the
 *     batch kernels in permutation.cl draw in parallel and only swap sequentially.
 *
 * Integer arithmetic only, so every device gives the same permutations.
 */
#ifndef CLSAMP_PERMUTATION_H
#define CLSAMP_PERMUTATION_H

#include "philox.h"
#include "inline_builtins.h"

/* The smallest 2^k - 1 >= l - 1 (l >= 1): the hash's domain [0, w]. */
inline uint clsamp_hash_mask(const uint l)
{
    uint w = l - 1u;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    return w;
}

/* Kensler's hash of x (a uint or a uint vector) with pattern p, applied once: a bijection
 * of [0, w]. Also the hash of number_theory.permutation_element (lowdiscrepancy.h). */
#define CLSAMP_KENSLER_HASH(x, p, w)  \
    do {                              \
        x ^= (p);                     \
        x *= 0xe170893du;             \
        x ^= (p) >> 16;               \
        x ^= (x & (w)) >> 4;          \
        x ^= (p) >> 8;                \
        x *= 0x0929eb3fu;             \
        x ^= (p) >> 23;               \
        x ^= (x & (w)) >> 1;          \
        x *= 1u | (p) >> 27;          \
        x *= 0x6935fa69u;             \
        x ^= (x & (w)) >> 11;         \
        x *= 0x74dcb303u;             \
        x ^= (x & (w)) >> 2;          \
        x *= 0x9e501cc3u;             \
        x ^= (x & (w)) >> 2;          \
        x *= 0xc860a3dfu;             \
        x &= (w);                     \
        x ^= x >> 5;                  \
    } while (0)

inline uint clsamp_permute(uint i, const uint l, const uint p)
{
    if (l <= 1u)
        return 0u;
    const uint w = clsamp_hash_mask(l);
    /* Cycle walking: the hash permutes [0, w], so re-apply it until the value lands
     * inside [0, l); w + 1 < 2l, so on average fewer than two rounds. */
    do {
        CLSAMP_KENSLER_HASH(i, p, w);
    } while (i >= l);
    /* Kensler's listing returns (i + p) % l in 32-bit arithmetic, which stops being a
     * bijection when i + p wraps past 2^32 (e.g. l = 3, p = 0xffffffff); rotating by
     * p % l gives the same values whenever the listing's sum does not wrap. */
    const uint rot = p % l;
    return i >= l - rot ? i - (l - rot) : i + rot;
}

/* clsamp_permute of four elements, one a lane (same length and pattern): every lane runs
 * the hash until its value lands in [0, l), the lanes that have landed keep theirs. */
inline uint4 clsamp_permute4(uint4 i, const uint l, const uint p)
{
    if (l <= 1u)
        return (uint4)(0u);
    const uint w = clsamp_hash_mask(l);
    int4 walking = (int4)(-1);
    do {
        uint4 h = i;
        CLSAMP_KENSLER_HASH(h, p, w);
        i = walking ? h : i;          /* vector ?: rather than select(), a call in PoCL */
        walking &= i >= l;
    } while (clsamp_any4(walking));
    const uint rot = p % l;
    return i >= l - rot ? i - (l - rot) : i + rot;
}

/* Philox counters of permutation `perm`: the first draw of step t is lane t%4 of
 * block (perm << 8) at index t/4 (one Philox call serves four steps); the rare
 * retries of step t use index t and blocks (perm << 8) | 128 | a/4, a = 0..511. */
#define CLSAMP_FY_RETRIES 512u

/* Lemire (2019): with m = x * range, m / 2^32 is uniform in [0, range) once the low
 * word of m is >= 2^32 mod range; `x` is the first draw of step `step`. The modulo
 * is computed only when the low word is below range (probability range / 2^32). */
inline uint clsamp_bounded_from(uint x, uint2 key, uint stream, uint realization, uint step,
                                uint perm, uint range)
{
    ulong m = (ulong)x * (ulong)range;
    if ((uint)m < range) {
        const uint threshold = (0u - range) % range;
        for (uint a = 0; (uint)m < threshold && a < CLSAMP_FY_RETRIES; ++a) {
            x = clsamp_bits(key, stream, realization, step, (perm << 10) | 512u | a);
            m = (ulong)x * (ulong)range;
        }
    }
    return (uint)(m >> 32);
}

inline uint clsamp_bounded(uint2 key, uint stream, uint realization, uint step, uint perm,
                           uint range)
{
    const uint x = clsamp_bits(key, stream, realization, step >> 2, (perm << 10) | (step & 3u));
    return clsamp_bounded_from(x, key, stream, realization, step, perm, range);
}

inline void clsamp_fisher_yates(__global uint *a, const uint length, uint2 key, uint stream,
                                uint realization, uint perm)
{
    for (uint t = 0; t < length; ++t)
        a[t] = t;
    uint4 block = (uint4)(0u);
    for (uint t = length - 1u; t > 0u; --t) {
        /* Steps descend, so a new Philox block is needed at t = length-1 and at t%4 == 3. */
        if (t == length - 1u || (t & 3u) == 3u)
            block = clsamp_block(key, stream, realization, t >> 2, perm << 8);
        const uint j = clsamp_bounded_from(clsamp_lane(block, t & 3u), key, stream, realization,
                                           t, perm, t + 1u);
        const uint swap = a[t];
        a[t] = a[j];
        a[j] = swap;
    }
}

#endif
