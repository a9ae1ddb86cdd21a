"""Benchmark of the limits: memory against mesh size, and VTK series cost against frame count.

* **memory**: one step of Δt = min(1 ms, the scene's default step) (after the same step once, which
  compiles or loads the Numba kernels and is reported apart as "compile and start-up") of the
  spin-up beam (floating frame, compiled loop), the pinned flexible pendulum (constraint), the
  rigid–flexible double pendulum and the slider–crank (joints between bodies) at 1 000, 10 000 and
  100 000 elements, each in a fresh subprocess that reports its own peak resident set size
  (``ru_maxrss``); memory must grow linearly with the mesh (no dense n × n anywhere). The
  slider–crank steps 0.1 ms, its default: at 1 ms (0.15 rad of crank per step) Newton fails on the
  compiled path and the Python path halves the step, which at 10 000 elements took minutes per step;
* **series**: writing N = 500, 1 000, 2 000 and 4 000 frames of the pendulum with
  :class:`skfem_flex.VTKSeries`; the cost per frame must not grow with N (the collections are
  rewritten only when the unlisted frames reach 1/256 of the listed ones, or after a second).

Run ``python examples/benchmark_limits.py [--sizes 1000 10000 100000] [--frames 500 1000 2000 4000]
[--out DIR]``; also ``python examples/benchmark.py --limits``. Writes ``OUT/benchmark_limits.md``.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): the memory table for the spin-up beam and
the slider–crank at 10 elements, the series at 5 and 10 frames (the code path, not a measurement).
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from skfem_flex.compiled.ahead import package_environment

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
SCENES = ("spin_up_beam", "slider_crank") if QUICK else ("spin_up_beam", "flexible_pendulum", "double_pendulum",
                                                         "slider_crank")

CHILD = r"""
import json, resource, sys, time
import skfem_flex as sf
name, n = sys.argv[1], int(sys.argv[2])
start = time.perf_counter()
factory = sf.scenes.get(name)
dt = min(1e-3, factory.defaults.get("dt", 1e-3))
scene = factory(n_elements=n)
built = time.perf_counter()
sf.simulate(scene, dt, dt)              # the same step once before: compiles or loads the kernels
warm = time.perf_counter()
sf.simulate(scene, dt, dt)
print(json.dumps({"n_dofs": scene.n, "dt": dt, "build_s": built - start, "startup_s": warm - built,
                  "step_s": time.perf_counter() - warm,
                  "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def memory(sizes, scenes=SCENES):
    """[(scene, elements, coordinates, Δt s, build s, compile and start-up s, step s, peak RSS MB)], one
    subprocess each."""
    rows = []
    for name in scenes:
        for n in sizes:
            proc = subprocess.run([sys.executable, "-c", CHILD, name, str(n)], capture_output=True, text=True,
                                  env=package_environment())
            if proc.returncode != 0:
                why = proc.stderr.strip().splitlines() or [f"exit status {proc.returncode} (killed?)"]
                rows.append((name, n, None, None, None, None, None, why[-1]))
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            rows.append((name, n, r["n_dofs"], r["dt"], r["build_s"], r["startup_s"], r["step_s"],
                         r["peak_rss_MB"]))
            print(rows[-1], flush=True)
    return rows


def series(frames):
    """([(N, seconds to write N frames, ms per frame)], s of the warm-up) of a pendulum series written frame
    by frame; the warm-up writes 2 frames to a series of its own first (imports, first file), timed apart."""
    import skfem_flex as sf

    scene = sf.scenes.pendulum()
    q, v = scene.initial_state()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        sink = sf.VTKSeries(d, "p")
        for k in range(2):
            sink.write(scene, 1e-3 * k, q, v)
        sink.close()
    warm = time.perf_counter() - start
    rows = []
    for n in frames:
        with tempfile.TemporaryDirectory() as d:
            sink = sf.VTKSeries(d, "p")
            start = time.perf_counter()
            for k in range(n):
                sink.write(scene, 1e-3 * k, q, v)
            sink.close()
            wall = time.perf_counter() - start
        rows.append((n, wall, 1e3 * wall / n))
        print(rows[-1], flush=True)
    return rows, warm


def table(mem, ser, series_warm=None):
    lines = [f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}.", "",
             "| scene | elements | coordinates | Δt (s) | build (s) | compile and start-up (s) | one step (s) "
             "| peak RSS (MB) |",
             "|---|---|---|---|---|---|---|---|"]
    for name, n, dofs, dt, build, warm, step, rss in mem:
        if dofs is None:
            lines.append(f"| {name} | {n} | failed: {rss} | | | | | |")
        else:
            lines.append(f"| {name} | {n} | {dofs} | {dt:g} | {build:.2f} | {warm:.2f} | {step:.2f} | {rss:.0f} |")
    lines += ["", "| frames | write time (s) | ms per frame |", "|---|---|---|"]
    lines += [f"| {n} | {wall:.2f} | {ms:.2f} |" for n, wall, ms in ser]
    if series_warm is not None:
        lines += ["", f"Start-up of the series writer (2 frames of a series of its own first, not counted above): "
                      f"{series_warm:.2f} s."]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[10] if QUICK else [1000, 10000, 100000],
                    help="mesh sizes of the memory table (none: skip it)")
    ap.add_argument("--frames", type=int, nargs="+", default=[5, 10] if QUICK else [500, 1000, 2000, 4000])
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    args = ap.parse_args(argv)
    text = table(memory(args.sizes), *series(args.frames))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmark_limits.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
