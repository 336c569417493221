/* L2-type discrepancies in closed form over pairs (clsamp/metrics/l2.py; NumPy twin:
 * discrepancy_reference there). For n points x_i in [0, 1)^D,
 *     D^2 = c0 + c1 / n * sum_i prod_k f(x_ik) + c2 / n^2 * sum_i sum_j prod_k g(x_ik, x_jk)
 * with f, g and the constants of the method (METHOD, below). These kernels compute the
 * per-point products (discrepancy_prepare) and the pair sum (discrepancy_pairs); the host
 * adds the sums exactly and applies the constants.
 *
 * Build options: METHOD (0 CD, 1 WD, 2 MD, 3 L2-star, 4 symmetric, 5 L2 unanchored), D (the
 * dimension, unrolled), RV (row vectors of four a work-item holds, 1 or 2), SORT0 (the points
 * come sorted by their first coordinate), CHUNK (columns summed plainly before a compensated
 * add). Built with -cl-mad-enable: a measurement, not a sampler; every run on one device
 * gives the same bits.
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

#ifndef RV
#define RV 1
#endif
#ifndef CHUNK
#define CHUNK 64
#endif
#define RB (4 * RV)
#ifndef SORT0
#define SORT0 0
#endif
/* the left half of a product over D factors: the largest power of two below D, at most 8 */
#define HALF (D > 8 ? 8 : D > 4 ? 4 : D > 2 ? 2 : 1)

/* |v|, max, min without built-ins: PoCL calls fabs, fmax, fmin and select out of line,
 * which costs more than the arithmetic of a pair */
inline double4 vabs(const double4 v)
{
    return as_double4(as_ulong4(v) & (ulong4)(0x7FFFFFFFFFFFFFFFUL));
}
inline double4 vmax(const double4 a, const double4 b) { return a > b ? a : b; }
inline double4 vmin(const double4 a, const double4 b) { return a < b ? a : b; }
inline double4 vxor(const double4 a, const double4 b)
{
    return as_double4(as_ulong4(a) ^ as_ulong4(b));
}
inline double sabs(const double v) { return v < 0.0 ? -v : v; }
/* 3/2 - t + t^2 and c - 3t/4 + t^2/2 in the fewest operations (t = |x_i - x_j|) */
inline double4 wd_term(const double4 t) { return t * (t - 1.0) + 1.5; }
inline double4 md_term(const double4 c, const double4 t) { return t * (0.5 * t - 0.75) + c; }

/* g over double4 lanes. Each point stores, per dimension, two numbers for its role as a
 * row (X, U) and two as a column (X, V); a = |x - 1/2|. Every form below rounds as little
 * as it can: the factors of L2-star, symmetric and CD are exact or rounded once, so the
 * rounding errors of the n^2 terms carry no bias (the textbook CD form, 1 + a_i/2 + a_j/2
 * - |x_i - x_j|/2 in three roundings, is biased by about -7e-17 relative per term, which
 * the cancellation of the formula turns into 1e-12 of D^2 at n = 16384). G0 is the first
 * factor when x_i0 <= x_j0 (SORT0): no |.|, and for L2-star, symmetric and L2 less still. */
#if METHOD == 0
/* 1 + min(a_i, a_j) on the same side of 1/2, 1 across it: the column holds 1 + a with the
 * sign of x - 1/2, the row 1 + a and its side as a sign bit (U = -0 below 1/2): the column
 * flipped by the row's sign is >= 1 exactly when both are on one side. */
