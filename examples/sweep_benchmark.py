"""Benchmark: a 16-case spin-up sweep on a local Dask cluster against 16 serial ``simulate`` calls.

Cases: ω ∈ {4, 6, 8, 10} rad/s × {32, 24, 16, 8} P1 elements, Δt = 1e-3 s, t_end
= 30 s (``--t-end``), energy-conserving scheme, every ``--record-every``-th
step recorded (default 10, as in ``benchmark.py``). The grid lists the large
meshes first so that the longest cases start first (the scheduler runs
tasks in submission order; this keeps the two workers evenly loaded at the end).

* serial: the 16 ``simulate`` calls one after another in this process, after
  a warm-up that loads the Numba kernels;
* sweep: ``skfem_flex.apps.sweep(..., n_workers=N, store=...)`` from start to
  return, *including* starting and closing the local cluster of N worker
  processes (each imports skfem_flex and loads the kernels from numba's
  cache once) and writing every case to the store;
* sweep on a running cluster: the same with a ``Client`` of
  ``skfem_flex.apps.sweep.local_cluster`` (the cluster a sweep starts, with the same
  Dask settings) started before the clock starts (the cost a sweep pays on a
  cluster that is already up);
* plain processes: the same 16 ``simulate`` calls handed out in grid order to N
  ``multiprocessing`` processes (``concurrent.futures.ProcessPoolExecutor``,
  forked from this process inside the clock, so the kernels are already
  loaded; no Dask, no store): what N processes give on this machine without
  any of the sweep's machinery.

Per-case overhead = (sweep wall time × N − Σ time the cases spent in
``simulate``) / 16: the worker time per case not spent integrating (task
transfer, scene building, the Dataset, the store, cluster start-up shared
out). A last sweep of the same 16 cases with a single step each measures that
overhead alone. The
load average of the machine is printed with the table, and a capacity check
first runs the same spin-up alone and then in N plain processes at once: the
ratio is the number of cores this machine actually gives us at that moment
(N on an idle machine; on a shared one other processes take the rest), the
most any N-worker sweep can gain over serial.

Every timed run is preceded by a run that loads the Numba kernels (serial: one short run in this
process; sweeps on a running cluster: one short run on each worker); its wall time is reported
apart as "compile and start-up". The sweep that starts its own cluster includes the workers'
start-up by design.

Run ``python examples/sweep_benchmark.py [--workers 2] [--t-end 30] [--out DIR]``;
writes ``OUT/sweep_benchmark.md`` (default ``examples/output``).

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 4 cases (ω ∈ {4, 10} rad/s × {16, 8}
elements), t_end = 0.02 s, the capacity check on a 0.05 s run (the code path, not a measurement).
"""
import argparse
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

import skfem_flex as sf

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
GRID = ({"n_elements": [16, 8], "omega": [4.0, 10.0]} if QUICK else
        {"n_elements": [32, 24, 16, 8], "omega": [4.0, 6.0, 8.0, 10.0]})
CAPACITY_T = 0.05 if QUICK else 5.0          # s, the spin-up run of the capacity check


def serial(t_end, dt, record_every):
    """Wall time (s) of the serial simulate calls, the sum of the times spent in them, and the wall time (s)
    of the warm-up run before them that loads the kernels (compile and start-up)."""
    start = time.perf_counter()
    sf.simulate(sf.scenes.spin_up_beam(), 0.01, dt)          # load the kernels (timed apart)
    warm = time.perf_counter() - start
    start, loop = time.perf_counter(), 0.0
    for n in GRID["n_elements"]:
        for w in GRID["omega"]:
            scene = sf.scenes.spin_up_beam(omega=w, n_elements=n)
            t0 = time.perf_counter()
            sf.simulate(scene, t_end, dt, record_every=record_every)
            loop += time.perf_counter() - t0
    return time.perf_counter() - start, loop, warm


def sweep(t_end, dt, record_every, workers, client=None):
    """(wall time, Σ simulate time over cases, the Dataset) of the sweep into a fresh store."""
    store = Path(tempfile.mkdtemp(prefix="sweep-benchmark-")) / "cases"
    try:
        start = time.perf_counter()
        ds = sf.sweep("spin_up_beam", vary=GRID, t_end=t_end, dt=dt, record_every=record_every, store=store,
                      client=client, n_workers=workers if client is None else None)
        wall = time.perf_counter() - start
    finally:
        shutil.rmtree(store.parent, ignore_errors=True)
    assert set(ds.status.values) == {"completed"}, ds.message.values
    return wall, float(ds.run_time.sum()), ds


