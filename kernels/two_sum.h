/* Knuth's TwoSum, shared by the compensated sums of kernels/integrands.cl and
 * kernels/families.cl: a + b = s + e exactly (no branch, any magnitudes), for a scalar or
 * vector type T. Build with FP_CONTRACT OFF, or the error term is not exact. */
#ifndef CLSAMP_TWO_SUM_H
#define CLSAMP_TWO_SUM_H

#define TWO_SUM(T, a, b, s, e) do {                   \
        s = (a) + (b);                                \
        const T bb_ = s - (a);                        \
        e = ((a) - (s - bb_)) + ((b) - bb_);          \
    } while (0)

#endif
