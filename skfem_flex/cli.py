"""The ``skfem-flex`` command.

::

    skfem-flex run [SCENE] [--set key=value ...] [--t-end T] [--dt DT]
                   [--integrator NAME] [--rho-inf R] [--out DIR] [--every N]
                   [--no-vtk] [--quiet]
    skfem-flex list
    skfem-flex study work-precision [CASE] [--schemes ...] [--quick] [--out DIR]
    skfem-flex study stability [--cases ...] [--schemes ...] [--quick] [--out DIR]
    skfem-flex modes SCENE [--set key=value ...] [--n N] [--about static|steady|initial]
                     [--out DIR] [--frames F] [--no-vtk] [--quiet]
    skfem-flex campbell SCENE --vary NAME=VALUES [--set ...] [--n N] [--about ...] [--out DIR]
    skfem-flex sweep SCENE --vary KEY=VALUES [--vary ...] [--set key=value ...]
                     [--t-end T] [--dt DT] [--integrator NAME] [--workers N | --scheduler ADDRESS]
                     [--resume | --no-resume] [--format netcdf|zarr] [--probe NAME] [--out DIR]

``run`` builds a catalogue scene (default :data:`DEFAULT_SCENE`), integrates
it and writes into DIR (default ``results/SCENE``): the VTK time series
(``SCENE.pvd``, ``SCENE.vtu.series``, ``SCENE_NNNNNN.vtu``), ``summary.json``,
``result.npz`` (:meth:`skfem_flex.Result.load`), ``probes.csv`` and PNG plots.

``sweep`` runs a scene over a grid of parameters as Dask tasks
(:func:`skfem_flex.sweep.sweep`) and writes into DIR (default
``results/sweep-SCENE``) the store ``sweep/`` (netCDF per case; ``sweep.zarr``
with ``--format zarr``), ``summary.csv``,
``sweep.json`` (counts of computed and skipped cases) and
``extremes_PROBE.png``; exit status 1 when a case did not complete.

Exit status: 0 on success, 2 on bad input (unknown scene or parameter, a
value of the wrong type, dt ≤ 0, an unwritable output directory; one line on
stderr, no traceback), 1 when the run stops early (Newton failure): the
outputs written up to the last good step are kept and the summary says why.

The parser is built from subcommands (:data:`SUBCOMMANDS`).
"""
from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import sys
import time
from pathlib import Path

__all__ = ["main", "build_parser", "UsageError", "convert_setting", "DEFAULT_SCENE", "SUBCOMMANDS"]

#: scene run by ``skfem-flex run`` without a SCENE argument
DEFAULT_SCENE = "spin_up_beam"
#: end time and step (s) for scenes that register no defaults of their own
FALLBACK_T_END, FALLBACK_DT = 1.0, 0.01
#: without --every, VTK output is thinned to at most about this many files
MAX_FRAMES = 200


class UsageError(Exception):
    """Bad command-line input: reported in one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse parser whose errors are one line (raised as UsageError, reported by :func:`main`)."""

    def error(self, message):
        raise UsageError(f"{message} (see '{self.prog} --help')")


def _positive_int(text):
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return n


def _number(text):
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


# --------------------------------------------------------------------- settings
_TRUE = {"1", "true", "yes", "on", "y", "t"}
_FALSE = {"0", "false", "no", "off", "n", "f"}


