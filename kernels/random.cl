/* The `random` sampler: i.i.d. uniform points, one Philox block per dimension pair.
 * NumPy reference: clsamp.philox.uniform_block. */
#include "philox.h"

/* Grid (n, realizations); out has shape (realizations, n, d). */
__kernel void random_points(__global double *out, const uint n, const uint d,
                            const uint start, const uint realization0,
                            const uint key_lo, const uint key_hi, const uint stream)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    __global double *p = out + ((size_t)r * n + i) * d;
    for (uint pair = 0; 2 * pair < d; ++pair) {
        const double2 u = clsamp_uniform2(key, stream, realization0 + r, start + i, pair);
        p[2 * pair] = u.x;
        if (2 * pair + 1 < d)
            p[2 * pair + 1] = u.y;
    }
}
