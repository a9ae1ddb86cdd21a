"""The ``skfem-flex`` command.

::

    skfem-flex run [SCENE] [--set key=value ...] [--t-end T] [--dt DT]
                   [--integrator NAME] [--rho-inf R] [--out DIR] [--every N]
                   [--no-vtk] [--quiet]
    skfem-flex list
    skfem-flex study work-precision [CASE] [--schemes ...] [--quick] [--no-peer] [--out DIR]
                     [--workers N | --scheduler ADDRESS] [--store DIR] [--resume | --no-resume]
    skfem-flex study stability [--cases ...] [--schemes ...] [--quick] [--out DIR]
                     [--workers N | --scheduler ADDRESS] [--store DIR] [--resume | --no-resume]
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
(:func:`skfem_flex.apps.sweep.sweep`) and writes into DIR (default
``results/sweep-SCENE``) the store ``sweep/`` (netCDF per case; ``sweep.zarr``
with ``--format zarr``), ``summary.csv``,
``sweep.json`` (counts of computed and skipped cases) and
``extremes_PROBE.png``; exit status 1 when a case did not complete.

``study`` runs its cases one after another in this process by default (their
wall times are what the work-precision study measures); ``--workers N`` or
``--scheduler ADDRESS`` spread them over a Dask cluster as ``sweep`` does, and
with ``--store DIR`` a rerun reads the runs already in that sweep store
instead of running them again (``--no-resume`` recomputes them).

Exit status: 0 on success; 2 on bad input (unknown scene or parameter, a
value of the wrong type, dt ≤ 0, an unwritable output directory, a run that
cannot fit in memory; one line on stderr, no traceback); 1 when the run stops
early (Newton failure) or an output cannot be written (disk full); 3 when the
run diverged ("diverged at t = …"); 130 after Ctrl-C and 143 after SIGTERM,
which finish the current step first. In every case the outputs up to the last
good step are kept (``result.npz``, ``probes.csv``, ``summary.json`` with
``"completed": false`` and ``"stopped"`` saying why). During the run the
histories are checkpointed every few seconds into ``checkpoint.npz``
(:meth:`skfem_flex.Result.load` reads it after a SIGKILL), and
``skfem-flex run --resume DIR`` continues an interrupted or killed run.

The parser is built from subcommands (:data:`SUBCOMMANDS`).
"""
from __future__ import annotations

import argparse
import inspect
import re
import json
import math
import os
import signal
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


def _positive_number(text):
    x = _number(text)
    if not math.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return x


def _number(text):
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


# --------------------------------------------------------------------- settings
_TRUE = {"1", "true", "yes", "on", "y", "t"}
_FALSE = {"0", "false", "no", "off", "n", "f"}


def convert_setting(key, text, default, option="--set"):
    """Convert ``text`` to the type of the parameter's ``default`` (bool, int, float or str).

    A parameter without a default (or with default None) takes an int, a
    float or, failing both, the string.

    Parameters
    ----------
    key, text : str
        Parameter name and the value as typed.
    default
        The parameter's default (its type is the target type), or None.
    option : str
        The command-line option the value came with (``--set``, ``--vary``), for messages.

    Raises
    ------
    UsageError
        Naming the option, the parameter and the value.
    """
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in _TRUE:
            return True
        if low in _FALSE:
            return False
        raise UsageError(f"{option} {key}={text}: {key} is a yes/no parameter (true/false, 1/0), got {text!r}")
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
        raise UsageError(f"{option} {key}={text}: {key} needs an integer, got {text!r}")
    if isinstance(default, float):
        try:
            x = float(text)
        except ValueError:
            raise UsageError(f"{option} {key}={text}: {key} needs a number, got {text!r}") from None
        if not math.isfinite(x):
            raise UsageError(f"{option} {key}={text}: {key} needs a finite number, got {text!r}")
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
    from .. import scenes

    params = {p: d for p, d, _ in scenes.parameters(name)}
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"--set expects key=value, got {item!r} (give the scene name before --set)")
        if key not in params:
            raise UsageError(f"scene {name!r} has no parameter {key!r}; it has: {', '.join(params) or 'none'}")
        if key in out:
            raise UsageError(f"--set {key} is given twice ({key}={out[key]!r} and {item!r}); give it once")
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


