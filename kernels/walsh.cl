/* The adaptive cubature's state on the device: the fast Walsh transform of a digital net's
 * doubling, the doubling's butterfly, a lattice's Fourier magnitudes put in wavenumber order,
 * and the wavenumber ordering (clsamp/cubature_device.py reads the bound's terms back from
 * the values it keeps in wavenumber order). NumPy twin: clsamp/cubature.py
 * (walsh_coefficients, Cubature.step, _order_wavenumbers), the same operations in the same
 * order, so the same bits (only additions, subtractions, halvings, comparisons, copies and
 * exact scalings by powers of 2).
 *
 * Hickernell and Jiménez Rugama, "Reliable adaptive cubature using digital sequences" and
 * Jiménez Rugama and Hickernell, "Adaptive multidimensional integration based on rank-1
 * lattices" (MCQMC 2014); the ordering is GAIL's kappanumap, as qmcpy's CubQMCNetG and
 * CubQMCLatticeG. */
#pragma OPENCL FP_CONTRACT OFF

#ifndef WALSH_BITS
#define WALSH_BITS 2
#endif
#define WALSH_SIZE (1 << WALSH_BITS)

/* WALSH_BITS butterfly levels over bits log2(h) .. log2(h) + WALSH_BITS - 1 of the index, as
 * that many of walsh_coefficients' radix-2 levels (its radix-4 pass is two of them, the same
 * additions): a work-item loads the 2^WALSH_BITS values b 2^WALSH_BITS h + j + r h
 * (r < 2^WALSH_BITS), applies the levels in order (level s: p + q and p - q over the pairs
 * r, r + 2^s), and writes them back times `scale` (1, or 1/n on the transform's last pass:
 * walsh_coefficients' final division by a power of 2, the same bits). Grid: n / 2^WALSH_BITS. */
__kernel void walsh_pass(__global double *y, const uint h, const double scale)
{
    const uint g = get_global_id(0);
    const uint j = g % h, b = g / h;
    __global double *a = y + (size_t)b * WALSH_SIZE * h + j;
    double v[WALSH_SIZE];
#pragma unroll
    for (int r = 0; r < WALSH_SIZE; ++r)
        v[r] = a[(size_t)r * h];
#pragma unroll
    for (int s = 1; s < WALSH_SIZE; s *= 2)
#pragma unroll
        for (int r = 0; r < WALSH_SIZE; ++r)
            if (!(r & s)) {
                const double p = v[r], q = v[r + s];
                v[r] = p + q;
                v[r + s] = p - q;
            }
#pragma unroll
    for (int r = 0; r < WALSH_SIZE; ++r)
        a[(size_t)r * h] = v[r] * scale;
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

/* A lattice's doubling, in place in arrays of room for 2n: kappa becomes (kappa, n + kappa)
 * and a holds the magnitudes of the 2n values' Fourier coefficients in that order,
 * a[i] = |c[kappa[i]]|, from those of the half spectrum (sizes[k] = |c[k]|, k <= n; a real
 * sequence's |c[2n - k]| = |c[k]|). Every coefficient changes with a doubling (the host
 * updates the whole spectrum), so every entry is written afresh. Grid: n. */
__kernel void lattice_sizes(__global double *a, __global const double *sizes, __global uint *kappa,
                            const uint n)
{
    const uint i = get_global_id(0);
    const uint k = kappa[i], k2 = n + k, size = 2u * n;
    a[i] = sizes[min(k, size - k)];
    a[n + i] = sizes[min(k2, size - k2)];
    kappa[n + i] = k2;
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
