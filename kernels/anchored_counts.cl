/* Points in anchored boxes, for the certified star-discrepancy bounds (star_bounds in
 * clsamp/metrics/star.py, which needs these counts at millions of box corners; NumPy twin:
 * anchored_counts_reference there).
 *
 * Grid (m4 / 4): counts[c] = #{points p : p_k < corner_k for every k} (STRICT 1) or
 * p_k <= corner_k (STRICT 0), four corners a work-item; corners (D, m4) coordinate-major,
 * points (n, D). Comparisons only: the same counts on every device. Without fp64
 * (CLSAMP_FP64 0) the kernel compares the float64 bit patterns as unsigned integers, whose
 * order is the order of the non-negative doubles they encode (points and corners lie in
 * [0, 1]): the same counts, exactly. Build options: D, STRICT. */
#if CLSAMP_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define COORD double
#define COORD4 double4
#else
#define COORD ulong
#define COORD4 ulong4
#endif

__kernel void anchored_counts(__global const COORD *points, const uint n,
                              __global const COORD *corners, const uint m4,
                              __global uint *counts)
{
    const uint w = get_global_id(0);
    if (4 * w >= m4)
        return;
    COORD4 c[D];
    for (int k = 0; k < D; ++k)
        c[k] = *(__global const COORD4 *)(corners + (size_t)k * m4 + 4 * w);
    long4 count = (long4)(0);
    for (uint i = 0; i < n; ++i) {
        __global const COORD *p = points + (size_t)i * D;
#if STRICT
        long4 inside = (COORD4)(p[0]) < c[0];
#pragma unroll
        for (int k = 1; k < D; ++k)
            inside &= (COORD4)(p[k]) < c[k];
#else
        long4 inside = (COORD4)(p[0]) <= c[0];
#pragma unroll
        for (int k = 1; k < D; ++k)
            inside &= (COORD4)(p[k]) <= c[k];
#endif
        /* a true comparison is -1 in every bit: the lanes count down, negated below. Not
         * `count -= inside`: LLVM turns that into a zero extension of the comparison, which
         * Oclgrind 21.10 extends to 255, not 1 (its counts came out 255 times too large) */
        count += inside;
    }
    counts[4 * w] = (uint)-count.x;
    counts[4 * w + 1] = (uint)-count.y;
    counts[4 * w + 2] = (uint)-count.z;
    counts[4 * w + 3] = (uint)-count.w;
}
