"""Where a step of the compiled loop spends its time, for one scene.

For a catalogue scene (or a hanging chain of rigid bars, ``--chain N``) this prints what the run is
made of — its element families, the Newton matrix's storage and solver, the matrix's size and
entries — and times

* one evaluation of the step's residual and Newton matrix at the start (``Stepper.evaluate``; it
  includes the Python call and the copy of the matrix, so it is an upper bound of the compiled cost),
* one solve of that matrix with numpy/scipy (for scale: the compiled loop solves it with its own
  solver, named in the header),
* a run of ``--steps`` steps through ``simulate`` (CPU time per step, Newton iterations per step),
* the same run with every element through its Python methods (``compiled=False``).

Usage::

    python examples/profile_step.py [SCENE] [--n-elements 16] [--dt 1e-3] [--steps 400]
    python examples/profile_step.py --chain 250 --dt 1e-3

Every timing runs once before it is timed; the first run (compiling what the cache does not hold) is
reported apart as "compile and start-up". Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the
tests): 20 evaluations, runs of 20 steps (5 on the Python path).
"""
import argparse
import inspect
import os
import time

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

import skfem_flex as sf
from skfem_flex.compiled.pack import build_key
from skfem_flex.schemes import make_scheme
from skfem_flex.schemes.stepper import Stepper

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")


def chain(n_links, length=0.1):
    """N rigid bars (0.1 kg, 0.1 m) along +x, the first pinned at the origin, each hinged to the next; gravity."""
    bars, joints = [], []
    for i in range(n_links):
        bar = sf.RigidBody.bar(length, 0.1, start=(i * length, 0.0), angle=0.0, name=f"bar {i}")
        joints.append(sf.Pin(bar.point((-0.5 * length, 0.0)), (0.0, 0.0), name="pin") if i == 0 else
                      sf.Revolute(bars[-1].point((0.5 * length, 0.0)), bar.point((-0.5 * length, 0.0)),
                                  name=f"hinge {i}"))
        bars.append(bar)
    return sf.Scene(bars, constraints=joints, forces=[sf.Gravity((0.0, -9.81))], name=f"chain of {n_links} bars")


def build(args):
    if args.chain:
        return chain(args.chain)
    factory = sf.scenes.get(args.scene)
    kw = {}
    if args.n_elements and "n_elements" in inspect.signature(factory).parameters:
        kw["n_elements"] = args.n_elements
    return factory(**kw)


def best_of(fn, n, rounds=3):
    """Seconds per call of ``fn`` (best of ``rounds`` rounds of ``n`` calls) after one call."""
    fn()
    best = np.inf
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - start) / n)
    return best


def cpu_per_step(scene_factory, steps, dt, scheme, compiled):
    """(CPU seconds per step, Newton iterations per step, the result) of a run of ``steps`` steps; the set-up
    of a run (packing, consistent start, first record) is taken out by subtracting a one-step run."""
    def run(n):
        start = time.process_time()
        res = sf.simulate(scene_factory(), n * dt, dt, scheme=scheme,
                          control=sf.Control(compiled=compiled, handle_signals=False))
        return time.process_time() - start - res.compile_time, res

    run(1)                                 # loads what the run needs from the cache
    # the best of three of each: a short run's CPU time is a few milliseconds, as noisy as its set-up
    one = min(run(1)[0] for _ in range(3))
    spent, res = min((run(steps) for _ in range(3)), key=lambda pair: pair[0])
    return max(spent - one, 0.0) / max(res.steps - 1, 1), res.newton_iterations[1:].mean(), res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", default="flexible_pendulum")
    ap.add_argument("--n-elements", type=int, default=None)
    ap.add_argument("--chain", type=int, default=0, help="profile a hanging chain of N rigid bars instead")
    ap.add_argument("--dt", type=float, default=1e-3, help="step (s)")
    ap.add_argument("--steps", type=int, default=200 if QUICK else 400)
    ap.add_argument("--scheme", default="energy-momentum")
    args = ap.parse_args(argv)

    scene = build(args)
    dt = args.dt or 1e-3
    scheme = make_scheme(args.scheme)
    key = build_key(scene, scheme.name)
    warm = time.perf_counter()
    stepper = Stepper(scene, scheme)
    q0, v0 = scene.initial_state()
    acc, lam, reaction = stepper.start(0.0, q0, v0)
    stepper.load(scheme.make_state(0.0, q0, v0, acc=acc, pseudo=acc.copy(), lam=lam, prescribed_force=reaction))
    pk = stepper.packed
    x = np.zeros(pk.nx)
    x[:pk.free.size] = q0[pk.free] if scheme.name == "energy-momentum" else acc[pk.free]
    res, mat, _ = stepper.evaluate(0.0, dt, x)
    startup = time.perf_counter() - warm

    nnz = mat.nnz if sps.issparse(mat) else int(np.count_nonzero(mat))
    print(f"{scene.name}: n = {scene.n} coordinates, {pk.m} multipliers, {pk.nx} Newton unknowns; "
          f"families: {', '.join(key[1]) or 'none'}")
    print(f"Newton matrix: {'dense' if pk.storage == 0 else 'CSR'} storage, {nnz} entries, solver {pk.solver}")
    print(f"compile and start-up: {startup:.2f} s (stepper, consistent start, first evaluation)")

    n_eval = 20 if QUICK else 2000
    t_eval = best_of(lambda: stepper.evaluate(0.0, dt, x), n_eval)
    if sps.issparse(mat):
        t_solve = best_of(lambda: spla.spsolve(mat.tocsc(), res), max(n_eval // 10, 2))
    else:
        t_solve = best_of(lambda: np.linalg.solve(mat, res), n_eval)
    print(f"one evaluation (residual + matrix, from Python): {t_eval * 1e6:9.1f} µs")
    print(f"one solve with numpy/scipy (scale only):          {t_solve * 1e6:9.1f} µs")

    factory = (lambda: build(args))
    fast, its, run = cpu_per_step(factory, args.steps, dt, scheme.name, None)
    print(f"compiled run: {fast * 1e6:9.1f} µs per step, {its:.2f} Newton iterations per step "
          f"({run.steps} steps of {dt:g} s); path {run.run_path}")
    n_python = 6 if QUICK else max(args.steps // 10, 5)
    slow, its_p, _ = cpu_per_step(factory, n_python, dt, scheme.name, False)
    print(f"Python-methods run: {slow * 1e6:9.1f} µs per step, {its_p:.2f} Newton iterations per step "
          f"({n_python} steps): " + (f"{slow / fast:.0f}× the compiled run" if fast > 0
                                     else "the compiled run was too short for the CPU clock to time"))


if __name__ == "__main__":
    main()
