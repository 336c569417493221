/* The digital-net cubature's state on the device: the fast Walsh transform of a doubling's
 * values, the doubling's butterfly, the wavenumber ordering and the terms of the bound.
 * NumPy twin: clsamp/cubature.py (walsh_coefficients, Cubature.step, _order_wavenumbers),
 * the same operations in the same order, so the same bits (only additions, subtractions,
 * halvings, comparisons and exact scalings by powers of 2).
 *
 * Hickernell and Jiménez Rugama, "Reliable adaptive cubature using digital sequences"
 * (MCQMC 2014); the ordering is GAIL's kappanumap, as qmcpy's CubQMCNetG. */
#pragma OPENCL FP_CONTRACT OFF

/* Two butterfly levels over bits log2(h) and log2(h) + 1 of the index (radix 4), as
 * walsh_coefficients' reshape(-1, 4, h) pass: s0 = p + q, d0 = p - q, s1 = r + s, d1 = r - s,
 * then (s0 + s1, d0 + d1, s0 - s1, d0 - d1). Grid: n / 4. */
__kernel void walsh_radix4(__global double *y, const uint h)
{
    const uint g = get_global_id(0);
    const uint j = g % h, b = g / h;
    __global double *a = y + (size_t)b * 4 * h + j;
    const double p = a[0], q = a[h], r = a[2 * h], s = a[3 * h];
    const double s0 = p + q, d0 = p - q, s1 = r + s, d1 = r - s;
    a[0] = s0 + s1;
    a[h] = d0 + d1;
    a[2 * h] = s0 - s1;
    a[3 * h] = d0 - d1;
}

/* One butterfly level over bit log2(h) (radix 2), with the scaling by `scale` (1/n, a power
 * of 2: exact) folded in where `last`. Grid: n / 2. */
__kernel void walsh_radix2(__global double *y, const uint h)
{
    const uint g = get_global_id(0);
    const uint j = g % h, b = g / h;
    __global double *a = y + (size_t)b * 2 * h + j;
    const double p = a[0], q = a[h];
    a[0] = p + q;
    a[h] = p - q;
}

/* y *= scale (a power of 2). Grid: n. */
__kernel void walsh_scale(__global double *y, const double scale)
{
    y[get_global_id(0)] *= scale;
}

/* The doubling: c2 = ((c + t) / 2, (c - t) / 2) as (c + t) * 0.5, and kappa2 = (kappa,
 * n + kappa). Grid: n. */
__kernel void walsh_double(__global const double *c, __global const double *t,
                           __global const uint *kappa, const uint n, __global double *c2,
                           __global uint *kappa2)
{
    const uint i = get_global_id(0);
    const double a = c[i], b = t[i];
    c2[i] = (a + b) * 0.5;
    c2[n + i] = (a - b) * 0.5;
    const uint k = kappa[i];
    kappa2[i] = k;
    kappa2[n + i] = n + k;
}

/* One level of the ordering: for j in [1, nl) the first block decides (|c[kappa[j + nl]]| >
 * |c[kappa[j]]|) and every block b of 2 nl swaps its entries j and j + nl alike, the blocks
 * one after another in the work-item (block 0's pair is read before it is written). Grid:
 * nl - 1 (j - 1). */
__kernel void walsh_order(__global const double *c, __global uint *kappa, const uint nl,
                          const uint blocks)
{
    const uint j = get_global_id(0) + 1u;
    if (!(fabs(c[kappa[j + nl]]) > fabs(c[kappa[j]])))
        return;
    for (uint b = 0; b < blocks; ++b) {
        const size_t at = (size_t)b * 2 * nl + j;
        const uint swap = kappa[at];
        kappa[at] = kappa[at + nl];
        kappa[at + nl] = swap;
    }
}

/* The bound's terms |c[kappa[low + i]]|, i < low. Grid: low. */
__kernel void walsh_terms(__global const double *c, __global const uint *kappa, const uint low,
                          __global double *out)
{
    const uint i = get_global_id(0);
    out[i] = fabs(c[kappa[low + i]]);
}
