"""The CCVT optimization in OpenCL (``kernels/ccvt.cl``): stepwise launches over all
realizations, or one work-group per realization in a single launch (``ccvt_solve``)."""

import numpy as np

from ... import runtime
from ...geometry import integer_torus as it
from .pairs import CCVT_BUCKETS, CCVT_META, PHASES, ccvt_defines, ccvt_grid_size, ccvt_near2

TAIL_SHARE = 8    # the last iterations, from n / TAIL_SHARE exchanges or fewer, in one launch


def device_buffers(q, sites, points, members):
    """Device buffers of both OpenCL paths: members (ids) and their coordinates (xy), the
    scratch slots of the rebuilds, the sites, the per-site records and bucket ranges.

    Parameters
    ----------
    q : pyopencl.CommandQueue
    sites : ndarray
        (r, n, 2) integer coordinates.
    points : ndarray or pyopencl.array.Array
        (r, M, 2) density points, on the host or the device.
    members : ndarray
        (r, n, p) point indices of each site.

    Returns
    -------
    dict of pyopencl.array.Array
        ``ids``, ``xy``, ``tids``, ``txy``, ``sites``, ``meta``, ``bstart``.
    """
    import pyopencl.array as cla
    r, n, p = members.shape
    ids = cla.to_device(q, np.ascontiguousarray(members, dtype=np.uint32))
    # each slot carries its point's coordinates (ccvt_gather), so the kernels stream
    # instead of gathering
    xy = cla.empty(q, (r, n, p, 2), np.uint32)
    if r and n * p:
        runtime.kernel("ccvt.cl", "ccvt_gather", ccvt_defines())(
            q, (n * p, r), None, runtime.to_device(points).data, ids.data, xy.data,
            np.uint32(n * p))
    return dict(ids=ids, xy=xy,
                tids=cla.empty(q, (r, n, p), np.uint32), txy=cla.empty(q, (r, n, p, 2), np.uint32),
                sites=cla.to_device(q, np.ascontiguousarray(sites, dtype=np.uint32)),
                meta=cla.zeros(q, (r, n, CCVT_META), np.int64),
                bstart=cla.zeros(q, (r, n, CCVT_BUCKETS + 1), np.uint32))


def _divisor(x, most):
    """The largest divisor of x that is at most ``most``."""
    return max(d for d in range(1, most + 1) if x % d == 0)


