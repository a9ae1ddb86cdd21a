"""Benchmark: cost per step of the time loop.

* spin-up beam (ω = 4 rad/s, Δt = 1e-3, energy-conserving scheme) for 4, 8,
  16, 64, 256 and 1024 P1 elements: the full 30 s for the small meshes, a
  shorter window (``--window``) for the large ones, where only µs per step is
  compared;
* the same 30 s spin-up at 8 elements with every step recorded, and on the
  pure-Python path (``compiled=False``), once each, for comparison;
* the pendulum, 10 000 steps at Δt = 1e-3 (Python path: it has a constraint);
* flexible bodies (``--flexible`` runs only these): the spin-up beam reduced by Craig–Bampton
  (``body="beam-modal"``, 10 modal coordinates) against the full 8-element beam, 5 s at
  Δt = 1e-3, each through the compiled loop and on the Python path; the slider–crank (one
  crank revolution, Δt = 1e-4) with the 8-element beam rod and with a plane-stress rod of
  250 × 8 = 2 000 Q2 elements reduced to 12 coordinates (``body="plane-stress-modal"``), whose
  one-off set-up (assembly, reduction, tensors) is timed separately.

Every run records every ``--record-every``-th step (default 10; energies,
momenta, probe and prescribed force are evaluated in Python at those steps)
and writes no files. Before timing, one short run of each kind compiles the
Numba kernels or loads them from numba's cache; that warm-up is reported but
not part of the table; the same warm-up in a fresh process with an empty
numba cache gives the one-off compile time. Each case then first runs 3 steps of its own scene on
its own path (the column "compile and start-up": the kernels it alone uses, compiled or loaded)
and is run ``--repeat`` times; the table gives the median wall time, µs per step and Newton
iterations per step, and is
written as Markdown to ``OUT/benchmark.md`` (``OUT/peer_benchmark.md`` with ``--no-loop``; default ``examples/output``),
which the README quotes.

More tables:

* every catalogue scene with its default settings under each scheme: µs per
  step (CPU time without the compile) over its whole default run (``--catalogue-steps N`` caps it),
  with the number of coordinates and the path that ran;
* random compositions (chains of rigid bars, floating-frame and exact beams, pins, hinges, gravity,
  sometimes a spring) built one after another in a fresh process with an empty numba cache: what
  each compiles (a scene compiles only the element families it holds, none twice);
* with exudyn installed (``pip install ".[bench]"``), the side-by-side tables of
  ``examples/benchmark_peers.py`` (planar and spatial problems, the reduced rotor and the reduced rotating
  beam, both codes in this process; its docstring says what each row holds; ``--only TEXT`` keeps the problems whose label holds TEXT).

Run ``python examples/benchmark.py [--repeat 3] [--window 1.0] [--record-every 10] [--catalogue-steps N]
[--no-loop] [--no-catalogue] [--no-peer] [--flexible] [--limits] [--out DIR]``;
``--flexible`` runs only the flexible-body rows (``flexible.md``); ``--limits`` runs
``examples/benchmark_limits.py`` instead (memory against mesh size, VTK series cost against frame count).

Parameter sweeps on a local Dask cluster (16 spin-up cases on 2 workers against
16 serial runs, per-case overhead) are timed by ``examples/sweep_benchmark.py``.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests) runs every part on tiny sizes, to
exercise the code, not to measure: spin-up on 4, 8 and 64 elements for 0.05 s, the pendulum for
0.05 s, the flexible cases for 0.02 s (the plane-stress rod 25 × 2 elements), one repeat, the
start-up table for the pendulum only and with the numba cache as it is (not emptied), the catalogue
for two scenes and 3 steps, the side-by-side problems as ``examples/benchmark_peers.py`` runs them in quick
mode; no cold compile (it would take minutes).
"""
import argparse
import os
import platform
import statistics
import time
from pathlib import Path

# OpenBLAS keeps a helper thread spinning for a while after each threaded call (the eigensolver that builds
# a reduced body makes one): the spin lands on the CPU time of the next short run, up to twice its own
# work. Threads do not speed up the time loop's small solves (bend_45: the same wall time); with one BLAS
# thread the CPU times are the loop's own work (set OPENBLAS_NUM_THREADS before running to override)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402  (after the BLAS setting, which takes effect when numpy loads)

