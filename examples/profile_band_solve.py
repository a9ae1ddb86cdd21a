"""Bordered band solve against dense LU on the compiled loop's Newton matrix (``linear_solver``).

Builds the bordered Newton matrix of a catalogue scene at its initial state (as
``examples/profile_compiled_scene.py`` does), its structural pattern (the union over a few
perturbed evaluations), the plan of :func:`skfem_flex.numerics.linear_solver.dense_bordered_plan`, and times,
inside compiled loops, :func:`skfem_flex.numerics.linear_solver.bordered_band_solve` and
``np.linalg.solve`` on it (best of several rounds). Usage::

    python examples/profile_band_solve.py [SCENE] [--n-elements 16 24 40] [--repeat 5000]

The first call of each timing loop compiles it (the loops here are not cached) and is timed apart as
"compile and start-up". Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 8 elements,
20 solves per round, 2 rounds.
"""
import argparse
import inspect
import os
import time

import numba
import numpy as np
import scipy.sparse as sps

import skfem_flex as sf
from skfem_flex.compiled import scene_loop as cs
from skfem_flex.numerics import linear_solver as ls

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")


@numba.njit
def _band_solves(mat, rhs, interior, border, lo, up, n):
    s = 0.0
    for _ in range(n):
        x, ok = ls.bordered_band_solve(mat, rhs, interior, border, lo, up)
        s += x[0]
    return s


@numba.njit
def _dense_solves(mat, rhs, n):
    s = 0.0
    for _ in range(n):
        s += np.linalg.solve(mat, rhs)[0]
    return s


def _residual_and_matrix(system):
    """The residual and matrix of a ``newton_system`` after ``_evaluate`` (flat or (packed, step, workspace))."""
    if len(system) > 19:
        return system[18], system[19]
    mat = cs.newton_matrix(system)
    return system[2][0], (mat.toarray() if sps.issparse(mat) else mat)


def newton_matrix(scene, h=1e-3, n_patterns=4, seed=0):
    """(matrix, residual, pattern) of the compiled loop's first Newton evaluation of ``scene``."""
    q0 = np.concatenate([np.asarray(b.q0, dtype=float) for b in scene.bodies])
    v0 = np.concatenate([np.asarray(b.v0, dtype=float) for b in scene.bodies]) + 0.01
    system, x = cs.newton_system(scene, q0, v0, h)
    cs._evaluate(system, x)
    res, mat = (v.copy() for v in _residual_and_matrix(system))
    pattern = mat != 0.0
    rng = np.random.default_rng(seed)
    for _ in range(n_patterns):        # entries that vanish at one state are kept
        cs._evaluate(system, x + 1e-3 * rng.normal(size=x.size))
        pattern |= _residual_and_matrix(system)[1] != 0.0
    return mat, res, pattern


def _best(fun, args, repeat, rounds):
    """(best time per call over ``rounds`` rounds of ``repeat`` calls, s; the first call's wall time, s: its
    compile)."""
    start = time.perf_counter()
    fun(*args, 1)
    warm = time.perf_counter() - start
    best = np.inf
    for _ in range(rounds):
        start = time.perf_counter()
        fun(*args, repeat)
        best = min(best, (time.perf_counter() - start) / repeat)
    return best, warm


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="flexible_pendulum")
    ap.add_argument("--n-elements", type=int, nargs="+", default=[8] if QUICK else [16], help="for scenes with a beam")
    ap.add_argument("--repeat", type=int, default=20 if QUICK else 5000, help="solves per timed round")
    ap.add_argument("--rounds", type=int, default=2 if QUICK else 7, help="timed rounds; the best is reported")
    args = ap.parse_args(argv)
    factory = sf.scenes.get(args.scene)
    takes_n = "n_elements" in inspect.signature(factory).parameters
    for n_el in (args.n_elements if takes_n else [None]):
        scene = factory(**({"n_elements": n_el} if takes_n else {}))
        if not cs.eligible(scene, sf.EnergyMomentum()):
            raise SystemExit(f"{args.scene} does not run on the compiled mechanism loop")
        mat, res, pattern = newton_matrix(scene)
        n = mat.shape[0]
        start = time.perf_counter()
        plan = ls.dense_bordered_plan(pattern)
        t_plan = time.perf_counter() - start
        label = f"{args.scene}" + (f" ({n_el} elements)" if n_el else "")
        t_dense, warm_dense = _best(_dense_solves, (mat, res), args.repeat, args.rounds)
        if plan is None:
            print(f"{label}: {n} × {n}, no bordered band plan (dense LU {1e6 * t_dense:.2f} µs; "
                  f"compile and start-up {warm_dense:.1f} s)")
            continue
        interior, border, lo, up = plan
        x, ok = ls.bordered_band_solve(mat, res, *plan)
        ref = np.linalg.solve(mat, res)
        t_band, warm_band = _best(_band_solves, (mat, res, interior, border, lo, up), args.repeat, args.rounds)
        print(f"{label}: {n} × {n}, border {border.tolist()}, band lo = {lo}, up = {up} "
              f"(plan {1e3 * t_plan:.1f} ms)")
        print(f"  bordered band solve: {1e6 * t_band:6.2f} µs   ok = {ok}, "
              f"max |x − x_dense| / max |x_dense| = {np.abs(x - ref).max() / np.abs(ref).max():.1e}")
        print(f"  np.linalg.solve:     {1e6 * t_dense:6.2f} µs   ({t_dense / t_band:.1f}× the bordered band time)")
        print(f"  compile and start-up of the timing loops (first call, not counted): bordered band "
              f"{warm_band:.1f} s, np.linalg.solve {warm_dense:.1f} s")


if __name__ == "__main__":
    main()
