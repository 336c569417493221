/* The exact L-infinity star discrepancy over the critical boxes (clsamp/metrics/star.py;
 * NumPy twin: star_discrepancy_reference there). For n points sorted by x, thresholds s
 * (the sorted y values and 1; in 3-D pairs (s, u) of y and z thresholds) and every x value
 * t, the local discrepancies of the closed box [0, t] x [0, s] (count/n - t s) and of the
 * open box [0, t) x [0, s) (t s - count/n) are evaluated in one sweep over the points.
 *
 * Launch: one work-item per four thresholds (2-D: four s; 3-D: one s and four u); each
 * sweeps all n points, so the work is O(n^2) in 2-D and O(n^3) in 3-D. flags[k]: bit 0 the
 * first point of its x value, bit 1 the last. Volumes (t s) u and counts / n, no
 * contraction: the same bits as the twins (the brute force's product over coordinates).
 * Build options: DIM (2 or 3).
 *
 * Without fp64 (CLSAMP_FP64 0) the same float64 result, bit for bit, in integer arithmetic
 * (kernels/f64bits.h): coordinates are compared as bit patterns (the order of non-negative
 * doubles), and a box's value fl(fl(c / n) - fl(fl(t s) u)) (or the reverse) is the
 * correctly rounded IEEE-754 result of the same operations; fl(c / n) comes from a table
 * the host fills (ratios[c], c = 0..n). The largest of those values is fl of the largest
 * exact difference D (rounding is monotone), so the maximum is the fp64 kernel's. Exact
 * evaluation costs tens of integer operations, so every box is first estimated in float,
 * within E = ESTIMATE_ERROR of its exact difference (the bound is derived below). Pass 1
 * (star_estimate) keeps each work-item's largest estimate; M, the largest of all, is the
 * estimate of some box, so M < D + E, and the box of D has an estimate > D - E > M - 2E.
 * Pass 2 (star_sweep) sweeps only the work-items whose largest estimate reaches M - 2E,
 * and evaluates exactly the boxes whose estimates reach b - 2E, b the largest of M and of
 * the estimates of the boxes it evaluated (each < D + E): the box of D is among them, and
 * the largest value found is fl(D). Both passes carry their counts in a state buffer, so
 * the host may cut the sweep into launches over a few points (llvmpipe's loop limit).
 * Coordinates below 2^-300 enter the volumes as 0: such a volume is below 2^-600 either
 * way, which changes no value fl(c / n - v) with c >= 1 (c / n >= 2^-32, its ulp far
 * above), and a value v - c / n below 2^-600 is never the maximum (D* >= 1 / (2n), the
 * bound of the first coordinate's projection); every volume then stays in the normal
 * range that f64bits.h's products need.
 */
#include "f64bits.h"
#pragma OPENCL FP_CONTRACT OFF

#if CLSAMP_FP64

inline double4 vmax4(const double4 a, const double4 b) { return a > b ? a : b; }

/* out[w] = the largest local discrepancy the work-item's thresholds give */
__kernel void star_sweep(__global const double *xs, __global const double *ys,
                         __global const double *zs, __global const uchar *flags, const uint n,
                         __global const double *sy, __global const double *sz, const uint ny,
                         const uint nz4, __global double *out)
{
    const uint w = get_global_id(0);
#if DIM == 2
    if (w >= nz4)
        return;
    const double4 s = *(__global const double4 *)(sy + 4 * w);
    const double4 u = (double4)(1.0);
#else
    if (w >= ny * nz4)
        return;
    const double4 s = (double4)(sy[w / nz4]);
    const double4 u = *(__global const double4 *)(sz + 4 * (w % nz4));
#endif
    const double count = (double)n;
    double4 closed = (double4)(0.0), open = (double4)(0.0), best = (double4)(0.0);
    for (uint k = 0; k < n; ++k) {
        const double t = xs[k];
        const uchar f = flags[k];
        const double4 volume = ((double4)(t) * s) * u;
        if (f & 1)                   /* [0, t) x [0, s): the points before t, strictly below */
            best = vmax4(best, volume - open / count);
        const double y = ys[k];
#if DIM == 2
        closed += (double4)(y) <= s ? (double4)(1.0) : (double4)(0.0);
        open += (double4)(y) < s ? (double4)(1.0) : (double4)(0.0);
#else
        const double z = zs[k];
        closed += (((double4)(y) <= s) & ((double4)(z) <= u)) ? (double4)(1.0) : (double4)(0.0);
        open += (((double4)(y) < s) & ((double4)(z) < u)) ? (double4)(1.0) : (double4)(0.0);
#endif
        if (f & 2)                   /* [0, t] x [0, s]: every point up to t */
            best = vmax4(best, closed / count - volume);
    }
    best = vmax4(best, (s * u) - open / count);      /* t = 1 */
    out[w] = fmax(fmax(best.x, best.y), fmax(best.z, best.w));
}