import skfem_flex as sf

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
SPIN_UP_ELEMENTS = (4, 8, 64) if QUICK else (4, 8, 16, 64, 256, 1024)
FULL_RUN_UP_TO = 16          # elements; larger meshes run a shorter window
SPIN_UP_T = 0.05 if QUICK else 30.0          # s, the spin-up runs up to FULL_RUN_UP_TO elements
PENDULUM_T = 0.05 if QUICK else 10.0         # s, at Δt = 1e-3
FLEXIBLE_T = 0.02 if QUICK else 5.0          # s, the flexible-body spin-up cases
REVOLUTIONS = 0.02 if QUICK else 1.0         # of the slider–crank's crank
ROD_MESH = (25, 2) if QUICK else (250, 8)    # Q2 elements along and across the plane-stress rod


def time_case(make_scene, t_end, dt, repeat, record_every, compiled=True, warm_steps=3):
    """(compile and start-up s, median wall time s, µs per step, Newton iterations per step, steps) over
    ``repeat`` runs.

    A run of ``warm_steps`` steps of the same scene on the same path goes first: its wall time (the
    one-off compile of the case's kernels, or their load from numba's cache) is the first value, apart
    from the timed runs.
    """
    start = time.perf_counter()
    sf.simulate(make_scene(), t_end=warm_steps * dt, dt=dt, compiled=compiled)
    startup = time.perf_counter() - start
    walls, its = [], []
    for _ in range(repeat):
        res = sf.simulate(make_scene(), t_end=t_end, dt=dt, record_every=record_every, compiled=compiled)
        walls.append(res.wall_time)
        # recorded steps carry their own iteration count; with record_every > 1 this samples the run
        its.append(float(np.mean(res.newton_iterations[1:])))
        steps = res.steps
    wall = statistics.median(walls)
    return startup, wall, 1e6 * wall / steps, statistics.median(its), steps


def warm_up():
    """Compile (or load from numba's cache) every kernel the timed runs use; returns the time, s."""
    start = time.perf_counter()
    for n in (8, 64):                      # dense and banded compiled loops
        sf.simulate(sf.scenes.spin_up_beam(omega=4.0, n_elements=n), t_end=0.01, dt=1e-3)
    sf.simulate(sf.scenes.spin_up_beam(omega=4.0, n_elements=8), t_end=0.01, dt=1e-3, compiled=False)
    return time.perf_counter() - start


def loop_name(scene, integrator="energy-momentum", compiled=None):
    """How ``simulate`` runs the scene (from ``result.run_path`` of a one-step run): "compiled", or
    "compiled + Python" when some elements run through their Python methods (all of them with
    ``compiled=False``)."""
    dt = 1e-4
    path = sf.simulate(scene, dt, dt, scheme=integrator, control=sf.Control(compiled=compiled)).run_path
    return "compiled + Python" if path["python_elements"] else "compiled"


STARTUP_SCENES = ("pendulum",) if QUICK else tuple(sorted(sf.scenes.CATALOGUE))


STARTUP_PROBE = ("import json, sys, time; t0 = time.perf_counter(); import skfem_flex as sf; "
                 "scene = sf.scenes.get(sys.argv[1])(); res = sf.simulate(scene, 0.05, 1e-3); "
                 "print(json.dumps([time.perf_counter() - t0, res.wall_time]))")


