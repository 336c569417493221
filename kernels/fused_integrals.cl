/* Integrands at points made in the same kernel: point generation, evaluation and
 * reduction fused, so no point is ever stored. Python side: clsamp/fused.py; the points
 * are those of the samplers (kernels/lowdiscrepancy.cl's sobol_points, kernels/lattice.cl's
 * lattice_points) from the same primitives (lowdiscrepancy.h, philox.h, f64bits.h) and the
 * integrands those of kernels/integrands.cl (integrand.h).
 *
 * Build options:
 *   DIM, INTEGRAND   the integrand (integrand.h)
 *   POINTS           FUSED_SOBOL: x_i = xor of columns[c] over the set bits c of
 *                    (GRAY ? i ^ (i >> 1) : i), and x_(i+1) = x_i ^ steps[ctz(i + 1)]
 *                    (Gray order: steps = columns; natural order: the prefix xors
 *                    columns[0] ^ .. ^ columns[c]); columns arrive bit-reversed for LD_OWEN,
 *                    as (32, FUSED_ROOM).
 *                    FUSED_LATTICE: frac(reverse_bits32(i) z_j 2^-32 + u_j), z = columns.
 *   GRAY             (FUSED_SOBOL) 1: the sampler's Gray-code order; 0: natural order
 *   RANDOMIZE        LD_SHIFT, LD_XOR or LD_OWEN (lowdiscrepancy.h): realization r's, with
 *                    the sampler's Philox draws (scramble_stream word (j, r, 0).x, shift
 *                    uniform(shift_stream, r, 0, j)); FUSED_LATTICE is always shifted
 *   PERIODIZE        0 none, 1 Baker's tent, 2 Sidi's sin^2 (clsamp.transforms): f(psi(x))
 *                    prod psi'(x_j), each coordinate then clamped below 1 (clsamp.cubature)
 *   FUSED_SUMS       1: out is (realizations, groups) double-double sums of f - integral,
 *                    as integrand_error_sums gives them; 0: out is the n values of f
 *   FUSED_BLOCK      consecutive points per work-item (a multiple of 4)
 *   FUSED_ROOM       (FUSED_SOBOL) the length of a row of columns and steps, >= DIM (zeros
 *                    past DIM: whole-vector rows keep the state's update vectorized); the
 *                    state carries FUSED_ROOM words, of which the points read DIM
 *
 * Grid (groups * local, realizations), work-group (local, 1), local a power of two; work-item
 * g makes points start + g FUSED_BLOCK .. start + (g + 1) FUSED_BLOCK - 1 (those below
 * start + n), four at a time in the lanes of a double4. The order of every addition
 * depends on (n, FUSED_BLOCK, local size) only.
 */
#pragma OPENCL FP_CONTRACT OFF
#include "philox.h"
#include "lowdiscrepancy.h"
#include "integrand.h"

#define FUSED_SOBOL 0
#define FUSED_LATTICE 1

#ifndef POINTS
#error "POINTS must be defined"
#endif
#ifndef GRAY
#define GRAY 1
#endif
#ifndef PERIODIZE
#define PERIODIZE 0
#endif
#ifndef FUSED_BLOCK
#define FUSED_BLOCK 64
#endif

#ifndef FUSED_ROOM
#define FUSED_ROOM DIM
#endif
#define FUSED_ONE_BELOW 0x1.fffffffffffffp-1
#define FUSED_PI 3.141592653589793115997963468544185161590576171875
#define FUSED_TWO_PI 6.28318530717958623199592693708837032318115234375

/* The double of a randomized 32-bit digit vector (Sobol), or of the lattice's point. */
inline double fused_coordinate(const uint x, const ulong random)
{
#if POINTS == FUSED_LATTICE
    return as_double(f64_shift_mod1(f64_scaled(x, -32), random));
#elif RANDOMIZE == LD_OWEN
    return (double)reverse_bits32(lk_hash(x, (uint)random)) * 0x1p-32;
#elif RANDOMIZE == LD_XOR
    return (double)(x ^ (uint)random) * 0x1p-32;
#else   /* LD_SHIFT: (x 2^-32 + u) mod 1, as sobol_points' shift32W_bits */
    const double y = (double)x * 0x1p-32 + as_double(random);
    return y >= 1.0 ? y - 1.0 : y;
#endif
}

/* Lane `lane` of the quad: point `index` (the state holds its digits), then the state of
 * index + 1; a lane past `end` repeats lane s0 (its value is masked). */
