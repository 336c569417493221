/* Low-discrepancy samplers: Sobol, and the radical-inverse family (van der Corput, Halton,
 * Hammersley), each unrandomized or with a per-realization randomization.
 * NumPy reference: clsamp/samplers/lowdiscrepancy.py on clsamp/number_theory.py.
 *
 * Build options:
 *   RANDOMIZE   LD_NONE, LD_SHIFT, LD_XOR, LD_OWEN or LD_PERMUTE (lowdiscrepancy.h)
 *   LD_BLOCK    consecutive points per work-item: the first is computed from its index,
 *               the others by an increment (Gray code step, digit carry), which is what
 *               makes the kernels fast; any value gives the same bits
 *   HAMMERSLEY  (radical_points) dimension 0 is i / n instead of a radical inverse
 *   DIMS_PER_ITEM  dimensions per work-item, grid axis 2 (dims.h; all when undefined)
 *   LD_LMS      (sobol_points) one table per realization, made by lms_matrices
 *   LD_INTERLACE  (lms_matrices) the order alpha of an interlaced (higher-order) net
 *
 * Kernels: sobol_points (any base-2 digital net in Gray-code order), sobol_points64,
 * lms_matrices, digital_points (base b >= 3),
 * radical_points, and (RANDOMIZE == LD_OWEN) owen_tables, which
 * radical_points' Owen scrambling in base >= 3 reads: the permutations of the nodes near
 * the roots of the digit trees, made once per launch instead of once per point.
 *
 * Grid: (work-items padded to the local size, realizations); out is (realizations, n, d).
 * Realization r's randomization comes from Philox with counter realization0 + r, so it does
 * not depend on how many realizations one launch makes. Integer arithmetic and exactly
 * rounded double operations only: every device gives the same bits. out holds the doubles'
 * bit patterns (f64bits.h), made by integer arithmetic where the device has no fp64.
 */
#pragma OPENCL FP_CONTRACT OFF
#include "philox.h"
#include "lowdiscrepancy.h"
#include "dims.h"

#ifndef RANDOMIZE
#define RANDOMIZE LD_NONE
#endif
#ifndef LD_BLOCK
#define LD_BLOCK 32
#endif
#ifndef LD_LMS
#define LD_LMS 0
#endif
#ifndef LD_INTERLACE
#define LD_INTERLACE 1
#endif

/* Vector types of width LD_WIDTH (2 or 4): Sobol works on LD_WIDTH dimensions at once,
 * which PoCL turns into SIMD instructions (it does not vectorize across work-items when a
 * kernel has an inner loop). No wider: a double8 handed to a built-in (vload8, vstore8)
 * crosses an ABI that PoCL's AVX-512 library and kernels compiled without AVX-512 disagree
 * on (see docs/design.md, "Kernels and the runtime"). */
#ifndef LD_WIDTH
#define LD_WIDTH 4
#endif
#define LD_CAT(a, b) a##b
#define LD_XCAT(a, b) LD_CAT(a, b)
#define uintW LD_XCAT(uint, LD_WIDTH)
#define ulongW LD_XCAT(ulong, LD_WIDTH)
#define as_ulongW LD_XCAT(as_ulong, LD_WIDTH)
#define longW LD_XCAT(long, LD_WIDTH)
#define vloadW LD_XCAT(vload, LD_WIDTH)
#define vstoreW LD_XCAT(vstore, LD_WIDTH)
#define intW LD_XCAT(int, LD_WIDTH)
#define as_intW LD_XCAT(as_int, LD_WIDTH)
/* Loads and stores of LD_WIDTH consecutive words, element by element, which the compiler
 * merges into vector moves: PoCL calls its vload/vstore built-ins as functions, once a
 * point in sobol_points' loop. */
#if LD_WIDTH == 4
#define LD_LOADW(a) ((uintW)((a)[0], (a)[1], (a)[2], (a)[3]))
#define LD_STOREW(y, a) ((a)[0] = (y).s0, (a)[1] = (y).s1, (a)[2] = (y).s2, (a)[3] = (y).s3)
#else
#define LD_LOADW(a) ((uintW)((a)[0], (a)[1]))
#define LD_STOREW(y, a) ((a)[0] = (y).s0, (a)[1] = (y).s1)
#endif
#if CLSAMP_FP64
#define doubleW LD_XCAT(double, LD_WIDTH)
#define as_doubleW LD_XCAT(as_double, LD_WIDTH)
#define convert_doubleW LD_XCAT(convert_double, LD_WIDTH)
#endif

