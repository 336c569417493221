/* Batches of exactly uniform random permutations (Fisher-Yates driven by Philox).
 * NumPy reference: clsamp.permutation.random_permutations.
 *
 * Two launches: the bounded draws j_t are independent of each other, so they are
 * made in parallel over (steps, permutations); only the swaps are sequential, one
 * work-item per permutation. Drawing inside the sequential loop would run its Philox
 * calls one at a time. */
#include "permutation.h"

/* Grid (ceil(length / 16) padded, count * perms); draws has shape (count, perms, length):
 * draws[row, t] uniform in [0, t] (t = 0 holds 0). Row w is permutation
 * perm0 + w % perms of realization realization0 + w / perms. Work-item q makes steps
 * 16q .. 16q + 15: the Philox blocks of its four quads in vector lanes, and each step's
 * multiply in lanes too; a lane whose multiply lands in Lemire's rejection zone (rare) is
 * redone by clsamp_bounded_from. */
__kernel void fisher_yates_draws(__global uint *draws, const uint length, const uint perms,
                                 const uint perm0, const uint realization0,
                                 const uint key_lo, const uint key_hi, const uint stream)
{
    const uint quad0 = 4u * get_global_id(0);
    const uint row = get_global_id(1);
    if (4u * (size_t)quad0 >= length)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint realization = realization0 + row / perms;
    const uint perm = perm0 + row % perms;
    const uint4 quad = (uint4)(quad0) + (uint4)(0u, 1u, 2u, 3u);
    uint4 word[4];
    philox4x32_10_x4(quad, (uint4)(realization), (uint4)(perm << 8), (uint4)(stream), key,
                     &word[0], &word[1], &word[2], &word[3]);
    __global uint *out = draws + (size_t)row * length;
    uint4 step[4];                      /* step[k], lane l: the draw of step 4 (quad0 + l) + k */
    for (uint k = 0; k < 4u; ++k) {
        const uint4 t = 4u * quad + k, range = t + 1u;
        const ulong4 m = convert_ulong4(word[k]) * convert_ulong4(range);
        uint4 j = convert_uint4(m >> 32);
        const int4 low = convert_uint4(m) < range;
        if (clsamp_any4(low)) {
            j = (uint4)(clsamp_bounded_from(word[k].s0, key, stream, realization, t.s0, perm, range.s0),
                        clsamp_bounded_from(word[k].s1, key, stream, realization, t.s1, perm, range.s1),
                        clsamp_bounded_from(word[k].s2, key, stream, realization, t.s2, perm, range.s2),
                        clsamp_bounded_from(word[k].s3, key, stream, realization, t.s3, perm, range.s3));
        }
        step[k] = j;
    }
    const uint t0 = 4u * quad0;
    const uint here = length - t0 < 16u ? length - t0 : 16u;
    for (uint s = 0; s < here; ++s) {
        out[t0 + s] = t0 + s == 0u ? 0u : clsamp_lane(step[s & 3u], s >> 2);
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