#define XR(x, a) (1.0 + (a))
#define UR(x, a) ((x) < 0.5 ? -0.0 : 0.0)
#define XC(x, a) ((x) < 0.5 ? -(1.0 + (a)) : 1.0 + (a))
#define VC(x, a) (0.0)
#define G(xi, ui, xj, vj) vmax((double4)(1.0), vmin((xi), vxor((xj), (ui))))
#define G0(xi, ui, xj, vj) G(xi, ui, xj, vj)
#define F(x, a) (1.0 + 0.5 * (a) - 0.5 * (a) * (a))
#elif METHOD == 1          /* 3/2 - |x_i - x_j| + (x_i - x_j)^2 */
#define XR(x, a) (x)
#define UR(x, a) (0.0)
#define XC(x, a) (x)
#define VC(x, a) (0.0)
#define G(xi, ui, xj, vj) wd_term(vabs((xi) - (xj)))
#define G0(xi, ui, xj, vj) wd_term((xj) - (xi))
#define F(x, a) (1.0)
#elif METHOD == 2          /* 15/8 - a_i/4 - a_j/4 - 3|x_i - x_j|/4 + (x_i - x_j)^2 / 2 */
#define XR(x, a) (x)
#define UR(x, a) (1.875 - 0.25 * (a))
#define XC(x, a) (x)
#define VC(x, a) (0.25 * (a))
#define G(xi, ui, xj, vj) md_term((ui) - (vj), vabs((xi) - (xj)))
#define G0(xi, ui, xj, vj) md_term((ui) - (vj), (xj) - (xi))
#define F(x, a) (5.0 - 0.75 * (a) - 0.75 * (a) * (a))  /* 3 f: 5/3 is not a double */
#elif METHOD == 3          /* 1 - max(x_i, x_j) = min(1 - x_i, 1 - x_j), exact */
#define XR(x, a) (1.0 - (x))
#define UR(x, a) (0.0)
#define XC(x, a) (1.0 - (x))
#define VC(x, a) (0.0)
#define G(xi, ui, xj, vj) vmin((xi), (xj))
#define G0(xi, ui, xj, vj) (xj)
#define F(x, a) (1.0 - (x) * (x))
#elif METHOD == 4          /* 1 - |x_i - x_j| = (1 - x_i - x_j) + 2 min, exact */
#define XR(x, a) (x)
#define UR(x, a) (1.0 - (x))
#define XC(x, a) (x)
#define VC(x, a) (x)
#define G(xi, ui, xj, vj) (((ui) - (vj)) + 2.0 * vmin((xi), (xj)))
#define G0(xi, ui, xj, vj) (((xi) - (xj)) + 1.0)
#define F(x, a) (1.0 + 2.0 * (x) - 2.0 * (x) * (x))
#elif METHOD == 5          /* min(x_i, x_j) - x_i x_j = min(x_i, x_j) min(1 - x_i, 1 - x_j) */
#define XR(x, a) (x)
#define UR(x, a) (1.0 - (x))
#define XC(x, a) (x)
#define VC(x, a) (1.0 - (x))
#define G(xi, ui, xj, vj) (vmin((xi), (xj)) * vmin((ui), (vj)))
#define G0(xi, ui, xj, vj) ((xi) * (vj))
#define F(x, a) ((x) * (1.0 - (x)))
#else
#error "METHOD must be 0..5"
#endif

/* Grid (npad, realizations): points (r, n, D) to the rows' layout xr, ur (r, D, npad) (four
 * consecutive rows of one dimension load as a double4), the columns' layout xc, vc
 * (r, npad, D) (one column's D numbers together) and the per-point product f (r, npad);
 * padding (i >= n) gets x = 0 and f = 0, and the pair kernel masks its rows. */
__kernel void discrepancy_prepare(__global const double *points, const uint n, const uint npad,
                                  __global double *xr, __global double *ur, __global double *xc,
                                  __global double *vc, __global double *f)
{
    const uint i = get_global_id(0), r = get_global_id(1);
    if (i >= npad)
        return;
    double prod = i < n ? 1.0 : 0.0;
    for (uint k = 0; k < D; ++k) {
        const double x = i < n ? points[((size_t)r * n + i) * D + k] : 0.0;
        const double a = sabs(x - 0.5);
        const size_t row = ((size_t)r * D + k) * npad + i, col = ((size_t)r * npad + i) * D + k;
        xr[row] = XR(x, a);
        ur[row] = UR(x, a);
        xc[col] = XC(x, a);
        vc[col] = VC(x, a);
        prod *= F(x, a);
    }
    f[(size_t)r * npad + i] = prod;
}

/* (s, c) += v, Neumaier's compensated sum */
inline void two_add(double *s, double *c, const double v)
{
    const double t = *s + v;
    *c += sabs(*s) >= sabs(v) ? (*s - t) + v : (v - t) + *s;
    *s = t;
}

/* acc + prod_k g(four rows, one column): the rows' numbers per dimension, the column's D.
 * With SORT0 the points are sorted by their first coordinate, so a row's x_0 is at most its
 * column's and the first factor takes the cheaper form G0. The product is a tree (a shorter
 * dependency chain) whose last multiplication is fused with the addition. */
inline double4 term_add(const double4 acc, const double4 *xv, const double4 *uv,
                        __global const double *cx, __global const double *cv)
{
    double4 g[D];
#if SORT0
    g[0] = G0(xv[0], uv[0], (double4)(cx[0]), (double4)(cv[0]));
#else
    g[0] = G(xv[0], uv[0], (double4)(cx[0]), (double4)(cv[0]));
#endif
#pragma unroll
    for (int k = 1; k < D; ++k)
        g[k] = G(xv[k], uv[k], (double4)(cx[k]), (double4)(cv[k]));
#if D == 1
    return g[0] + acc;
#else
    double4 left = g[0], right = g[HALF];
#pragma unroll
    for (int k = 1; k < HALF; ++k)
        left *= g[k];
#pragma unroll
    for (int k = HALF + 1; k < D; ++k)
        right *= g[k];
    return left * right + acc;
#endif
}

