/* The machinery of the CCVT exchanges (kernels/ccvt.cl): the site records, the buckets of
 * a site's members and the exchange of one pair of neighbouring sites (ccvt_pair).
 * NumPy twin: clsamp/samplers/ccvt/reference.py. */
#ifndef CLSAMP_CCVT_H
#define CLSAMP_CCVT_H

/* From the host (clsamp.samplers.ccvt.pairs, their one source): CCVT_TOP (candidates per
 * site and round), CCVT_SECTORS, CCVT_BANDS, CCVT_META (the per-site record's length). */
#if !defined(CCVT_TOP) || !defined(CCVT_SECTORS) || !defined(CCVT_BANDS) || !defined(CCVT_META)
#error "CCVT_TOP, CCVT_SECTORS, CCVT_BANDS and CCVT_META come from clsamp.samplers.ccvt.pairs"
#endif
#if CCVT_SECTORS != 16
#error "the sector rays below are written for 16 sectors"
#endif

/* Software prefetch, on CPU devices only (the host defines CCVT_PREFETCH there:
 * clsamp.samplers.ccvt.pairs.ccvt_defines). A pair's records and the points it reads are
 * scattered over megabytes, and each first touch of them waits on memory; the prefetches
 * below start those loads early (what they save: docs/performance.md). OpenCL's own
 * prefetch() compiles to nothing in PoCL. A prefetch never changes a result; without
 * CCVT_PREFETCH the loops that only prefetch are dead code. */
#if defined(CCVT_PREFETCH) && defined(__clang__)   /* a clang builtin */
#define ccvt_prefetch(p) __builtin_prefetch(p)
#else
#define ccvt_prefetch(p) ((void)(p))
#endif

/* max and min as plain comparisons: PoCL calls its builtins for them out of line, a call
 * per use in the loops below */
inline long ccvt_max(const long a, const long b) { return a > b ? a : b; }
inline long ccvt_min(const long a, const long b) { return a < b ? a : b; }

/* Exact integers only: no double (devices without fp64 run this file), and the pruning
 * bounds below are integer upper bounds, so every decision they make is exact on every
 * device. floor(sqrt(x)) for 0 <= x < 2^62: the float square root is only a first guess
 * (any error in it, even more than OpenCL's 3 ulp, is corrected by the two loops, which
 * check r^2 <= x < (r + 1)^2 in integers); for x < 2^48, as here, the guess is within a
 * few units and the loops run a step or two. */
inline long ccvt_isqrt(const long x)
{
    long r = (long)sqrt((float)x);
    while (r > 0 && r * r > x)
        --r;
    while ((r + 1) * (r + 1) <= x)
        ++r;
    return r;
}

/* ceil(sqrt(x)): an integer upper bound on a length whose square x is known. */
inline long ccvt_sqrt_up(const long x)
{
    const long r = ccvt_isqrt(x);
    return r * r == x ? r : r + 1;
}

/* Buckets. The members of a site are kept grouped in CCVT_BUCKETS buckets: 16 angular
 * sectors times 4 radial bands of their offset w from the site's `base` (its position
 * when the buckets were last built), each with the largest |w| in it; a point that
 * arrives is moved into its own bucket. That bounds u.D over a bucket for any
 * direction D without reading it, so a pair reads only the buckets that face it: the
 * points that can move between two neighbouring cells are a thin strip along their
 * common edge, a few per cent of them.
 * The bounds only ever decide what need not be read: a bucket is skipped only when no
 * point in it can matter, so the result is exactly that of reading everything (the
 * NumPy reference does), on every device. */
#define CCVT_BUCKETS (CCVT_SECTORS * CCVT_BANDS)
/* Per-site record (longs), kept exact between rebuilds by the exchanges and moves:
 * sums of the offsets u = x - s and of |u|^2 over the members (s: the site now), a
 * bound on the reach (largest |u|, rounded up), the largest |w| (rounded up), the base,
 * `wide`; then for each bucket its largest |w| (rounded up: integers >= the true
 * lengths, ccvt_sqrt_up).
 * A site is wide while its reach may exceed CCVT_LIMIT (1/8 of the torus): offsets of
 * its members could then wrap when it moves, so its sums are recomputed from scratch
 * instead of updated, and its buckets are read whole. Only rebuilds clear it. */
#define CCVT_SUMX 0
#define CCVT_SUMY 1
#define CCVT_ENERGY 2
#define CCVT_REACH 3
#define CCVT_FAR 4
#define CCVT_BASE 5
#define CCVT_WIDE 6
#define CCVT_RHO 7
#define CCVT_RHOSEC (CCVT_RHO + CCVT_BUCKETS)   /* per sector: the largest, -1 if empty */
#if CCVT_META != CCVT_RHOSEC + CCVT_SECTORS
#error "CCVT_META of the host does not match the record laid out here"
#endif
#define CCVT_LIMIT (1L << 19)
#if VOR_BITS > 22
#error "the integer bounds below are sized for VOR_BITS <= 22 (products below 2^46)"
#endif

