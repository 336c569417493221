"""Integrands at points made inside the kernel that evaluates them (``kernels/fused_integrals.cl``):
what :func:`clsamp.integrate` runs for an :class:`~clsamp.integrands.Integrand` (a shipped one
or :meth:`~clsamp.integrands.Integrand.from_opencl`'s), so that no point is ever stored.

A :class:`FusedRule` makes the points of one sequence of the samplers, bit for bit:

* ``"sobol"``: Sobol' (Joe-Kuo) in the sampler's Gray-code order with ``randomize``
  ``"owen"``, ``"xor"`` or ``"shift"`` (``make_sampler("sobol", randomize=...)``), for
  replicated RQMC: :meth:`FusedRule.sums` gives each realization's double-double sum of
  f - integral, one pair per work-group read back;
* ``"digital"``: Sobol' with Matoušek's linear matrix scrambling and a digital shift
  (``randomize="lms+shift"``) in natural order (point i = L C i xor the shift), realization 0,
  for :class:`clsamp.cubature.Cubature`;
* ``"lattice"``: the shifted rank-1 lattice (Kuo's vector) in radical-inverse order with
  a periodization.

The last two give the values: :meth:`FusedRule.values` reads them back (the lattice's
Fourier transform runs on the host), :meth:`FusedRule.fill` writes them into a device array
(the digital net's Walsh state, :mod:`clsamp.cubature_device`). A launch covers at most
:data:`CHUNK` points of a realization; the sums and :meth:`FusedRule.values` read each
launch's output back before the next, so their device memory is O(1) in n.
"""

import numpy as np

from . import generating_matrices as gm
from . import number_theory as nt
from . import philox, runtime
from .integrand_kernel import combine_sums, offset
from .samplers.lattice import kuo_vector

CHUNK = 2**20            # points of one realization a launch makes at most
KINDS = ("sobol", "digital", "lattice")
RANDOMIZE = {"shift": 1, "xor": 2, "owen": 3}     # LD_* of kernels/lowdiscrepancy.h
PERIODIZE = {"none": 0, "baker": 1, "sidi": 2}

__all__ = ["FusedRule", "fused_randomization", "CHUNK"]


def fused_randomization(name):
    """The randomization of a sampler name that :class:`FusedRule` makes, or None.

    Parameters
    ----------
    name : str
        A sampler spec as :func:`clsamp.make_sampler` takes it (``"sobol:owen"``).

    Returns
    -------
    str or None
        ``"owen"``, ``"xor"`` or ``"shift"`` for a 32-bit order-1 Sobol' sampler so named.
    """
    base, _, variant = name.strip().lower().partition(":")
    return variant if base == "sobol" and variant in RANDOMIZE else None


def _room(d):
    """The row length of the Sobol' tables in the kernel: d, or the next power of 2 for
    d = 3 .. 16 (rows of zeros past d). Rows that load as whole vectors keep PoCL's code
    for the state's update vectorized; some widths (3, 6, 11, ..) made the kernel 2-3x
    slower (docs/performance.md)."""
    return 1 << (d - 1).bit_length() if 3 <= d <= 16 else d