/* The bits of x 2^-32 (exact), and of (x 2^-32 + u) mod 1, lane by lane. In double
 * through a signed conversion, which has a SIMD instruction where the unsigned one has
 * none (AVX2): x = (x - 2^31) + 2^31, each step exact. */
#if CLSAMP_FP64
inline doubleW unit32W(uintW x)
{
    return (convert_doubleW(as_intW(x ^ 0x80000000u)) + 2147483648.0) * 0x1p-32;
}

inline ulongW unit32W_bits(uintW x) { return as_ulongW(unit32W(x)); }

inline ulongW shift32W_bits(uintW x, ulongW u)
{
    doubleW y = unit32W(x) + as_doubleW(u);
    return as_ulongW(select(y, y - 1.0, y >= 1.0));
}
#else
inline ulongW unit32W_bits(uintW x)
{
    uint in[LD_WIDTH];
    ulong out[LD_WIDTH];
    vstoreW(x, 0, in);
    for (uint l = 0; l < LD_WIDTH; ++l)
        out[l] = f64_scaled(in[l], -32);
    return vloadW(0, out);
}

inline ulongW shift32W_bits(uintW x, ulongW u)
{
    ulong y[LD_WIDTH], v[LD_WIDTH];
    vstoreW(unit32W_bits(x), 0, y);
    vstoreW(u, 0, v);
    for (uint l = 0; l < LD_WIDTH; ++l)
        y[l] = f64_shift_mod1(y[l], v[l]);
    return vloadW(0, y);
}
#endif

CLSAMP_REVERSE_BITS32(reverse_bits32W, uintW)
CLSAMP_LK_HASH(lk_hashW, uintW)

/* A work-item's block: points i0 .. i0 + count - 1 of the launch (index first = start + i0,
 * of type T)
 * of realization r, and where they go; items past the last block return. */
#define LD_ITEM_BLOCK(T)                                                     \
    const uint g = get_global_id(0);                                        \
    const uint r = get_global_id(1);                                        \
    if (g >= (n + LD_BLOCK - 1) / LD_BLOCK)                                 \
        return;                                                             \
    const uint i0 = g * LD_BLOCK;                                           \
    const uint count = min((uint)LD_BLOCK, n - i0);                         \
    const T first = start + i0;                                             \
    const uint2 key = (uint2)(key_lo, key_hi);                              \
    const uint realization = realization0 + r;                              \
    __global ulong *row = out + ((size_t)r * n + i0) * d

/* Sobol points in Gray-code order (as scipy): x_i = xor of V[c] over the set bits c of
 * i ^ (i >> 1), and x_(i+1) = x_i ^ V[ctz(i + 1)]. matrices is (32, padded d): row c holds
 * V[c] of every dimension, zero past d. For Owen scrambling V arrives bit-reversed, so the
 * state is already in the reversed order the LK hash works on. */