/* Rays of the sector boundaries, counter-clockwise (the octants, each halved by a ray
 * at 22.6 degrees from its first side); sector k lies between rays k and k + 1. */
__constant int CCVT_RAY[2 * (CCVT_SECTORS + 1)] = {
    1, 0, 12, 5, 1, 1, 5, 12, 0, 1, -5, 12, -1, 1, -12, 5, -1, 0,
    -12, -5, -1, -1, -5, -12, 0, -1, 5, -12, 1, -1, 12, -5, 1, 0};

/* An integer upper bound on e.D for the unit vector e along ray k, from dot = ray_k . D
 * (exact): |ray k| is 1 (k % 4 == 0), 13 (k odd: 12^2 + 5^2 = 13^2) or sqrt(2)
 * (k % 4 == 2), so e.D = dot, dot / 13 or dot / sqrt(2). dot / 13 rounds up (C's division
 * truncates toward zero, which is up for dot < 0). For sqrt(2) with h = floor(dot^2 / 2):
 * isqrt(h) <= |dot| / sqrt(2) < isqrt(h) + 1 (since h <= dot^2 / 2 < h + 1 and
 * (isqrt(h) + 1)^2 >= h + 1), so isqrt(h) + 1 bounds dot >= 0 and -isqrt(h) dot < 0.
 * On the diagonal rays |dot| <= |dx| + |dy| <= 2^VOR_BITS, so dot^2 <= 2^44. */
inline long ccvt_ray_dot(const int k, const long dot)
{
    if (k % 4 == 0)
        return dot;
    if (k & 1)
        return dot >= 0 ? (dot + 12) / 13 : dot / 13;
    const long h = ccvt_isqrt(dot * dot / 2);
    return dot >= 0 ? h + 1 : -h;
}

typedef struct {
    __global uint *ids;       /* members' point indices, p slots per site */
    __global uint2 *xy;       /* their coordinates */
    __global uint *tids;      /* scratch of the same shape, for rebuilds */
    __global uint2 *txy;
    __global uint *s;         /* sites */
    __global long *meta;      /* CCVT_META per site */
    __global uint *bstart;    /* CCVT_BUCKETS + 1 per site: the slot range of each bucket */
    __global const uint *dirty;
    __global uint *touched;
    uint p;
    long edge[CCVT_BANDS - 1];  /* squared radii between the bands */
    long lo[CCVT_BANDS];        /* radius below which no point of a band lies (rounded down) */
    long drift;                 /* drift from the base that makes the iteration's end rebuild */
} ccvt_t;

inline ccvt_t ccvt_state(const uint n, const uint p, __global uint *ids, __global uint2 *xy,
                         __global uint *tids, __global uint2 *txy, __global uint *s,
                         __global long *meta, __global uint *bstart,
                         __global const uint *dirty, __global uint *touched)
{
    ccvt_t c;
    c.ids = ids;
    c.xy = xy;
    c.tids = tids;
    c.txy = txy;
    c.s = s;
    c.meta = meta;
    c.bstart = bstart;
    c.dirty = dirty;
    c.touched = touched;
    c.p = p;
    /* band edges at 0.42, 0.49, 0.545 / sqrt(n): a cell of area 1/n has its inradius
     * near 0.54 / sqrt(n), so the outer bands hold the points near its edges. In
     * integers, exactly: edge = floor(f^2 2^(2 VOR_BITS) / n) with f^2 = 1764 / 10^4,
     * 2401 / 10^4 and 297025 / 10^6 (297025 << 44 < 2^63); the drift, a tenth of the
     * spacing, floor(sqrt(2^(2 VOR_BITS) / (100 n))) = isqrt(floor(2^(2 VOR_BITS) / (100 n))).
     * Which bucket a point is kept in, and when a site is rebuilt, change no result
     * (the buckets only decide what need not be read). */
    const long unit = 1L << (2 * VOR_BITS);
    const long num[CCVT_BANDS - 1] = {1764L, 2401L, 297025L};
    const long den[CCVT_BANDS - 1] = {10000L, 10000L, 1000000L};
    c.lo[0] = 0;
    c.drift = ccvt_isqrt(unit / (100L * (long)n));
    for (int b = 0; b < CCVT_BANDS - 1; ++b) {
        c.edge[b] = (num[b] << (2 * VOR_BITS)) / (den[b] * (long)n);
        c.lo[b + 1] = ccvt_isqrt(c.edge[b]);   /* a point of band b + 1 has |w|^2 >= edge */
    }
    return c;
}

