/* Progressive multi-jittered (0, 2) sequences. NumPy reference: clsamp/samplers/pmj.py.
 *
 * out is (realizations, total, 2); a coordinate is X 2^-53 with X a 53-bit integer, which
 * double holds exactly, so reading the strata back from out is exact on every device. out
 * holds the doubles' bit patterns and pmj02bn's distances are correctly rounded double
 * operations (f64bits.h): no kernel here needs fp64.
 */
#include "philox.h"

#define PMJ_BITS 53
#define PMJ_STREAM 0u                 /* philox.Stream.POINTS */

/* The 53 random bits of axis `axis` of point p: words (0, 1) for x, (2, 3) for y. */
inline ulong pmj_random53(uint4 w, uint axis)
{
    const uint hi = axis ? w.z : w.x, lo = axis ? w.w : w.y;
    return ((ulong)(hi >> 5) << 26) | (ulong)(lo >> 6);
}

inline ulong pmj_integer(ulong x) { return f64_to_fixed(x, PMJ_BITS); }
inline ulong pmj_bits(ulong x) { return f64_scaled(x, -PMJ_BITS); }

/* Point 0 of each realization: uniform. Grid (realizations). */
__kernel void pmj02_first(__global ulong *out, const uint total, const uint realization0,
                          const uint key_lo, const uint key_hi)
{
    const uint r = get_global_id(0);
    const uint4 w = clsamp_block((uint2)(key_lo, key_hi), PMJ_STREAM, realization0 + r, 0u, 0u);
    __global ulong *p = out + (size_t)r * total * 2;
    p[0] = pmj_bits(pmj_random53(w, 0u));
    p[1] = pmj_bits(pmj_random53(w, 1u));
}

/* Points N + i, N = 2^m, i < count: the other half of the stratum of width 1/N they share
 * with point i ^ mask[axis][m], and their own random bits below. Grid (ceil(count / 4)
 * padded, realizations): work-item q makes points N + 4q .. N + 4q + 3, their Philox blocks
 * in vector lanes (as random_points). */
__kernel void pmj02_level(__global ulong *out, __global const uint *masks, const uint total,
                          const uint m, const uint count, const uint realization0,
                          const uint key_lo, const uint key_hi)
{
    const uint i0 = 4 * get_global_id(0), r = get_global_id(1);
    if (i0 >= count)
        return;
    const uint size = 1u << m;
    uint4 w0, w1, w2, w3;
    philox4x32_10_x4((uint4)(size + i0) + (uint4)(0u, 1u, 2u, 3u), (uint4)(realization0 + r),
                     (uint4)(0u), (uint4)(PMJ_STREAM), (uint2)(key_lo, key_hi), &w0, &w1, &w2, &w3);
    const uint low = PMJ_BITS - m - 1;
    const ulong keep = ((ulong)1 << low) - 1;
    /* element by element: PoCL calls its vstore4 built-in as a function */
    const ulong4 bx = ((convert_ulong4(w0 >> 5) << 26) | convert_ulong4(w1 >> 6)) & keep;
    const ulong4 by = ((convert_ulong4(w2 >> 5) << 26) | convert_ulong4(w3 >> 6)) & keep;
    const ulong bits[2][4] = {{bx.s0, bx.s1, bx.s2, bx.s3}, {by.s0, by.s1, by.s2, by.s3}};
    __global ulong *base = out + (size_t)r * total * 2;
    const uint lanes = count - i0 < 4u ? count - i0 : 4u;
    const uint mx = masks[m], my = masks[32 + m];
    for (uint l = 0; l < lanes; ++l) {
        const uint i = i0 + l;
        const ulong sx = pmj_integer(base[(size_t)(i ^ mx) * 2]);
        const ulong sy = pmj_integer(base[(size_t)(i ^ my) * 2 + 1]);
        base[(size_t)(size + i) * 2] = pmj_bits((((sx >> low) ^ 1ul) << low) | bits[0][l]);
        base[(size_t)(size + i) * 2 + 1] = pmj_bits((((sy >> low) ^ 1ul) << low) | bits[1][l]);
    }
}

