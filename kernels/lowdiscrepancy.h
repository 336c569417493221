/* Number theory of the low-discrepancy samplers: the OpenCL twin of clsamp/number_theory.py.
 *
 * Same names, same integer formulas, unsigned arithmetic wrapping as in the NumPy reference,
 * so the kernels and the reference give the same bits. See number_theory.py for the maths
 * and the references (Kensler 2013; Laine-Karras 2011; Burley 2020; Vegdahl 2021; pbrt-v4).
 */
#ifndef CLSAMP_LOWDISCREPANCY_H
#define CLSAMP_LOWDISCREPANCY_H

#include "f64bits.h"
#include "inline_builtins.h"
#include "permutation.h"

/* Randomizations: the values of -DRANDOMIZE. */
#define LD_NONE 0
#define LD_SHIFT 1
#define LD_XOR 2
#define LD_OWEN 3
#define LD_PERMUTE 4

/* Counts trailing zeros of x != 0 (ctz is OpenCL 2.0 only). */
inline uint ld_ctz(uint x)
{
    return 31u - clz(x & (0u - x));
}

inline uint ld_ctz64(ulong x)
{
    return 63u - (uint)clz(x & (0UL - x));
}

/* The 32 bits of x in reverse order, and Vegdahl's LK hash on reversed bits (a nested
 * scramble of the binary digits; Burley 2020 after Laine and Karras 2011), for uint or a
 * uint vector T: the twins of clsamp.number_theory.reverse_bits32 and lk_hash.
 *
 * LLVM's instcombine turns the or-of-masked-shifts reversal into the intrinsic
 * llvm.bitreverse, which x86 lowers to a few byte shuffles but Oclgrind's interpreter
 * lacks ("Undefined external function"; a form with the bytes swapped by shifts, which
 * becomes llvm.bswap and a rotate, gave wrong bits there in vector lanes past the first).
 * There (CLSAMP_OCLGRIND, set by the runtime for that device only) the fields of 1, 2, 4,
 * 8 and 16 bits swap by delta swaps (t = ((x >> s) ^ x) & m; x ^= t ^ (t << s); Knuth,
 * TAOCP 4A, 7.1.3), which no idiom matcher sees. Same bits either way; elsewhere the
 * matched form keeps its speed (docs/performance.md). */
#if CLSAMP_OCLGRIND
#define CLSAMP_DELTA_SWAP(x, T, s, m)                                      \
    do {                                                                   \
        const T t_ = (((x) >> (s)) ^ (x)) & (m);                           \
        (x) ^= t_ ^ (t_ << (s));                                           \
    } while (0)
#define CLSAMP_REVERSE_BITS32(name, T)                                     \
    inline T name(T x)                                                     \
    {                                                                      \
        CLSAMP_DELTA_SWAP(x, T, 1, 0x55555555u);                           \
        CLSAMP_DELTA_SWAP(x, T, 2, 0x33333333u);                           \
        CLSAMP_DELTA_SWAP(x, T, 4, 0x0F0F0F0Fu);                           \
        CLSAMP_DELTA_SWAP(x, T, 8, 0x00FF00FFu);                           \
        CLSAMP_DELTA_SWAP(x, T, 16, 0x0000FFFFu);                          \
        return x;                                                          \
    }
#else
#define CLSAMP_REVERSE_BITS32(name, T)                                     \
    inline T name(T x)                                                     \
    {                                                                      \
        x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);           \
        x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);           \
        x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);           \
        x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);           \
        return (x >> 16) | (x << 16);                                      \
    }
#endif

#define CLSAMP_LK_HASH(name, T)                                            \
    inline T name(T x, T seed)                                             \
    {                                                                      \
        x ^= x * 0x3D20ADEAu;                                              \
        x += seed;                                                         \
        x *= (seed >> 16) | 1u;                                            \
        x ^= x * 0x05526C56u;                                              \
        x ^= x * 0x53A22864u;                                              \
        return x;                                                          \
    }

CLSAMP_REVERSE_BITS32(reverse_bits32, uint)
CLSAMP_LK_HASH(lk_hash, uint)

inline uint owen_scramble_base2(uint x, uint seed)
{
    return reverse_bits32(lk_hash(reverse_bits32(x), seed));
}