/* The sector of offset (x, y): its octant, then the side of the octant's middle ray. A
 * point on a ray may go either way: the cones are closed. */
inline int ccvt_sector(const long x, const long y)
{
    int octant;
    if (y >= 0)
        octant = x > 0 ? (y < x ? 0 : 1) : (-x <= y ? 2 : 3);
    else
        octant = x < 0 ? (-y < -x ? 4 : 5) : (x <= -y ? 6 : 7);
    const long mx = CCVT_RAY[4 * octant + 2], my = CCVT_RAY[4 * octant + 3];
    return 2 * octant + (mx * y - my * x >= 0);
}

inline int ccvt_bucket(const ccvt_t *c, const long x, const long y, const long d2)
{
    int band = 0;
    for (int b = 0; b < CCVT_BANDS - 1; ++b)
        band += d2 >= c->edge[b];
    return ccvt_sector(x, y) * CCVT_BANDS + band;
}

/* An upper bound on |u| from |u|^2: floor(sqrt) + 1, the value the reach bound has
 * always had (a wide site is one whose reach bound reaches CCVT_LIMIT). */
inline long ccvt_ceil_sqrt(const long d2)
{
    return ccvt_isqrt(d2) + 1;
}

/* The base of a site's record: where it was when its buckets were built. */
inline uint2 ccvt_base(__global const long *m)
{
    const ulong b = (ulong)m[CCVT_BASE];
    return (uint2)((uint)(b & 0xFFFFFFFFUL), (uint)(b >> 32));
}

/* Q: how far site i has moved since its buckets were built. */
inline long2 ccvt_drift(const ccvt_t *c, const uint i)
{
    const uint2 b = ccvt_base(c->meta + (size_t)i * CCVT_META);
    return (long2)(vor_delta(c->s[2 * i], b.x), vor_delta(c->s[2 * i + 1], b.y));
}

/* Site i to the rounded periodic mean of its members computed from scratch, unwrapped
 * relative to it (never raises its energy: vor_round_mean), as the NumPy reference does. */
inline void ccvt_recenter(const ccvt_t *c, const uint i)
{
    __global uint *s = c->s + 2 * i;
    __global const uint2 *q = c->xy + (size_t)i * c->p;
    const uint x0 = s[0], y0 = s[1];
    long sx = 0, sy = 0;
    for (uint t = 0; t < c->p; ++t) {
        sx += vor_delta(q[t].x, x0);
        sy += vor_delta(q[t].y, y0);
    }
    s[0] = (uint)((long)x0 + vor_round_mean(sx, (long)c->p)) & VOR_MASK;
    s[1] = (uint)((long)y0 + vor_round_mean(sy, (long)c->p)) & VOR_MASK;
}

/* The view of a site from a direction D: for each sector k, an integer upper bound on the
 * largest e.D over the unit vectors e between rays k and k + 1 (ceil |D| when D lies
 * between them, else the larger bound of the two rays, ccvt_ray_dot: e.D is a cosine in
 * the angle from D, so over an arc that does not hold D's direction it is largest at an
 * end), and Q.D with Q the site's drift from its base. A bucket's members w = u + Q then
 * have u.D = w.D - Q.D <= |w| cone - Q.D, which is at most rho cone - Q.D (rho >= |w| its
 * largest |w|) when cone >= 0, and at most lo cone - Q.D (lo <= |w| the smallest |w| of
 * its band) when cone < 0. All exact integers: |w|, |D| < 2^23, so the products stay
 * below 2^46 and every bound below is a true upper bound, never one rounded down. */
typedef struct {
    long cone[CCVT_SECTORS];
    long qd, dlen;
    int wide;
} ccvt_view;

/* A bound that never prunes: the site bound of a wide site (hi + hj and dd - 2 hj stay
 * far inside a long). */
#define CCVT_HUGE (1L << 60)

/* The parts of a view that belong to the site: Q.D and whether it is wide. */
inline void ccvt_look_site(const ccvt_t *c, const uint i, const long dx, const long dy,
                           ccvt_view *v)
{
    const long2 q = ccvt_drift(c, i);
    v->qd = q.x * dx + q.y * dy;
    v->wide = c->meta[(size_t)i * CCVT_META + CCVT_WIDE] != 0;
}

inline void ccvt_look(const ccvt_t *c, const uint i, const long dx, const long dy,
                      ccvt_view *v)
{
    ccvt_look_site(c, i, dx, dy, v);
    v->dlen = ccvt_sqrt_up(dx * dx + dy * dy);
    long dot = 0;
    int left = 0;
    for (int k = 0; k <= CCVT_SECTORS; ++k) {
        const int r = k % CCVT_SECTORS;
        const long ax = CCVT_RAY[2 * r], ay = CCVT_RAY[2 * r + 1];
        const long d = ccvt_ray_dot(r, ax * dx + ay * dy);
        const int l = ax * dy - ay * dx >= 0;
        if (k > 0)
            v->cone[k - 1] = left && !l ? v->dlen : ccvt_max(dot, d);
        dot = d;
        left = l;
    }
}

