"""Benchmark of the limits: memory against mesh size, and VTK series cost against frame count.

* **memory**: one 1 ms step of the spin-up beam (floating frame, compiled loop), the pinned
  flexible pendulum (Python path, constraint), the rigid–flexible double pendulum and the
  slider–crank (joints between bodies) at 1 000, 10 000 and 100 000 elements, each in
  a fresh subprocess that reports its own peak resident set size (``ru_maxrss``); memory must grow
  linearly with the mesh (no dense n × n anywhere);
* **series**: writing N = 500, 1 000, 2 000 and 4 000 frames of the pendulum with
  :class:`skfem_flex.VTKSeries`; the cost per frame must not grow with N (the collections are
  rewritten only when the unlisted frames reach 1/256 of the listed ones, or after a second).

Run ``python examples/benchmark_limits.py [--sizes 1000 10000 100000] [--frames 500 1000 2000 4000]
[--out DIR]``; also ``python examples/benchmark.py --limits``. Writes ``OUT/benchmark_limits.md``.
"""
import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, sys, time
import skfem_flex as sf
name, n = sys.argv[1], int(sys.argv[2])
start = time.perf_counter()
scene = sf.scenes.get(name)(n_elements=n)
built = time.perf_counter()
sf.simulate(scene, 1e-3, 1e-3)
print(json.dumps({"n_dofs": scene.n, "build_s": built - start, "step_s": time.perf_counter() - built,
                  "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def memory(sizes, scenes=("spin_up_beam", "flexible_pendulum", "double_pendulum", "slider_crank")):
    """[(scene, elements, coordinates, build s, step s, peak RSS MB)], one subprocess each."""
    rows = []
    for name in scenes:
        for n in sizes:
            env_path = str(ROOT)
            proc = subprocess.run([sys.executable, "-c", CHILD, name, str(n)], capture_output=True, text=True,
                                  env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"})
            if proc.returncode != 0:
                why = proc.stderr.strip().splitlines() or [f"exit status {proc.returncode} (killed?)"]
                rows.append((name, n, None, None, None, why[-1]))
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            rows.append((name, n, r["n_dofs"], r["build_s"], r["step_s"], r["peak_rss_MB"]))
            print(rows[-1], flush=True)
    return rows


def series(frames):
    """[(N, seconds to write N frames, ms per frame)] of a pendulum series written frame by frame."""
    import skfem_flex as sf

    scene = sf.scenes.pendulum()
    q, v = scene.initial_state()
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
    return rows


def table(mem, ser):
    lines = [f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}.", "",
             "| scene | elements | coordinates | build (s) | one step (s) | peak RSS (MB) |",
             "|---|---|---|---|---|---|"]
    for name, n, dofs, build, step, rss in mem:
        if dofs is None:
            lines.append(f"| {name} | {n} | failed: {rss} | | | |")
        else:
            lines.append(f"| {name} | {n} | {dofs} | {build:.2f} | {step:.2f} | {rss:.0f} |")
    lines += ["", "| frames | write time (s) | ms per frame |", "|---|---|---|"]
    lines += [f"| {n} | {wall:.2f} | {ms:.2f} |" for n, wall, ms in ser]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[1000, 10000, 100000],
                    help="mesh sizes of the memory table (none: skip it)")
    ap.add_argument("--frames", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    args = ap.parse_args(argv)
    text = table(memory(args.sizes), series(args.frames))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmark_limits.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