__kernel void sobol_points(__global ulong *out, __global const uint *matrices,
                           const uint n, const uint d, const uint start, const uint realization0,
                           const uint key_lo, const uint key_hi, const uint scramble_stream,
                           const uint shift_stream)
{
    LD_ITEM_BLOCK(uint);
    const uint stride = (d + LD_WIDTH - 1) / LD_WIDTH * LD_WIDTH;
    for (uint j = CLSAMP_DIM0; j < CLSAMP_DIM_END(d); j += LD_WIDTH) {
#if LD_LMS
        __global const uint *v = matrices + (size_t)r * 32 * stride + j;   /* realization r's */
#else
        __global const uint *v = matrices + j;
#endif
        uint gray = first ^ (first >> 1);
        uintW x = (uintW)(0u);
        while (gray) {
            x ^= LD_LOADW(v + (size_t)ld_ctz(gray) * stride);
            gray &= gray - 1u;
        }
#if RANDOMIZE == LD_SHIFT
        ulong lanes[LD_WIDTH];
        for (uint l = 0; l < LD_WIDTH; ++l)
            lanes[l] = j + l < d ? clsamp_uniform_bits(key, shift_stream, realization, 0, j + l) : 0;
        const ulongW u = vloadW(0, lanes);
#elif RANDOMIZE == LD_XOR || RANDOMIZE == LD_OWEN
        uint lanes[LD_WIDTH];
        for (uint l = 0; l < LD_WIDTH; ++l)
            lanes[l] = j + l < d ? clsamp_block(key, scramble_stream, realization, j + l, 0).x : 0u;
        const uintW seed = vloadW(0, lanes);
#endif
        const uint width = min((uint)LD_WIDTH, d - j);
        __global ulong *p = row + j;
        uint index = first;
        for (uint t = 0; t < count; ++t) {
#if RANDOMIZE == LD_SHIFT
            const ulongW y = shift32W_bits(x, u);
#elif RANDOMIZE == LD_XOR
            const ulongW y = unit32W_bits(x ^ seed);
#elif RANDOMIZE == LD_OWEN
            const ulongW y = unit32W_bits(reverse_bits32W(lk_hashW(x, seed)));
#else       /* LD_NONE (LD_PERMUTE is not offered for Sobol) */
            const ulongW y = unit32W_bits(x);
#endif
            if (width == LD_WIDTH) {
                LD_STOREW(y, p + (size_t)t * d);
            } else {
                ulong tail[LD_WIDTH];
                vstoreW(y, 0, tail);
                for (uint l = 0; l < width; ++l)
                    p[(size_t)t * d + l] = tail[l];
            }
            if (t + 1 < count) {
                ++index;
                x ^= LD_LOADW(v + (size_t)ld_ctz(index) * stride);
            }
        }
    }
}

/* Sobol points with 64-bit indices (bits=64): the same Gray-code walk over 64 columns of 64
 * bits (matrices is (64, d): row c holds V_c = m_c 2^(63-c) of every dimension), one
 * dimension at a time. The value is the top 53 bits, (x >> 11) 2^-53, exact and below 1;
 * below index 2^32 the low 32 bits of x are 0, so the points are sobol_points' bits. The
 * digital shift xors (words.x << 32 | words.y): its top half is sobol_points' seed. */
__kernel void sobol_points64(__global ulong *out, __global const ulong *matrices,
                             const uint n, const uint d, const ulong start, const uint realization0,
                             const uint key_lo, const uint key_hi, const uint scramble_stream,
                             const uint shift_stream)
{
    LD_ITEM_BLOCK(ulong);
    for (uint j = CLSAMP_DIM0; j < CLSAMP_DIM_END(d); ++j) {
        __global const ulong *v = matrices + j;
        ulong gray = first ^ (first >> 1);
        ulong x = 0;
        while (gray) {
            x ^= v[(size_t)ld_ctz64(gray) * d];
            gray &= gray - 1UL;
        }
#if RANDOMIZE == LD_SHIFT
        const ulong u = clsamp_uniform_bits(key, shift_stream, realization, 0, j);
#elif RANDOMIZE == LD_XOR
        const uint4 words = clsamp_block(key, scramble_stream, realization, j, 0);
        const ulong seed = ((ulong)words.x << 32) | words.y;
#endif
        __global ulong *p = row + j;
        ulong index = first;
        for (uint t = 0; t < count; ++t) {
#if RANDOMIZE == LD_SHIFT
            p[(size_t)t * d] = f64_shift_mod1(f64_scaled(x >> 11, -53), u);
#elif RANDOMIZE == LD_XOR
            p[(size_t)t * d] = f64_scaled((x ^ seed) >> 11, -53);
#else
            p[(size_t)t * d] = f64_scaled(x >> 11, -53);
#endif
            if (t + 1 < count) {
                ++index;
                x ^= v[(size_t)ld_ctz64(index) * d];
            }
        }
    }
}

/* Linear matrix scrambling (Matoušek 1998): out[r] = L_(r,j) V_j, for sobol_points with
 * LD_LMS, whose realization r reads matrices + r 32 stride. matrices is sobol_points' (32,
 * stride) table; row k of L_(r,j) is word 4 + k of Philox (scramble_stream, counter (j,
 * realization0 + r, block 1 + k / 4)), block 0 staying the seeds of the digital shift.
 * Grid: (stride, realizations); columns j >= d are zero. */
#if LD_INTERLACE > 1
/* Row k = LD_INTERLACE r + v of an interlaced L: row r of base dimension v's L, its entry l
 * (bit 31 - l) moved to column LD_INTERLACE l + v (generating_matrices.interlace_columns). */
