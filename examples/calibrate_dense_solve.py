"""The time of the linear solves of a Newton step against their size: the measurements behind the solvers'
cost models.

Times the compiled dense solve of the loop (:func:`skfem_flex.compiled.solvers.lapack_solve`: LAPACK's getrf and
getrs called by address, on a copy of the matrix, as each Newton solve does) and the written-out LU used below
``SMALL_DENSE`` unknowns, on diagonally dominant random matrices, and prints them beside the model of
:func:`skfem_flex.schemes.stepper.modeled_solve_seconds` (``DENSE_SOLVE_SECONDS``, ``DENSE_SOLVE_EXPONENT``),
which decides whether the static-pivot sparse LU replaces a scene's dense solver.

A second table times, on the Newton matrix of the first step of a few scenes (the reduced rotating beam of
the exudyn comparison, the spatial slider-crank, chains of rigid bars, the Bricard linkage, four planar beams
in the floating frame), the scene's own solver (dense or band, its compiled kernel as the loop calls it) and
the static-pivot sparse LU (:func:`skfem_flex.numerics.sparse_lu.static_lu_solve`, its solution's check left
out), each beside its model (:func:`~skfem_flex.schemes.stepper.modeled_solve_seconds`,
:func:`skfem_flex.numerics.sparse_lu.modeled_seconds`).

Usage::

    python examples/calibrate_dense_solve.py [--repeat 20000]

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 500 solves per size, two scenes.
"""
import argparse
import os
import time

import numba
import numpy as np
import scipy.sparse

import skfem_flex as sf
from skfem_flex.compiled.abi import call, fvec
from skfem_flex.compiled.solvers import SMALL_DENSE, lapack_solve, lapack_work, small_lu_solve
from skfem_flex.numerics.sparse_lu import modeled_seconds, static_lu_plan, static_lu_solve
from skfem_flex.schemes import make_scheme
from skfem_flex.schemes.stepper import Stepper, modeled_solve_seconds

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


@numba.njit(cache=True)
def _static_solves(vals, rhs, x, plan, lu, w, mark, z, repeat):
    for _ in range(repeat):
        static_lu_solve(vals, rhs, x, plan.prow, plan.qcol, plan.ptr, plan.idx, plan.diag, plan.src, lu, w, mark, z)


def _scenes():
    """(name, scene, Δt) of the static LU's table."""
    from skfem_flex.apps import peer_ffrf_beam
    cases = [("reduced rotating beam", lambda: peer_ffrf_beam.scene(probe=False), 1e-2),
             ("spatial_slider_crank", sf.scenes.spatial_slider_crank, 1e-3)]
    if not QUICK:
        cases += [(f"rigid_chain({k})", lambda k=k: sf.scenes.rigid_chain(k), 1e-3) for k in (2, 3, 7, 20)]
        cases += [("bricard", sf.scenes.bricard, 1e-3), ("flying_beam", sf.scenes.flying_beam, 0.05),
                  ("rotating_beam", sf.scenes.rotating_beam, 0.01), ("spin_up_beam", sf.scenes.spin_up_beam, 0.02),
                  ("spin_up_pinned", sf.scenes.spin_up_pinned, 0.01)]
    return cases


@numba.njit(cache=True)
def _own_solves(ctx, solver, saved, repeat, solve):
    """``repeat`` copies of the saved Newton matrix into the context's, each solved by the scene's solver
    kernel when ``solve`` (its solve destroys the matrix)."""
    c = ctx[0]
    mat = fvec(c.mat, saved.size)
    for _ in range(repeat):
        for i in range(saved.size):
            mat[i] = saved[i]
        if solve:
            call(solver[0].kernel, c.self, solver.ctypes.data)


def own_solver_seconds(stepper, repeat):
    """Seconds per solve of the stepper's own solver on its evaluated Newton matrix (the copy excluded)."""
    saved = stepper.ws.mat.copy()
    times = []
    for solve in (False, True):
        _own_solves(stepper.ws.ctx, stepper.solver, saved, 2, solve)
        start = time.perf_counter()
        _own_solves(stepper.ws.ctx, stepper.solver, saved, repeat, solve)
        times.append((time.perf_counter() - start) / repeat)
    return times[1] - times[0]


def static_lu_row(scene, dt, repeat):
    """(unknowns, the scene's solver, its measured s, its modeled s, static LU measured s, static LU modeled s)
    on the Newton matrix of the scene's first trapezoidal step (the scene's solver as before any switch)."""
    scheme = make_scheme("trapezoidal")
    start = sf.simulate(scene, t_end=dt, dt=dt, scheme=scheme)     # the consistent initial state
    q, v = start.q[0], start.v[0]
    stepper = Stepper(scene, scheme)          # its solver before plan_sparse_lu
    acc, lam, reaction = stepper.start(0.0, q, v)
    stepper.load(scheme.make_state(0.0, q, v, acc=acc, pseudo=acc.copy(), lam=lam, prescribed_force=reaction))
    pk = stepper.packed
    pattern = pk.pattern.tocsr()
    pattern.sort_indices()
    matrix = stepper.evaluate(0.0, dt)[1]
    dense = not scipy.sparse.issparse(matrix)
    plan = static_lu_plan(pattern, matrix, dense)
    if dense:
        vals = np.ascontiguousarray(matrix).ravel()
    else:
        csr = scipy.sparse.csr_matrix(matrix)
        vals = np.array([csr[i, j] for i in range(pk.nx) for j in pattern.indices[pattern.indptr[i]:pattern.indptr[i + 1]]])
    n = pk.nx
    rhs, x = np.random.default_rng(0).standard_normal(n), np.zeros(n)
    work = (np.zeros(plan.idx.size), np.zeros(n), np.full(n, -1, dtype=np.int64), np.zeros(n))
    _static_solves(vals, rhs, x, plan, *work, 2)
    start = time.perf_counter()
    _static_solves(vals, rhs, x, plan, *work, repeat)
    seconds = (time.perf_counter() - start) / repeat
    stepper.evaluate(0.0, dt)
    own = own_solver_seconds(stepper, repeat)
    return n, stepper.solver_name, own, modeled_solve_seconds(n, pk.plan, dense), seconds, modeled_seconds(plan)


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
    print()
    print("a scene's Newton matrix: its own solver and the static-pivot sparse LU (its check left out), "
          "µs per solve")
    print("| scene | unknowns | the scene's solver | its time | its model | static LU | static LU model |")
    print("|---|---|---|---|---|---|---|")
    for name, make, dt in _scenes():
        n, solver, own, own_model, seconds, model = static_lu_row(make(), dt, max(args.repeat // 4, 100))
        print(f"| {name} | {n} | {solver} | {1e6 * own:.2f} | {1e6 * own_model:.2f} | {1e6 * seconds:.2f} "
              f"| {1e6 * model:.2f} |")


if __name__ == "__main__":
    main()
