/* Float-float (double-single) arithmetic: a value is the unevaluated sum hi + lo of two
 * floats (|lo| <= ulp(hi) / 2), about 48 significant bits with float's exponent range, for
 * devices without fp64 (and for GPUs, whose fp64 runs at 1/32 to 1/64 of their float rate).
 * Error bounds, with u = 2^-24 (Joldes, Muller & Popescu, "Tight and rigorous error bounds
 * for basic building blocks of double-word arithmetic", ACM TOMS 44(2), 2017):
 *     FF_ADD (their Algorithm 6, AccurateDWPlusDW)   relative error <= 3u^2 + 13u^3
 *     FF_MUL (their Algorithm 12, DWTimesDW with FMA) relative error <= 5u^2
 *     FF_MUL_F (their Algorithm 9, DWTimesFP with FMA) relative error <= 2u^2
 *     FF_DIV (their Algorithm 17, DWDivDW2)           relative error <= 15u^2 + 56u^3
 * Each is a macro over the type T (float, or a float vector: one float-float a lane), its
 * operands and results hi/lo variables, as TWO_SUM is. Exact only with FP_CONTRACT OFF (the
 * includer's pragma) and correctly rounded float operations, which OpenCL requires of +, -,
 * * and fma. The host twin is clsamp.float_float (float64 into pairs and back). */
#ifndef CLSAMP_FLOAT_FLOAT_H
#define CLSAMP_FLOAT_FLOAT_H

#include "two_sum.h"

/* a + b = s + e exactly, given |a| >= |b| or a = 0 (Dekker's Fast2Sum); s and e may be
 * the variables a and b are computed from. */
#define FF_FAST_TWO_SUM(T, a, b, s, e) do {           \
        const T fa_ = (a), fb_ = (b);                 \
        s = fa_ + fb_;                                \
        e = fb_ - (s - fa_);                          \
    } while (0)

/* a b = p + e exactly (the FMA gives the product's rounding error). */
#define FF_TWO_PROD(T, a, b, p, e) do {               \
        p = (a) * (b);                                \
        e = fma((a), (b), -p);                        \
    } while (0)

#define FF_ADD(T, xh, xl, yh, yl, zh, zl) do {                          \
        T sh_, sl_, th_, tl_, vh_, vl_;                                 \
        TWO_SUM(T, xh, yh, sh_, sl_);                                   \
        TWO_SUM(T, xl, yl, th_, tl_);                                   \
        FF_FAST_TWO_SUM(T, sh_, sl_ + th_, vh_, vl_);                   \
        FF_FAST_TWO_SUM(T, vh_, tl_ + vl_, zh, zl);                     \
    } while (0)

#define FF_MUL(T, xh, xl, yh, yl, zh, zl) do {                          \
        T ch_, cl_;                                                     \
        FF_TWO_PROD(T, xh, yh, ch_, cl_);                               \
        const T t_ = fma((xh), (yl), (xl) * (yl));                      \
        FF_FAST_TWO_SUM(T, ch_, cl_ + fma((xl), (yh), t_), zh, zl);     \
    } while (0)

#define FF_MUL_F(T, xh, xl, y, zh, zl) do {                             \
        T ch_, cl_;                                                     \
        FF_TWO_PROD(T, xh, y, ch_, cl_);                                \
        FF_FAST_TWO_SUM(T, ch_, fma((xl), (y), cl_), zh, zl);           \
    } while (0)

/* z = x / y (their Algorithm 17, DWDivDW2), relative error <= 15u^2 + 56u^3 with correctly
 * rounded float division; OpenCL allows its float division 2.5 ulps, where the bound is not
 * proved (tests/test_float_float.py holds each device tested to it). */
#define FF_DIV(T, xh, xl, yh, yl, zh, zl) do {                          \
        const T th_ = (xh) / (yh);                                      \
        T rh_, rl_;                                                     \
        FF_MUL_F(T, yh, yl, th_, rh_, rl_);                             \
        const T tl_ = (((xh) - rh_) + ((xl) - rl_)) / (yh);             \
        FF_FAST_TWO_SUM(T, th_, tl_, zh, zl);                           \
    } while (0)

/* Complex float-float z = x y and z = x + y, each part a float-float (re h, re l, im h,
 * im l): four products and two sums, each rounded as above. */
#define CFF_MUL(T, xrh, xrl, xih, xil, yrh, yrl, yih, yil, zrh, zrl, zih, zil) do { \
        T p1h_, p1l_, p2h_, p2l_, p3h_, p3l_, p4h_, p4l_;                         \
        FF_MUL(T, xrh, xrl, yrh, yrl, p1h_, p1l_);                                \
        FF_MUL(T, xih, xil, yih, yil, p2h_, p2l_);                                \
        FF_MUL(T, xrh, xrl, yih, yil, p3h_, p3l_);                                \
        FF_MUL(T, xih, xil, yrh, yrl, p4h_, p4l_);                                \
        FF_ADD(T, p1h_, p1l_, -p2h_, -p2l_, zrh, zrl);                            \
        FF_ADD(T, p3h_, p3l_, p4h_, p4l_, zih, zil);                              \
    } while (0)

/* Scalar float-float values held as float2 (.x hi, .y lo): the operations above as
 * functions, and the square root and exponential the pair statistics and the NUFFT's
 * spreading need. */
inline float2 ff2_add(const float2 a, const float2 b)
{
    float h, l;
    FF_ADD(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

inline float2 ff2_mul(const float2 a, const float2 b)
{
    float h, l;
    FF_MUL(float, a.x, a.y, b.x, b.y, h, l);
    return (float2)(h, l);
}

/* a < b for normalized pairs (|lo| <= ulp(hi) / 2): by hi, then lo; exact */
inline int ff2_less(const float2 a, const float2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

/* sqrt(a) for a >= 0: the float square root, then one Newton correction from the exact
 * remainder a - s^2; relative error below 32u^2 with OpenCL's 3-ulp sqrt and 2.5-ulp
 * division (the bounds of clsamp.metrics.neighbors count it so). */
inline float2 ff2_sqrt(const float2 a)
{
    if (a.x <= 0.0f)
        return (float2)(0.0f);
    const float s = sqrt(a.x);
    float ph, pl, h, l;
    FF_TWO_PROD(float, s, s, ph, pl);
    FF_FAST_TWO_SUM(float, s, (((a.x - ph) - pl) + a.y) / (2.0f * s), h, l);
    return (float2)(h, l);
}

/* exp(x) for -87 <= x <= 87: x = k ln 2 + r with |r| <= 0.35, the degree-12 Taylor
 * polynomial of exp(r) in Horner form (its remainder below 2u^2), times 2^k exactly. The
 * coefficients 1/i! (coef[0..12]) and ln 2 (coef[13]) come split from the host
 * (clsamp.float_float.exp_coefficients). */
inline float2 ff2_exp(const float2 x, __global const float2 *coef)
{
    const float v = x.x * 1.44269504f;
    const int k = (int)(v < 0.0f ? v - 0.5f : v + 0.5f);      /* the nearest integer */
    float h, l;
    FF_MUL_F(float, coef[13].x, coef[13].y, (float)k, h, l);
    const float2 r = ff2_add(x, (float2)(-h, -l));
    float2 p = coef[12];
#pragma unroll
    for (int i = 11; i >= 0; --i)
        p = ff2_add(ff2_mul(p, r), coef[i]);
    return p * as_float((k + 127) << 23);
}

#endif
