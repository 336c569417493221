"""The relay of the CCVT start: the points over a site's capacity passed along neighbouring
sites until each rests at a site with room (:func:`relay`). NumPy, shared by both
backends."""

import numpy as np

from ...geometry import integer_torus as it
from ...geometry.cells import stable_order
from .pairs import ccvt_near2
from .power import start_grid_size, start_table

RELAY_BATCH = 128      # carried points a site hands on per round (more wait a round)


def members_matrix(owner, S, p):
    """Owners (-1: none yet) as a (S, p) matrix of point ids, ascending in each row, rows
    of sites with room ending in -1. A site given more than p keeps its first p (in id
    order).

    Parameters
    ----------
    owner : ndarray of int
        Each point's site (global id), -1 for none.
    S : int
        Sites, over all realizations.
    p : int
        Capacity.

    Returns
    -------
    matrix : ndarray of int
        (S, p).
    extra : ndarray of int
        The ids no site could keep, ascending.
    """
    key = np.where(owner < 0, S, owner)
    # each site's ids are one run of `order`, ascending, and a row is the first p of its
    # run, gathered in one go
    order = stable_order(key, S + 1)
    count = np.bincount(key, minlength=S + 1)[:S]
    start = np.cumsum(count) - count
    take = np.minimum(count, p)
    col = np.arange(p)
    mat = order[np.minimum(start[:, None] + col, max(len(order) - 1, 0))]
    mat = np.where(col < take[:, None], mat, -1)
    extra = count - take
    over = np.flatnonzero(extra)
    ends = np.cumsum(extra[over])
    pos = np.repeat(start[over] + p - ends + extra[over], extra[over]) + np.arange(ends[-1] if
                                                                              over.size else 0)
    return mat, np.sort(order[pos])


def _run_lengths(sorted_ids):
    """Values, first positions and lengths of the runs of a sorted array (np.unique's)."""
    if not len(sorted_ids):
        return sorted_ids, sorted_ids, sorted_ids
    first = np.flatnonzero(np.concatenate([[True], sorted_ids[1:] != sorted_ids[:-1]]))
    return sorted_ids[first], first, np.diff(np.append(first, len(sorted_ids)))


