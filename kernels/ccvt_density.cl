/* The density points of CCVT (clsamp/samplers/ccvt/density.py, density_points: the NumPy
 * twin, the same integers) on the integer torus of voronoi.h. */
#include "voronoi.h"
#include "philox.h"

/* Grid (M, r): the density, point j of realization realization0 + r from words 4, 5 (Philox
 * block 1) of (key, stream, realization, j), top VOR_BITS bits each; the NumPy twin is
 * clsamp.samplers.ccvt.density.density_points. */
__kernel void ccvt_density(__global uint2 *out, const uint M, const uint realization0,
                           const uint key_lo, const uint key_hi, const uint stream)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const uint4 b = clsamp_block((uint2)(key_lo, key_hi), stream, realization0 + r, j, 1);
    out[(size_t)r * M + j] = (uint2)(b.x >> (32 - VOR_BITS), b.y >> (32 - VOR_BITS));
}

/* Grid (M, r): the jittered density of clsamp.samplers.ccvt.density.density_points. Point j lies
 * in its own cell of an equal-area partition into exactly M cells: `rows` rows, row i holding
 * points floor(i M / rows) .. floor((i+1) M / rows) - 1 (c of them, row height c / M, cells
 * 1 / c wide), uniform in the cell from words 4, 5 of (key, stream, realization, j); then the
 * whole set moves by the realization's toroidal shift, words 6, 7 of index 0. Integer
 * arithmetic (every product stays below 2^55), so it equals the NumPy twin bit for bit. */
__kernel void ccvt_density_jittered(__global uint2 *out, const uint M, const uint rows,
                                    const uint realization0, const uint key_lo,
                                    const uint key_hi, const uint stream)
{
    const uint j = get_global_id(0), r = get_global_id(1);
    if (j >= M)
        return;
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint4 b = clsamp_block(key, stream, realization0 + r, j, 1);
    const uint4 t = clsamp_block(key, stream, realization0 + r, 0, 1);
    const ulong m = M, k = rows;
    const ulong row = (((ulong)j + 1) * k - 1) / m;
    const ulong start = row * m / k;
    const ulong c = (row + 1) * m / k - start;
    const ulong x = ((((ulong)j - start) << VOR_BITS) + (b.x >> (32 - VOR_BITS))) / c;
    const ulong y = ((start << VOR_BITS) + (ulong)(b.y >> (32 - VOR_BITS)) * c) / m;
    out[(size_t)r * M + j] = (uint2)(((uint)x + (t.z >> (32 - VOR_BITS))) & VOR_MASK,
                                     ((uint)y + (t.w >> (32 - VOR_BITS))) & VOR_MASK);
}
