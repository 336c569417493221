/* Void and cluster (Ulichney 1993) and its spatiotemporal energy (Wolfe et al. 2022): the
 * ranks of a dither mask, one work-item a mask. NumPy twin: _void_and_cluster in
 * clsamp/samplers/dither.py, the same bits: the energy of a pixel is a sum of the same
 * doubles added in the same order (the stencils in turn, no contraction), and every choice
 * is the first extreme in pixel order, as numpy's argmax and argmin give it.
 *
 * The grid: ndim axes (at most 5), dims[a] pixels each, C order (stride[a] = the product of
 * the dims after a); N pixels. Each of the nst stencils (at most 2) is, from meta[16 s]:
 *     [0] its axes' count na (at most 4), [1 .. 4] the axes, [5 .. 8] the offsets along
 *     each (lens), [9 .. 12] where each axis's offsets start in `offsets`, [13] where its
 *     weights start in `weights` (C order over its axes), [14] the window's size.
 * A one at p adds the window's weights at p + offsets (wrapped), the other coordinates p's.
 *
 * The state is the energy `e` and `on`; the tightest cluster (the largest energy among
 * ones) and the largest void (the smallest among zeros) are the roots of two tournament
 * trees (win_hi, win_lo: 2 P nodes each; leaf P + b the winner of the block b of VC_BLOCK
 * pixels, P the least power of 2 >= the blocks; node k the winner of 2k and 2k + 1; a tie
 * goes to the lower index, and a pixel always beats the padding). A step stamps the blocks
 * its windows touched (stamp, P; touched, the list, as long as the windows), and each of
 * them finds its winner again and replays its path to the root, up to the first node
 * whose winner is the same pixel as before and did not change in that step.
 *
 * Inputs: initial (ones: the initial ones, set in that order). Scratch: e2, on2 (the
 * state after the blue-noise reorganization, restored for phase 2). Output: rank (N).
 * Build option: VC_BLOCK (pixels a leaf, a power of 2; default 8).
 * Launch: one work-item, grid (1,).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

#define VC_MAXD 5
#define VC_NONE 0xffffffffu
#ifndef VC_BLOCK
#define VC_BLOCK 8
#endif

/* a pixel's key in the tree of ones (hi: its energy, -inf at a zero) or of zeros (lo: its
 * energy, +inf at a one); past N, the key that never wins */
inline double vc_key(__global const double *e, __global const uchar *on, uint i, uint N,
                     int hi)
{
    if (hi)
        return i < N && on[i] ? e[i] : -INFINITY;
    return i < N && !on[i] ? e[i] : INFINITY;
}

/* the winner of a and b: the larger key (hi) or the smaller (lo), a tie to the lower index */
inline uint vc_pick(__global const double *e, __global const uchar *on, uint a, uint b,
                    uint N, int hi)
{
    const double ka = vc_key(e, on, a, N, hi), kb = vc_key(e, on, b, N, hi);
    return (hi ? ka > kb : ka < kb) || (ka == kb && a < b) ? a : b;
}

/* the winner of block b's pixels (VC_NONE where it has none) */
inline uint vc_block(__global const double *e, __global const uchar *on, uint b, uint N,
                     int hi)
{
    uint w = VC_NONE;
    for (uint i = b * VC_BLOCK; i < min((b + 1) * VC_BLOCK, N); ++i)
        w = vc_pick(e, on, w, i, N, hi);
    return w;
}

/* block b's pixels changed in step `now`: its leaf again, then its path to the root up to
 * the first node whose winner is the same pixel as before and did not change in this step
 * (stamp[its block] != now) */
inline void vc_replay(__global const double *e, __global const uchar *on, __global uint *win,
                      __global const uint *stamp, uint now, uint b, uint N, uint P, int hi)
{
    win[P + b] = vc_block(e, on, b, N, hi);
    for (uint k = (P + b) >> 1; k >= 1; k >>= 1) {
        const uint w = vc_pick(e, on, win[2 * k], win[2 * k + 1], N, hi);
        if (w == win[k] && (w >= N || stamp[w / VC_BLOCK] != now))
            break;
        win[k] = w;
    }
}

inline void vc_build(__global const double *e, __global const uchar *on,
                     __global uint *win_hi, __global uint *win_lo, uint N, uint P)
{
    for (uint b = 0; b < P; ++b) {
        win_hi[P + b] = vc_block(e, on, b, N, 1);
        win_lo[P + b] = vc_block(e, on, b, N, 0);
    }
    for (uint k = P - 1; k >= 1; --k) {
        win_hi[k] = vc_pick(e, on, win_hi[2 * k], win_hi[2 * k + 1], N, 1);
        win_lo[k] = vc_pick(e, on, win_lo[2 * k], win_lo[2 * k + 1], N, 0);
    }
}

/* set pixel p to one (value 1) or zero (0) in step `now`: its state, its windows'
 * energies (the blocks they touch stamped and listed in `touched`), then the trees that
 * `trees` names (1: the ones', 2: the zeros', 3: both; a phase keeps only the one it asks,
 * and the other is built again before it is asked) */
