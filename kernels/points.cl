/* Checks of point sets that stay on the device (clsamp.validation.check_points).
 *
 * Grid (items): work-item g scans values g, g + items, ... of x and writes the smallest
 * and largest finite value it saw and how many were NaN or infinite; the host reduces the
 * items' answers. Comparisons only: exact, the same on every device. */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

__kernel void points_bounds(__global const double *x, const ulong n, __global double *lo,
                            __global double *hi, __global uint *bad)
{
    const size_t g = get_global_id(0), items = get_global_size(0);
    double a = INFINITY, b = -INFINITY;
    uint c = 0;
    for (size_t i = g; i < n; i += items) {
        const double v = x[i];
        if (!isfinite(v)) {
            ++c;
        } else {
            a = v < a ? v : a;
            b = v > b ? v : b;
        }
    }
    lo[g] = a;
    hi[g] = b;
    bad[g] = c;
}

