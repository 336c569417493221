/* Probes that expose kernels/philox.h to the tests (tests/test_philox.py). */
#include "philox.h"

__kernel void philox_words(__global const uint4 *counters, __global const uint2 *keys,
                           __global uint4 *out)
{
    const size_t i = get_global_id(0);
    out[i] = philox4x32_10(counters[i], keys[i]);
}

__kernel void uniform_probe(__global double *out, __global uint *words, const uint n,
                            const uint d, const uint key_lo, const uint key_hi,
                            const uint stream)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= n)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    for (uint j = 0; j < d; ++j) {
        out[((size_t)r * n + i) * d + j] = clsamp_uniform(key, stream, r, i, j);
        words[((size_t)r * n + i) * d + j] = clsamp_bits(key, stream, r, i, j);
    }
}