/* ---- pmj02bn: one work-item per realization (the construction is sequential) ----------------
 * occupied: per realization, bit s 2^L + y 2^(L-s) + x says whether the elementary interval
 * (x, y) of shape s (x resolution 2^(L-s), y resolution 2^s) holds a point; grid: per
 * realization, dim x dim point indices (-1: empty), at most one point per cell. */
#define PMJ_CANDIDATES 10
#define PMJ_CANDIDATE_STREAM 4u       /* philox.Stream.CANDIDATES */

typedef struct {
    __global ulong *x;
    __global uint *occupied;
    __global int *grid;
    uint L, dim, log2_dim;
} pmj_state;

inline ulong pmj_coord(const pmj_state *st, uint p, uint axis)
{
    return pmj_integer(st->x[(size_t)p * 2 + axis]);
}

inline void pmj_mark(pmj_state *st, uint p)
{
    const ulong X = pmj_coord(st, p, 0), Y = pmj_coord(st, p, 1);
    const uint L = st->L;
    for (uint s = 0; s <= L; ++s) {
        const ulong bit = ((ulong)s << L) + ((Y >> (PMJ_BITS - s)) << (L - s))
                          + (X >> (PMJ_BITS - L + s));
        st->occupied[bit >> 5] |= 1u << (uint)(bit & 31);
    }
    const uint shift = PMJ_BITS - st->log2_dim;
    st->grid[(size_t)(Y >> shift) * st->dim + (uint)(X >> shift)] = (int)p;
}

inline void pmj_subdivide(pmj_state *st, uint L, uint count)
{
    st->L = L;
    st->log2_dim = (L + 1) / 2;
    st->dim = 1u << st->log2_dim;
    const ulong words = (((ulong)(L + 1) << L) + 31) / 32;
    for (ulong w = 0; w < words; ++w)
        st->occupied[w] = 0u;
    for (ulong c = 0; c < (ulong)st->dim * st->dim; ++c)
        st->grid[c] = -1;
    for (uint p = 0; p < count; ++p)
        pmj_mark(st, p);
}

/* The valid fine strata below cell (x0, y0) of shape s0, ascending (pmj.py's _leaves): returns
 * their count, and in *leaf the one numbered `want` when there is one. */
inline uint pmj_leaves(const pmj_state *st, uint x0, uint y0, uint s0, uint depth, int along_x,
                       uint want, uint *leaf)
{
    const uint L = st->L;
    const ulong end = 1ul << depth;
    uint count = 0;
    ulong u = 0;
    while (u < end) {
        int blocked = 0;
        for (uint t = 0; t <= depth; ++t) {
            const ulong head = u >> (depth - t);
            ulong x, y;
            uint s;
            if (along_x) {
                x = ((ulong)x0 << t) + head; y = y0 >> t; s = s0 - t;
            } else {
                x = x0 >> t; y = ((ulong)y0 << t) + head; s = s0 + t;
            }
            const ulong bit = ((ulong)s << L) + (y << (L - s)) + x;
            if ((st->occupied[bit >> 5] >> (uint)(bit & 31)) & 1u) {
                u = (head + 1) << (depth - t);
                blocked = 1;
                break;
            }
        }
        if (!blocked) {
            if (count == want)
                *leaf = (uint)(u + ((ulong)(along_x ? x0 : y0) << depth));
            ++count;
            ++u;
        }
    }
    return count;
}

/* The squared toroidal distance of points with 53-bit coordinates, as double bits: the
 * differences and wraps are exact in integers, then dx dx + dy dy rounds as in double. */
inline ulong pmj_toroidal_d2(ulong ax, ulong ay, ulong bx, ulong by)
{
    const ulong one = 1UL << PMJ_BITS;
    ulong dx = ax > bx ? ax - bx : bx - ax, dy = ay > by ? ay - by : by - ay;
    dx = one - dx < dx ? one - dx : dx;
    dy = one - dy < dy ? one - dy : dy;
    const ulong fx = f64_scaled(dx, -PMJ_BITS), fy = f64_scaled(dy, -PMJ_BITS);
    return f64_add(f64_mul(fx, fx), f64_mul(fy, fy));
}