def convert_setting(key, text, default):
    """Convert ``text`` to the type of the parameter's ``default`` (bool, int, float or str).

    A parameter without a default (or with default None) takes an int, a
    float or, failing both, the string.

    Raises
    ------
    UsageError
        Naming the parameter and the value.
    """
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in _TRUE:
            return True
        if low in _FALSE:
            return False
        raise UsageError(f"--set {key}={text}: {key} is a yes/no parameter (true/false, 1/0), got {text!r}")
    if isinstance(default, int):
        try:
            return int(text)
        except ValueError:
            pass
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        if math.isfinite(x) and x == int(x):
            return int(x)
        raise UsageError(f"--set {key}={text}: {key} needs an integer, got {text!r}")
    if isinstance(default, float):
        try:
            x = float(text)
        except ValueError:
            raise UsageError(f"--set {key}={text}: {key} needs a number, got {text!r}") from None
        if not math.isfinite(x):
            raise UsageError(f"--set {key}={text}: {key} needs a finite number, got {text!r}")
        return x
    if isinstance(default, str):
        return text
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _scene_settings(name, items):
    """{parameter: value} from ``--set`` items, converted with the defaults' types."""
    from . import scenes

    params = {p: d for p, d, _ in scenes.parameters(name)}
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"--set expects key=value, got {item!r} (give the scene name before --set)")
        if key not in params:
            raise UsageError(f"scene {name!r} has no parameter {key!r}; it has: {', '.join(params) or 'none'}")
        default = params[key]
        out[key] = convert_setting(key, text, None if default is inspect.Parameter.empty else default)
    missing = [p for p, d in params.items() if d is inspect.Parameter.empty and p not in out]
    if missing:
        raise UsageError(f"scene {name!r} needs --set {missing[0]}=VALUE")
    return out


# ------------------------------------------------------------------- helpers
def _one_line(text):
    return " ".join(str(text).split())


def _jsonable(x):
    """x with numpy scalars/arrays made plain and non-finite floats made strings (strict JSON)."""
    import numpy as np

    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, (bool, int, float, str)) or x is None:
        return x
    return str(x)


def _prepare_out(out):
    """Create the output directory and check that it is writable (UsageError otherwise)."""
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is a file, not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".skfem-flex-write-test-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"cannot write to --out {str(out)!r}: {exc.strerror or exc}") from None


def _summary(name, scene, params, args, t_end, dt, result, error, files, wall):
    import numpy as np

    s = {"scene": name, "parameters": dict(scene.parameters) if scene.parameters else params,
         "integrator": args.integrator, "t_end": t_end, "dt": dt,
         "bodies": [getattr(b, "name", f"body{i}") for i, b in enumerate(scene.bodies)],
         "completed": error is None, "error": error, "wall_time_s": wall}
    if result is not None and len(result.t):
        its = np.asarray(result.newton_iterations)
        steps = int(result.steps)
        bal = np.abs(result.energy_balance_error)
        s.update({
            "steps": steps, "t_reached": float(result.t[-1]), "simulation_time_s": float(result.wall_time),
            "energy": {"initial_J": float(result.total_energy[0]), "final_J": float(result.total_energy[-1]),
                       "external_work_J": float(result.external_work[-1]),
                       "max_balance_error_J": float(bal.max()),
                       "relative_balance_error": result.relative_energy_error()},
            "max_constraint_residual": float(np.max(result.constraint_residual)),
            "max_velocity_constraint_residual": float(np.max(result.velocity_constraint_residual)),
            "newton": {"total_iterations": int(its.sum()),
                       "mean_iterations_per_step": float(its.sum() / steps) if steps else 0.0,
                       "max_iterations_per_recorded_step": int(its.max()) if its.size else 0,
                       "halved_steps": int(result.halvings)},
        })
    s["outputs"] = {k: (str(v) if not isinstance(v, (list, int)) else v) for k, v in files.items()}
    return _jsonable(s)