inline uint lms_interlaced_row(uint row, uint v)
{
    uint y = 0;
    for (uint l = 0; LD_INTERLACE * l + v < 32; ++l)
        y |= ((row >> (31u - l)) & 1u) << (31u - (LD_INTERLACE * l + v));
    return y;
}
#endif

__kernel void lms_matrices(__global uint *out, __global const uint *matrices, const uint d,
                           const uint stride, const uint realization0, const uint key_lo,
                           const uint key_hi, const uint scramble_stream)
{
    const uint j = get_global_id(0);
    const uint r = get_global_id(1);
    if (j >= stride)
        return;
    __global uint *o = out + (size_t)r * 32 * stride + j;
    uint rows[32];
    if (j < d) {
        const uint2 key = (uint2)(key_lo, key_hi);
#if LD_INTERLACE == 1
        for (uint b = 0; b < 8; ++b) {
            const uint4 w = clsamp_block(key, scramble_stream, realization0 + r, j, 1 + b);
            rows[4 * b] = lms_row(w.x, 4 * b);
            rows[4 * b + 1] = lms_row(w.y, 4 * b + 1);
            rows[4 * b + 2] = lms_row(w.z, 4 * b + 2);
            rows[4 * b + 3] = lms_row(w.w, 4 * b + 3);
        }
#else
        /* a higher-order net: the base dimensions' L, interlaced as their matrices are */
        for (uint v = 0; v < LD_INTERLACE; ++v)
            for (uint b = 0; LD_INTERLACE * 4 * b + v < 32; ++b) {
                const uint4 w = clsamp_block(key, scramble_stream, realization0 + r,
                                             LD_INTERLACE * j + v, 1 + b);
                const uint words[4] = {w.x, w.y, w.z, w.w};
                for (uint q = 0; q < 4; ++q) {
                    const uint k = LD_INTERLACE * (4 * b + q) + v;
                    if (k < 32)
                        rows[k] = lms_interlaced_row(lms_row(words[q], 4 * b + q), v);
                }
            }
#endif
    }
    for (uint c = 0; c < 32; ++c)
        o[(size_t)c * stride] = j < d ? lms_apply(rows, matrices[(size_t)c * stride + j]) : 0u;
}

/* The value of digit a at position k under the digit-wise randomizations. */
#if RANDOMIZE == LD_XOR
#define LD_DIGIT(a, k) ((a) + shift[k] >= base ? (a) + shift[k] - base : (a) + shift[k])
#elif RANDOMIZE == LD_PERMUTE
#define LD_DIGIT(a, k) permutation_element((a), base, hash[k])
#else
#define LD_DIGIT(a, k) (a)
#endif

/* Radical inverses: coordinate j of point i is v / b^m, v the (randomized) digits of i in
 * base bases[j] reversed, m the digit count of 32-bit indices (number_theory.digit_count).
 * Plain, shifted, xor and permuted digits are updated incrementally: adding one to the
 * index changes digit 0 and, on a carry, the next ones. Owen scrambling depends on every
 * digit below, so it maps all m digits for each point: at the depths that owen_tables
 * tabulated (owen_layout) by a look-up, deeper by owen_permutation_element. */
#if RANDOMIZE == LD_OWEN
/* The lanes of pi that owen_*4 rejected, redone one by one. */
#define OWEN_REDO(pi, bad, key, dk)                                                           \
    if (clsamp_any4(bad)) {                                                                   \
        if (bad.s0) pi.s0 = owen_permutation_element(key.s0, base, g, dk);                    \
        if (bad.s1) pi.s1 = owen_permutation_element(key.s1, base, g, dk);                    \
        if (bad.s2) pi.s2 = owen_permutation_element(key.s2, base, g, dk);                    \
        if (bad.s3) pi.s3 = owen_permutation_element(key.s3, base, g, dk);                    \
    }
#endif

