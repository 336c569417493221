/* The digital-net cubature's state on the device: the fast Walsh transform of a doubling's
 * values, the doubling's butterfly and the wavenumber ordering (clsamp/cubature_device.py
 * reads the bound's terms back from the coefficients, which it keeps in wavenumber order).
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

/* One butterfly level over bit log2(h) (radix 2), as walsh_coefficients' reshape(-1, 2, h)
 * pass. Grid: n / 2. */
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

/* The doubling, in place in arrays of room for 2n: the coefficients are kept in wavenumber
 * order, a[i] = c[kappa[i]] (what the ordering compares and the bound sums, read
 * contiguously), so the butterfly ((c + t) / 2, (c - t) / 2) as (c + t) * 0.5 becomes
 * a[i], a[n + i] = (a[i] + t[k]) * 0.5, (a[i] - t[k]) * 0.5 with k = kappa[i], and kappa
 * becomes (kappa, n + kappa). Grid: n. */
__kernel void walsh_double(__global double *a, __global const double *t, __global uint *kappa,
                           const uint n)
{
    const uint i = get_global_id(0);
    const uint k = kappa[i];
    const double c = a[i], v = t[k];
    a[i] = (c + v) * 0.5;
    a[n + i] = (c - v) * 0.5;
    kappa[n + i] = n + k;
}

/* One level of the ordering: for j in [1, nl) the first block decides (|a[j + nl]| > |a[j]|,
 * the sizes |c[kappa[.]]|) and every block b of 2 nl swaps its entries j and j + nl alike, in
 * kappa and in a, the blocks one after another in the work-item (block 0's pair is read
 * before it is written). Grid: at least nl - 1 (j - 1). */
__kernel void walsh_order(__global uint *kappa, __global double *a, const uint nl,
                          const uint blocks)
{
    const uint j = get_global_id(0) + 1u;
    if (j >= nl || !(fabs(a[j + nl]) > fabs(a[j])))
        return;
    for (uint b = 0; b < blocks; ++b) {
        const size_t at = (size_t)b * 2 * nl + j;
        const uint k = kappa[at];
        kappa[at] = kappa[at + nl];
        kappa[at + nl] = k;
        const double v = a[at];
        a[at] = a[at + nl];
        a[at + nl] = v;
    }
}
