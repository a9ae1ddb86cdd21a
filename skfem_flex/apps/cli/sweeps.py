"""``skfem-flex sweep`` and ``skfem-flex study``: many runs as the cases of a sweep, on a Dask cluster
(``--workers N``, ``--scheduler ADDRESS``) or one after another in this process, resumable from a store."""
from __future__ import annotations

import argparse
import inspect
import json
import math
import sys
import time
from pathlib import Path

from .arguments import number, positive_int, positive_number
from .errors import UsageError, one_line
from .outputs import jsonable, prepare_out
from .settings import scene_settings, split_setting, vary_values

__all__ = ["add_sweep", "add_study"]


# ------------------------------------------------- where sweeps run (sweep, study)
def _add_where_options(p, workers_default):
    """``--workers N | --scheduler ADDRESS`` and ``--resume/--no-resume``: where the cases of a sweep run
    and whether the store's cases are reused (the options of ``sweep`` and ``study``)."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=None, metavar="N",
                       help=f"run the cases on a local Dask cluster of N worker processes ({workers_default})")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="address of a running Dask scheduler (e.g. tcp://host:8786) to run the cases on")
    p.add_argument("--resume", action=argparse.BooleanOptionalAction, default=True,
                   help="skip cases already in the store (default); --no-resume recomputes them")


def _where(args, default):
    """(client, n_workers) for :func:`skfem_flex.apps.sweep.run_cases` from ``--workers``/``--scheduler``;
    ``default`` (None: a local cluster of one worker per core; "serial": this process) without either."""
    if args.scheduler:
        return args.scheduler, None
    if args.workers is not None:
        return None, args.workers
    return default, None


# --------------------------------------------------------------------- sweep
def _sweep_grid(name, items):
    """{name: [values]} from ``--vary KEY=VALUES`` (as for ``campbell``: a comma list or START:STOP:COUNT),
    converted to the type of the parameter's default; ``t_end``, ``dt`` and ``integrator`` may be varied too."""
    from ... import scenes
    from ..sweep import RUN_SETTINGS

    params = {p: d for p, d, _ in scenes.parameters(name)}
    run_defaults = {"t_end": 0.0, "dt": 0.0, "integrator": ""}     # only their types matter
    grid = {}
    for item in items or ():
        key, text = split_setting(item, "--vary expects KEY=VALUES, got {item!r}")
        if key in grid:
            raise UsageError(f"--vary {key} is given twice")
        # unknown names pass as text: the sweep's plan reports them, in the same words as for the API
        default = params.get(key, run_defaults[key] if key in RUN_SETTINGS else "")
        grid[key] = vary_values(key, text.strip(), None if default is inspect.Parameter.empty else default)
    return grid