__kernel void radical_points(__global ulong *out, __global const uint *bases,
                             const uint n, const uint d, const uint start, const uint realization0,
                             const uint key_lo, const uint key_hi, const uint scramble_stream,
                             const uint shift_stream
#if RANDOMIZE == LD_OWEN
                             , __global const uint *owen_table, __global const uint *owen_layout,
                             const uint owen_entries
#endif
                             )
{
    LD_ITEM_BLOCK(uint);
    for (uint j = CLSAMP_DIM0; j < CLSAMP_DIM_END(d); ++j) {
        __global ulong *p = row + j;
#if RANDOMIZE == LD_SHIFT
        const ulong u = clsamp_uniform_bits(key, shift_stream, realization, 0, j);
#elif RANDOMIZE != LD_NONE
        const uint4 words = clsamp_block(key, scramble_stream, realization, j, 0);
        const ulong seed64 = (ulong)words.x | ((ulong)words.y << 32);
#endif
#ifdef HAMMERSLEY
        if (j == 0) {
            /* i / n; the binary randomizations act on its 32-bit fixed-point digits. */
            for (uint t = 0; t < count; ++t) {
                const uint index = first + t;
#if RANDOMIZE == LD_NONE
                p[(size_t)t * d] = f64_div(index, n, 0);
#elif RANDOMIZE == LD_SHIFT
                p[(size_t)t * d] = f64_shift_mod1(f64_div(index, n, 0), u);
#else
                const uint fixed = (uint)(((ulong)index << 32) / n);
#if RANDOMIZE == LD_OWEN
                p[(size_t)t * d] = f64_scaled(owen_scramble_base2(fixed, words.x), -32);
#else
                p[(size_t)t * d] = f64_scaled(fixed ^ words.x, -32);
#endif
#endif
            }
            continue;
        }
#endif
        const uint base = bases[j];
        uint m = 0;
        ulong bm = 1;
        while (bm < 0x100000000UL) {
            bm *= base;
            ++m;
        }
#if RANDOMIZE == LD_OWEN
        if (base == 2u) {
            for (uint t = 0; t < count; ++t)
                p[(size_t)t * d] = f64_scaled(reverse_bits32(lk_hash(first + t, words.x)), -32);
            continue;
        }
#endif
        uint digit[32];
        {
            uint a = first;
            for (uint k = 0; k < m; ++k) {
                digit[k] = a % base;
                a /= base;
            }
        }
#if RANDOMIZE == LD_OWEN
        const uint g = owen_chunk_length(base);
        const uint tabulated = owen_layout[2 * j + 1];
        __global const uint *segment = owen_layout + 2 * d + 4 * owen_layout[2 * j];
        __global const uint *tab = owen_table + (size_t)r * owen_entries;
        uint offset[32];
        for (uint k = 0; k < tabulated; ++k)
            offset[k] = segment[4 * k + 3];
        uint top = m;                                  /* digits k >= top of the index are 0 */
        while (top > 0 && digit[top - 1] == 0)
            --top;
        /* Quads: 4 consecutive points whose digits k >= s agree (s the tabulated depths, at
         * least 1) map those digits together, a point a lane (vh: their part of v); the
         * digits below s, and points outside quads, each point on its own. */
        ulong product0 = 1;
        for (uint t = 0; t < min(g, base); ++t)
            product0 *= base - t;
        const ulong limit0 = 0x100000000UL % product0;
        const uint s = max(tabulated, 1u);
        ulong bs = 1, low = 0;                         /* b^s; the index mod b^s */
        for (uint k = s; k-- > 0;) {
            bs *= base;
            low = low * base + digit[k];
        }
        ulong place[32];                               /* b^(m-1-k): the place of digit k */
        place[m - 1] = 1;
        for (uint k = m - 1; k > 0; --k)
            place[k - 1] = place[k] * base;
        const ulong scale = place[s - 1];              /* b^(m-s): the place of vh */
        for (uint t = 0; t < count;) {
            ulong vh[4];
            uint lanes = 1, depth = m;
            if (count - t >= 4 && low + 3 < bs) {
                lanes = 4;
                depth = s;
                /* v4 = sum of π_k b^(m-1-k): the levels' products are independent, where
                 * Horner's v4 b + π_k would chain a 64-bit vector multiply per level */
                ulong4 prefix = low + (ulong4)(0, 1, 2, 3), v4 = 0;
                ulong power = bs;
                uint k = s;
                for (; k < top; ++k) {
                    const ulong4 key = mix64_4(seed64 ^ (prefix + power));
                    int4 bad;
                    uint4 pi = owen_permutation_element4(key, base, g, digit[k], product0, limit0, &bad);
                    OWEN_REDO(pi, bad, key, digit[k]);
                    v4 += convert_ulong4(pi) * place[k];
                    prefix += (ulong)digit[k] * power;
                    power *= base;
                }
                for (; k < m; ++k) {
                    const ulong4 key = mix64_4(seed64 ^ (prefix + power));
                    int4 bad;
                    uint4 pi = owen_first_draw4(key, base, product0, limit0, &bad);
                    OWEN_REDO(pi, bad, key, 0u);
                    v4 += convert_ulong4(pi) * place[k];
                    power *= base;
                }
                vh[0] = v4.s0;
                vh[1] = v4.s1;
                vh[2] = v4.s2;
                vh[3] = v4.s3;
            }
            for (uint l = 0; l < lanes; ++l, ++t) {
                ulong v = 0, prefix = 0, power = 1;
                uint k = 0;
                for (; k < tabulated; ++k) {
                    v = v * base + tab[offset[k] + (uint)prefix * base + digit[k]];
                    prefix += (ulong)digit[k] * power;
                    power *= base;
                }
                for (; k < clsamp_min(top, depth); ++k) {
                    const ulong key = mix64(seed64 ^ (prefix + power));
                    v = v * base + owen_permutation_element(key, base, g, digit[k]);
                    prefix += (ulong)digit[k] * power;
                    power *= base;
                }
                /* the leading zeros: prefix is the whole index, and each level's π(0) is its
                 * first draw; the levels are independent, so their hashes overlap */
                for (; k < depth; ++k) {
                    v = v * base + owen_permutation_element(mix64(seed64 ^ (prefix + power)), base, g, 0);
                    power *= base;
                }
                if (lanes == 4)
                    v = v * scale + vh[l];
                p[(size_t)t * d] = f64_div(v, bm, 0);
                for (uint k = 0; k < m; ++k) {
                    if (++digit[k] < base) {
                        top = clsamp_max(top, k + 1);
                        break;
                    }
                    digit[k] = 0;
                }
                if (++low == bs)
                    low = 0;
            }
        }
#else
#if RANDOMIZE == LD_XOR
        uint shift[32];
        for (uint k = 0; k < m; ++k)
            shift[k] = digit_shift(digit_hash(seed64, k), base);
#elif RANDOMIZE == LD_PERMUTE
        uint hash[32];
        for (uint k = 0; k < m; ++k)
            hash[k] = digit_hash(seed64, k);
#endif
        if (base == 2u) {
            /* v is the index's bits reversed, each digit's randomization an xor: no carries,
             * no division (v / 2^32 is exact) */
            uint mask = 0;
            for (uint k = 0; k < 32; ++k)
                mask |= (uint)LD_DIGIT(0u, k) << (31 - k);
            for (uint t = 0; t < count; ++t) {
                const ulong x = f64_scaled(reverse_bits32(first + t) ^ mask, -32);
#if RANDOMIZE == LD_SHIFT
                p[(size_t)t * d] = f64_shift_mod1(x, u);
#else
                p[(size_t)t * d] = x;
#endif
            }
            continue;
        }
        ulong weight[32];   /* b^(m-1-k): the place of digit k in the numerator */
        weight[m - 1] = 1;
        for (uint k = m - 1; k > 0; --k)
            weight[k - 1] = weight[k] * base;
        ulong v = 0;
        for (uint k = 0; k < m; ++k)
            v += (ulong)LD_DIGIT(digit[k], k) * weight[k];
        /* v = high + LD_DIGIT(a0, 0) w0: digits >= 1 (high) change once in b points, so
         * between those carries the points are independent (their divisions overlap) */
        uint a0 = digit[0];
        const ulong w0 = weight[0];
        ulong high = v - (ulong)LD_DIGIT(a0, 0) * w0;
        for (uint t = 0; t < count;) {
            const uint run = min(base - a0, count - t);       /* points before digit 0 wraps */
            for (uint q = 0; q < run; ++q) {
                const ulong x = high + (ulong)LD_DIGIT(a0 + q, 0) * w0;
#if RANDOMIZE == LD_SHIFT
                p[(size_t)(t + q) * d] = f64_shift_mod1(f64_div(x, bm, 0), u);
#else
                p[(size_t)(t + q) * d] = f64_div(x, bm, 0);
#endif
            }
            t += run;
            a0 += run;
            if (a0 == base && t < count) {
                a0 = 0;
                for (uint k = 1; k < m; ++k) {
                    const uint a = digit[k];
                    const uint b = a + 1u == base ? 0u : a + 1u;
                    digit[k] = b;
                    /* unsigned wrap-around cancels: high stays exact */
                    high += ((ulong)LD_DIGIT(b, k) - (ulong)LD_DIGIT(a, k)) * weight[k];
                    if (b != 0u)
                        break;
                }
            }
        }
#endif
    }
}