inline void vc_set(__global double *e, __global uchar *on, __global uint *win_hi,
                   __global uint *win_lo, __global uint *stamp, __global uint *touched,
                   uint now, uint p, uchar value, uint trees, uint N, uint P, uint ndim,
                   __global const uint *dims, __global const uint *stride, uint nst,
                   __global const int *meta, __global const int *offsets,
                   __global const double *weights)
{
    on[p] = value;
    stamp[p / VC_BLOCK] = now;
    uint count = 0;
    touched[count++] = p / VC_BLOCK;
    const double sign = value ? 1.0 : -1.0;
    uint coord[VC_MAXD];
    uint rest = p;
    for (int a = (int)ndim - 1; a >= 0; --a) {
        coord[a] = rest % dims[a];
        rest /= dims[a];
    }
    for (uint s = 0; s < nst; ++s) {
        __global const int *m = meta + 16 * s;
        const int na = m[0];
        uint base = p;
        for (int k = 0; k < na; ++k)
            base -= coord[m[1 + k]] * stride[m[1 + k]];
        const uint size = (uint)m[14];
        int j[4] = {0, 0, 0, 0};            /* the window's element t, an odometer */
        for (uint t = 0; t < size; ++t) {
            uint at = base;
            for (int k = 0; k < na; ++k) {
                /* |offset| < n: one wrap */
                const int a = m[1 + k], n = (int)dims[a];
                const int c = (int)coord[a] + offsets[m[9 + k] + j[k]];
                at += (uint)(c < 0 ? c + n : (c >= n ? c - n : c)) * stride[a];
            }
            for (int k = na - 1; k >= 0; --k) {
                if (++j[k] < m[5 + k])
                    break;
                j[k] = 0;
            }
            e[at] += sign * weights[m[13] + (int)t];
            const uint b = at / VC_BLOCK;
            if (stamp[b] != now) {
                stamp[b] = now;
                touched[count++] = b;
            }
        }
    }
    for (uint k = 0; k < count; ++k) {
        if (trees & 1)
            vc_replay(e, on, win_hi, stamp, now, touched[k], N, P, 1);
        if (trees & 2)
            vc_replay(e, on, win_lo, stamp, now, touched[k], N, P, 0);
    }
}

__kernel void void_and_cluster(const uint N, const uint P, const uint ndim,
                               __global const uint *dims, __global const uint *stride,
                               const uint nst, __global const int *meta,
                               __global const int *offsets, __global const double *weights,
                               __global const uint *initial, const uint ones,
                               __global double *e, __global uchar *on,
                               __global double *e2, __global uchar *on2,
                               __global uint *win_hi, __global uint *win_lo,
                               __global uint *stamp, __global uint *touched,
                               __global long *rank)
{
    if (get_global_id(0) != 0)
        return;
    uint now = 0;
#define VC_SET(p, v, trees) vc_set(e, on, win_hi, win_lo, stamp, touched, ++now, (p), (v), \
                                   (trees), N, P, ndim, dims, stride, nst, meta, offsets, \
                                   weights)
    for (uint i = 0; i < N; ++i) {
        e[i] = 0.0;
        on[i] = 0;
        rank[i] = -1;
    }
    for (uint b = 0; b < P; ++b)
        stamp[b] = 0;
    for (uint k = 0; k < ones; ++k)
        VC_SET(initial[k], 1, 0);
    vc_build(e, on, win_hi, win_lo, N, P);
    /* the blue-noise pattern: the tightest cluster into the largest void until they meet */
    for (ulong step = 0; step < 10 * (ulong)N; ++step) {
        const uint cluster = win_hi[1];
        VC_SET(cluster, 0, 3);
        const uint gap = win_lo[1];
        VC_SET(gap, 1, 3);
        if (gap == cluster)
            break;
    }
    for (uint i = 0; i < N; ++i) {
        e2[i] = e[i];
        on2[i] = on[i];
    }
    /* phase 1: the initial ones, tightest first out */
    for (uint left = ones; left-- > 0;) {
        const uint cluster = win_hi[1];
        rank[cluster] = left;
        VC_SET(cluster, 0, 1);
    }
    for (uint i = 0; i < N; ++i) {
        e[i] = e2[i];
        on[i] = on2[i];
    }
    vc_build(e, on, win_hi, win_lo, N, P);
    /* phase 2: fill the largest voids to half */
    for (uint count = ones; count < N / 2; ++count) {
        const uint gap = win_lo[1];
        rank[gap] = count;
        VC_SET(gap, 1, 2);
    }
    /* phase 3: the zeros, as the ones of the inverted pattern, tightest first out */
    for (uint i = 0; i < N; ++i) {
        on2[i] = on[i];
        e[i] = 0.0;
        on[i] = 0;
    }
    for (uint i = 0; i < N; ++i)
        if (!on2[i])
            VC_SET(i, 1, 0);
    vc_build(e, on, win_hi, win_lo, N, P);
    for (uint count = N / 2; count < N; ++count) {
        const uint cluster = win_hi[1];
        rank[cluster] = count;
        VC_SET(cluster, 0, 1);
    }
#undef VC_SET
}