#else   /* integer arithmetic only */

#define TINY 0x12B0000000000000UL          /* 2^-300 */

/* |estimate - exact difference| < ESTIMATE_ERROR = 2^-19 = 32 u (u = 2^-24), for counts
 * c <= n and coordinates in [0, 1]. c n^-1 in float is within 3 u (c / n) of c / n
 * (float(c), exact below 2^24; 1 / n; the product: one rounding each), and fl(c / n)
 * within 2^-53 of it. A volume estimate: three coordinates truncated to float (each within
 * 2 u relative, or 2^-126 absolute where flushed) and two float products (1 u each, or
 * 2^-126 flushed) are within 8 u (1 + 8 u) + 5 2^-126 of the exact product, which the
 * double volume is within 2^-52 of (and 2^-600 where TINY flushes). The difference of the
 * two estimates (at most 1 + 8 u) rounds with 1 u (1 + 8 u). In all below 13 u: E is
 * more than twice the bound. */
#define ESTIMATE_ERROR 0x1p-19f

/* A non-negative double (bits) truncated to float; 0 below 2^-126. */
inline float f64_estimate(ulong x)
{
    const int e = (int)(x >> 52) - 1023;
    return e < -126 ? 0.0f : as_float(((uint)(e + 127) << 23) | (uint)((x >> 29) & 0x7FFFFFu));
}

inline ulong volume_coordinate(ulong x) { return x < TINY ? 0 : x; }

/* fl(a - b) for a > b, else 0 (the value of a box that cannot beat the start, 0) */
inline ulong positive_difference(ulong a, ulong b) { return a > b ? f64_sub(a, b) : 0; }

/* The exact volume fl(fl(t s) u) of one box (fl(t s) in 2-D). */
inline ulong exact_volume(ulong t, ulong s, ulong u)
{
    const ulong ts = f64_mul(volume_coordinate(t), volume_coordinate(s));
#if DIM == 2
    return ts;
#else
    return f64_mul(ts, volume_coordinate(u));
#endif
}

/* The boxes of estimates d (one per lane) at x value t that pass the filter, evaluated
 * exactly: open (the volume minus counts / n) or closed (the reverse). Lanes are read from
 * private arrays: Oclgrind 21.10 simulates a chain `i == 0 ? v.x : i == 1 ? v.y : ...`
 * wrongly (kernels/philox.h, clsamp_lane). */
inline void evaluate(const float4 d, const int open, const ulong t, const ulong4 s, const ulong4 u,
                     const int4 counts, __global const ulong *ratios, ulong *best, float *best_f)
{
    const float threshold = *best_f - 2.0f * ESTIMATE_ERROR;
    if (!any(d >= (float4)(threshold)))
        return;
    float e[4];
    ulong sv[4], uv[4];
    int c[4];
    vstore4(d, 0, e);
    vstore4(s, 0, sv);
    vstore4(u, 0, uv);
    vstore4(counts, 0, c);
    for (int i = 0; i < 4; ++i) {
        if (e[i] < threshold)
            continue;
        const ulong volume = exact_volume(t, sv[i], uv[i]);
        const ulong ratio = ratios[c[i]];
        const ulong value = open ? positive_difference(volume, ratio)
                                 : positive_difference(ratio, volume);
        *best = max(*best, value);
        *best_f = fmax(*best_f, e[i]);
    }
}

/* The sweep of work-item `item` (its four thresholds as in the fp64 kernel) over the
 * points [k0, k1), from and to its state (12 words: the counts of the closed and open
 * boxes, then EXACT 0 the largest estimate of each lane, EXACT 1 the best value's bits
 * (2 words) and the best estimate, at st); where k1 = n the boxes of t = 1 close the sweep and
 * the result is returned. EXACT 0: the largest estimate of the work-item's boxes (as float
 * bits). EXACT 1: the bits of the largest value of its boxes whose estimates are no more
 * than 2 ESTIMATE_ERROR below the best estimate so far, which starts at the host's, an
 * estimate of some box. */