class FusedRule:
    """One integrand and one sequence, fused in one kernel.

    Parameters
    ----------
    f : Integrand
        With ``kernel_code`` (every :mod:`clsamp.integrands` integrand).
    kind : {"sobol", "digital", "lattice"}
        See the module's description.
    seed : int
        The sampler's seed.
    randomize : {"owen", "xor", "shift"}
        ``kind="sobol"`` only (``"digital"`` is LMS + the xor shift, ``"lattice"`` shift).
    periodization : {"none", "baker", "sidi"}
        ``kind="lattice"`` only.

    Examples
    --------
    >>> import numpy as np, clsamp
    >>> from clsamp.fused import FusedRule
    >>> f = clsamp.integrands.keister(4)
    >>> x = clsamp.make_sampler("sobol", d=4, randomize="owen", seed=3).sample(512, realizations=2)
    >>> sums = FusedRule(f, "sobol", 3, "owen").sums(512, 0, range(2)) + 512 * f.integral
    >>> bool(np.allclose(sums, f(x).sum(axis=1), rtol=1e-12))
    True
    """

    def __init__(self, f, kind, seed, randomize="xor", periodization="none"):
        runtime.require_fp64()
        self.f, self.kind, self.seed = f, kind, seed
        self.randomize = {"digital": "xor", "lattice": "shift"}.get(kind, randomize)
        d = f.d
        room = d if kind == "lattice" else _room(d)
        if kind == "lattice":
            self.columns = runtime.table(("fused lattice", d), lambda: kuo_vector(d))
            self.steps = self.columns
        else:
            owen = self.randomize == "owen"
            gray = kind == "sobol"
            # "digital": LMS + digital shift, realization 0's matrices L_j C_j (as the sampler's)
            lms = seed if kind == "digital" else None

            def columns():
                v = nt.sobol_matrices(d)              # (d, 32)
                if lms is not None:
                    v = gm.lms_apply(gm.lms_row_masks(lms, [0], d), v[None])[0]
                v = nt.reverse_bits32(v.T) if owen else v.T
                padded = np.zeros((32, room), dtype=v.dtype)   # rows of zeros past d
                padded[:, :d] = v
                return padded

            self.columns = runtime.table(("fused sobol", d, owen, lms), columns)
            self.steps = (self.columns if gray else runtime.table(
                ("fused sobol steps", d, owen, lms), lambda: np.bitwise_xor.accumulate(columns(), axis=0)))
        self.params = runtime.to_device(np.ascontiguousarray(f.kernel_params(), dtype=np.float64))
        cpu = runtime.current_device().type == "cpu" and runtime.loop_limit() is None
        # a work-item's block: long on a CPU (its start, a Gray-code walk over the index's
        # bits, is paid once), short on a GPU (more items in flight) and where loops are capped
        self.block = 256 if cpu else 16
        self.local = runtime.local_size(64)
        self.defines = {"DIM": d, "INTEGRAND": f.kernel_code, "POINTS": int(kind == "lattice"),
                        "GRAY": int(kind == "sobol"), "RANDOMIZE": RANDOMIZE[self.randomize],
                        "PERIODIZE": PERIODIZE[periodization], "FUSED_BLOCK": self.block,
                        "FUSED_ROOM": room}

    def _kernel(self, sums):
        return runtime.kernel("fused_integrals.cl", "fused_integrals",
                              defines={**self.defines, "FUSED_SUMS": int(sums)},
                              appendix=self.f.opencl_source)

    def _launch(self, kernel, count, start, realizations, out):
        import pyopencl as cl
        groups = -(-count // (self.block * self.local))
        kernel(runtime.queue(), (groups * self.local, len(realizations)), (self.local, 1),
               np.uint32(count), np.uint32(start), np.uint32(realizations.start),
               *philox.seed_key(self.seed), np.uint32(philox.Stream.SCRAMBLE),
               np.uint32(philox.Stream.SHIFT), self.columns.data, self.steps.data, self.params.data,
               np.float64(offset(self.f)), out.data, cl.LocalMemory(16 * self.local))
        return groups

    def sums(self, count, start, realizations):
        """Per realization, the sum of f - integral over points start .. start + count - 1.

        Parameters
        ----------
        count, start : int
            The points, as ``sample(count, start=start)`` gives them.
        realizations : range

        Returns
        -------
        ndarray, shape (len(realizations),)
            Added in double-double on the device, in order on the host.
        """
        import pyopencl.array as cla
        kernel = self._kernel(True)
        total = np.zeros(len(realizations))
        span = self.block * self.local
        for lo, hi in runtime.chunk_ranges(len(realizations), 16 * -(-min(count, CHUNK) // span), 2**24):
            run = range(realizations.start + lo, realizations.start + hi)
            for a in range(0, count, CHUNK):
                part = min(CHUNK, count - a)
                out = cla.empty(runtime.queue(), (hi - lo, -(-part // span), 2), np.float64)
                self._launch(kernel, part, start + a, run, out)
                total[lo:hi] += combine_sums(out.get())
        return total

    def values(self, start, count):
        """f at points start .. start + count - 1 of realization 0, periodized for a lattice.

        Parameters
        ----------
        start, count : int

        Returns
        -------
        ndarray of float64, shape (count,)
        """
        import pyopencl.array as cla
        kernel = self._kernel(False)
        out = np.empty(count)
        buffer = cla.empty(runtime.queue(), (min(count, CHUNK),), np.float64)
        for a in range(0, count, CHUNK):
            part = min(CHUNK, count - a)
            self._launch(kernel, part, start + a, range(0, 1), buffer)
            buffer[:part].get(ary=out[a:a + part])
        return out

    def fill(self, start, count, out):
        """:meth:`values` written into a device array instead of read back.

        Parameters
        ----------
        start, count : int
        out : pyopencl.array.Array of float64
            At least ``count`` entries; the first ``count`` get f at points
            start .. start + count - 1.
        """
        import pyopencl.array as cla
        kernel = self._kernel(False)
        for a in range(0, count, CHUNK):
            part = min(CHUNK, count - a)
            # a launch writes from its buffer's start: past the first, a region of `out` from entry a
            region = out.base_data.get_sub_region(8 * a, 8 * part) if a else out.data
            self._launch(kernel, part, start + a, range(0, 1),
                         cla.Array(runtime.queue(), (part,), np.float64, data=region))