def _summary(name, scene, params, integrator, rho_inf, t_end, dt, result, error, files, wall):
    import numpy as np

    s = {"scene": name, "parameters": dict(scene.parameters) if scene.parameters else params,
         "integrator": integrator, "rho_inf": rho_inf, "t_end": t_end, "dt": dt,
         "bodies": [getattr(b, "name", f"body{i}") for i, b in enumerate(scene.bodies)],
         "completed": error is None, "stopped": error or "", "error": error, "wall_time_s": wall}
    if result is not None and len(result.t):
        its = np.asarray(result.newton_iterations)
        steps = int(result.steps)
        bal = np.abs(result.energy_balance_error)
        rel = result.relative_energy_error()
        s.update({
            "steps": steps, "t_reached": float(result.t[-1]), "simulation_time_s": float(result.wall_time),
            "compile_time_s": float(result.compile_time),
            "energy": {"initial_J": float(result.total_energy[0]), "final_J": float(result.total_energy[-1]),
                       "external_work_J": float(result.external_work[-1]),
                       "max_balance_error_J": float(bal.max()),
                       "relative_balance_error": rel},
            "max_constraint_residual": float(np.max(result.constraint_residual)),
            "max_velocity_constraint_residual": float(np.max(result.velocity_constraint_residual)),
            "newton": {"total_iterations": int(its.sum()),
                       "mean_iterations_per_step": float(its.sum() / steps) if steps else 0.0,
                       "max_iterations_per_recorded_step": int(its.max()) if its.size else 0,
                       "halved_steps": int(result.halvings)},
        })
        warnings = _energy_warnings(integrator, rho_inf, rel)
        if warnings:
            s["warnings"] = warnings
    s["outputs"] = {k: (str(v) if not isinstance(v, (list, int)) else v) for k, v in files.items()}
    return _jsonable(s)


def _energy_warnings(integrator, rho_inf, relative_error):
    """A warning when a scheme meant to keep the energy balance misses it by more than ENERGY_WARNING.

    Generalized-α with ρ∞ < 1 dissipates high frequencies by design and gets none."""
    dissipative = integrator == "generalized-alpha" and (rho_inf is None or rho_inf < 1.0)
    if dissipative or not math.isfinite(relative_error) or relative_error <= ENERGY_WARNING:
        return [] if math.isfinite(relative_error) else ["the energy balance error is not finite"]
    return [f"energy balance error {100 * relative_error:.3g} % of the energy scale with {integrator} "
            f"(above {100 * ENERGY_WARNING:g} %): a smaller --dt, or the energy-momentum scheme, keeps it"]


# ----------------------------------------------------------------------- run
#: exit status of ``run`` per way of stopping (besides 0 = completed and 2 = bad input)
EXIT_STOPPED, EXIT_DIVERGED = 1, 3
#: exit status after SIGINT and SIGTERM (128 + signal number, the shell's convention)
EXIT_SIGNAL = {2: 130, 15: 143}
#: a run's settings, written when it starts, so that ``run --resume DIR`` can continue it
RUN_SETTINGS = "run.json"
#: histories checkpointed during a run (Result.load reads it after a SIGKILL)
CHECKPOINT = "checkpoint.npz"
#: seconds of wall time between checkpoints
CHECKPOINT_EVERY = 5.0
#: relative energy balance error above which a run's summary carries a warning (conservative schemes)
ENERGY_WARNING = 0.01
#: files of an earlier run in the same directory, removed when a fresh run starts there
_RUN_FILES = ("result.npz", CHECKPOINT, "summary.json", "probes.csv", RUN_SETTINGS)


class _Terminated(BaseException):
    """SIGTERM outside the time loop (the loop itself stops gracefully on it)."""


def _raise_terminated(signum, frame):
    raise _Terminated()


