"""The time of a dense LAPACK solve against its size: the measurement behind the dense solver's cost model.

Times the compiled dense solve of the loop (:func:`skfem_flex.compiled.solvers.lapack_solve`: LAPACK's getrf and
getrs called by address, on a copy of the matrix, as each Newton solve does) and the written-out LU used below
``SMALL_DENSE`` unknowns, on diagonally dominant random matrices, and prints them beside the model of
:func:`skfem_flex.schemes.stepper.modeled_solve_seconds` (``DENSE_SOLVE_SECONDS``, ``DENSE_SOLVE_EXPONENT``),
which decides whether the static-pivot sparse LU replaces a scene's dense solver.

Usage::

    python examples/calibrate_dense_solve.py [--repeat 20000]

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 500 solves per size.
"""
import argparse
import os
import time

import numba
import numpy as np

from skfem_flex.compiled.solvers import SMALL_DENSE, lapack_solve, lapack_work, small_lu_solve
from skfem_flex.schemes.stepper import modeled_solve_seconds

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK") == "1"
SIZES = (12, 20, 24, 28, 33, 40, 50, 64, 80, 100)


@numba.njit(cache=True)
def _solves(A, b, work, y, lapack, which, repeat):
    """``repeat`` solves of A y = b (which: 0 copy only, 1 LAPACK, 2 the written-out LU)."""
    n = b.size
    for _ in range(repeat):
        for i in range(n):
            y[i] = b[i]
            for j in range(n):
                work[i, j] = A[i, j]
        if which == 1:
            lapack_solve(lapack, work, y)
        elif which == 2:
            small_lu_solve(work, y, y)


def seconds_per_solve(n, repeat, rng):
    """(LAPACK, written-out LU) seconds per solve of n unknowns, the copy of the matrix excluded."""
    A = rng.standard_normal((n, n)) + n * np.eye(n)
    b = rng.standard_normal(n)
    _, lapack = lapack_work(n)
    work, y = np.empty((n, n)), np.empty(n)
    times = []
    for which in (0, 1, 2):
        _solves(A, b, work, y, lapack, which, 2)
        start = time.perf_counter()
        _solves(A, b, work, y, lapack, which, repeat)
        times.append((time.perf_counter() - start) / repeat)
    if which == 2 and not np.allclose(A @ y, b):
        raise RuntimeError(f"the solve of {n} unknowns is wrong")
    return times[1] - times[0], times[2] - times[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=500 if QUICK else 20000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print(f"dense solve of n unknowns, µs per solve (LU below {SMALL_DENSE} unknowns is written out)")
    print("| n | LAPACK | written-out LU | model |")
    print("|---|---|---|---|")
    for n in SIZES:
        lapack, small = seconds_per_solve(n, args.repeat, rng)
        print(f"| {n} | {1e6 * lapack:.2f} | {1e6 * small:.2f} | {1e6 * modeled_solve_seconds(n, None, True):.2f} |")


if __name__ == "__main__":
    main()
