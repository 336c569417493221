/* Sliced optimal transport sampling (Paulin et al. 2020): the three passes of one batch.
 * NumPy twins in clsamp/samplers/sot.py (quantiles_reference, project_reference,
 * move_reference), the same bits: exactly rounded double operations in the same order, no
 * contraction, no library function.
 *
 * sot_quantiles: for each direction (set, k) the n targets of the 1-D transport, the
 * quantiles q_i = F^-1((i + 1/2) / n) of <theta, U>, U uniform in [0, 1)^D. The direction
 * comes as the CDF of a sum of m scaled uniforms t = sum a_j U_j (clsamp.samplers.sot.Slice):
 *     F(t) = norm sum_v sign_v (t - c_v)_+^m,   v over the 2^m vertices,
 * c (2^D per direction, the first 2^m used) the vertex sums, sign = (-1)^|v|,
 * norm = 1 / (m! prod a_j), total = sum a_j; the quantile is base + t. Only i < n/2 is solved
 * (t in [0, total / 2], where no cancellation beyond the one Slice bounds occurs) and mirrored:
 * q_(n-1-i) = base + (total - t_i); an odd n's middle is base + total / 2. The solver is
 * Newton's step kept inside a bisection bracket (Numerical Recipes' rtsafe), stopped when
 * Newton's step (taken) or the step made is at most QTOL total, or after QMAX steps.
 * Launch: grid (directions, n / 2) as one axis, directions * ((n + 1) / 2) work-items.
 *
 * sot_project: proj[set, k, i] = sum_j theta[set, k, j] x[set, i, j], j in order.
 * Launch: one work-item per (set, k, i).
 *
 * sot_move: point i of a set moves by scale sum_k (q[set, k, rank[set, k, i]] - proj) theta_k
 * (scale = step / K), clamped into [0, 1 - 2^-53]; cost[set, i] = sum_k (q - proj)^2, the
 * point's transport cost over the batch before the move.
 * Launch: one work-item per (set, i).
 *
 * sot_sort_init, sot_bitonic, sot_rank: the rank of each projection in its row, ties by
 * index (the order of a stable sort, NumPy's argsort(kind="stable")), by a bitonic sort of
 * rows of P = 2^e >= n (key, index) pairs in global memory: sot_sort_init pads each row
 * with (+inf, index) (projections are finite, so the padding sorts last); each
 * sot_bitonic launch is one compare-exchange stage (k, j) over rows * P / 2 work-items,
 * ascending by (key, index) where bit k of the lower position is clear;
 * sot_bitonic_local runs the stages with j < L, L = 2 get_local_size(0) (a power of two
 * dividing P), in local memory, a work-group per L consecutive pairs of a row: for k from
 * kmin to kmax, j from jtop (k == kmin) or k / 2 down to 1; sot_rank scatters
 * rank[row, index[row, j]] = j for j < n. Lexicographic order on distinct (key, index)
 * pairs is total, so the sorted order is unique: the same as the stable sort's.
 *
 * Build options: D (dimensions), QTOL, QMAX.
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

#define VERTS (1 << D)

__kernel void sot_quantiles(__global const double *c, __global const double *sign,
                            __global const int *m_of, __global const double *norm_of,
                            __global const double *total_of, __global const double *base_of,
                            const uint n, const uint dirs, __global double *q)
{
    const uint nh = (n + 1) / 2;
    const uint gid = get_global_id(0);
    if (gid >= dirs * nh)
        return;
    const uint k = gid / nh, i = gid % nh;
    const double total = total_of[k], base = base_of[k], norm = norm_of[k];
    __global double *row = q + (size_t)k * n;
    if (2 * i + 1 == n) {
        row[i] = base + total * 0.5;
        return;
    }
    const int m = m_of[k];
    const uint nv = 1u << m;
    __global const double *ck = c + (size_t)k * VERTS;
    __global const double *sk = sign + (size_t)k * VERTS;
    const double p = ((double)i + 0.5) / (double)n;
    double lo = 0.0, hi = total * 0.5;
    double t = hi * 0.5, dx_old = hi;
    for (int it = 0; it < QMAX; ++it) {
        double F = 0.0, dF = 0.0;
        for (uint v = 0; v < nv; ++v) {
            const double u = t - ck[v];
            if (u > 0.0) {
                double w = 1.0;
                for (int j = 1; j < m; ++j)
                    w = w * u;
                F = F + sk[v] * (w * u);
                dF = dF + sk[v] * w;
            }
        }
        const double f = F * norm - p;
        const double df = dF * norm * (double)m;
        if (f < 0.0)
            lo = t;
        else
            hi = t;
        const double tn = t - f / df;
        if (df > 0.0 && fabs(tn - t) <= QTOL * total) {
            t = tn;
            break;
        }
        double next;
        if (df > 0.0 && tn > lo && tn < hi && fabs(tn - t) < 0.5 * fabs(dx_old))
            next = tn;
        else
            next = lo + (hi - lo) * 0.5;
        const double dx = next - t;
        dx_old = dx;
        t = next;
        if (fabs(dx) <= QTOL * total)
            break;
    }
    row[i] = base + t;
    row[n - 1 - i] = base + (total - t);
}

__kernel void sot_project(__global const double *x, __global const double *theta, const uint n,
                          const uint K, const uint sets, __global double *proj)
{
    const uint gid = get_global_id(0);
    if (gid >= sets * K * n)
        return;
    const uint i = gid % n, sk = gid / n, s = sk / K;
    __global const double *xi = x + ((size_t)s * n + i) * D;
    __global const double *th = theta + (size_t)sk * D;
    double p = th[0] * xi[0];
    for (int j = 1; j < D; ++j)
        p = p + th[j] * xi[j];
    proj[gid] = p;
}

__kernel void sot_move(__global const double *x, __global const double *theta,
                       __global const double *q, __global const uint *rank,
                       __global const double *proj, const uint n, const uint K, const uint sets,
                       const double scale, __global double *out, __global double *cost)
{
    const uint gid = get_global_id(0);
    if (gid >= sets * n)
        return;
    const uint s = gid / n, i = gid % n;
    double shift[D];
    for (int j = 0; j < D; ++j)
        shift[j] = 0.0;
    double c = 0.0;
    for (uint k = 0; k < K; ++k) {
        const size_t sk = (size_t)s * K + k;
        const double disp = q[sk * n + rank[sk * n + i]] - proj[sk * n + i];
        c = c + disp * disp;
        for (int j = 0; j < D; ++j)
            shift[j] = shift[j] + disp * theta[sk * D + j];
    }
    const double top = 1.0 - 0x1.0p-53;
    for (int j = 0; j < D; ++j) {
        double v = x[(size_t)gid * D + j] + shift[j] * scale;
        v = v < 0.0 ? 0.0 : v;
        out[(size_t)gid * D + j] = v > top ? top : v;
    }
    cost[gid] = c;
}

__kernel void sot_sort_init(__global const double *proj, const uint n, const uint P,
                            const uint rows, __global double *key, __global uint *index)
{
    const uint g = get_global_id(0);
    if (g >= rows * P)
        return;
    const uint row = g / P, i = g % P;
    key[g] = i < n ? proj[(size_t)row * n + i] : INFINITY;
    index[g] = i;
}

__kernel void sot_bitonic(__global double *key, __global uint *index, const uint P,
                          const uint rows, const uint k, const uint j)
{
    const uint g = get_global_id(0);
    const uint hp = P >> 1;
    if (g >= rows * hp)
        return;
    const uint row = g / hp, t = g % hp;
    const uint low = t & (j - 1);
    const uint i = ((t - low) << 1) + low;
    const size_t a = (size_t)row * P + i, b = a + j;
    const double ka = key[a], kb = key[b];
    const uint ia = index[a], ib = index[b];
    const int greater = ka > kb || (ka == kb && ia > ib);
    const int up = (i & k) == 0;
    if (greater == up) {
        key[a] = kb;
        key[b] = ka;
        index[a] = ib;
        index[b] = ia;
    }
}

__kernel void sot_bitonic_local(__global double *key, __global uint *index, const uint P,
                                const uint kmin, const uint kmax, const uint jtop,
                                __local double *lk, __local uint *li)
{
    const uint L2 = get_local_size(0), L = 2 * L2, lid = get_local_id(0);
    const uint blocks = P / L, grp = get_group_id(0);
    const uint base = (grp % blocks) * L;
    const size_t off = (size_t)(grp / blocks) * P + base;
    lk[lid] = key[off + lid];
    lk[lid + L2] = key[off + lid + L2];
    li[lid] = index[off + lid];
    li[lid + L2] = index[off + lid + L2];
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = kmin; k <= kmax; k <<= 1) {
        for (uint j = k == kmin ? jtop : k >> 1; j >= 1; j >>= 1) {
            const uint low = lid & (j - 1);
            const uint i = ((lid - low) << 1) + low;
            const double ka = lk[i], kb = lk[i + j];
            const uint ia = li[i], ib = li[i + j];
            const int greater = ka > kb || (ka == kb && ia > ib);
            const int up = ((base + i) & k) == 0;
            if (greater == up) {
                lk[i] = kb;
                lk[i + j] = ka;
                li[i] = ib;
                li[i + j] = ia;
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
    }
    key[off + lid] = lk[lid];
    key[off + lid + L2] = lk[lid + L2];
    index[off + lid] = li[lid];
    index[off + lid + L2] = li[lid + L2];
}

__kernel void sot_rank(__global const uint *index, const uint n, const uint P, const uint rows,
                       __global uint *rank)
{
    const uint g = get_global_id(0);
    if (g >= rows * n)
        return;
    const uint row = g / n, j = g % n;
    rank[(size_t)row * n + index[(size_t)row * P + j]] = j;
}
