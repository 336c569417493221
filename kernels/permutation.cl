/* Batches of exactly uniform random permutations (Fisher-Yates driven by Philox).
 * NumPy reference: clsamp.permutation.random_permutations.
 *
 * Two launches: the bounded draws j_t are independent of each other, so they are
 * made in parallel over (steps, permutations); only the swaps are sequential, one
 * work-item per permutation. Drawing inside the sequential loop would run its Philox
 * calls one at a time. */
#include "permutation.h"

/* Grid (ceil(length / 4), count * perms); draws has shape (count, perms, length):
 * draws[row, t] uniform in [0, t] (t = 0 holds 0). Row w is permutation
 * perm0 + w % perms of realization realization0 + w / perms. */
__kernel void fisher_yates_draws(__global uint *draws, const uint length, const uint perms,
                                 const uint perm0, const uint realization0,
                                 const uint key_lo, const uint key_hi, const uint stream)
{
    const uint quad = get_global_id(0);
    const uint row = get_global_id(1);
    if (4u * (size_t)quad >= length)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint realization = realization0 + row / perms;
    const uint perm = perm0 + row % perms;
    const uint4 block = clsamp_block(key, stream, realization, quad, perm << 8);
    const uint words[4] = {block.x, block.y, block.z, block.w};
    __global uint *out = draws + (size_t)row * length;
    for (uint lane = 0; lane < 4u; ++lane) {
        const uint t = 4u * quad + lane;
        if (t >= length)
            break;
        out[t] = t == 0u ? 0u
               : clsamp_bounded_from(words[lane], key, stream, realization, t, perm, t + 1u);
    }
}

/* One work-item per permutation: out[row] = identity, then swap t <-> draws[row, t]
 * for t = length-1 down to 1 (Durstenfeld). */
__kernel void fisher_yates_apply(__global uint *out, __global const uint *draws,
                                 const uint length, const uint rows)
{
    const size_t row = get_global_id(0);
    if (row >= rows)
        return;
    __global uint *a = out + row * length;
    __global const uint *j = draws + row * length;
    for (uint t = 0; t < length; ++t)
        a[t] = t;
    for (uint t = length - 1u; t > 0u; --t) {
        const uint s = j[t];
        const uint swap = a[t];
        a[t] = a[s];
        a[s] = swap;
    }
}

/* The same in pieces, for devices that stop long loops (runtime.loop_limit): identity rows
 * over a grid (length padded, rows), then the swaps t = t_high down to t_low + 1 of every
 * row per launch, launches in order. */
__kernel void fisher_yates_identity(__global uint *out, const uint length, const uint rows)
{
    const uint t = get_global_id(0);
    const size_t row = get_global_id(1);
    if (t < length && row < rows)
        out[row * length + t] = t;
}

__kernel void fisher_yates_swaps(__global uint *out, __global const uint *draws,
                                 const uint length, const uint rows, const uint t_high,
                                 const uint t_low)
{
    const size_t row = get_global_id(0);
    if (row >= rows)
        return;
    __global uint *a = out + row * length;
    __global const uint *j = draws + row * length;
    for (uint t = t_high; t > t_low; --t) {
        const uint s = j[t];
        const uint swap = a[t];
        a[t] = a[s];
        a[s] = swap;
    }
}

/* clsamp_permute on arrays: out[w] = permute(i[w], length, p[w]) (Kensler 2013).
 * NumPy reference: clsamp.permutation.permute. */
__kernel void kensler_permute(__global uint *out, __global const uint *i,
                              __global const uint *p, const uint length, const uint count)
{
    const size_t w = get_global_id(0);
    if (w >= count)
        return;
    out[w] = clsamp_permute(i[w], length, p[w]);
}

/* clsamp_bounded on arrays: out[w] uniform in [0, range[w]) from the words of
 * (realization, step[w], perm). NumPy reference: clsamp.permutation.bounded_integers. */
__kernel void bounded_integers(__global uint *out, __global const uint *step,
                               __global const uint *range, const uint count, const uint perm,
                               const uint realization, const uint key_lo, const uint key_hi,
                               const uint stream)
{
    const size_t w = get_global_id(0);
    if (w >= count)
        return;
    out[w] = clsamp_bounded((uint2)(key_lo, key_hi), stream, realization, step[w], perm, range[w]);
}

/* clsamp_fisher_yates in one work-item per row (what a kernel that needs a short
 * permutation does inline); the same rows as fisher_yates_draws + fisher_yates_apply. */
__kernel void fisher_yates_inline(__global uint *out, const uint length, const uint count,
                                  const uint perms, const uint perm0, const uint realization0,
                                  const uint key_lo, const uint key_hi, const uint stream)
{
    const size_t w = get_global_id(0);
    if (w >= (size_t)count * perms)
        return;
    clsamp_fisher_yates(out + w * length, length, (uint2)(key_lo, key_hi), stream,
                        realization0 + (uint)(w / perms), perm0 + (uint)(w % perms));
}