def startup():
    """[(scene, s of the first `skfem-flex run` in a fresh process with an empty numba cache, s of the same
    command in the next process, s of start-up in a later process)]. Start-up is what the package adds to
    a run: import, building the scene, loading the compiled kernels from the cache (the time to first
    step, without the steps themselves); the CLI's wall time also holds the interpreter, plots and files.

    Quick mode: the pendulum only, one CLI run with the numba cache as it is (no compile; the next
    run's column is NaN)."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    rows = []
    for name in STARTUP_SCENES:
        with tempfile.TemporaryDirectory() as tmp:
            # quick mode keeps the cache as it is: an empty one would compile for minutes
            env = dict(os.environ) if QUICK else dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
            cmd = [sys.executable, "-m", "skfem_flex.apps.cli", "run", name, "--t-end", "0.05", "--no-vtk", "--quiet",
                   "--out", str(Path(tmp) / "out")]
            times = []
            for _ in range(1 if QUICK else 2):
                start = time.perf_counter()
                subprocess.run(cmd, env=env, check=True, capture_output=True)
                times.append(time.perf_counter() - start)
            out = subprocess.run([sys.executable, "-c", STARTUP_PROBE, name], env=env, check=True,
                                 capture_output=True, text=True)
            total, sim = json.loads(out.stdout.strip().splitlines()[-1])
            rows.append((name, times[0], times[1] if len(times) > 1 else float("nan"), total - sim))
    return rows


def startup_table(rows):
    lines = ["`skfem-flex run SCENE --t-end 0.05 --no-vtk --quiet` in fresh processes sharing an empty numba "
             "cache (wall time, s, with the interpreter, plots and files), and the start-up a later process "
             "adds to a run (import, scene, kernels loaded from the cache; `simulate` of 0.05 s minus its steps)"
             + (" [quick mode: the cache as it was, so the first run did not compile]:" if QUICK else ":"),
             "", "| scene | first run (compiles) | next run | start-up of a later run |", "|---|---|---|---|"]
    lines += [f"| {n} | {a:.1f} | {b:.2f} | {c:.2f} |" for n, a, b, c in rows]
    return "\n".join(lines) + "\n"


def cold_compile():
    """(s, s): wall time of the warm-up in a fresh process with an empty numba cache (the one-off JIT
    compile), and of the same warm-up in the next fresh process, which finds that cache filled."""
    import os
    import subprocess
    import sys
    import tempfile
    times = []
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        code = "import time, benchmark; t = time.perf_counter(); benchmark.warm_up(); print(time.perf_counter() - t)"
        for _ in range(2):
            out = subprocess.run([sys.executable, "-c", code], env=env, cwd=str(Path(__file__).parent),
                                 capture_output=True, text=True, check=True)
            times.append(float(out.stdout.strip().splitlines()[-1]))
    return tuple(times)


def run(repeat=3, window=1.0, record_every=10, elements=SPIN_UP_ELEMENTS):
    """Rows (case, path, steps, compile and start-up s, wall s, µs/step, Newton/step)."""
    rows = []
    pendulum_steps = round(PENDULUM_T / 1e-3)
    for n in elements:
        t_end = SPIN_UP_T if n <= FULL_RUN_UP_TO else window
        warm, wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=n), t_end,
                                               1e-3, repeat if n <= 64 else 1, record_every)
        rows.append((f"spin-up, {n} P1 elements, {t_end:g} s", "compiled", steps, warm, wall, us, its))

    def spin_up_8():
        return sf.scenes.spin_up_beam(omega=4.0, n_elements=8)
    if record_every != 1:                 # what recording costs: the same run with every step recorded
        warm, wall, us, its, steps = time_case(spin_up_8, SPIN_UP_T, 1e-3, 1, 1)
        rows.append((f"spin-up, 8 P1 elements, {SPIN_UP_T:g} s, every step recorded", "compiled", steps,
                     warm, wall, us, its))
    warm, wall, us, its, steps = time_case(spin_up_8, SPIN_UP_T, 1e-3, 1, record_every, compiled=False)
    rows.append((f"spin-up, 8 P1 elements, {SPIN_UP_T:g} s", "Python", steps, warm, wall, us, its))
    pendulum = "pendulum, " + f"{pendulum_steps:,} steps".replace(",", " ")
    warm, wall, us, its, steps = time_case(sf.scenes.pendulum, PENDULUM_T, 1e-3, repeat, record_every)
    rows.append((pendulum, loop_name(sf.scenes.pendulum()), steps, warm, wall, us, its))
    warm, wall, us, its, steps = time_case(sf.scenes.pendulum, PENDULUM_T, 1e-3, 1, record_every, compiled=False)
    rows.append((pendulum, "Python", steps, warm, wall, us, its))
    return rows


def flexible(repeat=1, record_every=10):
    """Rows of the flexible-body cases (same columns as :func:`run`) and the reduced rod's set-up time, s."""
    rows = []
    for label, kw, compiled in ((f"spin-up, 8 P1 elements, {FLEXIBLE_T:g} s", {}, True),
                                (f"spin-up, 8 P1 elements, {FLEXIBLE_T:g} s", {}, False),
                                (f"spin-up, Craig–Bampton beam (10 coordinates), {FLEXIBLE_T:g} s",
                                 dict(body="beam-modal"), True),
                                (f"spin-up, Craig–Bampton beam (10 coordinates), {FLEXIBLE_T:g} s",
                                 dict(body="beam-modal"), False)):
        warm, wall, us, its, steps = time_case(lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=8, **kw),
                                               FLEXIBLE_T, 1e-3, repeat, record_every, compiled=compiled)
        loop = loop_name(sf.scenes.spin_up_beam(omega=4.0, n_elements=8, **kw), compiled=compiled)
        rows.append((label, loop, steps, warm, wall, us, its))
    run_time = REVOLUTIONS * 2 * np.pi / 150.0
    span = "one revolution" if REVOLUTIONS == 1 else f"{REVOLUTIONS:g} revolution"
    warm, wall, us, its, steps = time_case(lambda: sf.scenes.slider_crank(), run_time, 1e-4, repeat, record_every)
    rows.append((f"slider–crank, 8-element beam rod, {span}, dt = 1e-4 s", loop_name(sf.scenes.slider_crank()),
                 steps, warm, wall, us, its))
    start = time.perf_counter()
    rod_scene = sf.scenes.slider_crank(body="plane-stress-modal", n_elements=ROD_MESH[0], n_across=ROD_MESH[1])
    setup = time.perf_counter() - start
    warm, wall, us, its, steps = time_case(lambda: rod_scene, run_time, 1e-4, repeat, record_every)
    elements = f"{ROD_MESH[0] * ROD_MESH[1]:,}".replace(",", " ")
    rows.append((f"slider–crank, plane-stress rod {elements} Q2 elements → {rod_scene.bodies[1].n_elastic} "
                 f"coordinates, {span}, dt = 1e-4 s", loop_name(rod_scene), steps, warm, wall, us, its))
    return rows, setup


