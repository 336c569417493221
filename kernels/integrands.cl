/* Integrands evaluated at sample points and summed per realization, in fp64.
 * NumPy reference: clsamp/integrands.py (the functions) and
 * clsamp.estimates.IntegrandErrors with backend="numpy" (shift, evaluation, sum).
 *
 * Build options: DIM (dimension), INTEGRAND (code from clsamp/integrands.py),
 * HOMOGENIZE (1: shift realization r by the Philox vector uniform(seed, stream, r, 0, j),
 * the homogenization of Pilleboue et al. 2015).
 *
 * Work-group g of realization r sums f(x_i) - integral over its slice of points with
 * per-lane TwoSum (Knuth) error terms (Ogita, Rump and Oishi's Sum2, SIAM J. Sci. Comput.
 * 2005), then a tree of double-double additions in local memory: the slice's sum comes
 * out as an unevaluated (hi, lo) pair whose error is about n 2^-106 of the sum of
 * |terms|, so the error of an estimate keeps its relative accuracy however small it is
 * (no rounding floor on the MSE). Subtracting the integral from every term, not from
 * the total, is what keeps a 1e-8 error from cancelling against a 0.1 integral.
 * The order of every addition depends on (n, slice, local size) only, never on timing.
 */
/* numpy evaluates a*b + c with two roundings; so does this file, on every device */
#pragma OPENCL FP_CONTRACT OFF
#include "integrand.h"

/* Grid (groups * local, realizations), work-group (local, 1), local a power of two.
 * points: (realizations, n, DIM) on the device; slice: points per work-group;
 * out: (realizations, groups) pairs (hi, lo) of sum_i (f(x_i) - integral) over the slice. */
__kernel void integrand_error_sums(__global const double *points, const uint n, const uint slice,
                                   const uint realization0, const uint key_lo, const uint key_hi,
                                   const uint stream, __global const double *params,
                                   const double integral, __global double2 *out,
                                   __local double2 *scratch)
{
    const uint lid = get_local_id(0);
    const uint local_n = get_local_size(0);
    const uint g = get_group_id(0);
    const uint groups = get_num_groups(0);
    const uint r = get_global_id(1);
    const uint lo = g * slice;
    const uint hi = min(n, lo + slice);
    __global const double *base = points + (size_t)r * n * DIM;

#if HOMOGENIZE
    double shift[DIM];
    TORUS_HOMOGENIZING_SHIFT(shift, (uint2)(key_lo, key_hi), stream, realization0 + r, DIM);
#endif

    vec sum = (vec)(0.0), err = (vec)(0.0);
    for (uint i = lo + 4u * lid; i < hi; i += 4u * local_n) {
        /* the last quad of a slice may run past it: repeat its last point, masked below */
        const uint i1 = min(i + 1u, hi - 1u), i2 = min(i + 2u, hi - 1u), i3 = min(i + 3u, hi - 1u);
        vec x[DIM];
#if DIM == 2
        /* a whole quad is 8 consecutive doubles: two vector loads, split by parity */
        double4 a, b;
        if (i + 3u < hi) {
            a = vload4(0, base + (size_t)i * 2);
            b = vload4(1, base + (size_t)i * 2);
        } else {
            a = (double4)(base[(size_t)i * 2], base[(size_t)i * 2 + 1],
                          base[(size_t)i1 * 2], base[(size_t)i1 * 2 + 1]);
            b = (double4)(base[(size_t)i2 * 2], base[(size_t)i2 * 2 + 1],
                          base[(size_t)i3 * 2], base[(size_t)i3 * 2 + 1]);
        }
        x[0] = (vec)(a.s02, b.s02);
        x[1] = (vec)(a.s13, b.s13);
#endif
        for (int j = 0; j < DIM; ++j) {
#if DIM == 2
            vec c = x[j];
#else
            vec c = (vec)(base[(size_t)i * DIM + j], base[(size_t)i1 * DIM + j],
                          base[(size_t)i2 * DIM + j], base[(size_t)i3 * DIM + j]);
#endif
#if HOMOGENIZE
            c = torus_shift4(c, (vec)(shift[j]));
#endif
            x[j] = c;
        }
        vec v = integrand(x, params) - integral;
        const long4 live = (long4)(i, i + 1u, i + 2u, i + 3u) < (long4)(hi);
        v = select((vec)(0.0), v, live);
        vec s, e;
        TWO_SUM(vec, sum, v, s, e);
        sum = s;
        err = err + e;
    }
    const double2 total = integrand_group_sum(sum, err, scratch);
    if (lid == 0)
        out[(size_t)r * groups + g] = total;
}

/* f at given points, four a work-item: points (n, DIM), out (n). Grid: ceil(n / 4) padded
 * to the local size. The evaluation of clsamp.Integrand.from_opencl's integrands on the
 * host's points (their __call__). */
__kernel void integrand_values(__global const double *points, const uint n,
                               __global const double *params, __global double *out)
{
    const uint i = 4u * get_global_id(0);
    if (i >= n)
        return;
    const uint i1 = min(i + 1u, n - 1u), i2 = min(i + 2u, n - 1u), i3 = min(i + 3u, n - 1u);
    vec x[DIM];
    for (int j = 0; j < DIM; ++j)
        x[j] = (vec)(points[(size_t)i * DIM + j], points[(size_t)i1 * DIM + j],
                     points[(size_t)i2 * DIM + j], points[(size_t)i3 * DIM + j]);
    integrand_store4(out, i, n, integrand(x, params));
}