/* ccvt_look for E = -D, from the view along D: the rays are symmetric (ray k + 8 = -ray k),
 * so the cone of sector k toward E is that of sector k + 8 toward D. */
inline void ccvt_look_back(const ccvt_t *c, const uint j, const long ex, const long ey,
                           const ccvt_view *front, ccvt_view *v)
{
    ccvt_look_site(c, j, ex, ey, v);
    v->dlen = front->dlen;
    for (int k = 0; k < CCVT_SECTORS; ++k)
        v->cone[k] = front->cone[(k + CCVT_SECTORS / 2) % CCVT_SECTORS];
}

/* An upper bound on u.D over the members of bucket k whose largest |w| is at most rho. */
inline long ccvt_bound(const ccvt_t *c, const ccvt_view *v, const int k, const long rho)
{
    const long e = v->cone[k / CCVT_BANDS];
    return (e >= 0 ? rho : c->lo[k % CCVT_BANDS]) * e - v->qd;
}

/* An upper bound on u.D over the members of a sector whose largest |w| is at most rho. */
inline long ccvt_sector_bound(const ccvt_view *v, const int sector, const long rho)
{
    return rho * ccvt_max(v->cone[sector], 0) - v->qd;
}

/* An upper bound on max u.D over all members of site i: per sector, the largest |w| of
 * its members (CCVT_RHOSEC); CCVT_HUGE while the site is wide. */
inline long ccvt_site_bound(const ccvt_t *c, const uint i, const ccvt_view *v)
{
    if (v->wide)
        return CCVT_HUGE;
    __global const long *m = c->meta + (size_t)i * CCVT_META;
    long b = -CCVT_HUGE;
    for (int k = 0; k < CCVT_SECTORS; ++k) {
        const long rho = m[CCVT_RHOSEC + k];
        if (rho >= 0)
            b = ccvt_max(b, ccvt_sector_bound(v, k, rho));
    }
    return b;
}

/* The record and bucket ranges of site i on their way into the cache (ccvt_prefetch). */
inline void ccvt_prefetch_site(const ccvt_t *c, const uint i)
{
    __global const long *m = c->meta + (size_t)i * CCVT_META;
    __global const uint *bs = c->bstart + (size_t)i * (CCVT_BUCKETS + 1);
    for (int k = 0; k < CCVT_META; k += 8)
        ccvt_prefetch(m + k);
    ccvt_prefetch(m + CCVT_META - 1);
    for (int k = 0; k <= CCVT_BUCKETS; k += 16)
        ccvt_prefetch(bs + k);
}

/* Order of the candidates, members of one site in slots k and k2: larger gain first, then
 * the smaller point index (read only on a tie). */
inline int ccvt_before(const long g, const uint k, const long g2, const uint k2,
                       __global const uint *ids)
{
    return g > g2 || (g == g2 && ids[k] < ids[k2]);
}

inline void ccvt_insert(const long g, const uint k, const uint bucket, uint *c, long *gain,
                        uint *slot, uint *bk, __global const uint *ids)
{
    if (*c == CCVT_TOP && !ccvt_before(g, k, gain[CCVT_TOP - 1], slot[CCVT_TOP - 1], ids))
        return;
    uint q = *c < CCVT_TOP ? (*c)++ : CCVT_TOP - 1;
    while (q > 0 && ccvt_before(g, k, gain[q - 1], slot[q - 1], ids)) {
        gain[q] = gain[q - 1];
        slot[q] = slot[q - 1];
        bk[q] = bk[q - 1];
        --q;
    }
    gain[q] = g;
    slot[q] = k;
    bk[q] = bucket;
}

/* The CCVT_TOP points of site i that gain most by moving to the site at offset D from it,
 * among those with gain > floor, sorted by ccvt_before; only the buckets whose bound B on
 * u.D can give such a gain (2 B - dd > floor) are read. Returns how many. The gain
 * of x, with u its offset from s_i, is
 *     |u|^2 - |u - D|^2 = 2 u.D - |D|^2  (dd = |D|^2),
 * the exact change of its squared distance when the other site's image at s_i + D is the
 * nearest, and never more than the true change otherwise (the torus can only bring the
 * other site nearer): an exchange accepted on these gains lowers the energy at least as
 * much as they say. */
