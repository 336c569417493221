/* Points to the integer torus of voronoi.h. Build options from the host
 * (clsamp.geometry.integer_torus.DEFINES): VOR_BITS. */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#include "voronoi.h"

/* Grid (items): x (n doubles in [0, 1)) to the integer torus, out[i] = min(floor(x 2^B),
 * 2^B - 1) with B = VOR_BITS from the host: the NumPy twin is
 * clsamp.geometry.integer_torus.to_torus (x 2^B is exact, so the same integers). */
__kernel void points_to_torus(__global const double *x, const ulong n, __global uint *out)
{
    const size_t i = get_global_id(0);
    if (i >= n)
        return;
    const double v = floor(x[i] * (double)(1u << VOR_BITS));
    out[i] = (uint)min(v, (double)((1u << VOR_BITS) - 1u));
}