/* For the candidates c = 0, stride, 2 stride, ... (count of them) in grid cell (cx, cy),
 * at 53-bit coordinates (px, py): best[c] = squared toroidal distance (double bits) to the
 * nearest point of the grid (pmj.py's nearest_d2), searched together ring by ring until
 * each candidate's nearest is known. Non-negative doubles order as their bits. */
inline void pmj_nearest_d2(const pmj_state *st, int cx, int cy, const ulong *px,
                           const ulong *py, uint stride, uint count, ulong *best)
{
    const int dim = (int)st->dim;
    for (uint c = 0; c < count; ++c)
        best[c * stride] = 0x4020000000000000UL;       /* 8.0 */
    for (int ring = 0; ring < dim; ++ring) {
        for (int gy = cy - ring; gy <= cy + ring; ++gy) {
            const int edge = (gy == cy - ring || gy == cy + ring);
            const int step = (edge || ring == 0) ? 1 : 2 * ring;
            for (int gx = cx - ring; gx <= cx + ring; gx += step) {
                const int wx = gx & (dim - 1), wy = gy & (dim - 1);      /* dim: a power of 2 */
                const int q = st->grid[(size_t)wy * dim + wx];
                if (q < 0)
                    continue;
                const ulong qx = pmj_coord(st, q, 0), qy = pmj_coord(st, q, 1);
                for (uint c = 0; c < count; ++c) {
                    const ulong d2 = pmj_toroidal_d2(px[c * stride], py[c * stride], qx, qy);
                    best[c * stride] = d2 < best[c * stride] ? d2 : best[c * stride];
                }
            }
        }
        const ulong bound = f64_div((ulong)ring * ring, (ulong)dim * dim, 0);
        int done = 1;
        for (uint c = 0; c < count; ++c)
            done &= best[c * stride] <= bound;
        if (done || 2 * ring + 1 >= dim)
            break;
    }
}

/* Point p at the best of PMJ_CANDIDATES candidates, candidate c in cell c % cells of
 * (cx[], cy[]); returns the cell taken, or -1 if a cell has no valid stratum. */
inline int pmj_place(pmj_state *st, uint p, const uint *cx, const uint *cy, uint cells,
                     uint2 key, uint realization)
{
    const uint L = st->L, j = L / 2;
    const ulong keep = ((ulong)1 << (PMJ_BITS - L)) - 1;
    ulong X[PMJ_CANDIDATES], Y[PMJ_CANDIDATES], d2[PMJ_CANDIDATES];
    for (uint o = 0; o < cells; ++o) {
        uint sx0, sx1, sx2, sy0, sy1, sy2;
        if (L % 2 == 0) {
            sx0 = cx[o]; sx1 = cy[o]; sx2 = j; sy0 = cx[o]; sy1 = cy[o]; sy2 = j;
        } else {
            sx0 = cx[o]; sx1 = cy[o] >> 1; sx2 = j; sy0 = cx[o] >> 1; sy1 = cy[o]; sy2 = j + 1;
        }
        uint first_x = 0, first_y = 0;
        const uint nx = pmj_leaves(st, sx0, sx1, sx2, sx2, 1, 0u, &first_x);
        const uint ny = pmj_leaves(st, sy0, sy1, sy2, L - sy2, 0, 0u, &first_y);
        if (nx == 0 || ny == 0)
            return -1;
        uint count = 0;
        for (uint c = o; c < PMJ_CANDIDATES; c += cells, ++count) {
            const uint4 a = clsamp_block(key, PMJ_CANDIDATE_STREAM, realization, p, 2 * c);
            const uint4 b = clsamp_block(key, PMJ_CANDIDATE_STREAM, realization, p, 2 * c + 1);
            const uint wx = (uint)(((ulong)a.x * nx) >> 32), wy = (uint)(((ulong)a.y * ny) >> 32);
            uint fx = first_x, fy = first_y;
            if (wx)
                pmj_leaves(st, sx0, sx1, sx2, sx2, 1, wx, &fx);
            if (wy)
                pmj_leaves(st, sy0, sy1, sy2, L - sy2, 0, wy, &fy);
            X[c] = ((ulong)fx << (PMJ_BITS - L)) | (pmj_random53((uint4)(a.z, a.w, 0u, 0u), 0u) & keep);
            Y[c] = ((ulong)fy << (PMJ_BITS - L)) | (pmj_random53((uint4)(0u, 0u, b.x, b.y), 1u) & keep);
        }
        pmj_nearest_d2(st, (int)cx[o], (int)cy[o], X + o, Y + o, cells, count, d2 + o);
    }
    uint best = 0;
    for (uint c = 1; c < PMJ_CANDIDATES; ++c)
        if (d2[c] > d2[best])
            best = c;
    st->x[(size_t)p * 2] = pmj_bits(X[best]);
    st->x[(size_t)p * 2 + 1] = pmj_bits(Y[best]);
    pmj_mark(st, p);
    return (int)(best % cells);
}