/* Matoušek's linear matrix scrambling (generating_matrices.lms_row_masks, lms_apply): row k
 * of a random non-singular lower-triangular L from a Philox word (the diagonal bit 31 - k
 * set, the bits left of it random), and L v over GF(2) for a column word v. */
inline uint lms_row(uint word, uint k)
{
    const uint diagonal = 1u << (31u - k);
    return (word & ~(diagonal - 1u)) | diagonal;
}

inline uint lms_apply(const uint *rows, uint v)
{
    uint y = 0;
    for (uint k = 0; k < 32; ++k)
        y |= (popcount(rows[k] & v) & 1u) << (31u - k);
    return y;
}

/* mix64 of one word, and mix64_4 of four words in lanes */
#define CLSAMP_MIX64(name, T)             \
    CLSAMP_ALWAYS_INLINE T name(T v)      \
    {                                     \
        v ^= v >> 31;                     \
        v *= 0x7FB5D329728EA185UL;        \
        v ^= v >> 27;                     \
        v *= 0x81DADEF4BC2DD44DUL;        \
        v ^= v >> 33;                     \
        return v;                         \
    }
CLSAMP_MIX64(mix64, ulong)
CLSAMP_MIX64(mix64_4, ulong4)

inline uint digit_hash(ulong seed64, ulong key)
{
    return (uint)(mix64(seed64 ^ key) >> 32);
}

inline uint digit_shift(uint h, uint base)
{
    return (uint)(((ulong)h * base) >> 32);
}

/* An entry of Matoušek's L in base b (generating_matrices.lms_digits): uniform in [1, b) on
 * the diagonal, else in [0, b), drawn as digit_shift draws (bias below b / 2^32). */
inline uint lms_digit(uint word, uint base, int diagonal)
{
    return diagonal ? 1u + digit_shift(word, base - 1u) : digit_shift(word, base);
}

/* Kensler's permutation element: i-th element of the permutation of [0, l) chosen by p
 * (number_theory.permutation_element). */
inline uint permutation_element(uint i, uint l, uint p)
{
    const uint w = clsamp_hash_mask(l);
    do {
        CLSAMP_KENSLER_HASH(i, p, w);
    } while (i >= l);
    return (uint)(((ulong)i + p) % l);   /* in 64 bits: a 32-bit sum wraps for p > 2^32 - l */
}

/* Nested uniform scrambling in base b >= 3 (number_theory.owen_*): node keys, the batched
 * Fisher-Yates draws of a node, and π(d) of the node's uniformly random permutation. */
#define OWEN_ATTEMPT_STRIDE 0x8000000UL   /* 2^27 word slots per rejection attempt */
#define OWEN_MAX_CHUNK 20                 /* owen_chunk_length(3): the longest chunk */

inline uint owen_chunk_length(uint base)
{
    uint g = 0;
    ulong power = 1;
    while (power * base <= 0x100000000UL) {
        power *= base;
        ++g;
    }
    return g;
}

inline uint owen_word(ulong key, ulong slot)
{
    const ulong u = slot >> 1;
    const ulong block = u == 0 ? key : mix64(key ^ u);
    return (slot & 1) ? (uint)(block >> 32) : (uint)block;
}

/* The draws r_j, j in [c g, c g + need), of chunk c: r[t] uniform on [0, b - c g - t), from
 * one 32-bit word by multiplications (a rejected word, rare, is replaced). The word's last
 * remainder after all len multiplications is x P mod 2^32 (P the product of the bounds),
 * so accepting it takes one product and only the draws asked for are made. Returns len. */
CLSAMP_ALWAYS_INLINE uint owen_chunk_draws(ulong key, uint base, uint g, uint c, uint *r, uint need)
{
    const uint j0 = c * g;
    const uint len = min(g, base - j0);
    ulong product = 1;
    for (uint t = 0; t < len; ++t)
        product *= base - j0 - t;
    for (ulong a = 0;; ++a) {
        ulong x = owen_word(key, (ulong)c + a * OWEN_ATTEMPT_STRIDE);
        const ulong last = (x * product) & 0xFFFFFFFFUL;
        /* 2^32 mod P < P: most words pass the first test without a division */
        if (last < product && last < 0x100000000UL % product)
            continue;
        for (uint t = 0; t < clsamp_min(need, len); ++t) {
            x *= base - j0 - t;
            r[t] = (uint)(x >> 32);
            x &= 0xFFFFFFFFUL;
        }
        return len;
    }
}

