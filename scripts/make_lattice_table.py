"""Write clsamp/data/lattice_kuo_33002.npz: the generating vector of Cools, Kuo and Nuyens'
embedded rank-1 lattice sequence in base 2 (2^10 to 2^20 points, 9125 dimensions), file
lattice-33002-1024-1048576.9125 of https://web.maths.unsw.edu.au/~fkuo/lattice/ .

    python scripts/make_lattice_table.py [path to the table: Kuo's .txt or qmcpy's .npy]

Without a path it takes the copy qmcpy ships (pip install qmcpy).
"""

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def main():
    if len(sys.argv) > 1:
        path = Path(sys.argv[1])
    else:
        import qmcpy
        path = (Path(qmcpy.__file__).parent / "discrete_distribution" / "lattice" / "generating_vectors"
                / "kuo.lattice-33002-1024-1048576.9125.npy")
    if path.suffix == ".npy":
        z = np.load(path)
        via = f"the copy in qmcpy {__import__('qmcpy').__version__} ({path.name})"
    else:
        z = np.array([int(line.split()[-1]) for line in path.read_text().split("\n") if line.strip()])
        via = path.name
    z = np.asarray(z, dtype=np.uint64)
    assert z.shape == (9125,) and z[0] == 1 and np.all(z < 2**20) and np.all(z % 2 == 1)
    source = ("Cools, Kuo, Nuyens (2006), lattice-33002-1024-1048576.9125, "
              f"https://web.maths.unsw.edu.au/~fkuo/lattice/, from {via} by scripts/make_lattice_table.py")
    out = ROOT / "clsamp" / "data" / "lattice_kuo_33002.npz"
    np.savez_compressed(out, z=z.astype(np.uint32), source=np.array(source))
    print(f"wrote {out} ({z.size} dimensions)")


if __name__ == "__main__":
    main()
