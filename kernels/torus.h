/* The float geometry of the unit torus [0, 1)^d: the OpenCL twin of
 * clsamp/geometry/torus.py, operation for operation (exactly rounded double operations;
 * build with FP_CONTRACT OFF), so distances and shifted points agree with the NumPy
 * references bit for bit.
 *
 * torus_delta, torus_distance2: the wrapped difference min(|a - b|, 1 - |a - b|) and the
 * squared distance summed from the first coordinate to the last (the Poisson-disk
 * acceptance test, the nearest-neighbour distances); cube_delta, cube_distance2 the same
 * in the unit cube without wrapping (the pair statistics' periodic=False).
 * torus_shift (double, double4) and torus_wrapped4, each from one definition over its
 * type: (x + u) mod 1 with one rounding (the Cranley-Patterson shift) and a difference
 * wrapped into [-1/2, 1/2].
 * TORUS_HOMOGENIZING_SHIFT: the random shift of realization r that homogenizes an
 * experiment (Pilleboue et al. 2015), Philox point 0 of (stream, r).
 * torus_delta_bits, torus_distance2_bits: torus_delta and torus_distance2 on float64 bit
 * patterns (f64bits.h), the same bits on devices without fp64; torus_closer_bits the
 * comparison of the latter with a threshold.
 */
#ifndef CLSAMP_TORUS_H
#define CLSAMP_TORUS_H

#include "philox.h"

#if CLSAMP_FP64
inline double torus_delta(const double a, const double b)
{
    const double d = a - b;
    const double t = d < 0.0 ? -d : d;
    const double u = 1.0 - t;
    return t < u ? t : u;
}

/* |a - b|: the coordinate distance in the unit cube, without wrapping */
inline double cube_delta(const double a, const double b)
{
    const double d = a - b;
    return d < 0.0 ? -d : d;
}

/* Squared distance of the private point a and the global point b, `dims` coordinates,
 * summed from the first to the last: on the torus (torus_distance2) and in the unit cube
 * (cube_distance2), clsamp.geometry.torus.distance2(a, b, periodic) */
#define CLSAMP_DISTANCE2(name, DELTA)                                           \
    inline double name(const double *a, __global const double *b, const int dims) \
    {                                                                           \
        double t = DELTA(a[0], b[0]);                                           \
        double total = t * t;                                                   \
        for (int k = 1; k < dims; ++k) {                                        \
            t = DELTA(a[k], b[k]);                                              \
            total = total + t * t;                                              \
        }                                                                       \
        return total;                                                           \
    }
CLSAMP_DISTANCE2(torus_distance2, torus_delta)
CLSAMP_DISTANCE2(cube_distance2, cube_delta)

/* (x + u) mod 1 for x, u in [0, 1): x + u less 1 where it reaches 1, one rounding */
#define CLSAMP_TORUS_SHIFT(name, T)                             \
    CLSAMP_ALWAYS_INLINE T name(const T x, const T u)           \
    {                                                           \
        const T c = x + u;                                      \
        return c >= 1.0 ? c - 1.0 : c;                          \
    }

/* x - c wrapped into [-1/2, 1/2] for x, c in [0, 1), T a double vector: numpy's
 * w - round(w) for w in (-1, 1) (half to even keeps +-1/2), by comparisons and select,
 * the faster form on PoCL (docs/performance.md, "One definition per primitive (issue
 * 36)") */
#define CLSAMP_TORUS_WRAPPED(name, T)                           \
    CLSAMP_ALWAYS_INLINE T name(const T x, const T c)           \
    {                                                           \
        T w = x - c;                                            \
        w = select(w, w - 1.0, w > 0.5);                        \
        return select(w, w + 1.0, w < -0.5);                    \
    }

CLSAMP_TORUS_SHIFT(torus_shift, double)
CLSAMP_TORUS_SHIFT(torus_shift4, double4)
CLSAMP_TORUS_WRAPPED(torus_wrapped4, double4)

/* The homogenizing shift of realization r: u[j] = uniform(seed, stream, r, 0, j) for j <
 * dims. A statement, not a function, so that the loop unrolls in the kernel and the shift
 * stays in registers (docs/performance.md, "One definition per primitive (issue 36)"). */
#define TORUS_HOMOGENIZING_SHIFT(u, key, stream, realization, dims)              \
    for (uint j_ = 0; j_ < (uint)(dims); ++j_)                                   \
        (u)[j_] = clsamp_uniform((key), (stream), (realization), 0u, j_)
#endif

/* torus_delta on bit patterns of [0, 1): the double function where there is fp64; else
 * |a - b| as b - a where a < b (round to nearest is symmetric), the patterns of
 * non-negative doubles compared as integers. */
#if CLSAMP_FP64
inline ulong torus_delta_bits(const ulong a, const ulong b)
{
    return as_ulong(torus_delta(as_double(a), as_double(b)));
}
#else
inline ulong torus_delta_bits(const ulong a, const ulong b)
{
    const ulong t = a < b ? f64_sub(b, a) : f64_sub(a, b);
    const ulong u = f64_sub(F64_ONE, t);
    return t < u ? t : u;
}
#endif

/* torus_distance2 on bit patterns: the same operations in the same order. */
inline ulong torus_distance2_bits(const ulong *a, __global const ulong *b, const int dims)
{
    ulong t = torus_delta_bits(a[0], b[0]);
    ulong total = f64_mul(t, t);
    for (int k = 1; k < dims; ++k) {
        t = torus_delta_bits(a[k], b[k]);
        total = f64_add(total, f64_mul(t, t));
    }
    return total;
}

/* Whether torus_distance2_bits(a, b, dims) < r2. Without fp64 the scan stops at the first
 * partial sum that reaches r2: the terms are non-negative and rounding is monotone, so the
 * sums only grow and the answer is the full sum's (most pairs of a dart's neighbourhood
 * are out after a coordinate or two, and each soft operation is dear). */
inline bool torus_closer_bits(const ulong *a, __global const ulong *b, const int dims,
                              const ulong r2)
{
#if CLSAMP_FP64
    return f64_less(torus_distance2_bits(a, b, dims), r2);
#else
    ulong total = 0;                /* 0 + x = x: the first term as torus_distance2 has it */
    for (int k = 0; k < dims; ++k) {
        const ulong t = torus_delta_bits(a[k], b[k]);
        total = f64_add(total, f64_mul(t, t));
        if (!f64_less(total, r2))
            return false;
    }
    return true;
#endif
}

#endif