def _run_settings(args):
    """(name, params, t_end, dt, integrator, rho_inf, every, no_vtk, out) from the arguments, or with
    ``--resume DIR`` from DIR's run.json (explicit --t-end may extend the run)."""
    from .. import scenes

    if args.resume is not None:
        if args.resume == "":
            raise UsageError("--resume needs the output directory of the run to continue, got ''")
        out = Path(args.resume)
        try:
            saved = json.loads((out / RUN_SETTINGS).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise UsageError(f"--resume {str(out)!r}: no readable {RUN_SETTINGS} of an earlier run there "
                             f"({getattr(exc, 'strerror', None) or _one_line(exc)})") from None
        for opt, given in (("scene", args.scene), ("--set", args.set or None), ("--dt", args.dt),
                           ("--integrator", args.integrator), ("--rho-inf", args.rho_inf), ("--every", args.every)):
            if given is not None:
                raise UsageError(f"--resume continues the run with its own settings; drop {opt} "
                                 f"(only --t-end may change)")
        if args.out is not None and Path(args.out) != out:
            raise UsageError("--resume writes into the run's own directory; drop --out")
        t_end = saved["t_end"] if args.t_end is None else args.t_end
        return (saved["scene"], saved["parameters"], t_end, saved["dt"], saved["integrator"], saved["rho_inf"],
                saved["every"], saved["no_vtk"], out)
    name = args.scene if args.scene is not None else DEFAULT_SCENE
    if name not in scenes.CATALOGUE:
        known = ", ".join(sorted(scenes.CATALOGUE))
        if args.scene is None:
            raise UsageError(f"the default scene {DEFAULT_SCENE!r} is not in this catalogue; name one of: {known}")
        raise UsageError(f"unknown scene {name!r}; known scenes: {known}")
    params = _scene_settings(name, args.set)
    defaults = getattr(scenes.get(name), "defaults", {}) or {}
    t_end = args.t_end if args.t_end is not None else defaults.get("t_end", FALLBACK_T_END)
    dt = args.dt if args.dt is not None else defaults.get("dt", FALLBACK_DT)
    if args.out is not None and not args.out.strip():
        raise UsageError("--out must name a directory, got ''")
    out = Path(args.out) if args.out is not None else Path("results") / name
    integrator = args.integrator or "energy-momentum"
    return name, params, t_end, dt, integrator, args.rho_inf, args.every, args.no_vtk, out


def _cmd_run(args):
    import numpy as np

    from .. import scenes
    from ..errors import DivergenceError, Interrupted
    from ..errors import SimulationError
    from ..io.files import write_text_atomically
    from ..io.output import VTKSeries
    from ..run.simulate import SignalStop, simulate

    name, params, t_end, dt, integrator, rho_inf, every, no_vtk, out = _run_settings(args)
    if not math.isfinite(dt) or dt <= 0:
        raise UsageError(f"--dt must be a positive number of seconds, got {dt!r}")
    if not math.isfinite(t_end) or t_end < 0:
        raise UsageError(f"--t-end must be a non-negative number of seconds, got {t_end!r}")
    n_steps = _step_count(t_end, dt)
    factory = scenes.get(name)
    try:
        with np.errstate(all="ignore"):       # overflow is reported by the checks, in one line
            scene = factory(**params)
    except (ValueError, TypeError, OverflowError, ArithmeticError) as exc:
        raise UsageError(f"scene {name!r}: {_one_line(exc)}") from None
    _prepare_out(out)
    resume = None
    if args.resume is not None:
        resume = _resume_file(out)
        reached = float(resume.t[-1])
        if args.t_end is not None and t_end <= reached:
            raise UsageError(f"--resume {str(out)!r}: the run already reached t = {reached:g} s; --t-end must be "
                             f"beyond it, got {t_end:g} s")
    else:
        for f in _RUN_FILES:
            (out / f).unlink(missing_ok=True)
    # temporary files of a killed earlier run (the VTK series removes its own)
    stale = re.compile(r"^\.(" + "|".join(re.escape(f) for f in _RUN_FILES) + r")\.\d+\.tmp$")
    for p in out.iterdir():
        if stale.match(p.name):
            p.unlink(missing_ok=True)
    effective = {p: d for p, d, _ in scenes.parameters(name)}
    effective.update(params)

    if every is None:
        every = max(1, math.ceil(n_steps / MAX_FRAMES))
    if resume is None:
        write_text_atomically(out / RUN_SETTINGS, json.dumps(_jsonable(
            {"scene": name, "parameters": params, "t_end": t_end, "dt": dt, "integrator": integrator,
             "rho_inf": rho_inf, "every": every, "no_vtk": no_vtk}), indent=2) + "\n")
    sinks = [] if no_vtk else [VTKSeries(out, name, every=every)]
    error, result, status = None, None, 0
    start = time.perf_counter()
    try:
        with np.errstate(all="ignore"):       # non-finite states are caught by simulate's divergence rule
            result = simulate(scene, t_end, dt, integrator=integrator, rho_inf=rho_inf, output=sinks,
                              progress=not args.quiet, checkpoint=out / CHECKPOINT,
                              checkpoint_every=args.checkpoint_every, resume=resume)
    except SimulationError as exc:
        result, error = exc.result, _one_line(exc)
        status = (EXIT_SIGNAL.get(getattr(exc, "signal", None), 130) if isinstance(exc, Interrupted)
                  else EXIT_DIVERGED if isinstance(exc, DivergenceError) else EXIT_STOPPED)
    except OSError as exc:
        raise _OutputError(exc) from None
    except (ValueError, TypeError) as exc:
        raise UsageError(_one_line(exc)) from None
    wall = time.perf_counter() - start

    held = SignalStop(True)                   # a signal now waits until the outputs are complete
    try:
        files = _write_run_outputs(scene, result, sinks, out)
        summary = _summary(name, scene, effective, integrator, rho_inf, t_end, dt, result, error, files, wall)
        try:
            write_text_atomically(out / "summary.json", json.dumps(summary, indent=2) + "\n")
        except OSError as exc:
            raise _OutputError(exc) from None
        if status == 0 and result is not None:
            (out / CHECKPOINT).unlink(missing_ok=True)        # result.npz holds all of it now
    finally:
        held.restore()
    if held.signum is not None and status == 0:
        print(f"skfem-flex: {signal.Signals(held.signum).name} while writing the outputs: the run is complete "
              f"and so are its outputs in {out}", file=sys.stderr)
        return EXIT_SIGNAL.get(held.signum, 130)
    for warning in summary.get("warnings", []):
        print(f"skfem-flex: warning: {warning}", file=sys.stderr)
    if error is not None:
        what = {EXIT_DIVERGED: "run diverged", EXIT_STOPPED: "run stopped early"}.get(status, "run interrupted")
        resume_hint = f"; continue it with 'skfem-flex run --resume {out}'" if status in EXIT_SIGNAL.values() else ""
        print(f"skfem-flex: {what}: {error}; outputs up to the last good step are in {out}{resume_hint}",
              file=sys.stderr)
        return status
    if not args.quiet:
        _report(name, summary, files, out)
    return 0


class _OutputError(Exception):
    """Writing an output file failed (disk full, permissions): one line, exit status 1."""

    def __init__(self, exc):
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        super().__init__(f"cannot write the outputs: {exc.strerror or _one_line(exc)}{where}")


def _step_count(t_end, dt):
    """Steps of a run; UsageError if the request cannot fit in the memory available."""
    from ..numerics.resources import check_fits

    ratio = t_end / dt
    if not math.isfinite(ratio) or ratio > 1e15:
        raise UsageError(f"--t-end {t_end:g} s with --dt {dt:g} s asks for {ratio:.3g} steps; that run cannot end")
    n_steps = math.ceil(ratio - 1e-9) if t_end > 0 else 0
    # every step is recorded: at least t, q, v and the energies per step (16 coordinates as a floor)
    try:
        check_fits((n_steps + 1) * 8 * 40, f"a run of {n_steps:.3g} steps (--t-end {t_end:g} s / --dt {dt:g} s)")
    except ValueError as exc:
        raise UsageError(_one_line(exc)) from None
    return int(n_steps)


def _resume_file(out):
    """The saved state to continue in ``out``: result.npz or checkpoint.npz, whichever reaches further."""
    from ..io.result import Result

    best = None
    for f in ("result.npz", CHECKPOINT):
        try:
            res = Result.load(out / f)
        except (OSError, ValueError):
            continue
        if res.final_state is not None and (best is None or float(res.t[-1]) > float(best.t[-1])):
            best = res
    if best is None:
        raise UsageError(f"--resume {str(out)!r}: neither result.npz nor {CHECKPOINT} holds a saved state to continue")
    return best


def _write_run_outputs(scene, result, sinks, out):
    """result.npz, probes.csv and plots (what the run reached); {key: path} of the files written."""
    files = {}
    if sinks and sinks[0].written:
        files.update(pvd=sinks[0].pvd_path, series=sinks[0].series_path, vtu_files=len(sinks[0].written))
    if result is None or not len(result.t):
        files["summary"] = out / "summary.json"
        return files
    try:
        files["result"] = result.save(out / "result.npz")
        if result.probes:
            files["probes_csv"] = result.probes_to_csv(out / "probes.csv")
    except OSError as exc:
        raise _OutputError(exc) from None
    from ..io.plots import save_plots
    try:
        for k, p in save_plots(scene, result, out).items():
            files[f"plot_{k}"] = p
    except (OSError, ValueError, OverflowError) as exc:           # a diverged run may not plot
        print(f"skfem-flex: warning: plots not written: {_one_line(exc)}", file=sys.stderr)
    files["summary"] = out / "summary.json"
    return files


def _steps_text(summary):
    """"N steps of Δt s", in the words the numbers need: the run's last step is shortened to land on
    t_end, so a run shorter than one step takes a single step of t_end, not of Δt."""
    steps, dt = int(summary.get("steps", 0)), float(summary["dt"])
    if steps == 0:
        return "0 steps"
    last = float(summary.get("t_reached", summary["t_end"])) - (steps - 1) * dt
    if not 0.0 < last <= dt * (1 + 1e-9):          # a resumed run whose steps are not all on one grid
        return f"{steps} steps of up to {dt:.4g} s"
    if steps == 1:
        return f"1 step of {last:.4g} s"
    if abs(last - dt) > 1e-9 * dt:
        return f"{steps} steps of {dt:.4g} s (the last one {last:.4g} s)"
    return f"{steps} steps of {dt:.4g} s"


def _report(name, summary, files, out):
    e = summary.get("energy", {})
    nw = summary.get("newton", {})
    print(f"{name}: {_steps_text(summary)} to t = {summary.get('t_reached', summary['t_end']):.4g} s "
          f"with {summary['integrator']} in {summary['wall_time_s']:.2f} s"
          + (f" (of which {summary['compile_time_s']:.1f} s compiling, once per machine)"
             if summary.get("compile_time_s", 0.0) > 0 else ""))
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
    from ..schemes import SCHEMES as INTEGRATORS

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
    p.add_argument("--integrator", choices=sorted(INTEGRATORS), default=None,
                   help="time integrator (default: energy-momentum)")
    p.add_argument("--rho-inf", type=_number, default=None, metavar="R",
                   help="spectral radius of generalized-alpha (default 0.9)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/SCENE)")
    p.add_argument("--every", type=_positive_int, default=None, metavar="N",
                   help=f"write a VTK file every N steps (default: at most about {MAX_FRAMES} files)")
    p.add_argument("--no-vtk", action="store_true", help="skip the VTK series")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--checkpoint-every", type=_positive_number, default=CHECKPOINT_EVERY, metavar="S",
                   help=f"save the histories to {CHECKPOINT} every S seconds of wall time (default {CHECKPOINT_EVERY:g})")
    p.add_argument("--resume", default=None, metavar="DIR",
                   help=f"continue the interrupted or killed run in DIR from its last saved state (result.npz or "
                        f"{CHECKPOINT}), with its own settings; --t-end may extend it")
    p.set_defaults(func=_cmd_run)


