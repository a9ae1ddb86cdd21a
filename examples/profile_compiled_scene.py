"""Where a step of the compiled mechanism loop spends its time (``skfem_flex.compiled.scene_loop``).

Times, in compiled loops, one residual evaluation (with its Newton matrix), one solve of that
matrix and one evaluation of the constraint terms for a catalogue scene at its initial state, the
average Newton iterations per step of a short run, and the cost per step of the same run on the Python
path (``compiled=False``). Usage::

    python examples/profile_compiled_scene.py [SCENE] [--n-elements 16] [--dt 1e-3]
    python examples/profile_compiled_scene.py --chain 250 --dt 1e-3
    python examples/profile_compiled_scene.py --n-elements 64 --dt 2e-4 --dense-storage-limit 1000

``--chain N`` profiles a hanging chain of N rigid bars joined by revolute joints instead of a catalogue
scene (3N coordinates, 2N multipliers: a Newton matrix that is a band only after reordering).

Every timing runs once before it is timed (the evaluation and solve loops here are compiled on their
first call; the runs compile or load the package's kernels); those first calls are timed apart and
printed as "compile and start-up". Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests):
8 elements, 20 evaluations and solves, runs of 20 steps (5 on the Python path).
"""
import argparse
import inspect
import os
import time

import numba
import numpy as np

import skfem_flex as sf
from skfem_flex.compiled import scene_loop as cs

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")


@numba.njit
def _evaluations(system, x, n):
    s = 0.0
    for _ in range(n):
        s += cs._evaluate(system, x)
    return s


@numba.njit
def _solves(system, n):
    for _ in range(n):
        cs._solve(system[0][9][5], system)


def rigid_chain(n_links, length=0.1):
    """N rigid bars (0.1 kg, 0.1 m) along +x, the first pinned at the origin, each hinged to the next; gravity."""
    bars, joints = [], []
    for i in range(n_links):
        bar = sf.RigidBody.bar(length, 0.1, start=(i * length, 0.0), angle=0.0, name=f"bar {i}")
        joints.append(sf.Pin(bar.point((-0.5 * length, 0.0)), (0.0, 0.0), name="pin") if i == 0 else
                      sf.Revolute(bars[-1].point((0.5 * length, 0.0)), bar.point((-0.5 * length, 0.0)),
                                  name=f"hinge {i}"))
        bars.append(bar)
    return sf.Scene(bars, constraints=joints, forces=[sf.Gravity((0.0, -9.81))], name=f"chain of {n_links} bars")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="flexible_pendulum")
    ap.add_argument("--n-elements", type=int, default=8 if QUICK else 16, help="for scenes with a beam")
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--repeat", type=int, default=20 if QUICK else 5000)
    ap.add_argument("--chain", type=int, default=0, help="profile a chain of this many rigid bars instead")
    ap.add_argument("--dense-storage-limit", type=int, default=cs.DENSE_STORAGE_LIMIT,
                    help="store the Newton matrix dense up to this many rows (to compare the two storages)")
    args = ap.parse_args(argv)
    cs.DENSE_STORAGE_LIMIT = args.dense_storage_limit
    if args.chain:
        scene = rigid_chain(args.chain)
        args.scene = scene.name
    else:
        factory = sf.scenes.get(args.scene)
        kw = {"n_elements": args.n_elements} if "n_elements" in inspect.signature(factory).parameters else {}
        scene = factory(**kw)
    if not cs.eligible(scene, sf.EnergyMomentum()):
        raise SystemExit(f"{args.scene} does not run on the compiled mechanism loop")
    n, m = scene.n, scene.n_constraints
    free = scene.free_index
    q0 = np.concatenate([np.asarray(b.q0, dtype=float) for b in scene.bodies])
    v0 = np.concatenate([np.asarray(b.v0, dtype=float) for b in scene.bodies]) + 0.01
    h = args.dt
    system, x = cs.newton_system(scene, q0, v0, h)
    start = time.perf_counter()
    _evaluations(system, x, 1)
    _solves(system, 1)
    warm_loops = time.perf_counter() - start
    start = time.perf_counter()
    _evaluations(system, x, args.repeat)
    t_eval = (time.perf_counter() - start) / args.repeat
    _evaluations(system, x, 1)
    start = time.perf_counter()
    _solves(system, args.repeat)
    t_solve = (time.perf_counter() - start) / args.repeat
    steps, py_steps = (20, 5) if QUICK else (200, 20)
    start = time.perf_counter()
    sf.simulate(scene, 5 * h, h)
    warm_run = time.perf_counter() - start
    res = sf.simulate(scene, steps * h, h, record_every=10 ** 6)
    res_all = sf.simulate(scene, steps * h, h)
    start = time.perf_counter()
    sf.simulate(scene, 2 * h, h, record_every=10 ** 6, compiled=False)       # warm-up of the Python path
    warm_py = time.perf_counter() - start
    res_py = sf.simulate(scene, py_steps * h, h, record_every=10 ** 6, compiled=False)
    storage = "CSR" if cs._planned(scene)[9][4][-1] == cs.CSR else "dense"
    print(f"{args.scene}: {n} coordinates, {m} multipliers, Newton matrix {free.size + m} × {free.size + m} "
          f"stored {storage}")
    print(f"one residual evaluation with its Newton matrix: {1e6 * t_eval:.1f} µs")
    print(f"one solve of the Newton matrix (as the loop):   {1e6 * t_solve:.1f} µs")
    print(f"Newton iterations per step:                     {res_all.newton_iterations[1:].mean():.2f}")
    print(f"per step, nothing recorded:                     {1e6 * res.wall_time / res.steps:.1f} µs")
    print(f"per step, every step recorded:                  {1e6 * res_all.wall_time / res_all.steps:.1f} µs")
    print(f"per step on the Python path, nothing recorded:  {1e6 * res_py.wall_time / res_py.steps:.1f} µs")
    print(f"compile and start-up (first calls, not counted): evaluation and solve loops {warm_loops:.1f} s, "
          f"compiled run {warm_run:.1f} s, Python path {warm_py:.1f} s")


if __name__ == "__main__":
    main()