#if RANDOMIZE == LD_OWEN
/* The permutations of the shallow nodes of the Owen digit trees, for radical_points:
 * node (dimension j, depth k, prefix q < b^k) of realization r gets its b entries
 * π(0), ..., π(b-1) at owen_table[r * owen_entries + offset + q * b], made by the same
 * Fisher-Yates shuffle as owen_permutation_element, in place.
 * owen_layout: per dimension (first segment, number of tabulated depths), then per
 * segment (dimension, depth, first node, offset), segments in order of their first node.
 * Grid: (nodes of all segments, padded; realizations); one work-item per node. */
__kernel void owen_tables(__global uint *owen_table, __global const uint *owen_layout,
                          __global const uint *bases, const uint d, const uint segments,
                          const uint nodes, const uint owen_entries, const uint realization0,
                          const uint key_lo, const uint key_hi, const uint scramble_stream)
{
    const uint node = get_global_id(0);
    const uint r = get_global_id(1);
    if (node >= nodes)
        return;
    __global const uint *segs = owen_layout + 2 * d;
    uint lo = 0, hi = segments;          /* the last segment whose first node <= node */
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (segs[4 * mid + 2] <= node)
            lo = mid;
        else
            hi = mid;
    }
    __global const uint *seg = segs + 4 * lo;
    const uint j = seg[0];
    const uint depth = seg[1];
    const uint q = node - seg[2];
    const uint base = bases[j];
    const uint g = owen_chunk_length(base);
    ulong power = 1;
    for (uint k = 0; k < depth; ++k)
        power *= base;
    const uint4 words = clsamp_block((uint2)(key_lo, key_hi), scramble_stream, realization0 + r, j, 0);
    const ulong seed64 = (ulong)words.x | ((ulong)words.y << 32);
    const ulong key = mix64(seed64 ^ (q + power));
    __global uint *a = owen_table + (size_t)r * owen_entries + seg[3] + (size_t)q * base;
    for (uint i = 0; i < base; ++i)
        a[i] = i;
    uint draws[OWEN_MAX_CHUNK];
    for (uint c = 0; c * g < base; ++c) {
        const uint len = owen_chunk_draws(key, base, g, c, draws, g);
        for (uint t = 0; t < len; ++t) {
            const uint i = c * g + t;
            const uint other = i + draws[t];
            const uint held = a[i];
            a[i] = a[other];
            a[other] = held;
        }
    }
}
#endif