def table(rows, record_every, warm, cold=None):
    lines = [f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
             f"numpy {np.__version__}, numba {_numba_version()}; energy-momentum scheme, dt = 1e-3 s unless stated; "
             f"every {record_every}th step recorded (energies, momenta, probes), no file output; "
             f"median of the repeats, after a warm-up run in this process that compiled what the package's "
             f"cache lacked or loaded it ({warm:.1f} s, not counted); each case first runs 3 steps of its own scene, whose wall time "
             f"(compile or cache load of the case's kernels, start-up) is the column \"compile and start-up\", "
             f"apart from the timed runs.", "",
             "| case | time loop | steps | compile and start-up (s) | wall time (s) | µs per step "
             "| Newton iterations per step (recorded steps) |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {c} | {p} | {s} | {a:.2f} | {w:.3g} | {u:.1f} | {i:.2f} |" if u < 100 else
              f"| {c} | {p} | {s} | {a:.2f} | {w:.3g} | {u:.0f} | {i:.2f} |" for c, p, s, a, w, u, i in rows]
    us = {r[0].split(",")[1].strip(): r[5] for r in rows if r[1] == "compiled" and "every step" not in r[0]}
    if "8 P1 elements" in us and "1024 P1 elements" in us:
        lines += ["", f"Cost per step at 1024 elements / at 8 elements: "
                      f"{us['1024 P1 elements'] / us['8 P1 elements']:.0f}."]
    if cold is not None:
        lines += ["", f"One-off JIT compile of the kernels (the warm-up in a fresh process with an empty numba "
                      f"cache): {cold[0]:.1f} s; the same warm-up in the next fresh process, with that cache "
                      f"filled: {cold[1]:.1f} s."]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ every catalogue scene
SCHEMES = ("energy-momentum", "trapezoidal", "generalized-alpha")
#: the catalogue scenes of quick mode (all of them otherwise)
QUICK_CATALOGUE = ("pendulum", "flexible_pendulum")