inline uint ccvt_top(const ccvt_t *c, const uint i, const long dx, const long dy, const long dd,
                     const ccvt_view *v, const long floor, long *gain, uint *slot, uint *bk)
{
    __global const uint *bs = c->bstart + (size_t)i * (CCVT_BUCKETS + 1);
    __global const uint *ids = c->ids + (size_t)i * c->p;
    __global const uint2 *q = c->xy + (size_t)i * c->p;
    __global long *m = c->meta + (size_t)i * CCVT_META;
    const uint sx = c->s[2 * i], sy = c->s[2 * i + 1];
    /* w = u + Q: a bucket that is read anyway gets its exact largest |w| back (arrivals
     * only ever raise it, departures leave it high) */
    const long2 drift = ccvt_drift(c, i);
    const long qx = drift.x, qy = drift.y;
    uint count = 0;
    /* a bucket whose bound B has 2 B <= thr = dd + floor holds no point with gain > floor;
     * once CCVT_TOP candidates are in, one with 2 B < cut = dd + the last one's gain only
     * points that gain less than it: neither is read. (|floor| <= 2^61: ccvt_pair) */
    const long thr = dd + floor;
    long cut = LONG_MIN;
    long low = floor;
    /* the sectors nearest the direction of D first (the best candidates lie there, so
     * the list fills with them early and the rest are mostly skipped or rejected) */
    const int facing = ccvt_sector(dx, dy);
    /* the points of the three sectors facing D outside band 0 are nearly always read */
    for (int d = CCVT_SECTORS - 1; d <= CCVT_SECTORS + 1; ++d) {
        const int k = ((facing + d) % CCVT_SECTORS) * CCVT_BANDS;
        for (uint t = bs[k + 1]; t < bs[k + CCVT_BANDS]; t += 8)
            ccvt_prefetch(q + t);
        if (bs[k + 1] < bs[k + CCVT_BANDS])
            ccvt_prefetch(q + bs[k + CCVT_BANDS] - 1);
    }
    for (int turn = 0; turn < CCVT_SECTORS; ++turn) {
        const int step = (turn + 1) / 2;   /* facing, facing + 1, facing - 1, facing + 2, ... */
        const int sector = (facing + (turn & 1 ? step : CCVT_SECTORS - step)) % CCVT_SECTORS;
        const long top = m[CCVT_RHOSEC + sector];
        if (top < 0)
            continue;   /* no members */
        if (!v->wide) {
            const long b = 2 * ccvt_sector_bound(v, sector, top);
            if (b <= thr || b < cut)
                continue;
        }
        long most = -1;
        for (int band = CCVT_BANDS - 1; band >= 0; --band) {
            const int k = sector * CCVT_BANDS + band;
            if (bs[k] == bs[k + 1])
                continue;
            const long rho = m[CCVT_RHO + k];
            if (!v->wide) {
                const long b = 2 * ccvt_bound(c, v, k, rho);
                if (b <= thr || b < cut) {
                    most = ccvt_max(most, rho);
                    continue;
                }
            }
            long w2 = 0;
            const uint first = bs[k], end = bs[k + 1];
            for (uint t = first; t < end; ++t) {
                const uint2 x = q[t];
                const long ux = vor_delta(x.x, sx), uy = vor_delta(x.y, sy);
                const long g = 2 * (ux * dx + uy * dy) - dd;
                const long r2 = (ux + qx) * (ux + qx) + (uy + qy) * (uy + qy);
                w2 = ccvt_max(w2, r2);
                if (g > low) {
                    ccvt_insert(g, t, (uint)k, &count, gain, slot, bk, ids);
                    if (count == CCVT_TOP)   /* a point below the last one cannot enter */
                        low = ccvt_max(low, gain[CCVT_TOP - 1] - 1);
                }
            }
            if (count == CCVT_TOP)
                cut = dd + gain[CCVT_TOP - 1];
            const long exact = ccvt_sqrt_up(w2);
            if (!v->wide)
                m[CCVT_RHO + k] = exact;
            most = ccvt_max(most, exact);
        }
        if (!v->wide)
            m[CCVT_RHOSEC + sector] = most;
    }
    return count;
}

/* Point `in` takes the place of `out` among the members of site i: the sums change by the
 * difference and the reach bound grows to cover it (its bucket: ccvt_rehome). */
inline void ccvt_enter(const ccvt_t *c, const uint i, const uint2 in, const uint2 out)
{
    __global long *m = c->meta + (size_t)i * CCVT_META;
    const uint sx = c->s[2 * i], sy = c->s[2 * i + 1];
    const long ux = vor_delta(in.x, sx), uy = vor_delta(in.y, sy);
    const long vx = vor_delta(out.x, sx), vy = vor_delta(out.y, sy);
    const long u2 = ux * ux + uy * uy;
    m[CCVT_SUMX] += ux - vx;
    m[CCVT_SUMY] += uy - vy;
    m[CCVT_ENERGY] += u2 - (vx * vx + vy * vy);
    m[CCVT_REACH] = ccvt_max(m[CCVT_REACH], ccvt_ceil_sqrt(u2));
    if (m[CCVT_REACH] >= CCVT_LIMIT)
        m[CCVT_WIDE] = 1;
}