inline ulong sweep(const int exact, const uint item, __global const ulong *xs,
                   __global const ulong *ys, __global const ulong *zs,
                   __global const uchar *flags, const uint n, __global const ulong *sy,
                   __global const ulong *sz, const uint nz4, __global const ulong *ratios,
                   const float inverse_n, const uint k0, const uint k1, __global uint *st)
{
#if DIM == 2
    const ulong4 s = vload4(item, sy);
    const ulong4 u = (ulong4)(F64_ONE);
#else
    const ulong4 s = (ulong4)(sy[item / nz4]);
    const ulong4 u = vload4(item % nz4, sz);
#endif
    const float4 su_f = (float4)(f64_estimate(s.x), f64_estimate(s.y), f64_estimate(s.z),
                                 f64_estimate(s.w))
                        * (float4)(f64_estimate(u.x), f64_estimate(u.y), f64_estimate(u.z),
                                   f64_estimate(u.w));
    /* bit 63 is 0: signed comparisons order them as well (and vectorize on more CPUs) */
    const long4 sl = as_long4(s), ul = as_long4(u);
    int4 closed = as_int4(vload4(0, st)), open = as_int4(vload4(1, st));
    float4 top = as_float4(vload4(2, st));
    ulong best = (ulong)st[8] | ((ulong)st[9] << 32);
    float best_f = as_float(st[10]);
    for (uint k = k0; k < k1; ++k) {
        const ulong t = xs[k];
        const uchar f = flags[k];
        const float4 volume_f = (float4)(f64_estimate(t)) * su_f;
        if (f & 1) {                 /* [0, t) x [0, s): the points before t, strictly below */
            const float4 d = volume_f - convert_float4(open) * inverse_n;
            if (exact)
                evaluate(d, 1, t, s, u, open, ratios, &best, &best_f);
            else
                top = fmax(top, d);
        }
        const long y = (long)ys[k];
#if DIM == 2
        closed -= convert_int4((long4)(y) <= sl);        /* a true comparison is -1 */
        open -= convert_int4((long4)(y) < sl);
#else
        const long z = (long)zs[k];
        closed -= convert_int4(((long4)(y) <= sl) & ((long4)(z) <= ul));
        open -= convert_int4(((long4)(y) < sl) & ((long4)(z) < ul));
#endif
        if (f & 2) {                 /* [0, t] x [0, s]: every point up to t */
            const float4 d = convert_float4(closed) * inverse_n - volume_f;
            if (exact)
                evaluate(d, 0, t, s, u, closed, ratios, &best, &best_f);
            else
                top = fmax(top, d);
        }
    }
    if (k1 < n) {
        vstore4(as_uint4(closed), 0, st);
        vstore4(as_uint4(open), 1, st);
        if (exact) {
            st[8] = (uint)best;
            st[9] = (uint)(best >> 32);
            st[10] = as_uint(best_f);
        } else {
            vstore4(as_uint4(top), 2, st);
        }
        return 0;
    }
    const float4 d = su_f - convert_float4(open) * inverse_n;              /* t = 1 */
    if (!exact) {
        top = fmax(top, d);
        return as_uint(fmax(fmax(top.x, top.y), fmax(top.z, top.w)));
    }
    evaluate(d, 1, F64_ONE, s, u, open, ratios, &best, &best_f);
    return best;
}

/* Pass 1, every work-item: estimates[w] = the largest estimate of its boxes. */
__kernel void star_estimate(__global const ulong *xs, __global const ulong *ys,
                            __global const ulong *zs, __global const uchar *flags, const uint n,
                            __global const ulong *sy, __global const ulong *sz, const uint items,
                            const uint nz4, const float inverse_n, const uint k0, const uint k1,
                            __global uint *state, __global float *estimates)
{
    const uint w = get_global_id(0);
    if (w >= items)
        return;
    const ulong top = sweep(0, w, xs, ys, zs, flags, n, sy, sz, nz4, 0, inverse_n, k0, k1,
                           state + (size_t)12 * w);
    if (k1 == n)
        estimates[w] = as_float((uint)top);
}

/* Pass 2, the work-items the host picked (those whose largest estimate is within
 * 2 ESTIMATE_ERROR of the largest of all): out[w] = the bits of the largest local
 * discrepancy among their boxes that could be D*, the fp64 kernel's double for D*. */
__kernel void star_sweep(__global const ulong *xs, __global const ulong *ys,
                         __global const ulong *zs, __global const uchar *flags, const uint n,
                         __global const ulong *sy, __global const ulong *sz,
                         __global const uint *picked, const uint count, const uint nz4,
                         __global const ulong *ratios, const float inverse_n, const uint k0,
                         const uint k1, __global uint *state, __global ulong *out)
{
    const uint w = get_global_id(0);
    if (w >= count)
        return;
    const ulong best = sweep(1, picked[w], xs, ys, zs, flags, n, sy, sz, nz4, ratios, inverse_n,
                             k0, k1, state + (size_t)12 * w);
    if (k1 == n)
        out[w] = best;
}

#endif