# ----------------------------------------------------------------------- run
def _cmd_run(args):
    from . import scenes
    from .integrators import SimulationError
    from .output import VTKSeries, _atomic_write_text
    from .simulate import simulate

    name = args.scene if args.scene is not None else DEFAULT_SCENE
    if name not in scenes.CATALOGUE:
        known = ", ".join(sorted(scenes.CATALOGUE))
        if args.scene is None:
            raise UsageError(f"the default scene {DEFAULT_SCENE!r} is not in this catalogue; name one of: {known}")
        raise UsageError(f"unknown scene {name!r}; known scenes: {known}")
    factory = scenes.get(name)
    params = _scene_settings(name, args.set)
    defaults = getattr(factory, "defaults", {}) or {}
    t_end = args.t_end if args.t_end is not None else defaults.get("t_end", FALLBACK_T_END)
    dt = args.dt if args.dt is not None else defaults.get("dt", FALLBACK_DT)
    if not math.isfinite(dt) or dt <= 0:
        raise UsageError(f"--dt must be a positive number of seconds, got {dt!r}")
    if not math.isfinite(t_end) or t_end < 0:
        raise UsageError(f"--t-end must be a non-negative number of seconds, got {t_end!r}")
    out = Path(args.out) if args.out is not None else Path("results") / name
    try:
        scene = factory(**params)
    except (ValueError, TypeError) as exc:
        raise UsageError(f"scene {name!r}: {_one_line(exc)}") from None
    _prepare_out(out)
    effective = {p: d for p, d, _ in scenes.parameters(name)}
    effective.update(params)

    n_steps = int(math.ceil(t_end / dt - 1e-9)) if t_end > 0 else 0
    every = args.every if args.every is not None else max(1, math.ceil(n_steps / MAX_FRAMES))
    sinks = [] if args.no_vtk else [VTKSeries(out, name, every=every)]
    error, result = None, None
    start = time.perf_counter()
    try:
        result = simulate(scene, t_end, dt, integrator=args.integrator, rho_inf=args.rho_inf, output=sinks,
                          progress=not args.quiet)
    except SimulationError as exc:
        result, error = exc.result, _one_line(exc)
    except ValueError as exc:
        raise UsageError(_one_line(exc)) from None
    wall = time.perf_counter() - start

    files = {}
    if sinks and sinks[0].written:
        files.update(pvd=sinks[0].pvd_path, series=sinks[0].series_path, vtu_files=len(sinks[0].written))
    if result is not None and len(result.t):
        files["result"] = result.save(out / "result.npz")
        if result.probes:
            files["probes_csv"] = result.probes_to_csv(out / "probes.csv")
        from .plots import save_plots
        for k, p in save_plots(scene, result, out).items():
            files[f"plot_{k}"] = p
    files["summary"] = out / "summary.json"
    summary = _summary(name, scene, effective, args, t_end, dt, result, error, files, wall)
    _atomic_write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")

    if error is not None:
        print(f"skfem-flex: run stopped early: {error}; outputs up to the last good step are in {out}",
              file=sys.stderr)
        return 1
    if not args.quiet:
        _report(name, summary, files, out)
    return 0


def _report(name, summary, files, out):
    e = summary.get("energy", {})
    nw = summary.get("newton", {})
    print(f"{name}: {summary.get('steps', 0)} steps of {summary['dt']:.4g} s to t = {summary['t_end']:.4g} s "
          f"with {summary['integrator']} in {summary['wall_time_s']:.2f} s")
    print(f"  energy balance error {e.get('max_balance_error_J', 0.0):.3g} J "
          f"(relative {e.get('relative_balance_error', 0.0):.3g}), "
          f"max |constraint| {summary.get('max_constraint_residual', 0.0):.3g}, "
          f"Newton {nw.get('mean_iterations_per_step', 0.0):.2f} iterations/step")
    print(f"outputs in {out.resolve()}/")
    if "pvd" in files:
        print(f"  {Path(files['pvd']).name:<22} VTK time series, {files['vtu_files']} steps "
              f"(open in ParaView; also {Path(files['series']).name})")
    print(f"  {'summary.json':<22} run summary")
    if "result" in files:
        print(f"  {'result.npz':<22} all histories (skfem_flex.Result.load)")
    if "probes_csv" in files:
        print(f"  {'probes.csv':<22} probe histories")
    plots = [Path(v).name for k, v in files.items() if k.startswith("plot_")]
    if plots:
        print(f"  {' '.join(plots)}")


