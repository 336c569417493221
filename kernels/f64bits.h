/* Float64 results as IEEE-754 bit patterns (ulong), on devices with or without fp64.
 *
 * Each function returns the bits of one correctly rounded binary64 operation: where the
 * device has fp64 (CLSAMP_FP64 1, which the runtime defines by device) by the hardware
 * operation, elsewhere by integer arithmetic with round-to-nearest-even. IEEE-754 makes
 * both the same bits, so a sampler whose coordinates are built from these gives the same
 * numbers on every device (tests/test_f64bits.py holds both paths to NumPy's float64).
 *
 * Operands: non-negative, finite, zero or normal doubles (the samplers' coordinates and
 * their parts), integers below 2^53 where they meet a double, results in the normal
 * range. Kernels keep their output as `__global ulong *`; the host views it as float64.
 */
#ifndef CLSAMP_F64BITS_H
#define CLSAMP_F64BITS_H

#ifndef CLSAMP_FP64
#define CLSAMP_FP64 1
#endif

/* Inline this function whatever its size (every kernel includes this header): PoCL's
 * inliner can leave a large unrolled function a call, its results through memory
 * (docs/performance.md, "Philox in 64-bit lanes, always inlined"). */
#ifdef __clang__
#define CLSAMP_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define CLSAMP_ALWAYS_INLINE inline
#endif

#define F64_MANTISSA 0x000FFFFFFFFFFFFFUL
#define F64_HIDDEN 0x0010000000000000UL
#define F64_ONE 0x3FF0000000000000UL

#if CLSAMP_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

/* 2^e for a normal power (-1022 <= e <= 1023). */
inline double f64_pow2(int e) { return as_double((ulong)(e + 1023) << 52); }

/* m 2^e, m an integer (rounded once when it has more than 53 bits). */
inline ulong f64_scaled(ulong m, int e) { return as_ulong((double)m * f64_pow2(e)); }

/* a / b 2^e, correctly rounded; a, b < 2^53, b > 0. */
inline ulong f64_div(ulong a, ulong b, int e)
{
    return as_ulong((double)a / (double)b * f64_pow2(e));
}

/* x / c, correctly rounded; x a double, 0 < c < 2^53. */
inline ulong f64_div_int(ulong x, ulong c) { return as_ulong(as_double(x) / (double)c); }

/* x + y, correctly rounded. */
inline ulong f64_add(ulong x, ulong y) { return as_ulong(as_double(x) + as_double(y)); }

/* x c, correctly rounded; c < 2^53. */
inline ulong f64_mul_int(ulong x, ulong c) { return as_ulong(as_double(x) * (double)c); }

/* x y, correctly rounded. */
inline ulong f64_mul(ulong x, ulong y) { return as_ulong(as_double(x) * as_double(y)); }

/* y - 1 for 1 <= y < 2, exact (Sterbenz). */
inline ulong f64_minus_one(ulong y) { return as_ulong(as_double(y) - 1.0); }

/* x - y for x >= y, correctly rounded. */
inline ulong f64_sub(ulong x, ulong y) { return as_ulong(as_double(x) - as_double(y)); }

#else   /* integer arithmetic only: no double reaches the compiler */

inline ulong f64_bitlength(ulong m) { return 64u - clz(m); }

/* m 2^e, round to nearest even. The result's biased exponent is added to the 53-bit
 * significand whose hidden bit sits at 2^52: a significand that rounds up to 2^53 carries
 * into the exponent, which is the right answer. */
inline ulong f64_scaled(ulong m, int e)
{
    if (m == 0)
        return 0;
    const int n = (int)f64_bitlength(m);
    const long exponent = (long)e + n - 1;          /* m 2^e = 1.f 2^exponent */
    ulong significand;
    if (n <= 53) {
        significand = m << (53 - n);
    } else {
        const int s = n - 53;
        significand = m >> s;
        const ulong rest = m & ((1UL << s) - 1);
        const ulong halfway = 1UL << (s - 1);
        significand += (rest > halfway || (rest == halfway && (significand & 1)));
    }
    return ((ulong)(exponent + 1022) << 52) + significand;
}

/* (hi 2^64 + lo) 2^e, round to nearest even. */
inline ulong f64_round128(ulong hi, ulong lo, int e)
{
    if (hi == 0)
        return f64_scaled(lo, e);
    const int n = 128 - (int)clz(hi);                /* 65 .. 128 bits */
    const int s = n - 53;                            /* 12 .. 75 bits dropped */
    ulong significand, guard, sticky;
    if (s < 64) {
        significand = (hi << (64 - s)) | (lo >> s);
        guard = (lo >> (s - 1)) & 1;
        sticky = (lo & ((1UL << (s - 1)) - 1)) != 0;
    } else if (s == 64) {
        significand = hi;
        guard = lo >> 63;
        sticky = (lo << 1) != 0;
    } else {
        const int t = s - 64;
        significand = hi >> t;
        guard = (hi >> (t - 1)) & 1;
        sticky = ((hi & ((1UL << (t - 1)) - 1)) | lo) != 0;
    }
    significand += guard & (sticky | (significand & 1));
    const long exponent = (long)e + n - 1;
    return ((ulong)(exponent + 1022) << 52) + significand;
}