/* Exchanges the contents of slots a and b of a site, and follows them in pend[0..np). */
inline void ccvt_slot_swap(__global uint *ids, __global uint2 *q, const uint a, const uint b,
                           uint *pend, const uint np)
{
    if (a == b)
        return;
    const uint t = ids[a];
    ids[a] = ids[b];
    ids[b] = t;
    const uint2 u = q[a];
    q[a] = q[b];
    q[b] = u;
    for (uint k = 0; k < np; ++k)
        pend[k] = pend[k] == a ? b : (pend[k] == b ? a : pend[k]);
}

/* The member that arrived in slot t of site i (the bucket `from` of the one it replaced)
 * moves to its own bucket: it crosses the buckets between one boundary at a time, each
 * time exchanging places with the boundary slot, which moves that boundary by one. The
 * bucket's largest |w| grows to cover it. pend[0..np) are slots still to move. */
inline void ccvt_rehome(const ccvt_t *c, const uint i, uint t, int from, uint *pend,
                        const uint np)
{
    __global long *m = c->meta + (size_t)i * CCVT_META;
    __global uint *bs = c->bstart + (size_t)i * (CCVT_BUCKETS + 1);
    __global uint *ids = c->ids + (size_t)i * c->p;
    __global uint2 *q = c->xy + (size_t)i * c->p;
    const uint2 base = ccvt_base(m);
    const long wx = vor_delta(q[t].x, base.x), wy = vor_delta(q[t].y, base.y);
    const long w2 = wx * wx + wy * wy;
    const int to = ccvt_bucket(c, wx, wy, w2);
    const long w = ccvt_sqrt_up(w2);
    const int top = CCVT_RHOSEC + to / CCVT_BANDS;   /* its sector's largest |w| */
    m[CCVT_RHO + to] = ccvt_max(m[CCVT_RHO + to], w);
    m[top] = ccvt_max(m[top], w);
    m[CCVT_FAR] = ccvt_max(m[CCVT_FAR], w);
    for (; from < to; ++from) {
        const uint last = bs[from + 1] - 1;
        ccvt_slot_swap(ids, q, t, last, pend, np);
        t = last;
        bs[from + 1] = last;
    }
    for (; from > to; --from) {
        const uint first = bs[from];
        ccvt_slot_swap(ids, q, t, first, pend, np);
        t = first;
        bs[from] = first + 1;
    }
}

/* Sums, energy, reach, base and buckets of site i from scratch, relative to where it is;
 * the slots are regrouped by bucket (through the scratch slots). */
inline void ccvt_rebuild(const ccvt_t *c, const uint i)
{
    const uint p = c->p;
    __global uint *ids = c->ids + (size_t)i * p;
    __global uint2 *q = c->xy + (size_t)i * p;
    __global uint *tids = c->tids + (size_t)i * p;
    __global uint2 *txy = c->txy + (size_t)i * p;
    __global long *m = c->meta + (size_t)i * CCVT_META;
    __global uint *bs = c->bstart + (size_t)i * (CCVT_BUCKETS + 1);
    const uint sx = c->s[2 * i], sy = c->s[2 * i + 1];
    uint count[CCVT_BUCKETS];
    long top[CCVT_BUCKETS];
    for (int k = 0; k < CCVT_BUCKETS; ++k) {
        count[k] = 0;
        top[k] = 0;
    }
    long sumx = 0, sumy = 0, e = 0, far = 0;
    for (uint t = 0; t < p; ++t) {
        const long ux = vor_delta(q[t].x, sx), uy = vor_delta(q[t].y, sy);
        const long d2 = ux * ux + uy * uy;
        sumx += ux;
        sumy += uy;
        e += d2;
        far = ccvt_max(far, d2);
        const int k = ccvt_bucket(c, ux, uy, d2);
        count[k] += 1;
        top[k] = ccvt_max(top[k], d2);
    }
    uint at = 0;
    for (int k = 0; k < CCVT_BUCKETS; ++k) {
        bs[k] = at;
        at += count[k];
        count[k] = bs[k];
        m[CCVT_RHO + k] = ccvt_sqrt_up(top[k]);
    }
    bs[CCVT_BUCKETS] = at;
    for (int sector = 0; sector < CCVT_SECTORS; ++sector) {
        long most = -1;
        for (int band = 0; band < CCVT_BANDS; ++band) {
            const int k = sector * CCVT_BANDS + band;
            if (bs[k] != bs[k + 1])
                most = ccvt_max(most, m[CCVT_RHO + k]);
        }
        m[CCVT_RHOSEC + sector] = most;
    }
    for (uint t = 0; t < p; ++t) {
        const long ux = vor_delta(q[t].x, sx), uy = vor_delta(q[t].y, sy);
        const uint to = count[ccvt_bucket(c, ux, uy, ux * ux + uy * uy)]++;
        tids[to] = ids[t];
        txy[to] = q[t];
    }
    for (uint t = 0; t < p; ++t) {
        ids[t] = tids[t];
        q[t] = txy[t];
    }
    m[CCVT_SUMX] = sumx;
    m[CCVT_SUMY] = sumy;
    m[CCVT_ENERGY] = e;
    m[CCVT_REACH] = ccvt_ceil_sqrt(far);
    m[CCVT_FAR] = ccvt_sqrt_up(far);
    m[CCVT_BASE] = (long)((ulong)sx | ((ulong)sy << 32));   /* read by ccvt_base */
    m[CCVT_WIDE] = m[CCVT_REACH] >= CCVT_LIMIT;
}