# ---------------------------------------------------------------------- list
def _cmd_list(args):
    from .. import scenes

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
    from .sweep import connect

    out = Path(args.out or f"results/study-{args.kind}")
    _prepare_out(out)
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
        raise UsageError(_one_line(str(exc))) from None
    csv_path, md_path = studies.write_table(rows, stem)
    if not args.quiet:
        print(md_path.read_text())
        print(f"{len(rows)} runs: {computed} computed, {skipped} read from the store"
              + (f" {args.store}" if args.store is not None else ""))
        print(f"wrote {md_path}, {csv_path} and {figure}")
    return 0


def _add_study(sub):
    from . import studies
    from ..schemes import SCHEMES as INTEGRATORS

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
    p.add_argument("--budget", type=_positive_number, default=300.0, metavar="S",
                   help="stability: wall-clock seconds per run before it is stopped and reported (default 300)")
    _add_where_options(p, workers_default="default: run the cases one after another in this process, so that "
                                          "their wall times do not disturb each other")
    p.add_argument("--store", type=Path, default=None, metavar="DIR",
                   help="sweep store of the runs (one netCDF file per run; a Zarr hierarchy if DIR ends in "
                        ".zarr): a rerun reads the runs already there, timings included (default: no store)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/study-KIND)")
    p.add_argument("--quiet", action="store_true", help="no progress lines and no table on stdout")
    p.set_defaults(func=_cmd_study)