def _cmd_sweep(args):
    from ... import scenes
    from ...io.plots import plot_sweep_extremes
    from ...io.files import write_text_atomically
    from ..sweep import plan, probe_extremes, run_cases

    if args.scene not in scenes.CATALOGUE:
        raise UsageError(f"unknown scene {args.scene!r}; known scenes: {', '.join(sorted(scenes.CATALOGUE))}")
    if not args.vary:
        raise UsageError("give at least one --vary key=value1,value2,...")
    grid = _sweep_grid(args.scene, args.vary)
    fixed = scene_settings(args.scene, args.set) if args.set else {}
    clash = sorted(set(fixed) & set(grid))
    if clash:
        raise UsageError(f"{clash[0]} is both fixed (--set) and varied (--vary)")
    for k, v in (("--dt", args.dt), ("--t-end", args.t_end)):
        if v is not None and (not math.isfinite(v) or v <= 0):
            raise UsageError(f"{k} must be a positive number of seconds, got {v!r}")
    options = {} if args.rho_inf is None else {"rho_inf": args.rho_inf}
    try:
        specs = plan(args.scene, vary=grid, fixed=fixed, t_end=args.t_end, dt=args.dt, integrator=args.integrator,
                     record_every=args.record_every, **options)
    except (ValueError, TypeError) as exc:
        raise UsageError(one_line(exc)) from None
    out = Path(args.out) if args.out is not None else Path("results") / f"sweep-{args.scene}"
    prepare_out(out)
    client, n_workers = _where(args, default=None)
    start = time.perf_counter()
    store = out / ("sweep.zarr" if args.format == "zarr" else "sweep")
    ds = run_cases(specs, store=store, client=client, resume=args.resume, n_workers=n_workers,
                   progress=not args.quiet)
    wall = time.perf_counter() - start

    probes = [k[len("probe_"):] for k in ds.data_vars if k.startswith("probe_")]
    probe = args.probe if args.probe is not None else (probes[0] if probes else None)
    columns = list(grid) + ["status", "steps", "wall_time", "newton_per_step", "max_energy_balance_error"]
    table = ds[columns].reset_coords().drop_vars([k for k in ds.coords if k not in columns], errors="ignore")
    table = table.to_dataframe().reset_index(drop=True)
    files = {"store": store, "summary_csv": out / "summary.csv"}
    if probe is not None:
        try:
            ext = probe_extremes(ds, probe)
        except ValueError as exc:
            raise UsageError(f"--probe: {one_line(exc)}") from None
        comps = ext.values.reshape(ds.sizes["case"], -1)
        for c in range(comps.shape[1]):
            table[f"{probe} extreme" + (f"[{c}]" if comps.shape[1] > 1 else "")] = comps[:, c]
        files["plot"] = out / f"extremes_{probe}.png"
        plot_sweep_extremes(comps, {k: ds[k].values for k in grid}, files["plot"],
                            title=f"{args.scene}: extreme of probe {probe!r}")
    table["message"] = ds["message"].values
    table.to_csv(files["summary_csv"], index=False)
    status = ds["status"].values
    report = {"scene": args.scene, "cases": int(ds.sizes["case"]), "computed": int(ds.attrs["computed"]),
              "skipped": int(ds.attrs["skipped"]), "wall_time_s": wall,
              "status": {k: int((status == k).sum()) for k in dict.fromkeys(status.tolist())},
              "outputs": {k: str(v) for k, v in files.items()}}
    write_text_atomically(out / "sweep.json", json.dumps(jsonable(report), indent=2) + "\n")
    if not args.quiet:
        import pandas as pd
        with pd.option_context("display.width", 200, "display.max_columns", 30, "display.max_colwidth", 60):
            print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
        print(f"{report['cases']} cases: {report['computed']} computed, {report['skipped']} read from the store, "
              f"in {wall:.1f} s; outputs in {out.resolve()}/ ({store.name}, summary.csv, sweep.json"
              + (f", {files['plot'].name})" if "plot" in files else ")"))
    bad = int((status != "completed").sum())
    if bad:
        print(f"skfem-flex: {bad} of {len(status)} cases did not complete (status and message in "
              f"{files['summary_csv']})", file=sys.stderr)
        return 1
    return 0


def add_sweep(sub):
    """Add the ``sweep`` subcommand to the subparsers ``sub``."""
    from ...schemes import SCHEMES as INTEGRATORS

    p = sub.add_parser("sweep", help="run a scene over a parameter grid on Dask; results as an xarray/Zarr store",
                       description="Run a catalogue scene for every combination of the --vary values, one Dask "
                                   "task per case (a local cluster of worker processes, or --scheduler). Writes "
                                   "the store (DIR/sweep or DIR/sweep.zarr; open with skfem_flex.open_sweep or xarray), "
                                   "summary.csv, sweep.json and a PNG of a probe's extreme against the varied "
                                   "parameters into --out. Cases already in the store are not run again "
                                   "(--no-resume recomputes them).")
    p.add_argument("scene", metavar="SCENE", help="scene name from 'skfem-flex list'")
    p.add_argument("--vary", action="append", default=[], metavar="KEY=VALUES",
                   help="a scene parameter (or t_end, dt, integrator) and its values: a comma list or "
                        "START:STOP:COUNT (repeatable: a grid)")
    p.add_argument("--set", action="extend", nargs="+", metavar="KEY=VALUE", default=[],
                   help="a scene parameter fixed for every case (repeatable)")
    p.add_argument("--t-end", type=number, default=None, metavar="T", help="end time, s (default: the scene's)")
    p.add_argument("--dt", type=number, default=None, metavar="DT", help="time step, s (default: the scene's)")
    p.add_argument("--integrator", choices=sorted(INTEGRATORS), default="energy-momentum",
                   help="time integrator (default: energy-momentum)")
    p.add_argument("--rho-inf", type=number, default=None, metavar="R",
                   help="spectral radius of generalized-alpha (default 0.9)")
    p.add_argument("--record-every", type=positive_int, default=1, metavar="N",
                   help="store every N-th step (default 1)")
    _add_where_options(p, workers_default="default: one per core")
    p.add_argument("--format", choices=["netcdf", "zarr"], default="netcdf",
                   help="store layout: one netCDF file per case in DIR/sweep (default) or a Zarr hierarchy "
                        "DIR/sweep.zarr")
    p.add_argument("--probe", default=None, metavar="NAME", help="probe whose extreme is plotted (default: the first)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/sweep-SCENE)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no table")
    p.set_defaults(func=_cmd_sweep)



