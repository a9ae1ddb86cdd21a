"""Benchmark: cost per step of the time loop.

* spin-up beam (ω = 4 rad/s, Δt = 1e-3, energy-conserving scheme) for 4, 8,
  16, 64, 256 and 1024 P1 elements: the full 30 s for the small meshes, a
  shorter window (``--window``) for the large ones, where only µs per step is
  compared;
* the pendulum, 10 000 steps at Δt = 1e-3.

Each case is run ``--repeat`` times; the table gives the median wall time,
µs per step and Newton iterations per step, and is written as Markdown to
``OUT/benchmark.md`` (default ``examples/output``), which the README quotes.

Run ``python examples/benchmark.py [--repeat 3] [--window 1.0] [--out DIR]``.
"""
import argparse
import platform
import statistics
from pathlib import Path

import numpy as np

import skfem_flex as sf

SPIN_UP_ELEMENTS = (4, 8, 16, 64, 256, 1024)
FULL_RUN_UP_TO = 16          # elements; larger meshes run a shorter window


def time_case(make_scene, t_end, dt, repeat):
    """Median wall time (s), µs per step and Newton iterations per step over ``repeat`` runs."""
    walls, its = [], []
    for _ in range(repeat):
        res = sf.simulate(make_scene(), t_end=t_end, dt=dt)
        walls.append(res.wall_time)
        its.append(float(np.sum(res.newton_iterations)) / res.steps)
        steps = res.steps
    wall = statistics.median(walls)
    return wall, 1e6 * wall / steps, statistics.median(its), steps


def run(repeat=3, window=1.0, elements=SPIN_UP_ELEMENTS):
    """Rows (case, steps, wall s, µs/step, Newton/step)."""
    rows = []
    for n in elements:
        t_end = 30.0 if n <= FULL_RUN_UP_TO else window
        wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=n), t_end, 1e-3,
                                         repeat if n <= 64 else 1)
        rows.append((f"spin-up, {n} P1 elements, {t_end:g} s", steps, wall, us, its))
    wall, us, its, steps = time_case(sf.scenes.pendulum, 10.0, 1e-3, repeat)
    rows.append(("pendulum, 10 000 steps", steps, wall, us, its))
    return rows


def table(rows):
    lines = [f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
             f"numpy {np.__version__}; energy-momentum scheme, dt = 1e-3 s.", "",
             "| case | steps | wall time (s) | µs per step | Newton iterations per step |", "|---|---|---|---|---|"]
    lines += [f"| {c} | {s} | {w:.3g} | {u:.0f} | {i:.2f} |" for c, s, w, u, i in rows]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--window", type=float, default=1.0, help="simulated seconds for meshes above 16 elements")
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    args = ap.parse_args()
    text = table(run(args.repeat, args.window))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmark.md").write_text(text)
    print(text)
    print(f"written to {out / 'benchmark.md'}")
