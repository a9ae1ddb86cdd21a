"""Benchmark: cost per step of the time loop.

* spin-up beam (ω = 4 rad/s, Δt = 1e-3, energy-conserving scheme) for 4, 8,
  16, 64, 256 and 1024 P1 elements: the full 30 s for the small meshes, a
  shorter window (``--window``) for the large ones, where only µs per step is
  compared. These scenes run through the compiled loop
  (:mod:`skfem_flex.compiled_loop`);
* the same 30 s spin-up at 8 elements with every step recorded, and on the
  pure-Python path (``compiled=False``), once each, for comparison;
* the pendulum, 10 000 steps at Δt = 1e-3 (Python path: it has a constraint).

Every run records every ``--record-every``-th step (default 10; energies,
momenta, probe and prescribed force are evaluated in Python at those steps)
and writes no files. Before timing, one short run of each kind compiles the
Numba kernels or loads them from numba's cache; that warm-up is reported but
not part of the table; the same warm-up in a fresh process with an empty
numba cache gives the one-off compile time. Each case is run ``--repeat`` times; the table gives
the median wall time, µs per step and Newton iterations per step, and is
written as Markdown to ``OUT/benchmark.md`` (default ``examples/output``),
which the README quotes.

Run ``python examples/benchmark.py [--repeat 3] [--window 1.0] [--record-every 10] [--out DIR]``;
``--limits`` runs ``examples/benchmark_limits.py`` instead (memory against mesh size, VTK series
cost against frame count).
"""
import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import skfem_flex as sf

SPIN_UP_ELEMENTS = (4, 8, 16, 64, 256, 1024)
FULL_RUN_UP_TO = 16          # elements; larger meshes run a shorter window


def time_case(make_scene, t_end, dt, repeat, record_every, compiled=True):
    """Median wall time (s), µs per step and Newton iterations per step over ``repeat`` runs."""
    walls, its = [], []
    for _ in range(repeat):
        res = sf.simulate(make_scene(), t_end=t_end, dt=dt, record_every=record_every, compiled=compiled)
        walls.append(res.wall_time)
        # recorded steps carry their own iteration count; with record_every > 1 this samples the run
        its.append(float(np.mean(res.newton_iterations[1:])))
        steps = res.steps
    wall = statistics.median(walls)
    return wall, 1e6 * wall / steps, statistics.median(its), steps


def warm_up():
    """Compile (or load from numba's cache) every kernel the timed runs use; returns the time, s."""
    start = time.perf_counter()
    for n in (8, 64):                      # dense and banded compiled loops
        sf.simulate(sf.scenes.spin_up_beam(omega=4.0, n_elements=n), t_end=0.01, dt=1e-3)
    sf.simulate(sf.scenes.spin_up_beam(omega=4.0, n_elements=8), t_end=0.01, dt=1e-3, compiled=False)
    return time.perf_counter() - start


def cold_compile():
    """Wall time (s) of the warm-up in a fresh process with an empty numba cache: the one-off JIT compile."""
    import os
    import subprocess
    import sys
    import tempfile
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        code = "import time, benchmark; t = time.perf_counter(); benchmark.warm_up(); print(time.perf_counter() - t)"
        out = subprocess.run([sys.executable, "-c", code], env=env, cwd=str(Path(__file__).parent),
                             capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def run(repeat=3, window=1.0, record_every=10, elements=SPIN_UP_ELEMENTS):
    """Rows (case, path, steps, wall s, µs/step, Newton/step)."""
    rows = []
    for n in elements:
        t_end = 30.0 if n <= FULL_RUN_UP_TO else window
        wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=n), t_end, 1e-3,
                                         repeat if n <= 64 else 1, record_every)
        rows.append((f"spin-up, {n} P1 elements, {t_end:g} s", "compiled", steps, wall, us, its))
    if record_every != 1:                 # what recording costs: the same run with every step recorded
        wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=8), 30.0, 1e-3, 1, 1)
        rows.append(("spin-up, 8 P1 elements, 30 s, every step recorded", "compiled", steps, wall, us, its))
    wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=8), 30.0, 1e-3, 1,
                                     record_every, compiled=False)
    rows.append(("spin-up, 8 P1 elements, 30 s", "Python", steps, wall, us, its))
    wall, us, its, steps = time_case(sf.scenes.pendulum, 10.0, 1e-3, repeat, record_every)
    rows.append(("pendulum, 10 000 steps", "Python", steps, wall, us, its))
    return rows


def table(rows, record_every, warm, cold=None):
    lines = [f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
             f"numpy {np.__version__}, numba {_numba_version()}; energy-momentum scheme, dt = 1e-3 s; "
             f"every {record_every}th step recorded (energies, momenta, probes), no file output; "
             f"median of the repeats, after a warm-up run that compiled or loaded the kernels "
             f"({warm:.1f} s, not counted).", "",
             "| case | time loop | steps | wall time (s) | µs per step | Newton iterations per step (recorded steps) |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {c} | {p} | {s} | {w:.3g} | {u:.1f} | {i:.2f} |" if u < 100 else
              f"| {c} | {p} | {s} | {w:.3g} | {u:.0f} | {i:.2f} |" for c, p, s, w, u, i in rows]
    us = {r[0].split(",")[1].strip(): r[4] for r in rows if r[1] == "compiled" and "every step" not in r[0]}
    if "8 P1 elements" in us and "1024 P1 elements" in us:
        lines += ["", f"Cost per step at 1024 elements / at 8 elements: "
                      f"{us['1024 P1 elements'] / us['8 P1 elements']:.0f}."]
    if cold is not None:
        lines += ["", f"One-off JIT compile of the kernels (the warm-up in a fresh process with an empty numba "
                      f"cache): {cold:.1f} s; the warm-up with the cache filled: {warm:.1f} s."]
    return "\n".join(lines) + "\n"


def _numba_version():
    import numba
    return numba.__version__


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--window", type=float, default=1.0, help="simulated seconds for meshes above 16 elements")
    ap.add_argument("--record-every", type=int, default=10, help="record every n-th step")
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    ap.add_argument("--limits", action="store_true",
                    help="instead: peak memory at 10³–10⁵ elements and VTK series cost per frame "
                         "(examples/benchmark_limits.py)")
    args = ap.parse_args()
    if args.limits:
        import benchmark_limits
        benchmark_limits.main(["--out", args.out])
        raise SystemExit(0)
    cold = cold_compile()
    warm = warm_up()
    text = table(run(args.repeat, args.window, args.record_every), args.record_every, warm, cold)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmark.md").write_text(text)
    print(text)
    print(f"written to {out / 'benchmark.md'}")
