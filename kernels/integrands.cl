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
#include "torus.h"
#include "two_sum.h"
#include "inline_builtins.h"
#include "normal.h"

/* numpy evaluates a*b + c with two roundings; so does this file, on every device */
#pragma OPENCL FP_CONTRACT OFF

#ifndef DIM
#error "DIM must be defined"
#endif
#ifndef INTEGRAND
#error "INTEGRAND must be defined"
#endif

#define GAUSSIAN 0
#define DISK 1
#define HEAVISIDE 2
#define PMJ_DISK 3
#define PMJ_GAUSSIAN 4
#define PMJ_BILINEAR 5
#define PMJ_STEP 6
#define PMJ_TRIANGLE 7
#define GENZ_OSCILLATORY 8      /* Genz's six families (clsamp.integrands.Genz): */
#define GENZ_PRODUCT_PEAK 9     /* p = (a_0 .. a_{D-1}, u_0 .. u_{D-1}, 2 pi u_0) */
#define GENZ_CORNER_PEAK 10
#define GENZ_GAUSSIAN 11
#define GENZ_CONTINUOUS 12
#define GENZ_DISCONTINUOUS 13
#define KEISTER 14              /* p = (pi^(d/2), 1/sqrt(2)) */

#define M_1_PI_D 0.318309886183790671537767526745028724   /* rounds to the float 1/pi */
#define M_2_PI_D 0.636619772367581343075535053490057448   /* rounds to the float 2/pi */

typedef double4 vec;

/* f at four points; x[j] holds coordinate j of the four. Parameters (see kernel_params):
 * GAUSSIAN p = (s = -1/(2 sigma^2), centre, exp(2 s)), DISK p = (r^2, centre), HEAVISIDE p = (offset, normal). */
inline vec integrand(const vec *x, __global const double *p)
{
#if INTEGRAND == GAUSSIAN
    /* images at |w|, 1 - |w|, 1 + |w|: E0 (1 + B + exp(2s) / B), two exps a dimension */
    const double s = p[0], e2s = p[1 + DIM];
    vec f = (vec)(1.0);
    for (int j = 0; j < DIM; ++j) {
        const vec w = torus_wrapped4(x[j], (vec)(p[1 + j]));
        const vec e0 = exp(s * (w * w));
        const vec b = exp(s * (1.0 - 2.0 * fabs(w)));
        const vec far = select((vec)(0.0), e2s / b, b > 0.0);   /* b underflows only if far does */
        f = f * (e0 * ((1.0 + b) + far));
    }
    return f;
#elif INTEGRAND == DISK
    vec q = (vec)(0.0);
    for (int j = 0; j < DIM; ++j) {
        const vec w = torus_wrapped4(x[j], (vec)(p[1 + j]));
        q = q + w * w;
    }
    return clsamp_indicator4(q < p[0]);
#elif INTEGRAND == HEAVISIDE
    vec s = x[0] * p[1];
    for (int j = 1; j < DIM; ++j)
        s = s + x[j] * p[1 + j];
    return clsamp_indicator4(s < p[0]);
#elif INTEGRAND == PMJ_DISK
    return clsamp_indicator4(x[0] * x[0] + x[1] * x[1] < M_2_PI_D);
#elif INTEGRAND == PMJ_GAUSSIAN
    return exp(-(x[0] * x[0]) - x[1] * x[1]);
#elif INTEGRAND == PMJ_BILINEAR
    return x[0] * x[1];
#elif INTEGRAND == PMJ_STEP
    return clsamp_indicator4(x[0] < M_1_PI_D);
#elif INTEGRAND == PMJ_TRIANGLE
    return clsamp_indicator4(x[1] > x[0]);
#elif INTEGRAND == GENZ_OSCILLATORY
    vec s = (vec)(p[2 * DIM]);
    for (int j = 0; j < DIM; ++j)
        s = s + p[j] * x[j];
    return cos(s);
#elif INTEGRAND == GENZ_PRODUCT_PEAK
    vec f = (vec)(1.0);
    for (int j = 0; j < DIM; ++j) {
        const vec w = x[j] - p[DIM + j];
        f = f / (1.0 / (p[j] * p[j]) + w * w);
    }
    return f;
#elif INTEGRAND == GENZ_CORNER_PEAK
    vec t = (vec)(1.0);
    for (int j = 0; j < DIM; ++j)
        t = t + p[j] * x[j];
    vec q = t;
    for (int j = 0; j < DIM; ++j)
        q = q * t;
    return 1.0 / q;
#elif INTEGRAND == GENZ_GAUSSIAN || INTEGRAND == GENZ_CONTINUOUS
    vec s = (vec)(0.0);
    for (int j = 0; j < DIM; ++j) {
#if INTEGRAND == GENZ_GAUSSIAN
        const vec w = p[j] * (x[j] - p[DIM + j]);
        s = s + w * w;
#else
        s = s + p[j] * fabs(x[j] - p[DIM + j]);
#endif
    }
    return exp(-s);
#elif INTEGRAND == GENZ_DISCONTINUOUS
    vec s = (vec)(0.0);
    for (int j = 0; j < DIM; ++j)
        s = s + p[j] * x[j];
#if DIM > 1
    const long4 inside = (x[0] <= p[DIM]) & (x[1] <= p[DIM + 1]);
#else
    const long4 inside = x[0] <= p[DIM];
#endif
    return select((vec)(0.0), exp(s), inside);
#elif INTEGRAND == KEISTER
    vec s = (vec)(0.0);
    for (int j = 0; j < DIM; ++j) {
        const vec y = (vec)(clsamp_to_normal(x[j].s0), clsamp_to_normal(x[j].s1),
                            clsamp_to_normal(x[j].s2), clsamp_to_normal(x[j].s3)) * p[1];
        s = s + y * y;
    }
    return p[0] * cos(sqrt(s));
#else
#error "unknown INTEGRAND"
#endif
}


inline double2 dd_add(double2 a, double2 b)
{
    double s, e;
    TWO_SUM(double, a.x, b.x, s, e);
    e = e + (a.y + b.y);
    const double hi = s + e;
    return (double2)(hi, e - (hi - s));
}

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
    double2 acc = (double2)(0.0, 0.0);
    acc = dd_add(acc, (double2)(sum.x, err.x));
    acc = dd_add(acc, (double2)(sum.y, err.y));
    acc = dd_add(acc, (double2)(sum.z, err.z));
    acc = dd_add(acc, (double2)(sum.w, err.w));
    scratch[lid] = acc;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint step = local_n >> 1; step > 0; step >>= 1) {
        if (lid < step)
            scratch[lid] = dd_add(scratch[lid], scratch[lid + step]);
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0)
        out[(size_t)r * groups + g] = scratch[0];
}
