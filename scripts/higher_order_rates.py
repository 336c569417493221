"""Fitted MSE rates of higher-order Sobol' nets (``order=1, 2, 3``) on smooth products.

For each dimension, integrand and (order, randomize), the MSE of the estimate over
``--realizations`` independent realizations at N = 2^6 .. 2^16, and the least-squares slope of
log2 MSE against log2 N (all eleven N, then without the last two, where 32-bit points reach
their floor). Integrands: prod exp(x_j), integral (e - 1)^d, and prod (exp(x_j) - (e - 1) x_j),
integral ((e - 1) / 2)^d, whose one-dimensional factor takes the same value at 0 and 1 (so the
bias of 32-bit points, 2^-33 times the integral of the gradient, vanishes to first order).
The numbers of docs/performance.md, "Higher-order nets: `sobol` with `order=2 | 3` (issue 38)".

Usage: ``PYTHONPATH=. python scripts/higher_order_rates.py [--realizations 64] [--d 2,3]``
"""

import argparse

import numpy as np

import clsamp

E1 = np.e - 1
INTEGRANDS = {
    "exp": (lambda x: np.prod(np.exp(x), axis=-1), lambda d: E1 ** d),
    "exp-(e-1)x": (lambda x: np.prod(np.exp(x) - E1 * x, axis=-1), lambda d: (E1 / 2) ** d),
}
CASES = [(1, "xor"), (1, "lms+shift"), (2, "xor"), (2, "lms+shift"), (3, "xor"), (3, "lms+shift")]


def slopes(d, integrand, order, randomize, realizations):
    """(slope over all m, slope without the last two, MSE at the first and last m)."""
    ms = np.arange(6, 17)
    f, integral = INTEGRANDS[integrand]
    s = clsamp.make_sampler("sobol", d=d, order=order, randomize=randomize, seed=1)
    mse = np.array([np.mean((f(s.sample(2**int(m), realizations=realizations)).mean(axis=1)
                             - integral(d)) ** 2) for m in ms])
    return (np.polyfit(ms, np.log2(mse), 1)[0], np.polyfit(ms[:-2], np.log2(mse[:-2]), 1)[0],
            mse[0], mse[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--realizations", type=int, default=64)
    parser.add_argument("--d", default="2,3")
    args = parser.parse_args()
    print("| d | integrand | order | randomize | slope 2^6..2^16 | slope 2^6..2^14 | MSE at 2^6 | at 2^16 |")
    print("|---|---|---|---|---|---|---|---|")
    for d in (int(v) for v in args.d.split(",")):
        for name in INTEGRANDS:
            for order, randomize in CASES:
                a, b, lo, hi = slopes(d, name, order, randomize, args.realizations)
                print(f"| {d} | {name} | {order} | `{randomize}` | {a:.2f} | {b:.2f} | {lo:.2e} | {hi:.2e} |",
                      flush=True)


if __name__ == "__main__":
    main()