def _add_run(sub):
    from .integrators import INTEGRATORS

    p = sub.add_parser("run", help="run a catalogue scene and write VTK series, plots and a summary",
                       description="Run a catalogue scene; write the VTK time series (.vtu + .pvd), "
                                   "PNG plots, result.npz, probes.csv and summary.json into --out.")
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help=f"scene name from 'skfem-flex list' (default: {DEFAULT_SCENE})")
    p.add_argument("--set", action="extend", nargs="+", metavar="KEY=VALUE", default=[],
                   help="scene parameter, converted to the type of its default (repeatable)")
    p.add_argument("--t-end", type=_number, default=None, metavar="T",
                   help=f"end time, s (default: the scene's, else {FALLBACK_T_END:g})")
    p.add_argument("--dt", type=_number, default=None, metavar="DT",
                   help=f"time step, s (default: the scene's, else {FALLBACK_DT:g})")
    p.add_argument("--integrator", choices=sorted(INTEGRATORS), default="energy-momentum",
                   help="time integrator (default: energy-momentum)")
    p.add_argument("--rho-inf", type=_number, default=None, metavar="R",
                   help="spectral radius of generalized-alpha (default 0.9)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/SCENE)")
    p.add_argument("--every", type=_positive_int, default=None, metavar="N",
                   help=f"write a VTK file every N steps (default: at most about {MAX_FRAMES} files)")
    p.add_argument("--no-vtk", action="store_true", help="skip the VTK series")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.set_defaults(func=_cmd_run)


# ---------------------------------------------------------------------- list
def _cmd_list(args):
    from . import scenes

    for name in sorted(scenes.CATALOGUE):
        fn = scenes.get(name)
        doc = (inspect.getdoc(fn) or "").strip().splitlines()
        d = getattr(fn, "defaults", {}) or {}
        run = (f"t_end {d.get('t_end', FALLBACK_T_END):g} s, dt {d.get('dt', FALLBACK_DT):g} s"
               + ("" if d else " (generic)"))
        print(f"{name}{'  (default)' if name == DEFAULT_SCENE else ''}")
        if doc:
            print(f"    {doc[0]}")
        print(f"    run: {run}")
        for p, default, unit in scenes.parameters(name):
            shown = "(required)" if default is inspect.Parameter.empty else repr(default)
            print(f"    {p:<16} = {shown:<12} {unit}")
    return 0


def _add_list(sub):
    p = sub.add_parser("list", help="list the scenes with their parameters, defaults and units",
                       description="List the catalogue scenes with their parameters, defaults and units.")
    p.set_defaults(func=_cmd_list)


# --------------------------------------------------------------------- study
def _cmd_study(args):
    from . import studies

    out = Path(args.out or f"results/study-{args.kind}")
    _prepare_out(out)
    say = (lambda line: None) if args.quiet else (lambda line: print(line, file=sys.stderr))
    try:
        if args.kind == "work-precision":
            names = [args.scene] if args.scene else sorted(studies.WORK_PRECISION_CASES)
            rows = []
            for name in names:
                if name not in studies.WORK_PRECISION_CASES:
                    raise UsageError(f"no work-precision case {name!r}; known: "
                                     f"{', '.join(sorted(studies.WORK_PRECISION_CASES))}")
                case = studies.WORK_PRECISION_CASES[name]()
                dts = case.dts[:2] if args.quick else case.dts
                rows += studies.work_precision(case, schemes=args.schemes, dts=dts, out_dir=out, name=name,
                                               progress=say)
            stem = out / "work_precision"
            figure = studies.plot_work_precision(rows, stem.with_suffix(".png"))
        else:
            if args.scene:
                raise UsageError("'study stability' takes no SCENE; choose cases with --cases")
            rows = studies.stability(cases=args.cases, schemes=args.schemes, progress=say, quick=args.quick,
                                     budget=args.budget)
            stem = out / "stability"
            figure = studies.plot_stability(rows, stem.with_suffix(".png"))
    except ValueError as exc:
        raise UsageError(_one_line(str(exc))) from None
    csv_path, md_path = studies.write_table(rows, stem)
    if not args.quiet:
        print(md_path.read_text())
        print(f"wrote {md_path}, {csv_path} and {figure}")
    return 0