/* Digital nets in base b >= 3 from generating matrices, in natural order (NumPy twin:
 * generating_matrices.digital_net_digits and the sampler's reference): point i, dimension j
 * has the digits y = C_j a mod b (a the DN_COLS digits of i, least significant first; y the
 * DN_ROWS digits of the coordinate, most significant first) and the value v / b^DN_ROWS,
 * v = Σ_r y_r b^(DN_ROWS-1-r) < 2^53, one correctly rounded division. matrices and sums are
 * (d, DN_COLS, DN_ROWS): column k of C_j, and its running sum D_k = C_0 + ... + C_k mod b.
 * The first point of a work-item costs a matrix-vector product; the next ones an addition:
 * when i + 1 turns c trailing digits b - 1 of i into 0 and adds one to digit c,
 * y += D_c (mod b). LD_XOR adds to digit r the random digit digit_shift(digit_hash(seed64,
 * r), b) (a digital shift, as radical_points' xor), LD_SHIFT is the Cranley-Patterson
 * rotation. With LD_LMS, matrices and sums hold one table per realization (lms_digits).
 * Grid and arguments as sobol_points. */
#ifdef DN_ROWS
__kernel void digital_points(__global ulong *out, __global const uint *matrices,
                             const uint n, const uint d, const uint start, const uint realization0,
                             const uint key_lo, const uint key_hi, const uint scramble_stream,
                             const uint shift_stream, __global const uint *sums, const uint base,
                             const ulong denominator)
{
    LD_ITEM_BLOCK(uint);
    for (uint j = CLSAMP_DIM0; j < CLSAMP_DIM_END(d); ++j) {
#if LD_LMS
        const size_t table = ((size_t)r * d + j) * DN_COLS * DN_ROWS;   /* realization r's */
#else
        const size_t table = (size_t)j * DN_COLS * DN_ROWS;
#endif
        __global const uint *c = matrices + table;
        __global const uint *s = sums + table;
        __global ulong *p = row + j;
        uint a[DN_COLS], y[DN_ROWS];
        {
            uint i = first;
            for (uint k = 0; k < DN_COLS; ++k) {
                a[k] = i % base;
                i /= base;
            }
        }
        for (uint q = 0; q < DN_ROWS; ++q) {
            ulong acc = 0;                      /* < DN_COLS b^2 <= 2^64 for b <= 2^20 */
            for (uint k = 0; k < DN_COLS; ++k)
                acc += (ulong)c[k * DN_ROWS + q] * a[k];
            y[q] = (uint)(acc % base);
        }
#if RANDOMIZE == LD_SHIFT
        const ulong u = clsamp_uniform_bits(key, shift_stream, realization, 0, j);
#elif RANDOMIZE == LD_XOR
        uint shift[DN_ROWS];
        {
            const uint4 words = clsamp_block(key, scramble_stream, realization, j, 0);
            const ulong seed64 = (ulong)words.x | ((ulong)words.y << 32);
            for (uint q = 0; q < DN_ROWS; ++q)
                shift[q] = digit_shift(digit_hash(seed64, q), base);
        }
#endif
        for (uint t = 0; t < count; ++t) {
            ulong v = 0;
            for (uint q = 0; q < DN_ROWS; ++q) {
#if RANDOMIZE == LD_XOR
                const uint e = y[q] + shift[q];
                v = v * base + (e >= base ? e - base : e);
#else
                v = v * base + y[q];
#endif
            }
#if RANDOMIZE == LD_SHIFT
            p[(size_t)t * d] = f64_shift_mod1(f64_div(v, denominator, 0), u);
#else
            p[(size_t)t * d] = f64_div(v, denominator, 0);
#endif
            if (t + 1 < count) {
                uint k = 0;
                while (k < DN_COLS && a[k] == base - 1)
                    a[k++] = 0;
                if (k < DN_COLS) {
                    ++a[k];
                    __global const uint *dk = s + k * DN_ROWS;
                    for (uint q = 0; q < DN_ROWS; ++q) {
                        const uint e = y[q] + dk[q];
                        y[q] = e >= base ? e - base : e;
                    }
                }
            }
        }
    }
}

