/* Float-float (double-single) arithmetic: a value is the unevaluated sum hi + lo of two
 * floats (a float2, .x = hi, .y = lo, |lo| <= ulp(hi) / 2), about 48 significant bits with
 * float's exponent range, for devices without fp64 (and for GPUs, whose fp64 runs at 1/32
 * to 1/64 of their float rate). Error bounds, with u = 2^-24 (Joldes, Muller & Popescu,
 * "Tight and rigorous error bounds for basic building blocks of double-word arithmetic",
 * ACM TOMS 44(2), 2017):
 *     ff_add (their Algorithm 6, "AccurateDWPlusDW")   relative error <= 3u^2 + 13u^3
 *     ff_mul (their Algorithm 12, DWTimesDW with FMA)  relative error <= 5u^2
 *     ff_mul_f (their Algorithm 9, DWTimesFP with FMA) relative error <= 2u^2
 * Exact only with FP_CONTRACT OFF (the includer's pragma) and correctly rounded float
 * operations, which OpenCL requires of +, -, * and fma. The host twin is
 * clsamp.float_float (splitting float64 into pairs and back). */
#ifndef CLSAMP_FLOAT_FLOAT_H
#define CLSAMP_FLOAT_FLOAT_H

#include "two_sum.h"

/* a + b = s + e exactly, given |a| >= |b| or a = 0 (Dekker's Fast2Sum). */
inline float2 ff_fast_two_sum(const float a, const float b)
{
    const float s = a + b;
    return (float2)(s, b - (s - a));
}

/* a * b = p + e exactly (the FMA gives the product's rounding error). */
inline float2 ff_two_prod(const float a, const float b)
{
    const float p = a * b;
    return (float2)(p, fma(a, b, -p));
}

inline float2 ff_add(const float2 x, const float2 y)
{
    float sh, sl, th, tl;
    TWO_SUM(float, x.x, y.x, sh, sl);
    TWO_SUM(float, x.y, y.y, th, tl);
    const float2 v = ff_fast_two_sum(sh, sl + th);
    return ff_fast_two_sum(v.x, tl + v.y);
}

inline float2 ff_mul(const float2 x, const float2 y)
{
    const float2 c = ff_two_prod(x.x, y.x);
    const float t = fma(x.x, y.y, x.y * y.y);
    return ff_fast_two_sum(c.x, c.y + fma(x.y, y.x, t));
}

inline float2 ff_mul_f(const float2 x, const float y)
{
    const float2 c = ff_two_prod(x.x, y);
    return ff_fast_two_sum(c.x, fma(x.y, y, c.y));
}

#endif
