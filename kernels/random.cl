/* The `random` sampler: i.i.d. uniform points, one Philox block per dimension pair.
 * NumPy reference: clsamp.philox.uniform_block. */
#include "philox.h"
#include "dims.h"

#ifndef POINTS_PER_ITEM
#define POINTS_PER_ITEM 8
#endif
#define SETS (POINTS_PER_ITEM / 4)
#if POINTS_PER_ITEM != 1 && POINTS_PER_ITEM % 4 != 0
#error "POINTS_PER_ITEM must be 1 or a multiple of 4"
#endif

/* Grid (ceil(n / POINTS_PER_ITEM), realizations): work-item q makes points
 * q POINTS_PER_ITEM .. (q + 1) POINTS_PER_ITEM - 1 of its realization, their Philox blocks
 * in SETS sets of four vector lanes, inlined side by side so that their chains of
 * dependent multiplies overlap; with POINTS_PER_ITEM 1 (a GPU's shape) one scalar block a
 * dimension pair, the same words. out has shape (realizations, n, d), float64 written as
 * its bit patterns (f64bits.h), so no device needs fp64. */
__kernel void random_points(__global ulong *out, const uint n, const uint d,
                            const uint start, const uint realization0,
                            const uint key_lo, const uint key_hi, const uint stream)
{
    const uint i = POINTS_PER_ITEM * get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint4 realization = (uint4)(realization0 + r);
#if POINTS_PER_ITEM == 1
    __global ulong *q = out + ((size_t)r * n + i) * d;
    for (uint pair = CLSAMP_DIM0 / 2; 2 * pair < CLSAMP_DIM_END(d); ++pair) {
        const ulong2 u = clsamp_uniform2_bits(key, stream, realization0 + r, start + i, pair);
        q[2 * pair] = u.x;
        if (2 * pair + 1 < d)
            q[2 * pair + 1] = u.y;
    }
#else
    const uint lanes = n - i < POINTS_PER_ITEM ? n - i : POINTS_PER_ITEM;
    /* dimension pairs: DIMS_PER_ITEM is even where it is defined */
    for (uint pair = CLSAMP_DIM0 / 2; 2 * pair < CLSAMP_DIM_END(d); ++pair) {
        const uint c = 2 * pair;
#pragma unroll
        for (uint s = 0; s < SETS; ++s) {
            const uint4 index = (uint4)(start + i + 4 * s) + (uint4)(0u, 1u, 2u, 3u);
            uint4 w0, w1, w2, w3;
            philox4x32_10_x4(index, realization, (uint4)pair, (uint4)stream, key, &w0, &w1, &w2, &w3);
            const ulong4 x = clsamp_unit4_bits(w0, w1), y = clsamp_unit4_bits(w2, w3);
            __global ulong *p = out + ((size_t)r * n + i + 4 * s) * d;
            if (lanes == POINTS_PER_ITEM && d == 2u) {     /* four points: 8 consecutive words */
                /* element by element, which the compiler merges into vector stores: PoCL
                 * calls its vstore4 built-in as a function */
                p[0] = x.s0;
                p[1] = y.s0;
                p[2] = x.s1;
                p[3] = y.s1;
                p[4] = x.s2;
                p[5] = y.s2;
                p[6] = x.s3;
                p[7] = y.s3;
            } else if (lanes == POINTS_PER_ITEM) {
                p[c] = x.s0;
                p[d + c] = x.s1;
                p[2 * d + c] = x.s2;
                p[3 * d + c] = x.s3;
                if (c + 1 < d) {
                    p[c + 1] = y.s0;
                    p[d + c + 1] = y.s1;
                    p[2 * d + c + 1] = y.s2;
                    p[3 * d + c + 1] = y.s3;
                }
            } else {                                       /* the last points */
                const uint here = lanes > 4 * s ? lanes - 4 * s : 0u;
#define CLSAMP_STORE(l, x, y) if (l < here) { p[l * d + c] = x; if (c + 1 < d) p[l * d + c + 1] = y; }
                CLSAMP_STORE(0, x.s0, y.s0) CLSAMP_STORE(1, x.s1, y.s1)
                CLSAMP_STORE(2, x.s2, y.s2) CLSAMP_STORE(3, x.s3, y.s3)
#undef CLSAMP_STORE
            }
        }
    }
#endif
}