def catalogue_rows(steps=None, repeat=1):
    """Rows (scene, coordinates, scheme, dt, µs per step, message, path) for every catalogue scene with its
    default parameters over its whole default run (t_end, Δt of the catalogue): CPU time of ``simulate``
    (the scene built before) without its compile, divided by the steps, median of ``repeat`` runs.
    ``steps``: cap the run at this many steps (quick mode)."""
    rows = []
    for name in (QUICK_CATALOGUE if QUICK else sorted(sf.scenes.CATALOGUE)):
        factory = sf.scenes.CATALOGUE[name]
        dt = factory.defaults.get("dt", 1e-3)
        t_end = factory.defaults.get("t_end", 200 * dt)
        if steps is not None:
            t_end = min(t_end, steps * dt)
        n = factory().n
        for scheme in SCHEMES:
            try:
                sf.simulate(factory(), t_end=2 * dt, dt=dt, integrator=scheme)         # compile / load
                per_step = []
                for _ in range(repeat):
                    scene = factory()                   # built outside the timing: the CPU time of simulate
                    start = time.process_time()
                    res = sf.simulate(scene, t_end=t_end, dt=dt, integrator=scheme)
                    per_step.append(1e6 * (time.process_time() - start - res.compile_time) / res.steps)
                rows.append((name, n, scheme, dt, float(np.median(per_step)), "", loop_name(factory(), scheme)))
            except sf.SimulationError as exc:
                rows.append((name, n, scheme, dt, float("nan"), str(exc).splitlines()[0][:80], ""))
    return rows


def catalogue_table(rows, steps):
    span = "its whole default run" if steps is None else f"its default run, at most {steps} steps"
    lines = [f"Every catalogue scene with its default parameters and step over {span} (CPU time of `simulate` "
             f"without its compile, divided by the steps; the scene built before; median of the repeats), every "
             f"step recorded, no files.", "",
             "| scene | coordinates | Δt (s) | " + " | ".join(f"{s} µs/step" for s in SCHEMES)
             + " | path (" + "; ".join(SCHEMES) + ") |",
             "|---|---|---|" + "---|" * (len(SCHEMES) + 1)]
    by, loops = {}, {}
    for name, n, scheme, dt, us, msg, loop in rows:
        by.setdefault((name, n, dt), {})[scheme] = f"{us:.0f}" if np.isfinite(us) else f"failed: {msg}"
        loops.setdefault((name, n, dt), {})[scheme] = loop
    for (name, n, dt), cells in by.items():
        lines.append(f"| {name} | {n} | {dt:g} | " + " | ".join(cells.get(s, "") for s in SCHEMES)
                     + " | " + "; ".join(loops[(name, n, dt)].get(s, "") for s in SCHEMES) + " |")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ random compositions: what compiles
COMPOSITIONS = 3 if QUICK else 8


def composition(rng):
    """A random chain of 1–4 one-metre links (rigid bars, floating-frame beams, exact beams), the first
    pinned to the ground, each hinged to the next, under gravity, sometimes with a spring from the last tip
    to the ground; built from the public API as a user would."""
    import skfem
    sec = sf.Section(EA=1e6, EI=1e3, kGA=5e5, rhoA=1.0, rhoI=1e-3)
    links, joints, parts = [], [], []
    for k in range(int(rng.integers(1, 5))):
        kind = ("rigid", "floating", "exact")[int(rng.integers(0, 3))]
        x0 = float(k)
        if kind == "rigid":
            body = sf.RigidBody.bar(1.0, 1.0, start=(x0, 0.0), name=f"bar {k}")
            root, tip = body.point((-0.5, 0.0)), body.point((0.5, 0.0))
        elif kind == "floating":
            beam = sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, 1.0, 5)), sec)
            body = sf.FloatingBeam(beam, position=(x0, 0.0), name=f"beam {k}")
            root, tip = body.point(0.0), body.point(1.0)
        else:
            body = sf.ExactBeam.from_points(sec, (x0, 0.0), (x0 + 1.0, 0.0), n_elements=4, name=f"exact {k}")
            root, tip = body.point(0.0), body.point(1.0)
        joints.append(sf.Pin(root, (0.0, 0.0), name="pin") if k == 0 else
                      sf.Revolute(links[-1][1], root, name=f"hinge {k}"))
        links.append((body, tip))
        parts.append(kind)
    forces = [sf.Gravity((0.0, -9.81))]
    if rng.random() < 0.5:
        forces.append(sf.LinearSpring(links[-1][1], None, 100.0, name="spring"))
        parts.append("spring")
    return sf.Scene([b for b, _ in links], constraints=joints, forces=forces, name=" + ".join(parts)), parts


def compositions_worker(n, seed):
    """In a fresh process (empty cache): n random compositions one after another, 5 steps each; prints JSON
    rows (parts, compile time s, wall time of simulate s)."""
    import json
    rng = np.random.default_rng(seed)
    for _ in range(n):
        scene, parts = composition(rng)
        start = time.perf_counter()
        res = sf.simulate(scene, 5e-3, 1e-3)
        print(json.dumps([parts, res.compile_time, time.perf_counter() - start]), flush=True)