/* a / b 2^e, round to nearest even; a < 2^62, 0 < b < 2^62. Aligned so that
 * b <= a < 2b, then 55 quotient bits by restoring division; the remainder is the sticky
 * bit below them. */
inline ulong f64_div(ulong a, ulong b, int e)
{
    if (a == 0)
        return 0;
    int k = (int)f64_bitlength(a) - (int)f64_bitlength(b);
    if (k >= 0)
        b <<= k;
    else
        a <<= -k;
    if (a < b) {
        a <<= 1;
        --k;
    }
    ulong q = 1, r = a - b;
    for (int i = 0; i < 55; ++i) {
        r <<= 1;
        q <<= 1;
        if (r >= b) {
            r -= b;
            q |= 1;
        }
    }
    return f64_scaled((q << 1) | (r != 0), k + e - 56);
}

/* The significand (hidden bit included) and exponent of a double: x = m 2^e. */
inline ulong f64_significand(ulong x) { return (x & F64_MANTISSA) | F64_HIDDEN; }
inline int f64_exponent(ulong x) { return (int)(x >> 52) - 1075; }

inline ulong f64_div_int(ulong x, ulong c)
{
    return x == 0 ? 0 : f64_div(f64_significand(x), c, f64_exponent(x));
}

inline ulong f64_add(ulong x, ulong y)
{
    if (x == 0)
        return y;
    if (y == 0)
        return x;
    if (x < y) {
        const ulong t = x;
        x = y;
        y = t;
    }
    const int d = f64_exponent(x) - f64_exponent(y);
    if (d > 74)              /* y is far below half an ulp of x */
        return x;
    const ulong mx = f64_significand(x), my = f64_significand(y);
    ulong hi, lo;
    if (d == 0) {
        hi = 0;
        lo = mx;
    } else if (d < 64) {
        hi = mx >> (64 - d);
        lo = mx << d;
    } else {
        hi = mx << (d - 64);
        lo = 0;
    }
    lo += my;
    hi += lo < my;
    return f64_round128(hi, lo, f64_exponent(y));
}

inline ulong f64_mul_int(ulong x, ulong c)
{
    if (x == 0 || c == 0)
        return 0;
    const ulong m = f64_significand(x);
    return f64_round128(mul_hi(m, c), m * c, f64_exponent(x));
}

inline ulong f64_mul(ulong x, ulong y)
{
    if (x == 0 || y == 0)
        return 0;
    const ulong mx = f64_significand(x), my = f64_significand(y);
    return f64_round128(mul_hi(mx, my), mx * my, f64_exponent(x) + f64_exponent(y));
}

inline ulong f64_minus_one(ulong y) { return f64_scaled((y & F64_MANTISSA), -52); }

/* x - y for x >= y, round to nearest even: x's significand shifted up to y's exponent
 * (127 bits at most), y's subtracted, the 128-bit difference rounded once. A y more than
 * 74 binades below x is less than a quarter of x's ulp (a power of two's gap below is half
 * an ulp): the result is x. The difference must be zero or normal (it is a multiple of y's
 * ulp, so x, y >= 2^-969 suffices). */
inline ulong f64_sub(ulong x, ulong y)
{
    if (y == 0)
        return x;
    if (x == y)
        return 0;
    const int d = f64_exponent(x) - f64_exponent(y);
    if (d > 74)
        return x;
    const ulong mx = f64_significand(x), my = f64_significand(y);
    ulong hi, lo;
    if (d == 0) {
        hi = 0;
        lo = mx;
    } else if (d < 64) {
        hi = mx >> (64 - d);
        lo = mx << d;
    } else {
        hi = mx << (d - 64);
        lo = 0;
    }
    hi -= lo < my;
    lo -= my;
    return f64_round128(hi, lo, f64_exponent(y));
}

#endif

/* Exact conversions and moves, the same code on every device. */
inline ulong f64_from_int(ulong k) { return f64_scaled(k, 0); }

/* The next double up or down (x > 0 finite). */
inline ulong f64_next_up(ulong x) { return x + 1; }
inline ulong f64_next_down(ulong x) { return x - 1; }

/* (x + u) mod 1 for x, u in [0, 1): one rounding, then an exact wrap. */
inline ulong f64_shift_mod1(ulong x, ulong u)
{
    const ulong y = f64_add(x, u);
#if CLSAMP_FP64
    const ulong wrapped = f64_minus_one(y);    /* both, then a select: the wrap is a coin toss */
    return y >= F64_ONE ? wrapped : y;
#else
    return y >= F64_ONE ? f64_minus_one(y) : y;
#endif
}

/* floor(x 2^k) of a double 0 <= x < 2^(64 - k) that is a multiple of 2^-k. */
inline ulong f64_to_fixed(ulong x, int k)
{
    if (x == 0)
        return 0;
    const int e = (int)(x >> 52) - 1075 + k;
    const ulong m = (x & F64_MANTISSA) | F64_HIDDEN;
    return e >= 0 ? m << e : m >> -e;
}

#endif