# --------------------------------------------------------------------- study
def _cmd_study(args):
    from .. import studies
    from ..sweep import connect

    out = Path(args.out or f"results/study-{args.kind}")
    prepare_out(out)
    say = (lambda line: None) if args.quiet else (lambda line: print(line, file=sys.stderr))
    if args.kind == "work-precision":
        names = [args.scene] if args.scene else sorted(studies.WORK_PRECISION_CASES)
        for name in names:
            if name not in studies.WORK_PRECISION_CASES:
                raise UsageError(f"no work-precision case {name!r}; known: "
                                 f"{', '.join(sorted(studies.WORK_PRECISION_CASES))}")
    elif args.scene:
        raise UsageError("'study stability' takes no SCENE; choose cases with --cases")
    client, n_workers = _where(args, default="serial")
    computed = skipped = 0
    try:
        # one cluster (or none: "serial") for all the study's sweeps
        with connect(client, n_workers) as where:
            run = {"store": args.store, "client": where, "resume": args.resume}
            if args.kind == "work-precision":
                rows = []
                for name in names:
                    case = studies.WORK_PRECISION_CASES[name]()
                    dts = case.dts[:2] if args.quick else case.dts
                    part = studies.work_precision(case, schemes=args.schemes, dts=dts, out_dir=out, name=name,
                                                  progress=say, peer=not args.no_peer, **run)
                    rows += part
                    computed, skipped = computed + part.computed, skipped + part.skipped
                stem = out / "work_precision"
                figure = studies.plot_work_precision(rows, stem.with_suffix(".png"))
            else:
                rows = studies.stability(cases=args.cases, schemes=args.schemes, progress=say, quick=args.quick,
                                         budget=args.budget, **run)
                computed, skipped = rows.computed, rows.skipped
                stem = out / "stability"
                figure = studies.plot_stability(rows, stem.with_suffix(".png"))
    except ValueError as exc:
        raise UsageError(one_line(str(exc))) from None
    csv_path, md_path = studies.write_table(rows, stem)
    if not args.quiet:
        print(md_path.read_text())
        print(f"{len(rows)} runs: {computed} computed, {skipped} read from the store"
              + (f" {args.store}" if args.store is not None else ""))
        print(f"wrote {md_path}, {csv_path} and {figure}")
    return 0


def add_study(sub):
    """Add the ``study`` subcommand to the subparsers ``sub``."""
    from .. import studies
    from ...schemes import SCHEMES as INTEGRATORS

    p = sub.add_parser("study", help="work-precision or stability study: Markdown, CSV and PNG into --out",
                       description="Run a study over the catalogue scenes and write its table as Markdown "
                                   "and CSV plus a PNG plot into --out.")
    p.add_argument("kind", choices=["work-precision", "stability"], help="which study")
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help=f"work-precision: one case (default: all): {', '.join(studies.WORK_PRECISION_CASES)}")
    p.add_argument("--schemes", nargs="+", choices=sorted(INTEGRATORS), default=list(INTEGRATORS),
                   help="integrators to compare (default: all)")
    p.add_argument("--cases", nargs="+", default=None, metavar="CASE",
                   help=f"stability: case names (default: all): {', '.join(studies.STABILITY_CASES)}")
    p.add_argument("--quick", action="store_true",
                   help=f"short runs, a smoke test of the study (at most {studies.QUICK_STEPS} steps and "
                        f"{studies.QUICK_BUDGET:g} s each)")
    p.add_argument("--no-peer", action="store_true",
                   help="work-precision: leave out the exudyn rows (by default, with exudyn installed, its models "
                        "of flexible_pendulum and spin_up_beam run at the same steps against the same reference)")
    p.add_argument("--budget", type=positive_number, default=300.0, metavar="S",
                   help="stability: wall-clock seconds per run before it is stopped and reported (default 300)")
    _add_where_options(p, workers_default="default: run the cases one after another in this process, so that "
                                          "their wall times do not disturb each other")
    p.add_argument("--store", type=Path, default=None, metavar="DIR",
                   help="sweep store of the runs (one netCDF file per run; a Zarr hierarchy if DIR ends in "
                        ".zarr): a rerun reads the runs already there, timings included (default: no store)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/study-KIND)")
    p.add_argument("--quiet", action="store_true", help="no progress lines and no table on stdout")
    p.set_defaults(func=_cmd_study)
