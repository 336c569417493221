/* Power spectra of point sets: the exact separable sum ("direct" method).
 *
 * NumPy references in clsamp/spectrum.py: twiddles_reference (spectrum_twiddles),
 * direct_reference (spectrum_direct1/2 + spectrum_power). The NUFFT's spreading is in nufft.cl.
 *
 * Spectra are measurements, not sampler bits: these kernels are built with -cl-mad-enable
 * (an FMA instead of a multiply and an add changes results by an ulp, well inside the
 * documented error bound). Phases are reduced exactly in 64-bit fixed point, so no
 * precision is lost to large u*x products.
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

#define TILE_U 4          /* register tile: one double4 of u frequencies ... */
#define TILE_V 4          /* ... times four v frequencies */
#ifndef SUPER
#define SUPER 4           /* register tiles per work-item along u and along v */
#endif
#ifndef KBLOCK
#define KBLOCK 128        /* points per cache block */
#endif
#ifndef FINE
#define FINE 16           /* twiddles per exact sincos: e(fX) = e(qFINE X) e(sX) */
#endif

/* 2 pi / 2^64: turns a 64-bit fixed-point phase into radians (exact scaling by 2^-64). */
#define PHASE_TO_RADIANS (0x1.921fb54442d18p+2 * 0x1p-64)

/* x in [0, 1) as a 64-bit fixed-point fraction, x * 2^64 truncated: every step is exact
 * (scaling by 2^32, taking a fractional part), so only bits below 2^-64 are lost. */
inline ulong fixed64(const double x)
{
    const double s = x * 4294967296.0;
    const double h = floor(s);
    const uint lo = (uint)((s - h) * 4294967296.0);
    return ((ulong)(uint)h << 32) | (ulong)lo;
}

/* e^{-2 pi i theta_l / 2^64} for four phases already reduced modulo 1 (uint64 wraparound)
 * at once: PoCL's double4 sincos runs far faster than four scalar calls. */
inline void twiddle4(const ulong4 theta, double4 *re, double4 *im)
{
    const double4 angle = convert_double4(as_long4(theta)) * PHASE_TO_RADIANS;
    double4 c;
    const double4 s = sincos(angle, &c);
    *re = c;
    *im = -s;
}

#if FINE % 4
#error "FINE must be a multiple of 4 (the steps are made four at a time)"
#endif

/* Twiddles e^{-2 pi i f x_k} of one coordinate (axis) for the frequencies f = f0 + m,
 * m in [0, count), count a multiple of `tile`, packed for the product kernels: one panel per
 * tile of frequencies, point-major inside the panel, `tile` real parts then `tile` imaginary
 * parts per point:
 *     out[(((r * (count / tile) + m / tile) * n + k) * 2 + {0: re, 1: im}) * tile + m % tile]
 * Only count / FINE + FINE sincos per point: e(fX) = e((f0 + q FINE) X) * e(s X), each factor
 * from an exactly reduced phase, so every twiddle is within a few ulps.
 * Grid (n, realizations). */
__kernel void spectrum_twiddles(__global const double *points, __global double *out,
                                const uint n, const uint d, const uint axis, const long f0,
                                const uint count, const uint tile)
{
    const uint k = get_global_id(0);
    const uint r = get_global_id(1);
    if (k >= n)
        return;
    const ulong X = fixed64(points[((size_t)r * n + k) * d + axis]);
    double step_re[FINE], step_im[FINE];
    for (uint s = 0; s < FINE; s += 4) {
        double4 re, im;
        twiddle4((ulong4)(s, s + 1, s + 2, s + 3) * X, &re, &im);
        vstore4(re, 0, step_re + s);
        vstore4(im, 0, step_im + s);
    }
    const uint tiles = count / tile;
    const uint coarse = (count + FINE - 1) / FINE;
    for (uint q0 = 0; q0 < coarse; q0 += 4) {
        double4 base_re, base_im;
        const long4 f = (long4)(f0) + (long4)(q0, q0 + 1, q0 + 2, q0 + 3) * (long)FINE;
        twiddle4(as_ulong4(f) * X, &base_re, &base_im);
        double bre[4], bim[4];
        vstore4(base_re, 0, bre);
        vstore4(base_im, 0, bim);
        for (uint l = 0; l < 4 && q0 + l < coarse; ++l) {
            for (uint s = 0; s < FINE; ++s) {
                const uint m = (q0 + l) * FINE + s;
                if (m >= count)
                    break;
                const double wr = bre[l] * step_re[s] - bim[l] * step_im[s];
                const double wi = bre[l] * step_im[s] + bim[l] * step_re[s];
                __global double *p = out + (((size_t)r * tiles + m / tile) * n + k) * 2 * tile;
                p[m % tile] = wr;
                p[tile + m % tile] = wi;
            }
        }
    }
}

/* One block of the 2-D sums of exponentials, as a blocked complex product:
 *     S_r(u, v) += sum_{k in this block of points} a_k(u) b_k(v)
 * S is (realizations, 2, TILE_U * tiles_u, TILE_V * tiles_v): real plane then imaginary plane.
 * The register tile is TILE_U x TILE_V (double4 over u): 32 flops per 16 doubles read, every
 * accumulator in a register. Each work-item owns SUPER x SUPER register tiles and walks the
 * points in blocks of KBLOCK, so the panel blocks it reads stay in L1/L2 and are reused SUPER
 * times; without that blocking the kernel streamed panels from DRAM at a fifth of the speed.
 * A and B come from spectrum_twiddles with tile TILE_U and TILE_V.
 * Grid (ceil(tiles_v / SUPER), ceil(tiles_u / SUPER)). */
