/* A probe that exposes kernels/float_float.h to the tests (tests/test_spectrum_ff.py): per
 * i, x and y float-float pairs and a float f; ff_add(x, y), ff_mul(x, y), ff_mul_f(x, f). */
#include "float_float.h"

#pragma OPENCL FP_CONTRACT OFF

__kernel void float_float_ops(__global const float2 *x, __global const float2 *y,
                              __global const float *f, __global float2 *out, const uint n)
{
    const uint i = get_global_id(0);
    if (i >= n)
        return;
    out[3 * i] = ff_add(x[i], y[i]);
    out[3 * i + 1] = ff_mul(x[i], y[i]);
    out[3 * i + 2] = ff_mul_f(x[i], f[i]);
}
