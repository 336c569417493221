/* The integrands of clsamp.integrands as OpenCL functions of four points at once, and the
 * double-double addition their sums use: what kernels/integrands.cl (points given) and
 * kernels/fused_integrals.cl (points made in the kernel) share.
 *
 * Build options: DIM (dimension), INTEGRAND (code from clsamp/integrands/base.py). With
 * INTEGRAND == USER_SOURCE the program's source ends with clsamp_user_integrand, the
 * function of clsamp.Integrand.from_opencl (clsamp/integrands/device.py), evaluated one
 * lane at a time; it may call to_normal (kernels/normal.h).
 * Include after a "#pragma OPENCL FP_CONTRACT OFF": numpy evaluates a*b + c with two
 * roundings, and so does every device.
 */
#ifndef CLSAMP_INTEGRAND_H
#define CLSAMP_INTEGRAND_H

#include "torus.h"
#include "two_sum.h"
#include "inline_builtins.h"
#include "normal.h"

#ifndef DIM
#error "DIM must be defined"
#endif
#ifndef INTEGRAND
#error "INTEGRAND must be defined"
#endif

#include "experiment_codes.h"

#define M_1_PI_D 0.318309886183790671537767526745028724   /* rounds to the float 1/pi */
#define M_2_PI_D 0.636619772367581343075535053490057448   /* rounds to the float 2/pi */

typedef double4 vec;

#if INTEGRAND == USER_SOURCE
double clsamp_user_integrand(const double *x);   /* defined at the end of the program */

inline double to_normal(const double u) { return clsamp_to_normal(u); }

#define CLSAMP_USER_LANE(f, x, lane)                 \
    do {                                             \
        double point_[DIM];                          \
        for (int j_ = 0; j_ < DIM; ++j_)             \
            point_[j_] = (x)[j_].lane;               \
        (f).lane = clsamp_user_integrand(point_);    \
    } while (0)
#endif


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
        const vec y = clsamp_to_normal4(x[j]) * p[1];
        s = s + y * y;
    }
    return p[0] * cos(sqrt(s));
#elif INTEGRAND == USER_SOURCE
    vec f;
    CLSAMP_USER_LANE(f, x, s0);
    CLSAMP_USER_LANE(f, x, s1);
    CLSAMP_USER_LANE(f, x, s2);
    CLSAMP_USER_LANE(f, x, s3);
    return f;
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

/* The four lanes of v to out[i .. i + 3], those below end (i < end). */
inline void integrand_store4(__global double *out, const uint i, const uint end, const vec v)
{
    out[i] = v.s0;
    if (i + 1u < end)
        out[i + 1u] = v.s1;
    if (i + 2u < end)
        out[i + 2u] = v.s2;
    if (i + 3u < end)
        out[i + 3u] = v.s3;
}

/* A work-group's double-double total of its lanes' (sum, err) pairs (per-lane TwoSum
 * sums, Ogita, Rump and Oishi's Sum2), added in a fixed tree in local memory: the order
 * depends on the local size only. scratch holds a double2 per work-item. */
inline double2 integrand_group_sum(const vec sum, const vec err, __local double2 *scratch)
{
    const uint lid = get_local_id(0);
    double2 acc = (double2)(0.0, 0.0);
    acc = dd_add(acc, (double2)(sum.x, err.x));
    acc = dd_add(acc, (double2)(sum.y, err.y));
    acc = dd_add(acc, (double2)(sum.z, err.z));
    acc = dd_add(acc, (double2)(sum.w, err.w));
    scratch[lid] = acc;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint step = get_local_size(0) >> 1; step > 0; step >>= 1) {
        if (lid < step)
            scratch[lid] = dd_add(scratch[lid], scratch[lid + step]);
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    return scratch[0];
}

#endif