def _case(args):
    """One case in a pool process: the time spent in simulate."""
    n, w, t_end, dt, record_every = args
    scene = sf.scenes.spin_up_beam(omega=w, n_elements=n)
    start = time.perf_counter()
    sf.simulate(scene, t_end, dt, record_every=record_every)
    return time.perf_counter() - start


def processes(t_end, dt, record_every, workers):
    """(wall time, Σ simulate time) of the 16 cases on ``workers`` plain processes, pool start included."""
    from concurrent.futures import ProcessPoolExecutor

    cases = [(n, w, t_end, dt, record_every) for n in GRID["n_elements"] for w in GRID["omega"]]
    start = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        loops = list(pool.map(_case, cases))
    return time.perf_counter() - start, sum(loops)


def _one_run(_=None):
    scene = sf.scenes.spin_up_beam(n_elements=16)
    sf.simulate(scene, 0.01, 1e-3)                      # kernels loaded
    start = time.perf_counter()
    sf.simulate(scene, CAPACITY_T, 1e-3, record_every=10)
    return time.perf_counter() - start


def capacity(workers):
    """How many cores this machine gives us now: the time of one spin-up run (``CAPACITY_T``) alone divided by its
    mean time when ``workers`` plain processes run it at once (``workers`` on an idle machine)."""
    from concurrent.futures import ProcessPoolExecutor

    alone = _one_run()
    with ProcessPoolExecutor(workers) as pool:
        together = list(pool.map(_one_run, range(workers)))
    return workers * alone / (sum(together) / workers)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--t-end", type=float, default=0.02 if QUICK else 30.0)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--record-every", type=int, default=10)
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    args = ap.parse_args()
    load0 = os.getloadavg()
    cores = capacity(args.workers)
    t_serial, loop_serial, warm_serial = serial(args.t_end, args.dt, args.record_every)
    # before any Dask cluster: a Nanny leaves its variables (OMP_NUM_THREADS, ...) in this process's environment
    t_plain, loop_plain = processes(args.t_end, args.dt, args.record_every, args.workers)
    t_sweep, run_sweep, ds = sweep(args.t_end, args.dt, args.record_every, args.workers)
    from distributed import Client
    from skfem_flex.apps.sweep import local_cluster
    with local_cluster(args.workers) as cluster, Client(cluster) as client:
        start = time.perf_counter()
        client.run(lambda: sf.simulate(sf.scenes.spin_up_beam(), 0.01, args.dt) and None)   # workers warm
        warm_workers = time.perf_counter() - start
        t_warm, run_warm, _ = sweep(args.t_end, args.dt, args.record_every, args.workers, client)
        t_empty, run_empty, _ = sweep(args.dt, args.dt, args.record_every, args.workers, client)
    load1 = os.getloadavg()
    n = ds.sizes["case"]
    w = args.workers
    rows = [
        (f"{n} serial simulate calls", t_serial, 1.0, loop_serial, float("nan")),
        (f"the {n} calls in {w} plain processes (no Dask)", t_plain,
         t_plain / t_serial, loop_plain, (t_plain * w - loop_plain) / n),
        (f"sweep, {w} workers, cluster started and closed by it", t_sweep, t_sweep / t_serial, run_sweep,
         (t_sweep * w - run_sweep) / n),
        (f"sweep, {w} workers, cluster already running", t_warm, t_warm / t_serial, run_warm,
         (t_warm * w - run_warm) / n),
        (f"the same {n} cases with one step each (pure overhead), cluster running", t_empty, float("nan"), run_empty,
         (t_empty * w - run_empty) / n),
    ]
    lines = [f"Spin-up sweep, {n} cases (ω × elements), Δt = {args.dt:g} s, t_end = {args.t_end:g} s, "
             f"every {args.record_every}th step recorded; {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores, load average {load0[0]:.1f} before / {load1[0]:.1f} after; "
             f"{args.workers} plain processes running at once got the throughput of {cores:.2f} cores "
             f"(the most a {args.workers}-worker sweep can gain over serial). Compile and start-up, not counted: "
             f"the serial warm-up run {warm_serial:.1f} s, the warm-up run on the running cluster's workers "
             f"{warm_workers:.1f} s.",
             "",
             "| run | wall time (s) | × serial | Σ time in simulate (s) | overhead per case (s) |",
             "|---|---|---|---|---|"]
    for name, wall, ratio, loop, over in rows:
        lines.append(f"| {name} | {wall:.1f} | " + ("–" if ratio != ratio else f"{ratio:.2f}") + f" | {loop:.1f} | "
                     + ("–" if over != over else f"{over:.2f}") + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "sweep_benchmark.md").write_text(text)


if __name__ == "__main__":
    main()