def _add_study(sub):
    from .integrators import INTEGRATORS

    p = sub.add_parser("study", help="work-precision or stability study: Markdown, CSV and PNG into --out",
                       description="Run a study over the catalogue scenes and write its table as Markdown "
                                   "and CSV plus a PNG plot into --out.")
    p.add_argument("kind", choices=["work-precision", "stability"], help="which study")
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help="work-precision: one case (default: all cases)")
    p.add_argument("--schemes", nargs="+", choices=sorted(INTEGRATORS), default=list(INTEGRATORS),
                   help="integrators to compare (default: all)")
    p.add_argument("--cases", nargs="+", default=None, metavar="CASE", help="stability: case names (default: all)")
    p.add_argument("--quick", action="store_true", help="short runs (a smoke test of the study)")
    p.add_argument("--budget", type=_number, default=300.0, metavar="S",
                   help="stability: wall-clock seconds per run before it is stopped and reported (default 300)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/study-KIND)")
    p.add_argument("--quiet", action="store_true", help="no progress lines and no table on stdout")
    p.set_defaults(func=_cmd_study)


# --------------------------------------------------------------- modes, campbell
def _catalogue_scene(name):
    from . import scenes

    if name not in scenes.CATALOGUE:
        raise UsageError(f"unknown scene {name!r}; known scenes: {', '.join(sorted(scenes.CATALOGUE))}")
    return scenes.get(name)


def _analysis(name, compute):
    """``compute()``; bad input becomes a UsageError (exit 2), an equilibrium that cannot be found
    (a SimulationError) is reported in one line and gives None (exit 1)."""
    from .errors import SimulationError

    try:
        return compute()
    except SimulationError as exc:
        print(f"skfem-flex: error: {_one_line(exc)}", file=sys.stderr)
        return None
    except (ValueError, TypeError) as exc:
        raise UsageError(f"scene {name!r}: {_one_line(exc)}") from None


def _cmd_modes(args):
    from .analysis import modes, write_mode_series
    from .output import _atomic_write_text

    factory = _catalogue_scene(args.scene)
    params = _scene_settings(args.scene, args.set)
    out = Path(args.out) if args.out is not None else Path("results") / f"{args.scene}-modes"
    scene = _analysis(args.scene, lambda: factory(**params))
    result = None if scene is None else _analysis(args.scene, lambda: modes(scene, about=args.about,
                                                                          n_modes=args.n))
    if result is None:
        return 1
    _prepare_out(out)
    rows = result.table()
    lines = ["mode,omega_rad_s,frequency_hz,damping_ratio,growth_rate_1_s"]
    lines += [f"{r['mode']},{r['omega_rad_s']!r},{r['frequency_hz']!r},{r['damping_ratio']!r},"
              f"{r['growth_rate_1_s']!r}" for r in rows]
    _atomic_write_text(out / "modes.csv", "\n".join(lines) + "\n")
    pvds = [] if args.no_vtk else write_mode_series(scene, result, out, frames=args.frames)
    summary = {"scene": args.scene, "parameters": dict(scene.parameters) or params, "about": result.about,
               "modes": rows, "stable": result.stable, "vtk": [str(p) for p in pvds]}
    _atomic_write_text(out / "summary.json", json.dumps(_jsonable(summary), indent=2) + "\n")
    if not args.quiet:
        print(f"{args.scene}: {len(rows)} modes about the {result.about} state"
              f"{'' if result.stable else ' (UNSTABLE: a mode grows)'}")
        print(f"{'mode':>4} {'omega (rad/s)':>15} {'f (Hz)':>13} {'damping ratio':>14} {'growth (1/s)':>13}")
        for r in rows:
            print(f"{r['mode']:>4} {r['omega_rad_s']:>15.8g} {r['frequency_hz']:>13.8g} "
                  f"{r['damping_ratio']:>14.4g} {r['growth_rate_1_s']:>13.4g}")
        print(f"outputs in {out.resolve()}/: modes.csv, summary.json"
              + (f", {len(pvds)} VTK series (one .pvd per mode, a cycle from t = 0 to 1)" if pvds else ""))
    return 0


def _vary_values(key, text, default):
    """Values of ``--vary NAME=VALUES``: a comma list, or START:STOP:COUNT (evenly spaced)."""
    import numpy as np

    if not text:
        raise UsageError(f"--vary {key}= needs values: a comma list (0,4,8) or START:STOP:COUNT")
    if text.count(":") == 2:
        a, b, c = text.split(":")
        lo, hi = convert_setting(key, a, 0.0), convert_setting(key, b, 0.0)
        count = convert_setting(key, c, 0)
        if count < 1:
            raise UsageError(f"--vary {key}={text}: COUNT must be a positive integer")
        return [float(x) for x in np.linspace(lo, hi, count)]
    return [convert_setting(key, item, 0.0 if default is None else default) for item in text.split(",")]