__kernel void spectrum_direct2(__global const double *A, __global const double *B,
                               __global double *S, const uint n, const uint tiles_u,
                               const uint tiles_v, const uint realizations)
{
    const uint sv0 = get_global_id(0) * SUPER;
    const uint su0 = get_global_id(1) * SUPER;
    if (sv0 >= tiles_v || su0 >= tiles_u)
        return;
    const uint nu = min((uint)SUPER, tiles_u - su0);
    const uint nv = min((uint)SUPER, tiles_v - sv0);
    const size_t width = (size_t)tiles_v * TILE_V;
    const size_t plane = (size_t)tiles_u * TILE_U * width;
    double4 acc[SUPER][SUPER][2 * TILE_V];
    for (uint r = 0; r < realizations; ++r) {
        for (uint i = 0; i < SUPER; ++i)
            for (uint j = 0; j < SUPER; ++j)
                for (uint t = 0; t < 2 * TILE_V; ++t)
                    acc[i][j][t] = (double4)(0.0);
        for (uint k0 = 0; k0 < n; k0 += KBLOCK) {
            const uint kn = min((uint)KBLOCK, n - k0);
            for (uint i = 0; i < nu; ++i) {
                __global const double *pa0 = A + (((size_t)r * tiles_u + su0 + i) * n + k0) * 2 * TILE_U;
                for (uint j = 0; j < nv; ++j) {
                    __global const double *pa = pa0;
                    __global const double *pb = B + (((size_t)r * tiles_v + sv0 + j) * n + k0) * 2 * TILE_V;
                    double4 re0 = acc[i][j][0], re1 = acc[i][j][1], re2 = acc[i][j][2], re3 = acc[i][j][3];
                    double4 im0 = acc[i][j][4], im1 = acc[i][j][5], im2 = acc[i][j][6], im3 = acc[i][j][7];
                    for (uint k = 0; k < kn; ++k) {
                        /* typed loads, not vload4: PoCL calls vload4 as a function, and the
                         * call spills every accumulator on each step (docs/design.md,
                         * "Kernels and the runtime") */
                        const double4 ar = ((__global const double4 *)pa)[0];
                        const double4 ai = ((__global const double4 *)pa)[1];
#define CLSAMP_MAC(t) { const double br = pb[t], bi = pb[TILE_V + t]; \
                re##t = ar * br + re##t; re##t = re##t - ai * bi; \
                im##t = ar * bi + im##t; im##t = ai * br + im##t; }
                        CLSAMP_MAC(0) CLSAMP_MAC(1) CLSAMP_MAC(2) CLSAMP_MAC(3)
#undef CLSAMP_MAC
                        pa += 2 * TILE_U;
                        pb += 2 * TILE_V;
                    }
                    acc[i][j][0] = re0; acc[i][j][1] = re1; acc[i][j][2] = re2; acc[i][j][3] = re3;
                    acc[i][j][4] = im0; acc[i][j][5] = im1; acc[i][j][6] = im2; acc[i][j][7] = im3;
                }
            }
        }
        __global double *s = S + (size_t)r * 2 * plane;
        for (uint i = 0; i < nu; ++i)
            for (uint j = 0; j < nv; ++j) {
                const size_t at = (size_t)(su0 + i) * TILE_U * width + (size_t)(sv0 + j) * TILE_V;
                for (uint t = 0; t < 2 * TILE_V; ++t) {
                    __global double *o = s + at + (t / TILE_V) * plane + t % TILE_V;
                    o[0] += acc[i][j][t].s0;
                    o[width] += acc[i][j][t].s1;
                    o[2 * width] += acc[i][j][t].s2;
                    o[3 * width] += acc[i][j][t].s3;
                }
            }
    }
}

/* One block of the 1-D sums S_r(u) += sum_k a_k(u); S is (realizations, 2, TILE_U * tiles_u).
 * Grid (tiles_u, realizations). */
__kernel void spectrum_direct1(__global const double *A, __global double *S, const uint n,
                               const uint tiles_u)
{
    const uint tu = get_global_id(0);
    const uint r = get_global_id(1);
    if (tu >= tiles_u)
        return;
    __global const double4 *pa = (__global const double4 *)(A + ((size_t)r * tiles_u + tu) * n * 2 * TILE_U);
    double4 re = (double4)(0.0), im = (double4)(0.0);
    for (uint k = 0; k < n; ++k) {
        re += pa[2 * k];
        im += pa[2 * k + 1];
    }
    __global double4 *s = (__global double4 *)(S + (size_t)r * 2 * tiles_u * TILE_U);
    s[tu] += re;
    s[tiles_u + tu] += im;
}

/* power[f] += scale * sum_r (re_r[f]^2 + im_r[f]^2) for S as written above (size numbers per
 * plane). Grid (size). */
__kernel void spectrum_power(__global const double *S, __global double *power, const uint size,
                             const uint realizations, const double scale)
{
    const uint f = get_global_id(0);
    if (f >= size)
        return;
    double sum = 0.0;
    for (uint r = 0; r < realizations; ++r) {
        const double re = S[(size_t)r * 2 * size + f];
        const double im = S[((size_t)r * 2 + 1) * size + f];
        sum += re * re + im * im;
    }
    power[f] += scale * sum;
}
