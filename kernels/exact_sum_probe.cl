/* A probe that exposes kernels/exact_sum.h to the tests (tests/test_gbn_resident.py): the
 * exact sum of each row of values (rows, cols), rounded once, into out (rows). One
 * work-item a row. */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#include "exact_sum.h"

__kernel void exact_sum_rows(__global const double *values, const uint cols, const uint rows,
                             __global double *out)
{
    const uint row = get_global_id(0);
    if (row >= rows)
        return;
    long acc[EXACT_DIGITS];
    exact_clear(acc);
    for (uint j = 0; j < cols; ++j)
        exact_add(acc, values[(size_t)row * cols + j]);
    out[row] = exact_round(acc);
}
