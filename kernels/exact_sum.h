/* The exact sum of doubles, rounded once: Python's math.fsum on the device.
 *
 * A fixed-point accumulator over the whole binary64 range (Kulisch's long accumulator,
 * U. Kulisch, "Computer Arithmetic and Validity", de Gruyter 2008): digit k of EXACT_DIGITS
 * holds a signed count of units 2^(32 k - 1074). A finite double is an integer m < 2^53
 * times 2^(e - 1075) (2^-1074 for subnormals), so exact_add adds m shifted into three
 * consecutive digits, a signed amount below 2^32 in each: no rounding, and no carry until
 * exact_round, for up to 2^31 terms (a digit's 64 bits hold 2^31 of them). exact_round
 * propagates the carries, takes the sign and magnitude, and rounds the magnitude to 53
 * bits, half to even: the correctly rounded sum, the value math.fsum returns (+0.0 for an
 * exact zero, as CPython's does; the order of the terms does not matter). Terms must be
 * finite; a sum past the largest double rounds to infinity (math.fsum raises
 * OverflowError there, and also where only a partial sum passes it).
 * tests/test_gbn_resident.py holds it to math.fsum.
 *
 * Private memory: EXACT_DIGITS longs (544 bytes). Build with fp64. */
#ifndef CLSAMP_EXACT_SUM_H
#define CLSAMP_EXACT_SUM_H

#pragma OPENCL EXTENSION cl_khr_fp64 : enable

/* bits 0 .. 2175 of the fixed point: the largest double's top bit is bit 2097, and 2^31
 * terms add 31 more */
#define EXACT_DIGITS 68

inline void exact_clear(long *acc)
{
    for (int k = 0; k < EXACT_DIGITS; ++k)
        acc[k] = 0;
}

inline void exact_add(long *acc, const double x)
{
    const ulong bits = as_ulong(x);
    const uint e = (uint)(bits >> 52) & 0x7ffu;
    ulong m = bits & 0x000FFFFFFFFFFFFFUL;
    uint pos = 0;                                   /* x = m 2^(pos - 1074) */
    if (e != 0) {
        m |= 0x0010000000000000UL;
        pos = e - 1;
    }
    const uint k = pos >> 5, s = pos & 31u;
    /* m 2^s < 2^85 as three 32-bit digits: ml 2^s < 2^63, mh 2^s < 2^52 */
    const ulong low = (m & 0xFFFFFFFFUL) << s;
    const ulong mid = ((m >> 32) << s) + (low >> 32);
    const long d0 = (long)(low & 0xFFFFFFFFUL), d1 = (long)(mid & 0xFFFFFFFFUL);
    const long d2 = (long)(mid >> 32);
    if (bits >> 63) {
        acc[k] -= d0;
        acc[k + 1] -= d1;
        acc[k + 2] -= d2;
    } else {
        acc[k] += d0;
        acc[k + 1] += d1;
        acc[k + 2] += d2;
    }
}

/* every digit but the last into [0, 2^32), the carries passed up */
inline void exact_carry(long *acc)
{
    for (int k = 0; k < EXACT_DIGITS - 1; ++k) {
        acc[k + 1] += acc[k] >> 32;                 /* floor(acc[k] / 2^32): sign-filled */
        acc[k] &= 0xFFFFFFFFL;
    }
}

inline double exact_round(long *acc)
{
    exact_carry(acc);
    ulong sign = 0;
    if (acc[EXACT_DIGITS - 1] < 0) {
        sign = 1;
        for (int k = 0; k < EXACT_DIGITS; ++k)
            acc[k] = -acc[k];
        exact_carry(acc);
    }
    int h = EXACT_DIGITS - 1;
    while (h >= 0 && acc[h] == 0)
        --h;
    if (h < 0)
        return 0.0;
    /* the magnitude N 2^-1074, its top bit at hb */
    const int hb = 32 * h + 63 - (int)clz((ulong)acc[h]);
    ulong out;
    if (hb < 53) {
        /* N < 2^53 is exact, and N is its own bit pattern (subnormal, or the smallest
         * binade, whose biased exponent 1 is N's bit 52) */
        out = (ulong)acc[0] | (h > 0 ? (ulong)acc[1] << 32 : 0UL);
    } else {
        const int shift = hb - 52;                  /* bits dropped: N = mant 2^shift + rest */
        const int k = shift >> 5, s = shift & 31;
        const ulong lo = (ulong)acc[k] | ((ulong)acc[k + 1] << 32);
        const ulong hi = k + 2 < EXACT_DIGITS ? (ulong)acc[k + 2] : 0UL;
        ulong mant = s == 0 ? lo : (lo >> s) | (hi << (64 - s));
        mant &= 0x001FFFFFFFFFFFFFUL;
        /* the first dropped bit, and whether any below it is set */
        const int r = shift - 1;
        const ulong rbit = ((ulong)acc[r >> 5] >> (r & 31)) & 1UL;
        ulong sticky = (ulong)acc[r >> 5] & ((1UL << (r & 31)) - 1UL);
        for (int j = 0; j < (r >> 5) && sticky == 0; ++j)
            sticky = (ulong)acc[j];
        if (rbit && (sticky || (mant & 1UL)))
            mant += 1;
        int biased = shift + 1;                     /* mant 2^(shift - 1074), mant in [2^52, 2^53] */
        if (mant >> 53) {
            mant >>= 1;
            biased += 1;
        }
        out = biased >= 2047 ? 0x7FF0000000000000UL
                             : ((ulong)biased << 52) | (mant & 0x000FFFFFFFFFFFFFUL);
    }
    return as_double(out | (sign << 63));
}

#endif
