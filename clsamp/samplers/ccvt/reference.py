"""The NumPy reference of the CCVT optimization (:func:`ccvt_reference`): every pair of
neighbouring sites exchanges points in the kernels' order, reading every point, so it
gives the kernels' integers bit for bit."""

import numpy as np

from ...geometry import integer_torus as it
from .pairs import CCVT_TOP, PHASES, ccvt_grid_size, ccvt_near2


def _recenter_reference(sites, points, members, which):
    """The sites ``which`` of one realization to the rounded periodic means of their
    members, unwrapped relative to each site (``ccvt_recenter``), in place."""
    px = points[members[which], 0].astype(np.int64)
    py = points[members[which], 1].astype(np.int64)
    p = members.shape[1]
    s = sites[which]
    x = (s[:, 0] + it.round_mean(it.delta(px, s[:, 0:1]).sum(1), p)) & it.MASK
    y = (s[:, 1] + it.round_mean(it.delta(py, s[:, 1:2]).sum(1), p)) & it.MASK
    sites[which] = np.stack([x, y], axis=1)


def _centroids_reference(sites, points, members, site_energy, which):
    """One realization's centroid step for the sites ``which`` (``ccvt_centroids``): moves
    them, refreshes their entries of site_energy, returns the total energy (int)."""
    _recenter_reference(sites, points, members, which)
    px = points[members[which], 0].astype(np.int64)
    py = points[members[which], 1].astype(np.int64)
    s = sites[which]
    site_energy[which] = it.distance2(px, py, s[:, 0:1], s[:, 1:2]).sum(axis=1)
    return it.split_total(site_energy)


def _gains(x, a, b):
    """Gains 2 u.D - |D|^2 of the points x (owned by the site at a) toward the site at b:
    u = delta(x, a), D = delta(b, a) (``ccvt_top``)."""
    dx, dy = it.delta(b[0], a[0]), it.delta(b[1], a[1])
    u = it.delta(x[:, 0], a[0]), it.delta(x[:, 1], a[1])
    return 2 * (u[0] * dx + u[1] * dy) - (dx * dx + dy * dy)


def _pair_reference(mi, mj, points, si, sj):
    """Balzer's swap of one pair, in place on the member rows mi, mj (the kernel's ccvt_pair)."""
    total = 0
    while True:
        gi = _gains(points[mi], si, sj)
        gj = _gains(points[mj], sj, si)
        oi = np.lexsort((mi, -gi))[:CCVT_TOP]
        oj = np.lexsort((mj, -gj))[:CCVT_TOP]
        positive = (gi[oi] + gj[oj]) > 0
        done = int(np.argmin(positive)) if not positive.all() else positive.size
        a, b = oi[:done], oj[:done]
        mi[a], mj[b] = mj[b].copy(), mi[a].copy()
        total += done
        if done < CCVT_TOP:
            return total


def _sweep_reference(sites, points, members, G, touched):
    """One realization's swap phases; returns the number of exchanges and marks the sites
    whose members changed in ``touched``."""
    start, order = it.build_grid(sites, G)

    def cell(cx, cy):
        c = cy * G + cx
        return order[start[c]:start[c + 1]]

    near2 = ccvt_near2(len(sites))

    def pair(i, j):
        if it.distance2(sites[i, 0], sites[i, 1], sites[j, 0], sites[j, 1]) >= near2:
            return 0
        made = _pair_reference(members[i], members[j], points, sites[i], sites[j])
        if made:
            touched[i] = touched[j] = True
            _recenter_reference(sites, points, members, [i, j])
        return made

    total = 0
    for ox, oy, parity in PHASES:
        if ox == 0 and oy == 0:
            for cy in range(G):
                for cx in range(G):
                    inside = cell(cx, cy)
                    for qa in range(len(inside)):
                        for qb in range(qa + 1, len(inside)):
                            total += pair(inside[qa], inside[qb])
            continue
        for a in range(G // 2):
            for b in range(G):
                ax, ay = (2 * a + parity, b) if ox else (b, 2 * a + parity)
                bx, by = (ax + ox) % G, (ay + oy) % G
                for i in cell(ax, ay):
                    for j in cell(bx, by):
                        total += pair(i, j)
    return total


def ccvt_reference(sites, points, members, iterations, callback=None):
    """NumPy twin of :func:`ccvt_device`: the same integers, one realization at a time.

    Parameters
    ----------
    sites, points, members, iterations, callback
        As :func:`ccvt_device` (the callback runs once, at the end).

    Returns
    -------
    sites : ndarray of uint32
    energies : list of list of int
        Per realization, the exact energy sum after each iteration run.
    members : ndarray of uint32
    converged : ndarray of bool
    """
    sites = np.array(sites, dtype=np.int64)
    members = np.array(members, dtype=np.int64)
    r, n, p = members.shape
    G = ccvt_grid_size(n)
    energies = [[] for _ in range(r)]
    converged = np.zeros(r, dtype=bool)
    for k in range(r):
        site_energy = np.zeros(n, dtype=np.int64)
        _centroids_reference(sites[k], points[k], members[k], site_energy, np.ones(n, bool))
        for _ in range(iterations):
            touched = np.zeros(n, dtype=bool)
            swaps = _sweep_reference(sites[k], points[k], members[k], G, touched)
            e = _centroids_reference(sites[k], points[k], members[k], site_energy, touched)
            energies[k].append(e)
            if swaps == 0:
                converged[k] = True
                break
    if callback is not None:
        callback(members.astype(np.uint32), sites.astype(np.uint32))
    return sites.astype(np.uint32), energies, members.astype(np.uint32), converged