/* Site i to the rounded periodic mean of its members (the value ccvt_recenter gives),
 * from the kept sums (moving by q changes them by -p q and -2 q.sum + p |q|^2, exactly, since no offset
 * wraps while the reach stays below CCVT_LIMIT); a wide site from scratch. */
inline void ccvt_move(const ccvt_t *c, const uint i)
{
    __global long *m = c->meta + (size_t)i * CCVT_META;
    __global uint *s = c->s + 2 * i;
    const long p = c->p;
    if (m[CCVT_WIDE]) {
        __global const uint2 *q = c->xy + (size_t)i * c->p;
        ccvt_recenter(c, i);
        long far = 0;
        for (uint t = 0; t < c->p; ++t)
            far = ccvt_max(far, vor_d2(q[t].x, q[t].y, s[0], s[1]));
        m[CCVT_REACH] = ccvt_ceil_sqrt(far);   /* the sums wait for the rebuild */
        return;
    }
    const long mx = vor_round_mean(m[CCVT_SUMX], p), my = vor_round_mean(m[CCVT_SUMY], p);
    m[CCVT_ENERGY] += p * (mx * mx + my * my) - 2 * (mx * m[CCVT_SUMX] + my * m[CCVT_SUMY]);
    m[CCVT_SUMX] -= p * mx;
    m[CCVT_SUMY] -= p * my;
    m[CCVT_REACH] += ((long)abs(mx)) + ((long)abs(my));
    if (m[CCVT_REACH] >= CCVT_LIMIT)
        m[CCVT_WIDE] = 1;
    s[0] = (uint)((long)s[0] + mx) & VOR_MASK;
    s[1] = (uint)((long)s[1] + my) & VOR_MASK;
}

/* A bound on the distance from site i to its farthest member: the reach bound, or the
 * largest |w| plus the drift from the base if that is smaller (not while wide). */
inline long ccvt_reach(const ccvt_t *c, const uint i)
{
    __global const long *m = c->meta + (size_t)i * CCVT_META;
    if (m[CCVT_WIDE])
        return m[CCVT_REACH];
    const long2 q = ccvt_drift(c, i);
    return ccvt_min(m[CCVT_REACH], m[CCVT_FAR] + (long)abs(q.x) + (long)abs(q.y));
}

/* Balzer's pairwise swap for sites i and j: their best candidates toward each other,
 * sorted, are exchanged in order while the two gains sum to more than zero (each exchange
 * lowers the energy by exactly that sum). A round looks at CCVT_TOP candidates a side;
 * when all of them were exchanged another round starts from the new memberships. A pair
 * that exchanged moves both sites to their centroids at once (as Balzer et al.'s code
 * does), so the pairs after it see them moved. */
