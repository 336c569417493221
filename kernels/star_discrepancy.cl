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
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

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
