/* A probe that exposes kernels/float_float.h to the tests (tests/test_float_float.py): per
 * i, x and y float-float pairs and a float f; FF_ADD(x, y), FF_MUL(x, y), FF_MUL_F(x, f),
 * in float and in float8 lanes; FF_DIV(x, y) in float (float_float_div). */
#include "float_float.h"

#pragma OPENCL FP_CONTRACT OFF

__kernel void float_float_ops(__global const float2 *x, __global const float2 *y,
                              __global const float *f, __global float2 *out, const uint n)
{
    const uint i = get_global_id(0);
    if (i >= n)
        return;
    float h, l;
    FF_ADD(float, x[i].x, x[i].y, y[i].x, y[i].y, h, l);
    out[3 * i] = (float2)(h, l);
    FF_MUL(float, x[i].x, x[i].y, y[i].x, y[i].y, h, l);
    out[3 * i + 1] = (float2)(h, l);
    FF_MUL_F(float, x[i].x, x[i].y, f[i], h, l);
    out[3 * i + 2] = (float2)(h, l);
}

/* The same in float8 lanes: eight consecutive i a work-item (n a multiple of 8). */
__kernel void float_float_ops8(__global const float2 *x, __global const float2 *y,
                               __global const float *f, __global float2 *out, const uint n)
{
    const uint i0 = 8 * get_global_id(0);
    if (i0 >= n)
        return;
    float8 xh, xl, yh, yl, fv, h, l;
    float *pxh = (float *)&xh, *pxl = (float *)&xl, *pyh = (float *)&yh, *pyl = (float *)&yl;
    float *pf = (float *)&fv, *ph = (float *)&h, *pl = (float *)&l;
    for (uint j = 0; j < 8; ++j) {
        pxh[j] = x[i0 + j].x; pxl[j] = x[i0 + j].y;
        pyh[j] = y[i0 + j].x; pyl[j] = y[i0 + j].y;
        pf[j] = f[i0 + j];
    }
    FF_ADD(float8, xh, xl, yh, yl, h, l);
    for (uint j = 0; j < 8; ++j)
        out[3 * (i0 + j)] = (float2)(ph[j], pl[j]);
    FF_MUL(float8, xh, xl, yh, yl, h, l);
    for (uint j = 0; j < 8; ++j)
        out[3 * (i0 + j) + 1] = (float2)(ph[j], pl[j]);
    FF_MUL_F(float8, xh, xl, fv, h, l);
    for (uint j = 0; j < 8; ++j)
        out[3 * (i0 + j) + 2] = (float2)(ph[j], pl[j]);
}

__kernel void float_float_div(__global const float2 *x, __global const float2 *y,
                              __global float2 *out, const uint n)
{
    const uint i = get_global_id(0);
    if (i >= n)
        return;
    float h, l;
    FF_DIV(float, x[i].x, x[i].y, y[i].x, y[i].y, h, l);
    out[i] = (float2)(h, l);
}
