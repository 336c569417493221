"""The adaptive cubature's state on the device (``kernels/walsh.cl``), for
:class:`clsamp.cubature.Cubature`: a digital net's transform, butterfly, wavenumber ordering
and bound terms; a lattice's wavenumber ordering and bound terms.

Once the host's state is loaded, the coefficients (in wavenumber order) and the ordering
stay on the device from one doubling to the next, in arrays with room to grow. A net's
doubling takes the new values (uploaded from the host, or written on the device by the
kernel that evaluates the integrand: :meth:`DeviceWalsh.values_buffer`), transforms them,
combines them with the coefficients already there in place, reorders the wavenumbers and
reads back only the first 2^(m-r) of them, in one transfer: the mean (coefficient 0) and
the bound's 2^(m-r-1) terms. A lattice's doubling (:meth:`DeviceWalsh.double_lattice`)
takes the magnitudes of the spectrum the host computed, puts them in the ordering's order
and reorders, the same way. The kernels do the NumPy twin's operations
(:func:`clsamp.cubature.walsh_coefficients`, ``Cubature.step``, ``_order_wavenumbers``) in
the same order: the same bits.
"""

import numpy as np

from . import runtime

PASS_BITS = 5            # butterfly levels a pass of the transform applies (kernels/walsh.cl)


