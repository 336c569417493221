/* Probes that expose kernels/f64bits.h to the tests (tests/test_f64bits.py), built with
 * CLSAMP_FP64 1 (hardware double) and 0 (integer arithmetic). */
#include "f64bits.h"
#include "torus.h"

#define F64BITS_RESULTS 16

/* Per i: x, y doubles (bits) and a, b integers; F64BITS_RESULTS results each (the larger
 * less the smaller for f64_sub, the floor of x b as a double, the torus distance of x and
 * y along one axis, the squared torus distance of the 2-D points (x[i], y[i]) and
 * (y[j], y[j + 1]), j = min(i, n - 2), x < y as 0.0 or 1.0, the larger of x and y, and
 * whether that distance is below x[i], itself and the next double up, as 0.0 or 1.0). */
__kernel void f64bits_ops(__global const ulong *x, __global const ulong *y,
                          __global const ulong *a, __global const ulong *b,
                          __global const int *e, __global ulong *out, const uint n)
{
    const uint i = get_global_id(0);
    if (i >= n)
        return;
    __global ulong *o = out + (size_t)F64BITS_RESULTS * i;
    o[0] = f64_add(x[i], y[i]);
    o[1] = f64_div(a[i], b[i], e[i]);
    o[2] = f64_div_int(x[i], b[i]);
    o[3] = f64_mul_int(x[i], b[i]);
    o[4] = f64_scaled(a[i], e[i]);
    o[5] = f64_shift_mod1(x[i], y[i]);
    o[6] = f64_mul(x[i], y[i]);
    o[7] = f64_sub(max(x[i], y[i]), min(x[i], y[i]));
    o[8] = f64_from_int(f64_floor(f64_mul_int(x[i], b[i])));
    o[9] = torus_delta_bits(x[i], y[i]);
    const ulong p[2] = {x[i], y[i]};
    o[10] = torus_distance2_bits(p, y + min(i, n - 2), 2);
    o[11] = f64_from_int(f64_less(x[i], y[i]));
    o[12] = f64_max(x[i], y[i]);
    __global const ulong *q = y + min(i, n - 2);
    o[13] = f64_from_int(torus_closer_bits(p, q, 2, x[i]));
    o[14] = f64_from_int(torus_closer_bits(p, q, 2, o[10]));
    o[15] = f64_from_int(torus_closer_bits(p, q, 2, f64_next_up(o[10])));
}