def _cmd_campbell(args):
    import inspect as _inspect

    from .analysis import campbell
    from . import scenes

    _catalogue_scene(args.scene)
    params = _scene_settings(args.scene, args.set)
    key, sep, text = args.vary.partition("=")
    key = key.strip()
    known = {p: d for p, d, _ in scenes.parameters(args.scene)}
    if not sep or not key:
        raise UsageError(f"--vary expects NAME=VALUES, got {args.vary!r}")
    if key not in known:
        raise UsageError(f"scene {args.scene!r} has no parameter {key!r}; it has: {', '.join(known) or 'none'}")
    default = None if known[key] is _inspect.Parameter.empty else known[key]
    if isinstance(default, (bool, str)):
        raise UsageError(f"--vary {key}: only numeric parameters can be varied, {key} is {type(default).__name__}")
    values = _vary_values(key, text.strip(), default)
    params.pop(key, None)
    out = Path(args.out) if args.out is not None else Path("results") / f"{args.scene}-campbell"
    diagram = _analysis(args.scene, lambda: campbell(args.scene, key, values, n_modes=args.n, about=args.about,
                                                     **params))
    if diagram is None:
        return 1
    _prepare_out(out)
    csv_path, md_path = diagram.write_table(out / "campbell")
    png = out / "campbell.png"
    diagram.plot(png)
    if not args.quiet:
        print(md_path.read_text(), end="")
        print(f"wrote {md_path}, {csv_path} and {png}")
    return 0


def _add_analysis_options(p, about_default):
    p.add_argument("scene", metavar="SCENE", help="scene name from 'skfem-flex list'")
    p.add_argument("--set", action="extend", nargs="+", metavar="KEY=VALUE", default=[],
                   help="scene parameter, converted to the type of its default (repeatable)")
    p.add_argument("--n", type=_positive_int, default=6, metavar="N", help="number of modes (default 6)")
    p.add_argument("--about", choices=["static", "steady", "initial"], default=about_default,
                   help=f"state to linearize about (default: {about_default})")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory")
    p.add_argument("--quiet", action="store_true", help="no table on stdout")


def _add_modes(sub):
    p = sub.add_parser("modes", help="modes of a scene about its static, steady or initial state",
                       description="Linearize a catalogue scene about its static equilibrium, its steady "
                                   "motion or its initial state and write the lowest modes (modes.csv, "
                                   "summary.json) and one VTK series per mode animating it (default "
                                   "results/SCENE-modes).")
    _add_analysis_options(p, "static")
    p.add_argument("--frames", type=_positive_int, default=24, metavar="F",
                   help="frames per cycle of each mode's VTK series (default 24)")
    p.add_argument("--no-vtk", action="store_true", help="skip the VTK series")
    p.set_defaults(func=_cmd_modes)


def _add_campbell(sub):
    p = sub.add_parser("campbell", help="Campbell diagram: frequencies against a scene parameter",
                       description="Frequencies of a catalogue scene against one parameter, each point "
                                   "linearized about its own steady (or static/initial) state; writes "
                                   "campbell.csv, campbell.md and campbell.png (default results/SCENE-campbell).")
    _add_analysis_options(p, "steady")
    p.add_argument("--vary", required=True, metavar="NAME=VALUES",
                   help="parameter and its values: a comma list (0,4,8) or START:STOP:COUNT")
    p.set_defaults(func=_cmd_campbell)


