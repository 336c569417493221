/* The convergence experiments in float-float, for devices without fp64: the integrands of
 * kernels/integrand.h (INTEGRAND) and the family members of kernels/families.cl (FAMILY),
 * evaluated per point and summed per realization in float-float (float_float.h), the
 * twins of those fp64 kernels (clsamp/experiments_ff.py runs them; its docstring derives
 * the error bound, and tests/test_experiments_ff.py holds the results to the fp64 ones).
 *
 * Points arrive as float64 bit patterns (ulong), so no double reaches the compiler. The
 * homogenizing shift is the fp64 kernels' to the bit (Philox bits, f64_shift_mod1 of
 * f64bits.h: one correctly rounded addition by integers); each shifted coordinate is then
 * rounded to a float-float pair (ff_from_bits, within 2^-48 of it, relative). Parameters
 * and constants come split from the host (float2: hi, lo). The transcendental functions
 * are built on float_float.h: exp (ff2_exp), cos (reduction by pi/2 with exact products,
 * Taylor series of cos and sin), log (the float log and one Newton step through ff2_exp),
 * sqrt (ff2_sqrt), the normal quantile (Wichura's AS 241 in float-float, its tail's
 * argument 1 - p exact from the bits).
 *
 * Build options: DIM; INTEGRAND (code of experiment_codes.h, not USER_SOURCE) or FAMILY;
 * HOMOGENIZE (1: the shift of realization r, Philox stream `stream`). FP_CONTRACT OFF: the
 * error-free transformations need every operation rounded as written.
 *
 * integrand_error_sums_ff: grid (groups * local, realizations), work-group (local, 1),
 * local a power of two; group g sums f(x_i) - integral over points g slice .. (g + 1)
 * slice - 1 (slice = per_item local: at most 64 points a work-item, strided), then a tree
 * of float-float additions in local memory; out (realizations, groups) float2.
 * family_error_sums_ff: grid (members, realizations, chunks); each work-item sums its
 * member over `chunk` points (a multiple of 64: 2^16, fewer where the device limits a
 * work-item's loops) in blocks of 64 and superblocks of 64 blocks; out (realizations,
 * chunks, members) float2. The order of every addition depends on (n, the local size or
 * the chunk) only; the host adds the chunks in double-double. */
#include "float_float.h"
#include "philox.h"
#include "experiment_codes.h"

#pragma OPENCL FP_CONTRACT OFF

#ifndef DIM
#error "DIM must be defined"
#endif

/* Where the constants table (clsamp.experiments_ff.constants) keeps what: [0, 14) ff2_exp's,
 * then the series of cos and sin, pi/2 in three parts, 1/pi, 2/pi, AS 241's constants
 * (0.180625, 1.6, 0.425) and its six polynomials of eight coefficients (A, B, C, D, E, F). */
#define C_COS 14
#define C_SIN 24
#define C_PI_2 33
#define C_1_PI 35
#define C_2_PI 36
#define C_SPLIT 37
#define C_NEAR 38
#define C_CENTRAL 39
#define C_AS241 40
#define C_LN2 13

/* The float64 x = m 2^(e - 1075) with bits b (non-negative, below 2^100) as a float-float
 * pair: the top 24 bits of its significand m rounded (half up) to t, the rest m - t 2^29
 * (|rest| <= 2^28) rounded to a float, both scaled by powers of two: exact where the
 * results are normal, so within 2^-48 of x, relative, for x >= 2^-126 (below 2^-174: 0).
 * Integer shifts and int-to-float conversions, no library call. */
inline float2 ff_from_bits(const ulong b)
{
    const int e = (int)(b >> 52) & 0x7FF;
    if (e < 849)
        return (float2)(0.0f);
    const ulong m = (b & F64_MANTISSA) | F64_HIDDEN;
    const ulong t = (m + 0x10000000UL) >> 29;
    const int rest = (int)((long)m - (long)(t << 29));
    const float scale = as_float((e - 1075 + 100 + 127) << 23), down = 0x1p-100f;
    return (float2)((((float)(uint)t * 0x1p29f) * scale) * down, (((float)rest) * scale) * down);
}

inline float2 ff2_sub(const float2 a, const float2 b) { return ff2_add(a, -b); }