/* π(d): what position d holds after the Fisher-Yates shuffle (swap j, j + r_j for
 * j = 0, 1, ...). Walk back from p = d + r_d through the swaps j < d, taking p = j where
 * j + r_j = p; chunks are made from d's down to 0, so r needs one chunk of room. For
 * d = 0 (the leading zero digits of small indices) that is one product and one draw. */
CLSAMP_ALWAYS_INLINE uint owen_permutation_element(ulong key, uint base, uint g, uint d)
{
    uint r[OWEN_MAX_CHUNK];
    const uint cd = d < g ? 0u : d / g;
    uint p = 0;
    for (uint c = cd + 1; c-- > 0;) {
        const uint j0 = c * g;
        uint top = g;
        if (c == cd) {
            top = d - j0;
            owen_chunk_draws(key, base, g, c, r, top + 1);
            p = d + r[top];
        } else {
            owen_chunk_draws(key, base, g, c, r, g);
        }
        for (uint t = top; t-- > 0;)
            if (j0 + t + r[t] == p)
                p = j0 + t;
    }
    return p;
}

/* Four nodes at once, one a lane, for the same d: owen_permutation_element of each key, and
 * owen_first_draw4 its π(0). product0 and limit0 are chunk 0's product of bounds and 2^32 mod
 * it (owen_chunk_draws). A lane whose word owen_chunk_draws would reject (rare) gets -1 in
 * *rejected and a wrong element; the caller redoes it with owen_permutation_element. */
CLSAMP_ALWAYS_INLINE int4 owen_chunk_draws4(ulong4 key, uint base, uint g, uint c, uint4 *r,
                                            uint need, ulong product0, ulong limit0)
{
    const uint j0 = c * g;
    const uint len = clsamp_min(g, base - j0);
    ulong product = product0;
    if (c > 0) {
        product = 1;
        for (uint t = 0; t < len; ++t)
            product *= base - j0 - t;
    }
    const ulong u = (ulong)c >> 1;
    const ulong4 block = u == 0 ? key : mix64_4(key ^ u);
    ulong4 x = (c & 1) ? block >> 32 : block & 0xFFFFFFFFUL;
    /* product < 2^32: the low word of x product is the product of the low words */
    const ulong4 last = (x * (product & 0xFFFFFFFFUL)) & 0xFFFFFFFFUL;
    const int4 small = convert_int4(last < product);
    int4 bad = 0;
    if (clsamp_any4(small))
        bad = small & convert_int4(last < (c > 0 ? 0x100000000UL % product : limit0));
    /* the mask beside the multiply: a 32 x 32 -> 64-bit product to the compiler
     * (vpmuludq, where a mask at the loop's end left a full 64-bit vector multiply) */
    for (uint t = 0; t < clsamp_min(need, len); ++t) {
        x = (x & 0xFFFFFFFFUL) * (ulong)(base - j0 - t);
        r[t] = convert_uint4(x >> 32);
    }
    return bad;
}

CLSAMP_ALWAYS_INLINE uint4 owen_permutation_element4(ulong4 key, uint base, uint g, uint d,
                                                     ulong product0, ulong limit0, int4 *rejected)
{
    uint4 r[OWEN_MAX_CHUNK];
    const uint cd = d < g ? 0u : d / g;
    uint4 p = 0;
    int4 bad = 0;
    for (uint c = cd + 1; c-- > 0;) {
        const uint j0 = c * g;
        uint top = g;
        if (c == cd) {
            top = d - j0;
            bad |= owen_chunk_draws4(key, base, g, c, r, top + 1, product0, limit0);
            p = d + r[top];
        } else {
            bad |= owen_chunk_draws4(key, base, g, c, r, g, product0, limit0);
        }
        for (uint t = top; t-- > 0;)
            p = j0 + t + r[t] == p ? (uint4)(j0 + t) : p;
    }
    *rejected = bad;
    return p;
}

CLSAMP_ALWAYS_INLINE uint4 owen_first_draw4(ulong4 key, uint base, ulong product0, ulong limit0,
                                            int4 *rejected)
{
    const ulong4 x = key & 0xFFFFFFFFUL;
    const ulong4 last = (x * (product0 & 0xFFFFFFFFUL)) & 0xFFFFFFFFUL;
    *rejected = convert_int4(last < product0 & last < limit0);
    return convert_uint4((x * base) >> 32);
}

#endif