# --------------------------------------------------------------------- sweep
def _sweep_grid(name, items):
    """{name: [values]} from ``--vary KEY=VALUES`` (as for ``campbell``: a comma list or START:STOP:COUNT),
    converted to the type of the parameter's default; ``t_end``, ``dt`` and ``integrator`` may be varied too."""
    from . import scenes
    from .sweep import RUN_SETTINGS

    params = {p: d for p, d, _ in scenes.parameters(name)}
    run_defaults = {"t_end": 0.0, "dt": 0.0, "integrator": ""}     # only their types matter
    grid = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"--vary expects KEY=VALUES, got {item!r}")
        if key in grid:
            raise UsageError(f"--vary {key} is given twice")
        # unknown names pass as text: the sweep's plan reports them, in the same words as for the API
        default = params.get(key, run_defaults[key] if key in RUN_SETTINGS else "")
        try:
            grid[key] = _vary_values(key, text.strip(), None if default is inspect.Parameter.empty else default)
        except UsageError as exc:
            raise UsageError(str(exc).replace(f"--set {key}=", f"--vary {key}=", 1)) from None
    return grid


def _cmd_sweep(args):
    from . import scenes
    from .plots import plot_sweep_extremes
    from .output import _atomic_write_text
    from .sweep import plan, probe_extremes, run_cases

    if args.scene not in scenes.CATALOGUE:
        raise UsageError(f"unknown scene {args.scene!r}; known scenes: {', '.join(sorted(scenes.CATALOGUE))}")
    if not args.vary:
        raise UsageError("give at least one --vary key=value1,value2,...")
    grid = _sweep_grid(args.scene, args.vary)
    fixed = _scene_settings(args.scene, args.set) if args.set else {}
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
        raise UsageError(_one_line(exc)) from None
    out = Path(args.out) if args.out is not None else Path("results") / f"sweep-{args.scene}"
    _prepare_out(out)
    client = args.scheduler if args.scheduler else None
    start = time.perf_counter()
    store = out / ("sweep.zarr" if args.format == "zarr" else "sweep")
    ds = run_cases(specs, store=store, client=client, resume=args.resume, n_workers=args.workers,
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
            raise UsageError(f"--probe: {_one_line(exc)}") from None
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
    _atomic_write_text(out / "sweep.json", json.dumps(_jsonable(report), indent=2) + "\n")
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


def _add_sweep(sub):
    from .integrators import INTEGRATORS

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
    p.add_argument("--t-end", type=_number, default=None, metavar="T", help="end time, s (default: the scene's)")
    p.add_argument("--dt", type=_number, default=None, metavar="DT", help="time step, s (default: the scene's)")
    p.add_argument("--integrator", choices=sorted(INTEGRATORS), default="energy-momentum",
                   help="time integrator (default: energy-momentum)")
    p.add_argument("--rho-inf", type=_number, default=None, metavar="R",
                   help="spectral radius of generalized-alpha (default 0.9)")
    p.add_argument("--record-every", type=_positive_int, default=1, metavar="N",
                   help="store every N-th step (default 1)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                       help="worker processes of the local Dask cluster (default: one per core)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="address of a running Dask scheduler (e.g. tcp://host:8786) to run the cases on")
    p.add_argument("--resume", action=argparse.BooleanOptionalAction, default=True,
                   help="skip cases already in the store (default); --no-resume recomputes them")
    p.add_argument("--format", choices=["netcdf", "zarr"], default="netcdf",
                   help="store layout: one netCDF file per case in DIR/sweep (default) or a Zarr hierarchy "
                        "DIR/sweep.zarr")
    p.add_argument("--probe", default=None, metavar="NAME", help="probe whose extreme is plotted (default: the first)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/sweep-SCENE)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no table")
    p.set_defaults(func=_cmd_sweep)


#: functions adding one subcommand each to the subparsers
SUBCOMMANDS = [_add_run, _add_list, _add_study, _add_modes, _add_campbell, _add_sweep]


def build_parser():
    """The argparse parser of ``skfem-flex`` with one subparser per entry of :data:`SUBCOMMANDS`."""
    from . import __version__

    parser = _Parser(prog="skfem-flex",
                     description="Planar flexible multibody dynamics on scikit-fem: run catalogue scenes "
                                 "and write VTK time series, plots and summaries.")
    parser.add_argument("--version", action="version", version=f"skfem-flex {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def main(argv=None):
    """Entry point of the ``skfem-flex`` console script; returns the exit status."""
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help(sys.stderr)
            return 2
        return args.func(args)
    except UsageError as exc:
        print(f"skfem-flex: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skfem-flex: interrupted; outputs written so far are kept", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