/* Grid (items, realizations). Rows come in blocks of RB = 4 RV, held as RV double4 per
 * dimension; block q pairs with the columns from its own block on (the sum is symmetric:
 * twice the strict upper part plus the diagonal block's own terms), and work-item w takes
 * blocks w and nb - 1 - w so every item does about the same work. out (r, nb, 2): per row
 * block, the sum as (hi, lo). */
__kernel void discrepancy_pairs(__global const double *xr, __global const double *ur,
                                __global const double *xc, __global const double *vc,
                                __global const double *valid, const uint n, const uint npad,
                                const uint nb, const uint items, __global double *out)
{
    const uint w = get_global_id(0), r = get_global_id(1);
    if (w >= items)
        return;
    __global const double *rx = xr + (size_t)r * D * npad;
    __global const double *ru = ur + (size_t)r * D * npad;
    __global const double *cx = xc + (size_t)r * D * npad;
    __global const double *cv = vc + (size_t)r * D * npad;
    for (int side = 0; side < 2; ++side) {
        const uint q = side ? nb - 1 - w : w;
        if (side && q == w)
            break;
        const uint i0 = q * RB;
        double4 xi[RV][D], ui[RV][D], mask[RV];
        for (int v = 0; v < RV; ++v) {
            for (int k = 0; k < D; ++k) {
                xi[v][k] = *(__global const double4 *)(rx + (size_t)k * npad + i0 + 4 * v);
                ui[v][k] = *(__global const double4 *)(ru + (size_t)k * npad + i0 + 4 * v);
            }
            mask[v] = *(__global const double4 *)(valid + i0 + 4 * v);
        }
        /* the strict upper part: columns [i0 + RB, n), each pair once */
        double s[RV][4], c[RV][4];
        for (int v = 0; v < RV; ++v)
            for (int l = 0; l < 4; ++l)
                s[v][l] = c[v][l] = 0.0;
        for (uint jc = i0 + RB; jc < n; jc += CHUNK) {
            const uint stop = jc + CHUNK < n ? jc + CHUNK : n;
            double4 acc[RV];
            for (int v = 0; v < RV; ++v)
                acc[v] = (double4)(0.0);
            for (uint j = jc; j < stop; ++j)
#pragma unroll
                for (int v = 0; v < RV; ++v)
                    acc[v] = term_add(acc[v], xi[v], ui[v], cx + (size_t)j * D,
                                      cv + (size_t)j * D);
            for (int v = 0; v < RV; ++v) {
                two_add(&s[v][0], &c[v][0], acc[v].x);
                two_add(&s[v][1], &c[v][1], acc[v].y);
                two_add(&s[v][2], &c[v][2], acc[v].z);
                two_add(&s[v][3], &c[v][3], acc[v].w);
            }
        }
        double hi = 0.0, lo = 0.0;
        for (int v = 0; v < RV; ++v) {
            const double m[4] = {mask[v].x, mask[v].y, mask[v].z, mask[v].w};
            for (int l = 0; l < 4; ++l) {
                two_add(&hi, &lo, 2.0 * m[l] * s[v][l]);
                lo += 2.0 * m[l] * c[v][l];
            }
        }
        /* the diagonal block: pairs (i, j) with i < j twice, (i, i) once */
        const double4 lane = (double4)(0.0, 1.0, 2.0, 3.0);
        for (uint j = i0; j < i0 + RB && j < n; ++j)
            for (int v = 0; v < RV; ++v) {
                const double4 row = lane + (double)(i0 + 4 * v);
                const double4 weight = row < (double)j ? (double4)(2.0)
                                       : (row == (double)j ? (double4)(1.0) : (double4)(0.0));
                const double4 t = term_add((double4)(0.0), xi[v], ui[v], cx + (size_t)j * D,
                                           cv + (size_t)j * D) * (weight * mask[v]);
                two_add(&hi, &lo, t.x);
                two_add(&hi, &lo, t.y);
                two_add(&hi, &lo, t.z);
                two_add(&hi, &lo, t.w);
            }
        out[((size_t)r * nb + q) * 2] = hi;
        out[((size_t)r * nb + q) * 2 + 1] = lo;
    }
}
