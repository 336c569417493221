/* Checks of point sets that stay on the device (clsamp.validation.check_points).
 *
 * Grid (items): work-item g scans values g, g + items, ... of x and writes the smallest
 * and largest finite value it saw and how many were NaN or infinite; the host reduces the
 * items' answers. Comparisons only: exact, the same on every device. Without fp64
 * (CLSAMP_FP64 0) the values are read as their bit patterns: non-finite where the exponent
 * is all ones, ordered by the integer key that flips a negative value's other bits (the
 * order of the doubles, -0 just below +0), and lo, hi written as the bits of the values. */
#if CLSAMP_FP64
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
#else
inline long order_key(const ulong v)
{
    return (long)(v >> 63 ? v ^ 0x7FFFFFFFFFFFFFFFUL : v);
}

__kernel void points_bounds(__global const ulong *x, const ulong n, __global ulong *lo,
                            __global ulong *hi, __global uint *bad)
{
    const size_t g = get_global_id(0), items = get_global_size(0);
    ulong a = 0x7FF0000000000000UL, b = 0xFFF0000000000000UL;      /* +inf, -inf */
    uint c = 0;
    for (size_t i = g; i < n; i += items) {
        const ulong v = x[i];
        if ((v & 0x7FF0000000000000UL) == 0x7FF0000000000000UL) {
            ++c;
        } else {
            a = order_key(v) < order_key(a) ? v : a;
            b = order_key(v) > order_key(b) ? v : b;
        }
    }
    lo[g] = a;
    hi[g] = b;
    bad[g] = c;
}
#endif