class DeviceWalsh:
    """The Walsh coefficients of a digital-net rule (or a lattice's Fourier magnitudes) and
    their wavenumber ordering, on the current device (fp64).

    Parameters
    ----------
    limit : int, optional
        The most coefficients the rule will hold (its ``max_n``): the arrays grow 4x at a
        time, never past it.

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.cubature import walsh_coefficients
    >>> from clsamp.cubature_device import DeviceWalsh
    >>> state = DeviceWalsh()
    >>> state.load(walsh_coefficients(np.array([1.0, 2.0])), np.arange(2))
    >>> state.double(np.array([3.0, 4.0]), 0)
    >>> state.coefficients().tolist()
    [2.5, -0.5, -1.0, 0.0]
    >>> walsh_coefficients(np.array([1.0, 2.0, 3.0, 4.0])).tolist()
    [2.5, -0.5, -1.0, 0.0]
    """

    def __init__(self, limit=None):
        runtime.require_fp64()
        self.q = runtime.queue()
        self.limit = limit
        self.n = 0
        self.a = self.kappa = self.t = None     # a[i] = c[kappa[i]], room for 2 n or more

    @staticmethod
    def _kernel(name, bits=None):
        return runtime.kernel("walsh.cl", name, defines=None if bits is None else {"WALSH_BITS": bits})

    def transform(self, y, out=None):
        """The discrete Walsh coefficients of values, on the device.

        Parameters
        ----------
        y : ndarray of float64
            On the host, length a power of 2, in the net's natural order.
        out : pyopencl.array.Array, optional
            Room for them (float64, at least ``y.size``).

        Returns
        -------
        pyopencl.array.Array of float64
            :func:`clsamp.cubature.walsh_coefficients` of ``y``, bit for bit (its passes), in
            the first ``y.size`` entries.
        """
        import pyopencl as cl
        import pyopencl.array as cla
        y = np.ascontiguousarray(y, dtype=np.float64)
        t = out if out is not None else cla.empty(self.q, y.size, np.float64)
        cl.enqueue_copy(self.q, t.data, y)
        self._transform(t, y.size)
        return t

    def _transform(self, t, n):
        """:meth:`transform` of the n values in the device array t, in place."""
        levels = n.bit_length() - 1
        passes = -(-levels // PASS_BITS)
        h = 1
        for p in range(passes):              # levels split evenly over the passes, the last scaled
            bits = (levels + p) // passes
            self._kernel("walsh_pass", bits)(self.q, (n >> bits,), None, t.data, np.uint32(h),
                                             np.float64(1.0 / n if p == passes - 1 else 1.0))
            h <<= bits

    def _order(self, top, bottom, m):
        for level in range(top, bottom, -1):
            nl = 2**level
            # nl - 1 work-items padded to whole groups (an odd count leaves PoCL groups of a few)
            local = min(nl, runtime.local_size(64))
            self._kernel("walsh_order")(self.q, (-(-(nl - 1) // local) * local,), (local,),
                                        self.kappa.data, self.a.data, np.uint32(nl),
                                        np.uint32(2**m // (2 * nl)))

    def _room(self, size):
        """Arrays for ``size`` coefficients, the ones held kept (grown 4x at a time: each
        growth is a copy, and fresh memory costs its first touch)."""
        import pyopencl as cl
        import pyopencl.array as cla
        if self.a is not None and self.a.size >= size:
            return
        room = max(size, 4 * (self.a.size if self.a is not None else 0))
        if self.limit is not None:
            room = max(size, min(room, self.limit))
        a, kappa = cla.empty(self.q, room, np.float64), cla.empty(self.q, room, np.uint32)
        if self.n:
            cl.enqueue_copy(self.q, a.data, self.a.data, byte_count=8 * self.n)
            cl.enqueue_copy(self.q, kappa.data, self.kappa.data, byte_count=4 * self.n)
        self.a, self.kappa = a, kappa
        # a net's new values, or a lattice's half spectrum (one more)
        self.t = cla.empty(self.q, room // 2 + 1, np.float64)

    def load(self, coefficients, kappa):
        """Take over a state made on the host.

        Parameters
        ----------
        coefficients : ndarray of float64 or None
            The Walsh coefficients of the first 2^m values (None for a lattice, whose
            doublings bring their whole spectrum: :meth:`double_lattice`).
        kappa : ndarray of int
            Their wavenumber ordering.
        """
        import pyopencl as cl
        kappa = np.asarray(kappa)
        self.n = 0
        self._room(2 * kappa.size)
        if coefficients is not None:
            cl.enqueue_copy(self.q, self.a.data,
                            np.ascontiguousarray(coefficients[kappa], dtype=np.float64))
        cl.enqueue_copy(self.q, self.kappa.data, np.ascontiguousarray(kappa, dtype=np.uint32))
        self.n = kappa.size

    def values_buffer(self):
        """Where a kernel may write the next doubling's values before :meth:`double` (None).

        Returns
        -------
        pyopencl.array.Array of float64
            At least n entries (n: the points so far), of which :meth:`double` reads the
            first n.
        """
        self._room(2 * self.n)
        return self.t

    def double(self, y, bottom):
        """Add the values of the next n points (n: the points so far).

        Parameters
        ----------
        y : ndarray of float64 or None
            The values of points n .. 2n - 1 on the host, or None where they were written
            into :meth:`values_buffer`.
        bottom : int
            After the doubling's butterfly the ordering runs from level m - 1 down to
            ``bottom`` + 1 (2^m = 2n).
        """
        n = self.n
        if y is not None and y.size != n:
            raise ValueError(f"a doubling of {n} values, got {y.size}")
        self._room(2 * n)
        if y is None:
            self._transform(self.t, n)
        else:
            self.transform(y, self.t)
        self._kernel("walsh_double")(self.q, (n,), None, self.a.data, self.t.data, self.kappa.data,
                                     np.uint32(n))
        self._doubled(bottom)

    def double_lattice(self, half, bottom):
        """A lattice's doubling: the ordering extended to 2n wavenumbers (n: the points so
        far) and reordered by the magnitudes of the 2n values' Fourier coefficients.

        Parameters
        ----------
        half : ndarray of float64
            |c_k| for k = 0 .. n, on the host (a real sequence's |c_(2n-k)| = |c_k|).
        bottom : int
            The ordering runs from level m - 1 down to ``bottom`` + 1 (2^m = 2n).
        """
        import pyopencl as cl
        n = self.n
        if half.size != n + 1:
            raise ValueError(f"a lattice's doubling of {n} values takes {n + 1} magnitudes, got {half.size}")
        self._room(2 * n)
        cl.enqueue_copy(self.q, self.t.data, np.ascontiguousarray(half, dtype=np.float64))
        self._kernel("lattice_sizes")(self.q, (n,), None, self.a.data, self.t.data, self.kappa.data,
                                      np.uint32(n))
        self._doubled(bottom)

    def _doubled(self, bottom):
        """After a doubling's kernel: 2n entries held, reordered from level m - 1 down to
        ``bottom`` + 1 (2^m = 2n)."""
        self.n *= 2
        m = self.n.bit_length() - 1
        self._order(m - 1, bottom, m)

    def summary(self, low):
        """The mean and the terms of the error bound, in one read from the device.

        Parameters
        ----------
        low : int
            2^(m-r-1) (at least 1).

        Returns
        -------
        mean : float
            The mean of the values so far: the coefficient of wavenumber 0 (always first; a
            lattice's: its magnitude).
        terms : ndarray of float64
            |c[kappa[low + i]]| for i < low, on the host (the bound sums them in NumPy).
        """
        head = self.a[:2 * low].get()
        return float(head[0]), np.abs(head[low:])

    def coefficients(self):
        """The coefficients.

        Returns
        -------
        ndarray of float64
            On the host, in wavenumber order 0 .. 2^m - 1.
        """
        out = np.empty(self.n)
        out[self.ordering()] = self.a[:self.n].get()
        return out

    def ordering(self):
        """The wavenumber ordering.

        Returns
        -------
        ndarray of int64
            On the host.
        """
        return self.kappa[:self.n].get().astype(np.int64)