def ccvt_device(sites, points, members, iterations, callback=None, fused=None, tail=None,
                progress=False):
    """OpenCL CCVT: integer sites (r, n, 2), points (r, M, 2) (host or device), members
    (r, n, p); returns (sites, energies, members, converged) as :func:`ccvt_reference`.

    With ``fused`` (default: when there are at least twice as many realizations as compute
    units and no callback) each realization runs whole in one work-group (``ccvt_solve``,
    one launch); otherwise every step is its own launch over all realizations, which keeps
    a single large realization spread over the whole device, until the iteration's
    exchanges fall to ``tail`` or fewer in every realization still running (default
    n / TAIL_SHARE; -1: never, and never with a callback): then ``ccvt_solve`` takes
    the rest in one launch, since a dozen launches cost more than the few exchanges left.
    All of these give the same bits. The members come back as sets: the kernels keep
    each site's slots grouped by bucket. ``progress`` shows a bar over the iterations once
    the run has taken 2 s.

    Parameters
    ----------
    sites : ndarray
        (r, n, 2) integer coordinates.
    points : ndarray or pyopencl.array.Array
        (r, M, 2) density points, M = n p.
    members : ndarray
        (r, n, p) the starting ownership.
    iterations : int
        At most this many.
    callback : callable, optional
        ``callback(members, sites)`` after every iteration (stepwise launches only).
    fused : bool, optional
    tail : int, optional
    progress : bool

    Returns
    -------
    sites : ndarray of uint32
    energies : list of list of int
        Per realization, the exact energy sum after each iteration run.
    members : ndarray of uint32
    converged : ndarray of bool
        Per realization: an iteration made no exchange.

    Raises
    ------
    NoDeviceError
        The current device lacks 64-bit integer atomics (``cl_khr_int64_base_atomics``: the
        energy totals) or stops long loops (llvmpipe). fp64 is not needed: every quantity,
        the pruning bounds included, is an exact integer (``kernels/ccvt.h``).
    """
    import pyopencl as cl
    import pyopencl.array as cla
    from tqdm import tqdm
    runtime.require_extension("cl_khr_int64_base_atomics", "ccvt")
    runtime.require_short_loops("ccvt")
    q = runtime.queue()
    r, n, p = members.shape
    if fused is None:
        fused = callback is None and r >= 2 * runtime.current_device().compute_units
    if tail is None:
        tail = n // TAIL_SHARE
    if callback is not None:
        tail = -1
    G = ccvt_grid_size(n)
    near2 = ccvt_near2(n)
    u32 = np.uint32
    b = device_buffers(q, sites, points, members)
    b.update(cell_start=cla.empty(q, (r, G * G + 1), np.uint32),
             cell_sites=cla.empty(q, (r, n), np.uint32),
             dirty=cla.zeros(q, (r, n), np.uint32), touched=cla.zeros(q, (r, n), np.uint32),
             site_energy=cla.zeros(q, (r, n), np.int64),
             status=cla.zeros(q, (r, 3), np.int64))
    active_host = np.ones(r, dtype=np.uint32)
    active = cla.to_device(q, active_host)
    energies = [[] for _ in range(r)]
    bar = tqdm(total=iterations, desc=f"ccvt {r} x {n} sites", unit="it", disable=not progress, delay=2)
    if fused:
        converged = solve_device(b, n, p, iterations, active, np.arange(r), 0, energies, bar)
        _finish(bar)
        return b["sites"].get(), energies, b["ids"].get(), converged
    slots = (b["ids"].data, b["xy"].data, b["tids"].data, b["txy"].data)
    swaps = cla.zeros(q, (r,), np.uint32)
    # every launch of the loop gets its arguments once, here: an iteration is a dozen
    # launches, and setting twenty arguments each time costs more than some of them run.
    # The phases run in work-groups of at most 4 x 4 cell pairs, so that the uneven work
    # of the pairs spreads over the compute units (one group per launch would keep a
    # phase on one core); the results do not depend on the grouping
    defines = ccvt_defines()
    build = runtime.kernel("ccvt.cl", "voronoi_build_grid", defines, instance="loop")
    swap = [runtime.kernel("ccvt.cl", "ccvt_swap", defines, instance=("loop", k))
            for k in range(len(PHASES))]
    centroids = runtime.kernel("ccvt.cl", "ccvt_centroids", defines, instance="loop")
    build.set_args(b["sites"].data, u32(n), u32(G), b["cell_start"].data,
                   b["cell_sites"].data, u32(r))
    phases = []
    for k, (ox, oy, parity) in zip(swap, PHASES, strict=True):
        k.set_args(*slots, u32(n), u32(p), b["sites"].data, b["meta"].data, b["bstart"].data,
                   b["cell_start"].data, b["cell_sites"].data, u32(G), np.int32(ox),
                   np.int32(oy), u32(parity), active.data, b["dirty"].data,
                   b["touched"].data, swaps.data, np.int64(near2))
        size = (G if ox == 0 and oy == 0 else G // 2, G, r)
        phases.append((k, size, (_divisor(size[0], 4), _divisor(size[1], 4), 1)))
    centroids.set_args(*slots, b["sites"].data, u32(n), u32(p), b["meta"].data,
                       b["bstart"].data, active.data, b["dirty"].data, b["touched"].data,
                       b["site_energy"].data, b["status"].data, swaps.data, u32(1))
    cl.enqueue_nd_range_kernel(q, centroids, (n, r), None)   # the sites to the start's centroids
    centroids.set_arg(15, u32(0))
    b["dirty"].fill(1)        # every pair meets in the first iteration
    status = np.zeros((r, 3), dtype=np.int64)
    converged = np.zeros(r, dtype=bool)
    for t in range(iterations):
        bar.update(1)
        cl.enqueue_nd_range_kernel(q, build, (r,), None)
        for k, size, local in phases:
            cl.enqueue_nd_range_kernel(q, k, size, local)
        cl.enqueue_nd_range_kernel(q, centroids, (n, r), None)
        cl.enqueue_copy(q, status, b["status"].data)
        totals = it.exact_total(status[:, 0], status[:, 1])
        running = np.flatnonzero(active_host)
        for k in running:
            energies[k].append(totals[k])
        if callback is not None:
            callback(b["ids"].get(), b["sites"].get())
        made = status[:, 2]
        done = (active_host == 1) & (made == 0)
        if done.any():
            converged |= done
            active_host[done] = 0
            if not active_host.any():
                break
            active.set(active_host)
        if t + 1 < iterations and made[active_host == 1].max() <= tail:
            tail_converged = solve_device(b, n, p, iterations - t - 1, active,
                                          np.flatnonzero(active_host), 1, energies, bar)
            converged |= tail_converged & (active_host == 1)
            break
    _finish(bar)
    return b["sites"].get(), energies, b["ids"].get(), converged


SOLVE_CHUNK = 64       # iterations of ccvt_solve per launch: Python runs between


def _finish(bar):
    """Close a progress bar at 100 % (a run that converged early has done its work); a bar
    still within its delay stays hidden."""
    if not bar.disable and bar.format_dict["elapsed"] >= bar.delay:
        bar.total = bar.n
        bar.refresh()
    bar.close()


def solve_device(b, n, p, iterations, active, running, resume, energies, bar=None):
    """``ccvt_solve`` over the buffers ``b`` of :func:`ccvt_device`: one work-group per
    active realization (``active`` on the device, ``running`` their indices), for
    ``iterations`` at most; from the start, or with ``resume`` from where the stepwise
    launches left them. Appends each iteration's energy to ``energies`` and returns which
    realizations converged (the sites and members stay on the device).

    The iterations run in launches of at most :data:`SOLVE_CHUNK`, each resuming where the
    last stopped (every piece of state is in the buffers, the energy in ``status``), with
    the realizations that converged taken out: the same bits as one launch; Ctrl-C is taken while a chunk runs
    (:func:`clsamp.runtime.wait`).

    Parameters
    ----------
    b : dict
        The buffers (:func:`device_buffers`, with the grid and scratch ones added).
    n, p : int
        Sites and points per site.
    iterations : int
    active : pyopencl.array.Array
        Per realization, whether it still runs.
    running : array_like of int
        The indices of the active realizations.
    resume : bool
    energies : list of list
        Appended to, per realization.
    bar : tqdm, optional

    Returns
    -------
    ndarray of bool
        Per realization, whether it converged.
    """
    import pyopencl.array as cla
    q = runtime.queue()
    r = b["ids"].shape[0]
    G = ccvt_grid_size(n)
    local = runtime.local_size(64)
    solve = runtime.kernel("ccvt.cl", "ccvt_solve", ccvt_defines())
    running = np.asarray(running)
    converged = np.zeros(r, dtype=bool)
    left = iterations
    while left > 0 and running.size:
        chunk = min(SOLVE_CHUNK, left)
        history = cla.zeros(q, (r, chunk, 2), np.int64)
        state = cla.zeros(q, (r, 2), np.uint32)
        solve(q, (local * r,), (local,), b["ids"].data, b["xy"].data, b["tids"].data,
              b["txy"].data, np.uint32(n), np.uint32(p), b["sites"].data, b["meta"].data,
              b["bstart"].data, b["cell_start"].data, b["cell_sites"].data, np.uint32(G),
              b["dirty"].data, b["touched"].data, b["site_energy"].data,
              np.int64(ccvt_near2(n)), np.uint32(chunk), np.uint32(resume), active.data,
              b["status"].data, history.data, state.data)
        runtime.wait()                          # Ctrl-C is taken within the chunk
        h, st = history.get(), state.get()
        for k in running:
            energies[k].extend(it.exact_total(h[k, :st[k, 0], 0], h[k, :st[k, 0], 1]))
        done = st[running, 1].astype(bool)
        converged[running[done]] = True
        running = running[~done]
        left -= chunk
        resume = 1
        if bar is not None:
            bar.update(int(st[:, 0].max()) if r else 0)
        if done.any() and running.size and left > 0:
            flags = np.zeros(r, dtype=np.uint32)
            flags[running] = 1
            active.set(flags)
    return converged
