"""A ``gbn`` run kept on the device (``gbn_control`` and ``gbn_pairs`` in
``kernels/gbn.cl``): on devices that share the host's cores (``Shape.host_sort``), on the
torus without a density, an iteration is two launches and no wait -- the pair pass and the
step control, which sums the energies exactly (``kernels/exact_sum.h``: math.fsum's
value), accepts or rejects the step, proposes the next one and sorts it by cell. The host
looks at the sets' flags every :data:`SETTLE` iterations, to stop once all have converged
(the iterations enqueued past a set's end do nothing to it).
The result is :func:`~clsamp.samplers.gbn.gbn_optimize`'s on the host, the same bits.
"""

import numpy as np

from .. import runtime

SETTLE = 8           # iterations between two looks at the sets' flags
# gbn_control's arguments: ten buffers, then n, sets, G, mode, it, iterations, tol, tau_min,
# propose (declared once, so that an iteration sets them in one fast call)
CONTROL_TYPES = [None] * 10 + [np.uint32, np.uint32, np.int32, np.int32, np.uint32, np.uint32,
                               np.float64, np.float64, np.int32]


def resident(kernel, density):
    """Whether a run of ``kernel`` stays on the current device: a device that shares the
    host's cores and runs long loops, the torus, no density.

    Parameters
    ----------
    kernel : Kernel
    density : Density or None

    Returns
    -------
    bool
    """
    return (density is None and kernel.periodic and runtime.shape().host_sort
            and runtime.loop_limit() is None)


def optimize_resident(x, kernel, defines, tau0, iterations, tol, tau_min):
    """Gradient descent on the Gaussian energy, every iteration on the device.

    Parameters
    ----------
    x : ndarray (sets, n, d)
        The starting sets, in [0, 1)^d.
    kernel : Kernel
        On the torus.
    defines : dict
        The pair pass's build options on the torus without widths
        (:func:`clsamp.samplers.gbn.pass_defines`).
    tau0 : float
        The first step.
    iterations : int
        The most iterations.
    tol : float
        Converged when an accepted step lowers the energy by at most ``tol`` of it.
    tau_min : float
        Converged when the step falls below it.

    Returns
    -------
    points : ndarray (sets, n, d)
    energy, initial, tau : ndarray (sets,)
        The last energy per point, the start's, the last step.
    converged : ndarray of bool (sets,)
    ran : ndarray of int64 (sets,)
        Iterations each set ran.
    history : ndarray (sets, max(ran))
        The energy after each iteration, the last one held past a set's own end.
    """
    import pyopencl as cl

    sets, n, d = x.shape
    G, total = kernel.cells, sets * n
    defines = {**defines, "RESIDENT": 1}
    pairs = runtime.kernel("gbn.cl", "gbn_pairs", defines, instance="resident")
    control = runtime.kernel("gbn.cl", "gbn_control", defines, instance="resident",
                             scalar_types=CONTROL_TYPES)
    queue = runtime.queue()
    x = np.ascontiguousarray(x, dtype=np.float64)
    points, proposal = runtime.work_buffer(array=x), runtime.work_buffer(array=x)
    force = runtime.work_buffer(x.nbytes)
    out = runtime.work_buffer(8 * total * (d + 1))
    ordered = runtime.work_buffer(x.nbytes)
    start = runtime.work_buffer(4 * (sets * G ** d + 1))
    order = runtime.work_buffer(4 * total)
    real = runtime.work_buffer(array=np.tile([0.0, tau0, 0.0], (sets, 1)))
    flags = runtime.work_buffer(array=np.tile(np.array([1, 0, 0], dtype=np.int32), (sets, 1)))
    history = runtime.work_buffer(8 * sets * max(iterations, 1))
    local = runtime.local_size(64)
    pairs.set_args(ordered, start, np.uint32(n), np.uint32(total), np.int32(G),
                   np.uint32(kernel.stencil), np.float64(kernel.R2), np.float64(kernel.inv2s2),
                   np.float64(kernel.gR), np.float64(kernel.reach ** 2), flags, out)
    fixed = (points, force, proposal, out, ordered, start, order, real, flags, history,
             n, sets, G)

    def step(mode, it, propose):
        control.set_args(*fixed, mode, it, iterations, tol, tau_min, propose)
        cl.enqueue_nd_range_kernel(queue, control, (sets,), (1,))
        if mode == 0 or propose:
            cl.enqueue_nd_range_kernel(queue, pairs, (-(-total // local) * local,), (local,))
        queue.flush()

    # the flags are read a look behind: while the host waits for the copy after one group
    # of iterations, the device runs the next group, and never idles
    live = np.empty((sets, 3), dtype=np.int32)
    step(0, 0, 1)
    step(1, 0, int(iterations > 0))
    looked = None
    for it in range(iterations):
        step(2, it, int(it + 1 < iterations))
        if (it + 1) % SETTLE == 0:
            if looked is not None:
                runtime.wait(looked)
                if not live[:, 0].any():
                    break
            looked = cl.enqueue_copy(queue, live, flags, is_blocking=False)
    runtime.wait()
    x_out = np.empty_like(x)
    state = np.empty((sets, 3))
    hist = np.empty((sets, max(iterations, 1)))
    for host, buffer in ((x_out, points), (state, real), (live, flags), (hist, history)):
        cl.enqueue_copy(queue, host, buffer, is_blocking=True)
    ran = live[:, 2].astype(np.int64)
    T = int(ran.max(initial=0))
    hist = hist[:, :T].copy()
    for s in range(sets):
        hist[s, ran[s]:] = state[s, 0]
    return x_out, state[:, 0].copy(), state[:, 2].copy(), state[:, 1].copy(), \
        live[:, 1].astype(bool), ran, hist

