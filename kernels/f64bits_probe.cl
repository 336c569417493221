/* Probes that expose kernels/f64bits.h to the tests (tests/test_f64bits.py), built with
 * CLSAMP_FP64 1 (hardware double) and 0 (integer arithmetic). */
#include "f64bits.h"

/* Per i: x, y doubles (bits) and a, b integers; seven results each. */
__kernel void f64bits_ops(__global const ulong *x, __global const ulong *y,
                          __global const ulong *a, __global const ulong *b,
                          __global const int *e, __global ulong *out, const uint n)
{
    const uint i = get_global_id(0);
    if (i >= n)
        return;
    __global ulong *o = out + (size_t)7 * i;
    o[0] = f64_add(x[i], y[i]);
    o[1] = f64_div(a[i], b[i], e[i]);
    o[2] = f64_div_int(x[i], b[i]);
    o[3] = f64_mul_int(x[i], b[i]);
    o[4] = f64_scaled(a[i], e[i]);
    o[5] = f64_shift_mod1(x[i], y[i]);
    o[6] = f64_mul(x[i], y[i]);
}

/* Per i: x[i] - y[i] for x[i] >= y[i]. */
__kernel void f64bits_sub(__global const ulong *x, __global const ulong *y, __global ulong *out,
                          const uint n)
{
    const uint i = get_global_id(0);
    if (i < n)
        out[i] = f64_sub(x[i], y[i]);
}
