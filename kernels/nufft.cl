/* The spreading step of a type-1 non-uniform FFT, for the "fast" power spectrum.
 * NumPy reference: clsamp.spectrum.spread_reference. The FFT and the deconvolution run on the
 * host (clsamp/spectrum.py).
 *
 * Build options: DIM (1, 2 or 3), WIDTH (kernel width in grid nodes, <= 16). Built with
 * -cl-mad-enable: spectra are measurements, and the NUFFT's error bound is far above an ulp.
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

/* The WIDTH weights of one axis, phi((i0 + l - t) 2 / WIDTH) for l = 0..WIDTH-1, into
 * w[0..15] (lanes >= WIDTH are 0), phi the exponential of semicircle kernel
 * exp(beta (sqrt(1 - z^2) - 1)) (Barnett, Magland, af Klinteberg 2019). In double4
 * pieces: PoCL runs scalar double exp far slower than its vector form, and no wider vector
 * may reach a built-in (docs/design.md, "Kernels and the runtime"). Returns
 * i0 = ceil(t - WIDTH / 2), the first node. */
inline int axis_weights(const double t, const double beta, double *w)
{
    const int i0 = (int)ceil(t - 0.5 * WIDTH);
    const double base = (double)i0 - t;
    for (int q = 0; q < (WIDTH + 3) / 4; ++q) {
        const double4 lane = (double4)(4 * q, 4 * q + 1, 4 * q + 2, 4 * q + 3);
        const double4 z = (base + lane) * (2.0 / WIDTH);
        const double4 z2 = z * z;
        /* sqrt(1 - z^2) - 1 without cancellation, so the weights near the centre, which
         * every point's sum is made of, are accurate to an ulp or two */
        const double4 phi = exp(-beta * z2 / (1.0 + sqrt(fmax(1.0 - z2, 0.0))));
        vstore4(select((double4)(0.0), phi, lane < (double4)(WIDTH)), q, w);
    }
    return i0;
}

inline int wrap(const int i, const int M)
{
    return i < 0 ? i + M : (i >= M ? i - M : i);
}

/* Add a * (wys[0..WIDTH-1]) to the WIDTH nodes j0 .. j0 + WIDTH - 1 (wrapped) of a row. */
inline void spread_row(__global double *row, const int j0, const uint M, const double a,
                       const double *wys)
{
    if (j0 >= 0 && j0 + WIDTH <= (int)M) {
        for (int m = 0; m < WIDTH; ++m)
            row[j0 + m] += a * wys[m];
    } else {
        for (int m = 0; m < WIDTH; ++m)
            row[wrap(j0 + m, M)] += a * wys[m];
    }
}

/* Every point of block c of realization r adds its tensor-product kernel to the WIDTH^DIM
 * nodes nearest to it on a periodic grid of M nodes per axis:
 *     copies[r][c][i][j] += phi((i - x M) 2 / WIDTH) phi((j - y M) 2 / WIDTH)
 * (and the factor phi((l - z M) 2 / WIDTH) of node l on a third axis in 3-D, the last axis
 * contiguous). Each work-item owns one grid copy, so there are no atomics and each node sums
 * its points in index order (deterministic); spectrum_sum_copies adds the copies when a
 * realization's points are split over several work-items. Grid (copies, realizations). */
__kernel void spectrum_spread(__global const double *points, __global double *copies,
                              const uint n, const uint M, const uint blocks, const double beta)
{
    const uint c = get_global_id(0);
    const uint r = get_global_id(1);
    if (c >= blocks)
        return;
    size_t size = M;
    for (int a = 1; a < DIM; ++a)
        size *= M;
    __global double *g = copies + ((size_t)r * blocks + c) * size;
    for (size_t i = 0; i < size; ++i)
        g[i] = 0.0;
    const uint per = (n + blocks - 1) / blocks;
    const uint k0 = c * per, k1 = min(n, k0 + per);
    __global const double *p = points + (size_t)r * n * DIM;
    for (uint k = k0; k < k1; ++k) {
        double wxs[16];
        const int i0 = axis_weights(p[k * DIM] * M, beta, wxs);
#if DIM == 1
        for (int l = 0; l < WIDTH; ++l)
            g[wrap(i0 + l, M)] += wxs[l];
#elif DIM == 2
        double wys[16];
        const int j0 = axis_weights(p[k * 2 + 1] * M, beta, wys);
        for (int l = 0; l < WIDTH; ++l)
            spread_row(g + (size_t)wrap(i0 + l, M) * M, j0, M, wxs[l], wys);
#else
        double wys[16], wzs[16];
        const int j0 = axis_weights(p[k * 3 + 1] * M, beta, wys);
        const int l0 = axis_weights(p[k * 3 + 2] * M, beta, wzs);
        for (int l = 0; l < WIDTH; ++l) {
            __global double *plane = g + (size_t)wrap(i0 + l, M) * M * M;
            for (int m = 0; m < WIDTH; ++m)
                spread_row(plane + (size_t)wrap(j0 + m, M) * M, l0, M, wxs[l] * wys[m], wzs);
        }
#endif
    }
}

/* out[r][i] = sum_c copies[r][c][i], in order of c. Grid (size, realizations). */
__kernel void spectrum_sum_copies(__global const double *copies, __global double *out,
                                  const uint size, const uint blocks)
{
    const uint i = get_global_id(0);
    const uint r = get_global_id(1);
    if (i >= size)
        return;
    __global const double *src = copies + (size_t)r * blocks * size + i;
    double sum = 0.0;
    for (uint c = 0; c < blocks; ++c)
        sum += src[(size_t)c * size];
    out[(size_t)r * size + i] = sum;
}