#if POINTS == FUSED_SOBOL
#define FUSED_LANE(lane)                                                            \
    do {                                                                            \
        if (k < end) {                                                              \
            for (int j = 0; j < DIM; ++j)                                           \
                x[j].lane = fused_coordinate(state[j], random[j]);                  \
            if (k + 1u < end) {                                                     \
                const uint c = ld_ctz(start + k + 1u);                              \
                for (int j = 0; j < FUSED_ROOM; ++j)                                \
                    state[j] ^= steps[c * FUSED_ROOM + j];                          \
            }                                                                       \
        } else {                                                                    \
            for (int j = 0; j < DIM; ++j)                                           \
                x[j].lane = x[j].s0;                                                \
        }                                                                           \
        ++k;                                                                        \
    } while (0)
#else
#define FUSED_LANE(lane)                                                            \
    do {                                                                            \
        if (k < end) {                                                              \
            const uint radical = reverse_bits32(start + k);                         \
            for (int j = 0; j < DIM; ++j)                                           \
                x[j].lane = fused_coordinate(radical * columns[j], random[j]);      \
        } else {                                                                    \
            for (int j = 0; j < DIM; ++j)                                           \
                x[j].lane = x[j].s0;                                                \
        }                                                                           \
        ++k;                                                                        \
    } while (0)
#endif

/* Sobol: columns and steps are (32, FUSED_ROOM); lattice: columns is z (DIM), steps unused.
 * params: the integrand's (integrand.h); integral: subtracted from every value when
 * FUSED_SUMS (the sums keep their relative accuracy). */
__kernel void fused_integrals(const uint n, const uint start, const uint realization0,
                              const uint key_lo, const uint key_hi, const uint scramble_stream,
                              const uint shift_stream, __global const uint *columns,
                              __global const uint *steps, __global const double *params,
                              const double integral, __global void *out,
                              __local double2 *scratch)
{
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint realization = realization0 + get_global_id(1);
    const uint first = get_global_id(0) * FUSED_BLOCK;
    const uint end = min(n, first + FUSED_BLOCK);      /* relative to start */

    ulong random[DIM];
    for (int j = 0; j < DIM; ++j) {
#if POINTS == FUSED_SOBOL && (RANDOMIZE == LD_XOR || RANDOMIZE == LD_OWEN)
        random[j] = clsamp_block(key, scramble_stream, realization, j, 0).x;
#else
        random[j] = clsamp_uniform_bits(key, shift_stream, realization, 0, j);
#endif
    }
#if POINTS == FUSED_SOBOL
    uint state[FUSED_ROOM];
    for (int j = 0; j < FUSED_ROOM; ++j)
        state[j] = 0u;
    if (first < end) {
        const uint i = start + first;
        uint bits = GRAY ? i ^ (i >> 1) : i;
        while (bits) {
            const uint c = ld_ctz(bits);
            for (int j = 0; j < FUSED_ROOM; ++j)
                state[j] ^= columns[c * FUSED_ROOM + j];
            bits &= bits - 1u;
        }
    }
#endif

#if FUSED_SUMS
    vec sum = (vec)(0.0), err = (vec)(0.0);
#endif
    for (uint k = first; k < end;) {
        const uint k0 = k;
        vec x[DIM];
        FUSED_LANE(s0);
        FUSED_LANE(s1);
        FUSED_LANE(s2);
        FUSED_LANE(s3);
#if PERIODIZE == 1
        for (int j = 0; j < DIM; ++j)
            x[j] = fmin(1.0 - fabs(2.0 * x[j] - 1.0), FUSED_ONE_BELOW);
#elif PERIODIZE == 2
        vec weight = (vec)(1.0);
        for (int j = 0; j < DIM; ++j) {
            const vec s = sin(FUSED_PI * x[j]);
            weight = weight * (2.0 * s * s);
            const vec psi = clamp(x[j] - sin(FUSED_TWO_PI * x[j]) / FUSED_TWO_PI, 0.0, 1.0);
            x[j] = fmin(psi, FUSED_ONE_BELOW);
        }
#elif !FUSED_SUMS
        for (int j = 0; j < DIM; ++j)
            x[j] = fmin(x[j], FUSED_ONE_BELOW);
#endif
        vec v = integrand(x, params);
#if PERIODIZE == 2
        v = v * weight;
#endif
#if FUSED_SUMS
        v = v - integral;
        const long4 live = (long4)(k0, k0 + 1u, k0 + 2u, k0 + 3u) < (long4)(end);
        v = select((vec)(0.0), v, live);
        vec s, e;
        TWO_SUM(vec, sum, v, s, e);
        sum = s;
        err = err + e;
#else
        integrand_store4((__global double *)out, k0, end, v);
#endif
    }
#if FUSED_SUMS
    const double2 total = integrand_group_sum(sum, err, scratch);
    if (get_local_id(0) == 0)
        ((__global double2 *)out)[(size_t)get_global_id(1) * get_num_groups(0) + get_group_id(0)] = total;
#endif
}