/* Grid (realizations). status[r] is 0, or 1 + the point that found no valid stratum. */
__kernel void pmj02bn_points(__global ulong *out, __global uint *occupied, __global int *grid,
                             __global uint *status, const uint total, const ulong occupied_words,
                             const ulong grid_cells, const uint realization0,
                             const uint key_lo, const uint key_hi)
{
    const uint r = get_global_id(0);
    const uint2 key = (uint2)(key_lo, key_hi);
    const uint k = realization0 + r;
    pmj_state st;
    st.x = out + (size_t)r * total * 2;
    st.occupied = occupied + r * occupied_words;
    st.grid = grid + r * grid_cells;
    const uint4 w = clsamp_block(key, PMJ_STREAM, k, 0u, 0u);
    st.x[0] = pmj_bits(pmj_random53(w, 0u));
    st.x[1] = pmj_bits(pmj_random53(w, 1u));
    status[r] = 0u;
    for (uint n = 1, j = 0; n < total; n *= 4, ++j) {
        pmj_subdivide(&st, 2 * j + 1, n);
        for (uint i = 0; i < n && n + i < total; ++i) {
            const uint shift = PMJ_BITS - st.log2_dim;
            const uint cx[1] = {(uint)(pmj_coord(&st, i, 0) >> shift) ^ 1u};
            const uint cy[1] = {(uint)(pmj_coord(&st, i, 1) >> shift) ^ 1u};
            if (pmj_place(&st, n + i, cx, cy, 1, key, k) < 0) {
                status[r] = 1u + n + i;
                return;
            }
        }
        if (2 * n >= total)
            break;
        pmj_subdivide(&st, 2 * j + 2, 2 * n);
        const uint shift = PMJ_BITS - st.log2_dim;
        for (uint i = 0; i < n && 2 * n + i < total; ++i) {
            const uint x = (uint)(pmj_coord(&st, i, 0) >> shift), y = (uint)(pmj_coord(&st, i, 1) >> shift);
            const uint cx[2] = {x ^ 1u, x}, cy[2] = {y, y ^ 1u};
            if (pmj_place(&st, 2 * n + i, cx, cy, 2, key, k) < 0) {
                status[r] = 1u + 2 * n + i;
                return;
            }
        }
        for (uint i = 0; i < n && 3 * n + i < total; ++i) {
            const uint p = 2 * n + i;
            const uint cx[1] = {(uint)(pmj_coord(&st, p, 0) >> shift) ^ 1u};
            const uint cy[1] = {(uint)(pmj_coord(&st, p, 1) >> shift) ^ 1u};
            if (pmj_place(&st, 3 * n + i, cx, cy, 1, key, k) < 0) {
                status[r] = 1u + 3 * n + i;
                return;
            }
        }
    }
}
