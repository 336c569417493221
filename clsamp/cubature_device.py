"""The digital-net cubature's transform, butterfly, wavenumber ordering and bound terms on the
device (``kernels/walsh.cl``), for :class:`clsamp.cubature.Cubature`.

Once the host's state is loaded, the coefficients and the ordering stay on the device from
one doubling to the next; a doubling uploads the new values, transforms them, combines
them with the coefficients already there, reorders the wavenumbers and reads back only
the 2^(m-r-1) terms of the bound. The kernels do the NumPy twin's operations
(:func:`clsamp.cubature.walsh_coefficients`, ``Cubature.step``, ``_order_wavenumbers``) in
the same order: the same bits.
"""

import numpy as np

from . import runtime


class DeviceWalsh:
    """The Walsh coefficients of a digital-net rule and their wavenumber ordering, on the
    current device (fp64).

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

    def __init__(self):
        runtime.require_fp64()
        self.q = runtime.queue()
        self.c = self.kappa = None

    @staticmethod
    def _kernel(name):
        return runtime.kernel("walsh.cl", name)

    def transform(self, y):
        """The discrete Walsh coefficients of values, on the device.

        Parameters
        ----------
        y : ndarray of float64
            On the host, length a power of 2, in the net's natural order.

        Returns
        -------
        pyopencl.array.Array of float64
            :func:`clsamp.cubature.walsh_coefficients` of ``y``, bit for bit (its passes).
        """
        import pyopencl.array as cla
        n = y.size
        t = cla.to_device(self.q, np.ascontiguousarray(y, dtype=np.float64))
        h = 1
        while h < n:
            if 4 * h <= n:
                self._kernel("walsh_radix4")(self.q, (n // 4,), None, t.data, np.uint32(h))
                h *= 4
            else:
                self._kernel("walsh_radix2")(self.q, (n // 2,), None, t.data, np.uint32(h))
                h *= 2
        self._kernel("walsh_scale")(self.q, (n,), None, t.data, np.float64(1.0 / n))
        return t

    def _order(self, top, bottom, m):
        for level in range(top, bottom, -1):
            nl = 2**level
            self._kernel("walsh_order")(self.q, (nl - 1,), None, self.c.data, self.kappa.data,
                                        np.uint32(nl), np.uint32(2**m // (2 * nl)))

    def load(self, coefficients, kappa):
        """Take over a state made on the host.

        Parameters
        ----------
        coefficients : ndarray of float64
            The Walsh coefficients of the first 2^m values.
        kappa : ndarray of int
            Their wavenumber ordering.
        """
        import pyopencl.array as cla
        self.c = cla.to_device(self.q, np.ascontiguousarray(coefficients, dtype=np.float64))
        self.kappa = cla.to_device(self.q, np.ascontiguousarray(kappa, dtype=np.uint32))

    def double(self, y, bottom):
        """Add the values of the next n points (n: the points so far).

        Parameters
        ----------
        y : ndarray of float64
            The values of points n .. 2n - 1 (host).
        bottom : int
            After the doubling's butterfly the ordering runs from level m - 1 down to
            ``bottom`` + 1 (2^m = 2n).
        """
        import pyopencl.array as cla
        n = y.size
        t = self.transform(y)
        c2 = cla.empty(self.q, 2 * n, np.float64)
        kappa2 = cla.empty(self.q, 2 * n, np.uint32)
        self._kernel("walsh_double")(self.q, (n,), None, self.c.data, t.data, self.kappa.data,
                                     np.uint32(n), c2.data, kappa2.data)
        self.c, self.kappa = c2, kappa2
        self._order((2 * n).bit_length() - 2, bottom, (2 * n).bit_length() - 1)

    def terms(self, low):
        """The terms of the error bound.

        Parameters
        ----------
        low : int
            2^(m-r-1).

        Returns
        -------
        ndarray of float64
            |c[kappa[low + i]]| for i < low, on the host (the bound sums them in NumPy).
        """
        import pyopencl.array as cla
        out = cla.empty(self.q, low, np.float64)
        self._kernel("walsh_terms")(self.q, (low,), None, self.c.data, self.kappa.data,
                                    np.uint32(low), out.data)
        return out.get()

    def coefficients(self):
        """The coefficients.

        Returns
        -------
        ndarray of float64
            On the host.
        """
        return self.c.get()

    def ordering(self):
        """The wavenumber ordering.

        Returns
        -------
        ndarray of int64
            On the host.
        """
        return self.kappa.get().astype(np.int64)
