/* The `random` sampler: i.i.d. uniform points, one Philox block per dimension pair.
 * NumPy reference: clsamp.philox.uniform_block. */
#include "philox.h"
#include "dims.h"

/* Grid (ceil(n / 4), realizations): work-item q makes points 4q .. 4q+3 of its
 * realization, their Philox blocks in vector lanes. out has shape (realizations, n, d),
 * float64 written as its bit patterns (f64bits.h), so no device needs fp64. */
__kernel void random_points(__global ulong *out, const uint n, const uint d,
                            const uint start, const uint realization0,
                            const uint key_lo, const uint key_hi, const uint stream)
{
    const uint i = 4 * get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint4 index = (uint4)(start + i) + (uint4)(0u, 1u, 2u, 3u);
    const uint4 realization = (uint4)(realization0 + r);
    __global ulong *p = out + ((size_t)r * n + i) * d;
    const uint lanes = n - i < 4u ? n - i : 4u;
    /* dimension pairs: DIMS_PER_ITEM is even where it is defined */
    for (uint pair = CLSAMP_DIM0 / 2; 2 * pair < CLSAMP_DIM_END(d); ++pair) {
        uint4 w0, w1, w2, w3;
        philox4x32_10_x4(index, realization, (uint4)pair, (uint4)stream, key, &w0, &w1, &w2, &w3);
        const ulong4 x = clsamp_unit4_bits(w0, w1), y = clsamp_unit4_bits(w2, w3);
        const uint c = 2 * pair;
        if (lanes == 4u) {
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
        } else {
            const ulong xs[4] = {x.s0, x.s1, x.s2, x.s3}, ys[4] = {y.s0, y.s1, y.s2, y.s3};
            for (uint l = 0; l < lanes; ++l) {
                p[l * d + c] = xs[l];
                if (c + 1 < d)
                    p[l * d + c + 1] = ys[l];
            }
        }
    }
}