inline float2 ff2_div(const float2 a, const float2 b)
{
    float h, l;
    FF_DIV(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

inline float2 ff2_abs(const float2 a) { return a.x < 0.0f ? -a : a; }

/* exp(x), 0 below -87 (where float's range ends; e^-87 < 2e-38 of the scale) */
inline float2 ff2_exp0(const float2 x, __global const float2 *c)
{
    return x.x < -87.0f ? (float2)(0.0f) : ff2_exp(x, c);
}

/* x - c wrapped into [-1/2, 1/2] (torus_wrapped4's comparisons) */
inline float2 ff2_wrapped(const float2 x, const float2 c)
{
    float2 w = ff2_sub(x, c);
    if (ff2_less((float2)(0.5f, 0.0f), w))
        w = ff2_add(w, (float2)(-1.0f, 0.0f));
    if (ff2_less(w, (float2)(-0.5f, 0.0f)))
        w = ff2_add(w, (float2)(1.0f, 0.0f));
    return w;
}

/* Horner's rule over `count` float-float coefficients from c[first] (highest degree first) */
inline float2 ff2_horner(const float2 x, __global const float2 *c, const int first, const int count)
{
    float2 p = c[first];
    for (int i = 1; i < count; ++i)
        p = ff2_add(ff2_mul(p, x), c[first + i]);
    return p;
}

/* cos(x) for |x| < 2^20: x = k pi/2 + r (k pi/2 from three parts of pi/2, the first two
 * products exact), |r| <= pi/4, the Taylor series of cos r (degree 18) or sin r (17) in
 * r^2 by Horner's rule, chosen and signed by k mod 4. */
inline float2 ff2_cos(const float2 x, __global const float2 *c)
{
    const float k = rint(x.x * 0.636619772f);
    float ph, pl, qh, ql;
    FF_TWO_PROD(float, k, c[C_PI_2].x, ph, pl);
    FF_TWO_PROD(float, k, c[C_PI_2].y, qh, ql);
    float2 r = ff2_sub(x, (float2)(ph, pl));
    r = ff2_sub(r, (float2)(qh, ql));
    r = ff2_sub(r, (float2)(k * c[C_PI_2 + 1].x, 0.0f));
    const float2 z = ff2_mul(r, r);
    const int q = ((int)k) & 3;
    if (q == 0 || q == 2) {
        const float2 v = ff2_horner(z, c, C_COS, 10);
        return q == 0 ? v : -v;
    }
    const float2 v = ff2_mul(r, ff2_horner(z, c, C_SIN, 9));
    return q == 1 ? -v : v;
}

/* log of the float64 with bits b (positive, normal): b's significand a in [1, 2) as a pair,
 * y0 = log(a.x) in float, one Newton step y0 + a exp(-y0) - 1, plus (exponent) ln 2 */
inline float2 ff_log_bits(const ulong b, __global const float2 *c)
{
    const int e = (int)(b >> 52) - 1023;
    const float2 a = ff_from_bits((b & F64_MANTISSA) | F64_ONE);
    const float y0 = log(a.x);
    const float2 t = ff2_add(ff2_mul(a, ff2_exp(-(float2)(y0, 0.0f), c)), (float2)(-1.0f, 0.0f));
    float h, l;
    FF_MUL_F(float, c[C_LN2].x, c[C_LN2].y, (float)e, h, l);
    return ff2_add(ff2_add((float2)(y0, 0.0f), t), (float2)(h, l));
}

#if defined(INTEGRAND) && INTEGRAND == KEISTER
/* The standard normal quantile of the float64 with bits b (normal_h's AS 241; u = 0 taken
 * as 2^-1022), in float-float: the central rational function of q = p - 1/2, or the tail's
 * of sqrt(-log t), t = p or 1 - p (exact: 1 - p for p >= 1/2 is an integer times 2^-53). */
inline float2 ff_to_normal_bits(ulong b, __global const float2 *c)
{
    b = b < 0x0010000000000000UL ? 0x0010000000000000UL : b;
    const float2 q = ff2_add(ff_from_bits(b), (float2)(-0.5f, 0.0f));
    if (!ff2_less(c[C_CENTRAL], ff2_abs(q))) {                  /* |q| <= 0.425 */
        const float2 r = ff2_sub(c[C_SPLIT], ff2_mul(q, q));
        return ff2_div(ff2_mul(q, ff2_horner(r, c, C_AS241, 8)), ff2_horner(r, c, C_AS241 + 8, 8));
    }
    const ulong t = q.x < 0.0f ? b : f64_scaled(F64_HIDDEN * 2 - ((b & F64_MANTISSA) | F64_HIDDEN), -53);
    const float2 tail = ff2_sqrt(-ff_log_bits(t, c));
    float2 value;
    if (!ff2_less((float2)(5.0f, 0.0f), tail)) {
        const float2 s = ff2_sub(tail, c[C_NEAR]);
        value = ff2_div(ff2_horner(s, c, C_AS241 + 16, 8), ff2_horner(s, c, C_AS241 + 24, 8));
    } else {
        const float2 s = ff2_add(tail, (float2)(-5.0f, 0.0f));
        value = ff2_div(ff2_horner(s, c, C_AS241 + 32, 8), ff2_horner(s, c, C_AS241 + 40, 8));
    }
    return q.x < 0.0f ? -value : value;
}
#endif

#ifdef INTEGRAND
#if INTEGRAND == USER_SOURCE
#error "an OpenCL C integrand has no float-float form (its source is fp64 code)"
#endif

/* f at one point: x its coordinates as pairs, bits their float64 bits; p the integrand's
 * kernel_params() as pairs, c the constants. The fp64 kernel's formulas (integrand.h). */
inline float2 integrand_ff(const float2 *x, const ulong *bits, __global const float2 *p,
                           __global const float2 *c)
{
#if INTEGRAND == GAUSSIAN
    /* the images at |w|, 1 - |w| and 1 + |w| sum to E0 (1 + B + exp(2s) / B), the fp64
     * kernel's form; where exp(2s) underflows float (sigma < 0.076) the far image, below
     * exp(s) < e^-43, is dropped */
    const float2 s = p[0], e2s = p[1 + DIM];
    float2 f = (float2)(1.0f, 0.0f);
    for (int j = 0; j < DIM; ++j) {
        const float2 w = ff2_wrapped(x[j], p[1 + j]);
        const float2 a = ff2_abs(w);
        const float2 e0 = ff2_exp0(ff2_mul(s, ff2_mul(w, w)), c);
        const float2 b = ff2_exp0(ff2_mul(s, ff2_sub((float2)(1.0f, 0.0f), ff2_add(a, a))), c);
        const float2 far = e2s.x > 0.0f ? ff2_div(e2s, b) : (float2)(0.0f);
        f = ff2_mul(f, ff2_mul(e0, ff2_add(ff2_add((float2)(1.0f, 0.0f), b), far)));
    }
    return f;
#elif INTEGRAND == DISK
    float2 q = (float2)(0.0f);
    for (int j = 0; j < DIM; ++j) {
        const float2 w = ff2_wrapped(x[j], p[1 + j]);
        q = ff2_add(q, ff2_mul(w, w));
    }
    return (float2)(ff2_less(q, p[0]) ? 1.0f : 0.0f, 0.0f);
#elif INTEGRAND == HEAVISIDE
    float2 s = ff2_mul(x[0], p[1]);
    for (int j = 1; j < DIM; ++j)
        s = ff2_add(s, ff2_mul(x[j], p[1 + j]));
    return (float2)(ff2_less(s, p[0]) ? 1.0f : 0.0f, 0.0f);
#elif INTEGRAND == PMJ_DISK
    const float2 q = ff2_add(ff2_mul(x[0], x[0]), ff2_mul(x[1], x[1]));
    return (float2)(ff2_less(q, c[C_2_PI]) ? 1.0f : 0.0f, 0.0f);
#elif INTEGRAND == PMJ_GAUSSIAN
    return ff2_exp0(-ff2_add(ff2_mul(x[0], x[0]), ff2_mul(x[1], x[1])), c);
#elif INTEGRAND == PMJ_BILINEAR
    return ff2_mul(x[0], x[1]);
#elif INTEGRAND == PMJ_STEP
    return (float2)(ff2_less(x[0], c[C_1_PI]) ? 1.0f : 0.0f, 0.0f);
#elif INTEGRAND == PMJ_TRIANGLE
    return (float2)(ff2_less(x[0], x[1]) ? 1.0f : 0.0f, 0.0f);
#elif INTEGRAND == GENZ_OSCILLATORY
    float2 s = p[2 * DIM];
    for (int j = 0; j < DIM; ++j)
        s = ff2_add(s, ff2_mul(p[j], x[j]));
    return ff2_cos(s, c);
#elif INTEGRAND == GENZ_PRODUCT_PEAK
    float2 f = (float2)(1.0f, 0.0f);
    for (int j = 0; j < DIM; ++j) {
        const float2 w = ff2_sub(x[j], p[DIM + j]);
        const float2 inv = ff2_div((float2)(1.0f, 0.0f), ff2_mul(p[j], p[j]));
        f = ff2_div(f, ff2_add(inv, ff2_mul(w, w)));
    }
    return f;
#elif INTEGRAND == GENZ_CORNER_PEAK
    float2 t = (float2)(1.0f, 0.0f);
    for (int j = 0; j < DIM; ++j)
        t = ff2_add(t, ff2_mul(p[j], x[j]));
    /* 1 / t^(d+1) as d + 1 divisions by t >= 1: no overflow where t^(d+1) passes float's
     * range (f then underflows towards 0, as it should) */
    float2 f = ff2_div((float2)(1.0f, 0.0f), t);
    for (int j = 0; j < DIM; ++j)
        f = ff2_div(f, t);
    return f;
#elif INTEGRAND == GENZ_GAUSSIAN || INTEGRAND == GENZ_CONTINUOUS
    float2 s = (float2)(0.0f);
    for (int j = 0; j < DIM; ++j) {
#if INTEGRAND == GENZ_GAUSSIAN
        const float2 w = ff2_mul(p[j], ff2_sub(x[j], p[DIM + j]));
        s = ff2_add(s, ff2_mul(w, w));
#else
        s = ff2_add(s, ff2_mul(p[j], ff2_abs(ff2_sub(x[j], p[DIM + j]))));
#endif
    }
    return ff2_exp0(-s, c);
#elif INTEGRAND == GENZ_DISCONTINUOUS
    float2 s = (float2)(0.0f);
    for (int j = 0; j < DIM; ++j)
        s = ff2_add(s, ff2_mul(p[j], x[j]));
    bool inside = !ff2_less(p[DIM], x[0]);
#if DIM > 1
    inside = inside && !ff2_less(p[DIM + 1], x[1]);
#endif
    return inside ? ff2_exp0(s, c) : (float2)(0.0f);
#elif INTEGRAND == KEISTER
    float2 s = (float2)(0.0f);
    for (int j = 0; j < DIM; ++j) {
        const float2 y = ff2_mul(ff_to_normal_bits(bits[j], c), p[1]);
        s = ff2_add(s, ff2_mul(y, y));
    }
    return ff2_mul(p[0], ff2_cos(ff2_sqrt(s), c));
#else
#error "unknown INTEGRAND"
#endif
}
#endif

#ifdef FAMILY
/* Member m at one point: params[k * members + m] is its parameter k (families.py's
 * params, transposed, as pairs). The fp64 kernel's formulas (families.cl). */
inline float2 member_ff(const float2 *x, __global const float2 *params, const uint mp, const uint m,
                        __global const float2 *c)
{
#define P(k) params[(size_t)(k) * mp + m]
#if FAMILY == GAUSSIANS
    /* centre (DIM), then A row-major (DIM * DIM); exp(-w^T A w / 2) */
    float2 w[DIM];
    for (int j = 0; j < DIM; ++j)
        w[j] = ff2_wrapped(x[j], P(j));
    float2 s = (float2)(0.0f);
    for (int i = 0; i < DIM; ++i) {
        float2 u = ff2_mul(P(DIM + i * DIM), w[0]);
        for (int j = 1; j < DIM; ++j)
            u = ff2_add(u, ff2_mul(P(DIM + i * DIM + j), w[j]));
        s = ff2_add(s, ff2_mul(w[i], u));
    }
    return ff2_exp0(-0.5f * s, c);
#elif FAMILY == HEAVISIDES
    /* normal (DIM), offset */
    float2 s = ff2_mul(x[0], P(0));
    for (int j = 1; j < DIM; ++j)
        s = ff2_add(s, ff2_mul(x[j], P(j)));
    return (float2)(ff2_less(s, P(DIM)) ? 1.0f : 0.0f, 0.0f);
#elif FAMILY == DISKS
    /* centre (DIM), radius^2 */
    float2 s = (float2)(0.0f);
    for (int j = 0; j < DIM; ++j) {
        const float2 w = ff2_wrapped(x[j], P(j));
        s = ff2_add(s, ff2_mul(w, w));
    }
    return (float2)(ff2_less(s, P(DIM)) ? 1.0f : 0.0f, 0.0f);
#elif FAMILY == BOXES
    /* corner (DIM), sides (DIM); the box wraps */
    bool inside = true;
    for (int j = 0; j < DIM; ++j) {
        float2 t = ff2_sub(x[j], P(j));
        if (t.x < 0.0f)
            t = ff2_add(t, (float2)(1.0f, 0.0f));
        inside = inside && ff2_less(t, P(DIM + j));
    }
    return (float2)(inside ? 1.0f : 0.0f, 0.0f);
#elif FAMILY == CLIPPED
    /* centre (DIM), h (DIM), lo (DIM), hi (DIM); exp(-sum h (x - c)^2) on [lo, hi) */
    float2 s = (float2)(0.0f);
    bool inside = true;
    for (int j = 0; j < DIM; ++j) {
        const float2 t = ff2_sub(x[j], P(j));
        s = ff2_add(s, ff2_mul(ff2_mul(t, t), P(DIM + j)));
        inside = inside && !ff2_less(x[j], P(2 * DIM + j)) && ff2_less(x[j], P(3 * DIM + j));
    }
    return inside ? ff2_exp0(-s, c) : (float2)(0.0f);
#else
#error "unknown FAMILY"
#endif
#undef P
}
#endif

/* Coordinates of point i of a realization's points (base), shifted when HOMOGENIZE: the
 * fp64 kernels' bits, then pairs */
inline void point_ff(__global const ulong *base, const uint i, const ulong *shift, float2 *x, ulong *bits)
{
    for (int j = 0; j < DIM; ++j) {
        ulong b = base[(size_t)i * DIM + j];
#if HOMOGENIZE
        b = f64_shift_mod1(b, shift[j]);
#endif
        bits[j] = b;
        x[j] = ff_from_bits(b);
    }
}

#define HOMOGENIZING_BITS(shift, key_lo, key_hi, stream, realization)                     \
    ulong shift[DIM];                                                                     \
    for (uint j_ = 0; j_ < DIM; ++j_)                                                     \
        shift[j_] = HOMOGENIZE ? clsamp_uniform_bits((uint2)(key_lo, key_hi), stream, realization, 0u, j_) : 0

#ifdef INTEGRAND
__kernel void integrand_error_sums_ff(__global const ulong *points, const uint n, const uint slice,
                                      const uint realization0, const uint key_lo, const uint key_hi,
                                      const uint stream, __global const float2 *params,
                                      const float2 integral, __global const float2 *c,
                                      __global float2 *out, __local float2 *scratch)
{
    const uint lid = get_local_id(0), local_n = get_local_size(0), g = get_group_id(0);
    const uint r = get_global_id(1);
    __global const ulong *base = points + (size_t)r * n * DIM;
    HOMOGENIZING_BITS(shift, key_lo, key_hi, stream, realization0 + r);
    float2 sum = (float2)(0.0f);
    for (uint i = g * slice + lid; i < min(n, (g + 1u) * slice); i += local_n) {
        float2 x[DIM];
        ulong bits[DIM];
        point_ff(base, i, shift, x, bits);
        sum = ff2_add(sum, ff2_sub(integrand_ff(x, bits, params, c), integral));
    }
    scratch[lid] = sum;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint step = local_n >> 1; step > 0; step >>= 1) {
        if (lid < step)
            scratch[lid] = ff2_add(scratch[lid], scratch[lid + step]);
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0)
        out[(size_t)r * get_num_groups(0) + g] = scratch[0];
}
#endif

#ifdef FAMILY
__kernel void family_error_sums_ff(__global const ulong *points, const uint n, const uint chunk,
                                   const uint realization0, const uint key_lo, const uint key_hi,
                                   const uint stream, __global const float2 *params, const uint mp,
                                   __global const float2 *integrals, __global const float2 *c,
                                   __global float2 *out)
{
    const uint m = get_global_id(0), r = get_global_id(1), k = get_global_id(2);
    if (m >= mp)
        return;
    HOMOGENIZING_BITS(shift, key_lo, key_hi, stream, realization0 + r);
    const float2 integral = integrals[m];
    __global const ulong *base = points + (size_t)r * n * DIM;
    const uint last = min(n, (k + 1u) * chunk);
    float2 total = (float2)(0.0f);
    for (uint s0 = k * chunk; s0 < last; s0 += 4096u) {
        float2 super = (float2)(0.0f);
        for (uint b0 = s0; b0 < min(last, s0 + 4096u); b0 += 64u) {
            float2 block = (float2)(0.0f);
            for (uint i = b0; i < min(last, b0 + 64u); ++i) {
                float2 x[DIM];
                ulong bits[DIM];
                point_ff(base, i, shift, x, bits);
                block = ff2_add(block, ff2_sub(member_ff(x, params, mp, m, c), integral));
            }
            super = ff2_add(super, block);
        }
        total = ff2_add(total, super);
    }
    out[((size_t)r * get_global_size(2) + k) * mp + m] = total;
}
#endif
