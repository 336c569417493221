"""Write clsamp/data/sobol_joe_kuo_6_21201.npz, the Sobol direction numbers clsamp ships.

Source: S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
projections", SIAM J. Sci. Comput. 30 (2008) 2635-2654; the file ``new-joe-kuo-6.21201``
from https://web.maths.unsw.edu.au/~fkuo/sobol/ (21201 dimensions, search criterion D(6)).
We convert the copy SciPy ships as ``scipy/stats/_sobol_direction_numbers.npz`` (the same
numbers, already parsed), so clsamp's unscrambled Sobol points equal
``scipy.stats.qmc.Sobol(d, scramble=False)`` bit for bit. SciPy is needed only to run this
script, never by clsamp at run time.

Layout of the output (a compressed .npz):

``poly`` : uint32 (21201,)
    Primitive polynomial of dimension j over GF(2), as bits: x^s + a_1 x^(s-1) + ... +
    a_(s-1) x + 1 -> 0b1 a_1 ... a_(s-1) 1 (so its degree s is ``poly.bit_length() - 1``).
    Dimension 0 (van der Corput) has poly 1 (degree 0).
``vinit`` : uint32 (21201, 18)
    The initial direction integers m_1 .. m_s of each dimension (zero beyond s).
``source`` : str
    The provenance above, in one line.

Run from the repository root::

    python scripts/make_sobol_table.py
"""

import os

import numpy as np
import scipy

SOURCE = ("Joe & Kuo (2008) new-joe-kuo-6.21201, https://web.maths.unsw.edu.au/~fkuo/sobol/, "
          f"converted from scipy {scipy.__version__} stats/_sobol_direction_numbers.npz "
          "by scripts/make_sobol_table.py")


def main():
    path = os.path.join(os.path.dirname(scipy.__file__), "stats", "_sobol_direction_numbers.npz")
    table = np.load(path)
    poly = table["poly"]
    vinit = table["vinit"]
    if poly.shape != (21201,) or vinit.shape != (21201, 18):
        raise SystemExit(f"unexpected table shapes {poly.shape}, {vinit.shape} in {path}")
    if poly.max() >= 2**32 or vinit.max() >= 2**32 or poly.min() < 1:
        raise SystemExit("direction numbers out of the uint32 range")
    degree = np.array([int(p).bit_length() - 1 for p in poly])
    # m_k must be odd and below 2^k for k = 1..s (Joe-Kuo's conditions); zero past the degree.
    for j in range(1, len(poly)):
        m = vinit[j, :degree[j]]
        bad = np.any(m % 2 == 0) or np.any(m >= 2 ** np.arange(1, degree[j] + 1))
        if bad or np.any(vinit[j, degree[j]:]):
            raise SystemExit(f"dimension {j}: initial direction numbers violate Joe-Kuo's conditions")
    out = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                       "clsamp", "data", "sobol_joe_kuo_6_21201.npz")
    np.savez_compressed(out, poly=poly.astype(np.uint32), vinit=vinit.astype(np.uint32),
                        source=np.array(SOURCE))
    print(f"wrote {out} ({os.path.getsize(out)} bytes): {SOURCE}")


if __name__ == "__main__":
    main()