inline uint ccvt_pair(const ccvt_t *c, const uint i, const uint j, const long near2)
{
    /* Skipping is exact, never a change of result: a pair where neither site moved nor
     * changed members since it last met found nothing then and finds nothing now. With
     * Hi >= max u.D over i's members and Hj >= max v.(-D) over j's (the bucket bounds), the
     * two gains of an exchange sum to at most 2 (Hi + Hj - |D|^2), so nothing moves unless
     * Hi + Hj > |D|^2, and a point of i is a candidate only if its gain exceeds
     * -(2 Hj - |D|^2); and Hi + Hj <= |D| (R_i + R_j) with the reaches R, so sites
     * farther apart than R_i + R_j are not even read. */
    const int fresh = c->touched[i] || c->touched[j];
    if (!fresh && !c->dirty[i] && !c->dirty[j])
        return 0;
    __global uint *s = c->s;
    const uint ix = s[2 * i], iy = s[2 * i + 1], jx = s[2 * j], jy = s[2 * j + 1];
    const long dist2 = vor_d2(ix, iy, jx, jy);
    if (dist2 >= near2)
        return 0;   /* not neighbours: the pair graph joins sites closer than ccvt_near */
    /* (a reach bound grows by at most a move's length per move, and a site moves a few
     * dozen times an iteration before the rebuild that resets a wide one: rr stays far
     * below 2^31; the guard keeps rr^2 in a long whatever happens) */
    const long rr = ccvt_reach(c, i) + ccvt_reach(c, j);
    if (rr < (1L << 31) && dist2 > rr * rr)
        return 0;
    ccvt_prefetch_site(c, i);
    ccvt_prefetch_site(c, j);
    /* offsets of each site from the other: delta is antisymmetric but at exactly half the
     * torus, so each direction is computed, not negated */
    const long dijx = vor_delta(jx, ix), dijy = vor_delta(jy, iy);
    const long djix = vor_delta(ix, jx), djiy = vor_delta(iy, jy);
    const long dd = dijx * dijx + dijy * dijy;
    __global uint *mi = c->ids + (size_t)i * c->p;
    __global uint *mj = c->ids + (size_t)j * c->p;
    __global uint2 *pi = c->xy + (size_t)i * c->p;
    __global uint2 *pj = c->xy + (size_t)j * c->p;
    ccvt_view vi, vj;
    long gi[CCVT_TOP], gj[CCVT_TOP];
    uint si[CCVT_TOP], sj[CCVT_TOP], ki[CCVT_TOP], kj[CCVT_TOP];
    uint total = 0;
    for (;;) {
        ccvt_look(c, i, dijx, dijy, &vi);
        if (djix == -dijx && djiy == -dijy)
            ccvt_look_back(c, j, djix, djiy, &vi, &vj);
        else
            ccvt_look(c, j, djix, djiy, &vj);
        const long hi = ccvt_site_bound(c, i, &vi), hj = ccvt_site_bound(c, j, &vj);
        if (hi + hj <= dd)
            break;
        /* a point of i can only be exchanged if its gain beats minus j's best, at most
         * 2 Hj - dd; one of j only if it beats minus i's best, gi[0] (all exact: with
         * |Hj| <= CCVT_HUGE = 2^60, dd - 2 Hj and dd + floor stay within 2^62) */
        const uint ci = ccvt_top(c, i, dijx, dijy, dd, &vi, dd - 2 * hj, gi, si, ki);
        if (ci == 0)
            break;
        const uint cj = ccvt_top(c, j, djix, djiy, dd, &vj, -gi[0], gj, sj, kj);
        const uint k = min(ci, cj);
        uint done = 0;
        while (done < k && gi[done] + gj[done] > 0) {
            const uint a = si[done], b = sj[done];
            const uint2 u = pi[a], v = pj[b];
            ccvt_enter(c, i, v, u);
            ccvt_enter(c, j, u, v);
            const uint t = mi[a];
            mi[a] = mj[b];
            mj[b] = t;
            pi[a] = v;
            pj[b] = u;
            ++done;
        }
        for (uint d = 0; d < done; ++d) {
            ccvt_rehome(c, i, si[d], (int)ki[d], si + d + 1, done - d - 1);
            ccvt_rehome(c, j, sj[d], (int)kj[d], sj + d + 1, done - d - 1);
        }
        total += done;
        if (done < CCVT_TOP)
            break;
    }
    if (total) {
        c->touched[i] = 1;
        c->touched[j] = 1;
        ccvt_move(c, i);
        ccvt_move(c, j);
    }
    return total;
}

/* The exchanges of one cell pair of a phase: (a, b) numbers the pair, (ox, oy) = (0, 0)
 * is phase 0 (the pairs inside cell (a, b)). Returns the number of exchanges. */
inline uint ccvt_cell_pairs(const ccvt_t *c, const uint a, const uint b, const int ox,
                            const int oy, const uint parity, const uint G,
                            __global const uint *start, __global const uint *list,
                            const long near2)
{
    uint total = 0;
    if (ox == 0 && oy == 0) {
        const uint cell = b * G + a;
        for (uint qa = start[cell]; qa < start[cell + 1]; ++qa)
            for (uint qb = qa + 1; qb < start[cell + 1]; ++qb)
                total += ccvt_pair(c, list[qa], list[qb], near2);
    } else {
        const uint ax = ox != 0 ? 2 * a + parity : b;
        const uint ay = ox != 0 ? b : 2 * a + parity;
        const uint bx = (uint)(((int)ax + ox + (int)G) % (int)G);
        const uint by = (uint)(((int)ay + oy + (int)G) % (int)G);
        const uint ca = ay * G + ax, cb = by * G + bx;
        for (uint qa = start[ca]; qa < start[ca + 1]; ++qa)
            for (uint qb = start[cb]; qb < start[cb + 1]; ++qb)
                total += ccvt_pair(c, list[qa], list[qb], near2);
    }
    return total;
}

#endif