def relay(sites, points, mat, room, left, start):
    """Places the carried points ``left`` (global ids) by passing excess along
    neighbouring sites (:func:`start_partition`, step 3).

    ``mat`` (S, p) holds the point ids of every site (-1: room), ``room`` its free slots;
    a carried point starts at ``start`` (its power owner; -1: none, then at the site with
    room nearest to it). Each round, a site a holding carried points fills its room with
    them (in id order); if k remain (at most RELAY_BATCH; more wait a round), it picks
    its target, the site with room nearest to it (ties: smaller index), and its next hop
    b: of its neighbours (sites closer than NEAR / sqrt(n), the optimizer's pairs), the
    one nearest to the target, or, where none is nearer to it than a (a gap in the
    sites), the site nearest to a of those nearer to the target. Of its p points and the
    k carried, the k with the smallest gain |u - D|^2 - |u|^2 of moving to b (u, D: the
    toroidal offsets of the point and of s_b from s_a; ties: the earlier slot, the
    carried last) are carried on to b, and the carried ones not chosen take the freed
    slots. The distance to the target falls with every hop and room is never lost, so
    every point comes to rest; the capacities stay
    exact at every step. Updates ``mat`` (rows left ascending) and ``room`` in place.

    Parameters
    ----------
    sites : ndarray
        (r, n, 2) integer coordinates.
    points : ndarray
        (r, M, 2) density points.
    mat : ndarray of int
        (S, p), S = r n: each site's point ids, -1 for room.
    room : ndarray of int
        (S,) free slots per site.
    left : ndarray of int
        The carried points' global ids.
    start : ndarray of int
        Each carried point's first site, -1 for none.
    """
    if not left.size:
        return
    r, n, _ = sites.shape
    M = points.shape[1]
    S, p = mat.shape
    sx = sites[..., 0].ravel().astype(np.int64)
    sy = sites[..., 1].ravel().astype(np.int64)
    px = points[..., 0].ravel().astype(np.int64)
    py = points[..., 1].ravel().astype(np.int64)
    # neighbours: the sites of the 3 x 3 cells around each site's cell
    G = start_grid_size(n)
    near = []
    for k in range(r):
        xy = np.stack([sx[k * n:(k + 1) * n], sy[k * n:(k + 1) * n]], axis=1)
        table, _ = start_table(xy, k * n + np.arange(n), G, -1)
        cell = it.cell_of(xy[:, 1], G) * G + it.cell_of(xy[:, 0], G) if G > 1 \
            else np.zeros(n, dtype=np.int64)
        near.append(table[cell])
    width = max(t.shape[1] for t in near)
    near = np.concatenate([np.pad(t, ((0, 0), (0, width - t.shape[1])), constant_values=-1)
                           for t in near])
    own = np.arange(S)[:, None]
    near = np.where(near < 0, own, near)              # padding: the site itself
    # neighbours as the optimizer's pairs: closer than NEAR / sqrt(n)
    far = it.distance2(sx[near], sy[near], sx[own], sy[own]) >= ccvt_near2(n)
    near = np.where(far, own, near)

    def nearest_room(x, y, realization):
        # the sites with room of every realization, ascending, padded (all at once)
        has = room.reshape(r, n) > 0
        count = has.sum(axis=1)
        width = max(1, int(count.max()))
        ids = np.argsort(~has, axis=1, kind="stable")[:, :width] + (np.arange(r) * n)[:, None]
        out = np.empty(len(x), dtype=np.int64)
        step = max(1, (1 << 22) // width)              # rows x rooms stays ~32 MB a piece
        for lo in range(0, len(x), step):
            q = slice(lo, lo + step)
            cand = ids[realization[q]]
            d2 = it.distance2(x[q, None], y[q, None], sx[cand], sy[cand])
            d2[np.arange(width)[None, :] >= count[realization[q]][:, None]] = np.iinfo(np.int64).max
            out[q] = cand[np.arange(len(cand)), np.argmin(d2, axis=1)]   # ties: the smaller index
        return out

    # a site's 3 x 3 cells hold every site within one cell width of it, so a room found
    # among its neighbours nearer than that (or than NEAR / sqrt(n) with one cell) is the
    # nearest room of all, ties included (rows ascending); the rest search everything
    reach2 = ccvt_near2(n) if G == 1 else (it.SIZE // G) ** 2

    def nearest_room_of_sites(a):
        nb = near[a]
        d2 = it.distance2(sx[nb], sy[nb], sx[a, None], sy[a, None])
        d2[room[nb] <= 0] = np.iinfo(np.int64).max
        pick = np.argmin(d2, axis=1)
        rows = np.arange(len(a))
        out = nb[rows, pick]
        miss = d2[rows, pick] >= reach2
        if miss.any():
            out[miss] = nearest_room(sx[a[miss]], sy[a[miss]], a[miss] // n)
        return out

    carry = left.copy()
    realization = carry // M
    target = np.full(S, -1, dtype=np.int64)         # each site's target, while it has room
    wide = S * r * M < 1 << 62                      # (site, point) keys fit in one int64
    cur = np.asarray(start, dtype=np.int64).copy()
    lost = cur < 0
    if lost.any():                                  # no candidate at all: straight to room
        cur[lost] = nearest_room(px[carry[lost]], py[carry[lost]], realization[lost])
    while carry.size:
        # the carried points by site, in the order of the points: groups of one site
        order = np.argsort(cur * (r * M) + carry) if wide else np.lexsort((carry, cur))
        carry, cur, realization = carry[order], cur[order], realization[order]
        sites_at, first, size = _run_lengths(cur)
        rank = np.arange(len(carry)) - np.repeat(first, size)
        free = np.repeat(room[sites_at], size)
        settle = rank < free                        # a site with room keeps what it can hold
        if settle.any():
            a = cur[settle]
            mat[a, p - free[settle] + rank[settle]] = carry[settle]
            room[sites_at] -= np.minimum(size, room[sites_at])
        # the rest hand on at most RELAY_BATCH a round (the others wait their turn)
        hand = ~settle & (rank < free + RELAY_BATCH)
        wait = ~settle & ~hand
        g = np.flatnonzero(hand)
        nxt_carry, nxt_cur = [carry[wait]], [cur[wait]]
        if g.size:
            a_all = cur[g]
            a, _, k = _run_lengths(a_all)
            stale = (target[a] < 0) | (room[np.maximum(target[a], 0)] <= 0)
            if stale.any():                             # a target is kept while it has room
                target[a[stale]] = nearest_room_of_sites(a[stale])
            z = target[a]
            nb = near[a]
            d2 = it.distance2(sx[nb], sy[nb], sx[z, None], sy[z, None])
            b = nb[np.arange(len(a)), np.argmin(d2, axis=1)]
            closer = (it.distance2(sx[b], sy[b], sx[z], sy[z])
                      < it.distance2(sx[a], sy[a], sx[z], sy[z]))
            # no neighbour nearer to the target (a gap in the sites): the nearest site that
            # is nearer to it, the target itself at worst
            stuck = np.flatnonzero(~closer)
            b[stuck] = z[stuck]
            step = max(1, (1 << 22) // n)
            for lo in range(0, len(stuck), step):
                q = stuck[lo:lo + step]
                every = (a[q] // n * n)[:, None] + np.arange(n)[None, :]
                toward = it.distance2(sx[every], sy[every], sx[z[q], None], sy[z[q], None]) \
                    < it.distance2(sx[a[q]], sy[a[q]], sx[z[q]], sy[z[q]])[:, None]
                d2 = it.distance2(sx[every], sy[every], sx[a[q], None], sy[a[q], None])
                d2[~toward] = np.iinfo(np.int64).max
                pick = np.argmin(d2, axis=1)
                found = toward[np.arange(len(q)), pick]
                b[q[found]] = every[np.arange(len(q)), pick][found]
            kmax = int(k.max())
            # candidates: the site's points, then the carried ones (padding: -1)
            col = np.arange(kmax)
            have = col[None, :] < k[:, None]
            extra = np.full((len(a), kmax), -1, dtype=np.int64)
            extra[have] = carry[g]                  # g is grouped by site, ids ascending
            cand = np.concatenate([mat[a], extra], axis=1)
            safe = np.maximum(cand, 0)
            # gain |u - D|^2 - |u|^2 = |D|^2 - 2 u.D of handing y to b (u, D: the toroidal
            # offsets of y and s_b from s_a): in the order of -u.D, ties to the earlier slot
            dx = it.delta(sx[b], sx[a])[:, None]
            dy = it.delta(sy[b], sy[a])[:, None]
            ux = it.delta(px[safe], sx[a, None])
            uy = it.delta(py[safe], sy[a, None])
            gain = -(ux * dx + uy * dy)
            width = cand.shape[1]
            bits = width.bit_length()
            top = np.iinfo(np.int64).max
            if it.BITS * 2 + 2 + bits <= 62:
                key = np.where(cand < 0, top, (gain << bits) | np.arange(width)[None, :])
            else:                                   # huge p: ranks of (gain, slot) instead
                key = np.empty_like(gain)
                rank_of = np.lexsort((np.broadcast_to(np.arange(width), gain.shape).ravel(),
                                      np.where(cand < 0, top, gain).ravel(),
                                      np.repeat(np.arange(len(a)), width)))
                key.ravel()[rank_of] = np.arange(gain.size)
            chosen = np.argpartition(key, kmax - 1, axis=1)[:, :kmax] if kmax < width \
                else np.broadcast_to(np.arange(width), key.shape).copy()
            chosen = np.take_along_axis(chosen, np.argsort(
                np.take_along_axis(key, chosen, axis=1), axis=1), axis=1)
            moved = np.take_along_axis(cand, chosen, axis=1)
            picked = np.zeros(cand.shape, dtype=bool)
            np.put_along_axis(picked, chosen, have, axis=1)
            # the carried points not handed on take the slots of the site's points that are
            # handed on
            row, slot = np.nonzero(picked[:, :p])
            mat[a[row], slot] = extra[~picked[:, p:] & have]
            nxt_carry.append(moved[have])
            nxt_cur.append(np.repeat(b, k))
        carry = np.concatenate(nxt_carry)
        cur = np.concatenate(nxt_cur)
        realization = carry // M
    changed = np.flatnonzero((np.diff(mat, axis=1) < 0).any(axis=1))
    mat[changed] = np.sort(mat[changed], axis=1)
