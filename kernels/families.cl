/* Integrand families: the error of every member's estimate for every realization, in
 * fp64. NumPy reference: clsamp/families.py (each family's _evaluate, errors_numpy).
 *
 * Build options: DIM (dimension), FAMILY (code from clsamp/families.py), HOMOGENIZE (1:
 * shift realization r by the Philox vector uniform(seed, stream, r, 0, j), as
 * kernels/integrands.cl does).
 *
 * Work-item (q, r) takes members 4q .. 4q + 3 as the lanes of a double4 and sums
 * f_m(x_i) - integral_m over the n points of realization r in order, with a TwoSum
 * (Knuth) error term per lane: the sum comes out as an unevaluated (hi, lo) pair whose
 * error is about n 2^-106 of the sum of |terms|. Parameters are parameter-major,
 * params[p * MP + m] (MP members, a multiple of 4), so one parameter of four members is one
 * double4 load. Every operation is the NumPy reference's, in its order, with no
 * contraction; only exp may differ by an ulp.
 */
#include "torus.h"
#include "two_sum.h"
#include "inline_builtins.h"
#include "experiment_codes.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef DIM
#error "DIM must be defined"
#endif
#ifndef FAMILY
#error "FAMILY must be defined"
#endif


typedef double4 vec;

inline vec param(__global const double *params, const uint mp, const uint p, const uint q)
{
    return *(__global const vec *)(params + (size_t)p * mp + 4u * q);
}

inline vec members_at(const double *x, __global const double *params, const uint mp, const uint q)
{
#if FAMILY == GAUSSIANS
    /* params: centre (DIM), then A row-major (DIM * DIM); f = exp(-w^T A w / 2) */
    vec w[DIM];
    for (int j = 0; j < DIM; ++j)
        w[j] = torus_wrapped4((vec)(x[j]), param(params, mp, j, q));
    vec s = (vec)(0.0);
    for (int i = 0; i < DIM; ++i) {
        vec u = param(params, mp, DIM + i * DIM, q) * w[0];
        for (int j = 1; j < DIM; ++j)
            u = u + param(params, mp, DIM + i * DIM + j, q) * w[j];
        const vec term = w[i] * u;
        s = i == 0 ? term : s + term;
    }
    return exp(s * -0.5);
#elif FAMILY == HEAVISIDES
    /* params: normal (DIM), offset */
    vec s = x[0] * param(params, mp, 0, q);
    for (int j = 1; j < DIM; ++j)
        s = s + x[j] * param(params, mp, j, q);
    return clsamp_indicator4(s < param(params, mp, DIM, q));
#elif FAMILY == DISKS
    /* params: centre (DIM), radius^2 */
    vec w = torus_wrapped4((vec)(x[0]), param(params, mp, 0, q));
    vec s = w * w;
    for (int j = 1; j < DIM; ++j) {
        w = torus_wrapped4((vec)(x[j]), param(params, mp, j, q));
        s = s + w * w;
    }
    return clsamp_indicator4(s < param(params, mp, DIM, q));
#elif FAMILY == BOXES
    /* params: corner (DIM), sides (DIM); the box wraps */
    long4 inside = (long4)(-1);
    for (int j = 0; j < DIM; ++j) {
        vec t = x[j] - param(params, mp, j, q);
        t = t < 0.0 ? t + 1.0 : t;
        inside = inside & (t < param(params, mp, DIM + j, q));
    }
    return clsamp_indicator4(inside);
#elif FAMILY == CLIPPED
    /* params: centre (DIM), h (DIM), lo (DIM), hi (DIM); exp(-sum h (x - c)^2) on [lo, hi) */
    vec t = x[0] - param(params, mp, 0, q);
    vec s = (t * t) * param(params, mp, DIM, q);
    long4 inside = (x[0] >= param(params, mp, 2 * DIM, q)) & (x[0] < param(params, mp, 3 * DIM, q));
    for (int j = 1; j < DIM; ++j) {
        t = x[j] - param(params, mp, j, q);
        s = s + (t * t) * param(params, mp, DIM + j, q);
        inside = inside & (x[j] >= param(params, mp, 2 * DIM + j, q))
                        & (x[j] < param(params, mp, 3 * DIM + j, q));
    }
    return inside ? exp(-s) : (vec)(0.0);
#else
#error "unknown FAMILY"
#endif
}

/* Grid (quads, realizations). points (realizations, n, DIM) on the device; integrals
 * (MP); out (realizations, 2, MP): the hi and lo parts of sum_i (f_m(x_i) - integral_m). */
__kernel void family_error_sums(__global const double *points, const uint n,
                                const uint realization0, const uint key_lo, const uint key_hi,
                                const uint stream, __global const double *params, const uint mp,
                                __global const double *integrals, __global double *out)
{
    const uint q = get_global_id(0), r = get_global_id(1);
    if (4u * q >= mp)
        return;
#if HOMOGENIZE
    double shift[DIM];
    TORUS_HOMOGENIZING_SHIFT(shift, (uint2)(key_lo, key_hi), stream, realization0 + r, DIM);
#endif
    const vec integral = *(__global const vec *)(integrals + 4u * q);
    __global const double *base = points + (size_t)r * n * DIM;
    vec sum = (vec)(0.0), err = (vec)(0.0);
    for (uint i = 0; i < n; ++i) {
        double x[DIM];
        for (int j = 0; j < DIM; ++j) {
#if HOMOGENIZE
            x[j] = torus_shift(base[(size_t)i * DIM + j], shift[j]);
#else
            x[j] = base[(size_t)i * DIM + j];
#endif
        }
        const vec v = members_at(x, params, mp, q) - integral;
        vec s, e;
        TWO_SUM(vec, sum, v, s, e);
        err = err + e;
        sum = s;
    }
    const vec hi = sum + err;
    const vec lo = err - (hi - sum);
    /* out may be host memory with only 16-byte alignment: unaligned stores */
    __global double *row = out + (size_t)r * 2 * mp;
    vstore4(hi, q, row);
    vstore4(lo, q, row + mp);
}