def compositions(n=COMPOSITIONS, seed=1):
    """Rows of :func:`compositions_worker` run in a fresh process with an empty numba cache (quick mode:
    the cache as it is)."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, SKFEM_FLEX_QUIET="1")
        if not QUICK:
            env["NUMBA_CACHE_DIR"] = tmp
        code = f"import benchmark; benchmark.compositions_worker({n}, {seed})"
        out = subprocess.run([sys.executable, "-c", code], env=env, cwd=str(Path(__file__).parent),
                             capture_output=True, text=True, check=True)
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("[")]


def compositions_table(rows):
    lines = ["Random compositions (chains of rigid bars, floating-frame and exact beams, pins, hinges, gravity, "
             "sometimes a spring), built one after another in one fresh process"
             + (" [quick mode: the cache as it was]" if QUICK else " with an empty numba cache")
             + ": what each compiles. A scene compiles only the element families it holds, and none it "
             "shares with an earlier scene.", "",
             "| # | links and forces | compile (s) | simulate, 5 steps, with its compile (s) |", "|---|---|---|---|"]
    lines += [f"| {i + 1} | {' + '.join(parts)} | {c:.1f} | {w:.2f} |" for i, (parts, c, w) in enumerate(rows)]
    return "\n".join(lines) + "\n"


def _numba_version():
    import numba
    return numba.__version__


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1 if QUICK else 3)
    ap.add_argument("--window", type=float, default=0.05 if QUICK else 1.0,
                    help="simulated seconds for meshes above 16 elements")
    ap.add_argument("--record-every", type=int, default=10, help="record every n-th step")
    ap.add_argument("--catalogue-steps", type=int, default=3 if QUICK else None,
                    help="at most this many steps per catalogue scene and scheme (default: the whole run)")
    ap.add_argument("--no-loop", action="store_true", help="skip the spin-up/pendulum time-loop table")
    ap.add_argument("--no-catalogue", action="store_true", help="skip the table of every catalogue scene")
    ap.add_argument("--no-peer", action="store_true", help="skip the side-by-side runs with exudyn")
    ap.add_argument("--only", default=None, help="only the side-by-side problems whose label holds this text")
    ap.add_argument("--no-startup", action="store_true", help="skip the first-run/next-run start-up table")
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    ap.add_argument("--flexible", action="store_true", help="only the flexible-body cases (flexible.md)")
    ap.add_argument("--limits", action="store_true",
                    help="instead: peak memory at 10³–10⁵ elements and VTK series cost per frame "
                         "(examples/benchmark_limits.py)")
    args = ap.parse_args()
    if args.limits:
        import benchmark_limits
        benchmark_limits.main(["--out", args.out])
        raise SystemExit(0)
    if args.flexible:
        warm = warm_up()
        rows, setup = flexible(args.repeat, args.record_every)
        elements = f"{ROD_MESH[0] * ROD_MESH[1]:,}".replace(",", " ")
        text = table(rows, args.record_every, warm) + (f"\nOne-off set-up of the reduced {elements}-element rod "
                                                        f"(assembly, Craig–Bampton, modal derivatives, tensors): "
                                                        f"{setup:.1f} s.\n")
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "flexible.md").write_text(text)
        print(text)
        raise SystemExit
    parts = []
    if not args.no_loop:
        cold = None if QUICK else cold_compile()          # minutes in a fresh cache: not in quick mode
        warm = warm_up()
        rows = run(args.repeat, args.window, args.record_every) + flexible(args.repeat, args.record_every)[0]
        parts.append(table(rows, args.record_every, warm, cold))
    if not args.no_startup:
        parts.append(startup_table(startup()))
    if not args.no_startup:
        parts.append(compositions_table(compositions()))
    if not args.no_catalogue:
        parts.append(catalogue_table(catalogue_rows(args.catalogue_steps, args.repeat), args.catalogue_steps))
    if not args.no_peer:
        import benchmark_peers
        parts.append(benchmark_peers.tables(args.out, args.repeat, args.only))
    text = "\n".join(parts)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    # the time-loop table and the catalogue/peer tables are separate documents: a run of only the
    # latter (--no-loop) must not overwrite the former
    name = "peer_benchmark.md" if args.no_loop else "benchmark.md"
    (out / name).write_text(text)
    print(text)
    print(f"written to {out / name}")