# --------------------------------------------------------------- modes, campbell
def _catalogue_scene(name):
    from .. import scenes

    if name not in scenes.CATALOGUE:
        raise UsageError(f"unknown scene {name!r}; known scenes: {', '.join(sorted(scenes.CATALOGUE))}")
    return scenes.get(name)


def _analysis(name, compute):
    """``compute()``; bad input becomes a UsageError (exit 2), an equilibrium that cannot be found
    (a SimulationError) is reported in one line and gives None (exit 1)."""
    from ..errors import SimulationError

    try:
        return compute()
    except SimulationError as exc:
        print(f"skfem-flex: error: {_one_line(exc)}", file=sys.stderr)
        return None
    except (ValueError, TypeError) as exc:
        msg = _one_line(exc)
        raise UsageError(msg if msg.startswith(f"scene {name!r}") else f"scene {name!r}: {msg}") from None


def _cmd_modes(args):
    from ..analysis import modes, write_mode_series
    from ..io.files import write_text_atomically

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
    write_text_atomically(out / "modes.csv", "\n".join(lines) + "\n")
    pvds = [] if args.no_vtk else write_mode_series(scene, result, out, frames=args.frames)
    summary = {"scene": args.scene, "parameters": dict(scene.parameters) or params, "about": result.about,
               "modes": rows, "stable": result.stable, "vtk": [str(p) for p in pvds]}
    write_text_atomically(out / "summary.json", json.dumps(_jsonable(summary), indent=2) + "\n")
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
        lo, hi = convert_setting(key, a, 0.0, "--vary"), convert_setting(key, b, 0.0, "--vary")
        count = convert_setting(key, c, 0, "--vary")
        if count < 1:
            raise UsageError(f"--vary {key}={text}: COUNT must be a positive integer")
        return [float(x) for x in np.linspace(lo, hi, count)]
    return [convert_setting(key, item, 0.0 if default is None else default, "--vary") for item in text.split(",")]