/* Linear matrix scrambling in base b (Matoušek 1998; generating_matrices.lms_digits): the
 * digits of realization r, dimension j are L C_j mod b, L lower triangular with entry (q, l)
 * the digit lms_digit(word 4 + q DN_ROWS + l of Philox (scramble_stream, counter (j,
 * realization0 + r, ...)), q == l): uniform in [1, b) on the diagonal, in [0, b) below it.
 * Writes digital_points' matrices and running sums. Grid: (d padded, realizations). */
__kernel void lms_digits(__global uint *out_c, __global uint *out_s, __global const uint *matrices,
                         const uint d, const uint base, const uint realization0, const uint key_lo,
                         const uint key_hi, const uint scramble_stream)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= d)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    __global const uint *c = matrices + (size_t)j * DN_COLS * DN_ROWS;
    const size_t table = ((size_t)r * d + j) * DN_COLS * DN_ROWS;
    uint sum[DN_ROWS];
    for (uint q = 0; q < DN_ROWS; ++q)
        sum[q] = 0;
    for (uint q = 0; q < DN_ROWS; ++q) {
        uint l_row[DN_ROWS];
        for (uint l = 0; l <= q; ++l)
            l_row[l] = lms_digit(clsamp_bits(key, scramble_stream, realization0 + r, j,
                                             4 + q * DN_ROWS + l), base, l == q);
        for (uint k = 0; k < DN_COLS; ++k) {
            ulong acc = 0;                      /* < DN_ROWS b^2 <= 2^64 for b <= 2^20 */
            for (uint l = 0; l <= q; ++l)
                acc += (ulong)l_row[l] * c[k * DN_ROWS + l];
            out_c[table + k * DN_ROWS + q] = (uint)(acc % base);
        }
    }
    for (uint k = 0; k < DN_COLS; ++k)
        for (uint q = 0; q < DN_ROWS; ++q) {
            const uint e = sum[q] + out_c[table + k * DN_ROWS + q];
            sum[q] = e >= base ? e - base : e;
            out_s[table + k * DN_ROWS + q] = sum[q];
        }
}
#endif