def _cmd_campbell(args):
    import inspect as _inspect

    from ..analysis import campbell
    from .. import scenes

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


# ------------------------------------------------- where sweeps run (sweep, study)
def _add_where_options(p, workers_default):
    """``--workers N | --scheduler ADDRESS`` and ``--resume/--no-resume``: where the cases of a sweep run
    and whether the store's cases are reused (the options of ``sweep`` and ``study``)."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int, default=None, metavar="N",
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
    from .. import scenes
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
        grid[key] = _vary_values(key, text.strip(), None if default is inspect.Parameter.empty else default)
    return grid


def _cmd_sweep(args):
    from .. import scenes
    from ..io.plots import plot_sweep_extremes
    from ..io.files import write_text_atomically
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
    write_text_atomically(out / "sweep.json", json.dumps(_jsonable(report), indent=2) + "\n")
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
    from ..schemes import SCHEMES as INTEGRATORS

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
    _add_where_options(p, workers_default="default: one per core")
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
    from .. import __version__

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
    import threading
    import warnings

    def one_line_warning(message, category, filename, lineno, file=None, line=None):
        # Python warnings (ours, numpy's, matplotlib's) as one line like the CLI's own: no source echo
        kind = "" if category is UserWarning else f"{category.__name__}: "
        try:
            print(f"skfem-flex: warning: {kind}{_one_line(message)}", file=sys.stderr if file is None else file)
        except OSError:
            pass

    old_term, old_show = None, warnings.showwarning
    if threading.current_thread() is threading.main_thread():
        old_term = signal.signal(signal.SIGTERM, _raise_terminated)
    warnings.showwarning = one_line_warning
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
    except _OutputError as exc:
        print(f"skfem-flex: error: {exc}", file=sys.stderr)
        return EXIT_STOPPED
    except BrokenPipeError:
        # the reader of stdout went away (``skfem-flex list | head``): not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 0
    except KeyboardInterrupt:
        print("skfem-flex: interrupted; outputs written so far are kept", file=sys.stderr)
        return EXIT_SIGNAL[2]
    except _Terminated:
        print("skfem-flex: terminated; outputs written so far are kept", file=sys.stderr)
        return EXIT_SIGNAL[15]
    except (ArithmeticError, MemoryError, RecursionError) as exc:
        # numbers beyond double precision deep inside a computation: one line, not a traceback
        print(f"skfem-flex: error: {type(exc).__name__}: {_one_line(exc)}", file=sys.stderr)
        return EXIT_STOPPED
    except Exception as exc:
        if os.environ.get("SKFEM_FLEX_DEBUG"):
            raise
        print(f"skfem-flex: internal error: {type(exc).__name__}: {_one_line(exc)} (please report it; "
              f"SKFEM_FLEX_DEBUG=1 shows the traceback)", file=sys.stderr)
        return EXIT_STOPPED
    finally:
        warnings.showwarning = old_show
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)


if __name__ == "__main__":
    raise SystemExit(main())
