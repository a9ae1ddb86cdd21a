"""``skfem-flex run``: a catalogue scene integrated and written out (VTK series, result.npz, probes.csv,
plots, summary.json), checkpointed as it goes; ``run --resume DIR`` continues an interrupted or killed
run from its last saved state."""
from __future__ import annotations

import json
import math
import re
import signal
import sys
import time
from pathlib import Path

from .arguments import number, positive_int, positive_number
from .errors import EXIT_DIVERGED, EXIT_SIGNAL, EXIT_STOPPED, OutputWriteError, UsageError, one_line
from .outputs import jsonable, prepare_out
from .run_summary import print_report, run_summary
from .settings import DEFAULT_SCENE, FALLBACK_DT, FALLBACK_T_END, scene_settings

__all__ = ["add_run", "MAX_FRAMES", "RUN_SETTINGS", "CHECKPOINT", "CHECKPOINT_EVERY"]

#: without --every, VTK output is thinned to at most about this many files
MAX_FRAMES = 200
#: a run's settings, written when it starts, so that ``run --resume DIR`` can continue it
RUN_SETTINGS = "run.json"
#: histories checkpointed during a run (Result.load reads it after a SIGKILL)
CHECKPOINT = "checkpoint.npz"
#: seconds of wall time between checkpoints
CHECKPOINT_EVERY = 5.0
#: files of an earlier run in the same directory, removed when a fresh run starts there
_RUN_FILES = ("result.npz", CHECKPOINT, "summary.json", "probes.csv", RUN_SETTINGS)


def _run_settings(args):
    """(name, params, t_end, dt, integrator, rho_inf, every, no_vtk, out) from the arguments, or with
    ``--resume DIR`` from DIR's run.json (explicit --t-end may extend the run)."""
    from ... import scenes

    if args.resume is not None:
        if args.resume == "":
            raise UsageError("--resume needs the output directory of the run to continue, got ''")
        out = Path(args.resume)
        try:
            saved = json.loads((out / RUN_SETTINGS).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise UsageError(f"--resume {str(out)!r}: no readable {RUN_SETTINGS} of an earlier run there "
                             f"({getattr(exc, 'strerror', None) or one_line(exc)})") from None
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
    params = scene_settings(name, args.set)
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

    from ... import scenes
    from ...errors import DivergenceError, Interrupted
    from ...errors import SimulationError
    from ...io.files import write_text_atomically
    from ...io.output import VTKSeries
    from ...run.simulate import SignalStop, simulate

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
        raise UsageError(f"scene {name!r}: {one_line(exc)}") from None
    prepare_out(out)
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
        write_text_atomically(out / RUN_SETTINGS, json.dumps(jsonable(
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
        result, error = exc.result, one_line(exc)
        status = (EXIT_SIGNAL.get(getattr(exc, "signal", None), 130) if isinstance(exc, Interrupted)
                  else EXIT_DIVERGED if isinstance(exc, DivergenceError) else EXIT_STOPPED)
    except OSError as exc:
        raise OutputWriteError(exc) from None
    except (ValueError, TypeError) as exc:
        raise UsageError(one_line(exc)) from None
    wall = time.perf_counter() - start

    held = SignalStop(True)                   # a signal now waits until the outputs are complete
    try:
        files = _write_run_outputs(scene, result, sinks, out, plots=not args.no_plots)
        summary = run_summary(name, scene, effective, integrator, rho_inf, t_end, dt, result, error, files, wall)
        try:
            write_text_atomically(out / "summary.json", json.dumps(summary, indent=2) + "\n")
        except OSError as exc:
            raise OutputWriteError(exc) from None
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
        print_report(name, summary, files, out)
    return 0


def _step_count(t_end, dt):
    """Steps of a run; UsageError if the request cannot fit in the memory available."""
    from ...numerics.resources import check_fits

    ratio = t_end / dt
    if not math.isfinite(ratio) or ratio > 1e15:
        raise UsageError(f"--t-end {t_end:g} s with --dt {dt:g} s asks for {ratio:.3g} steps; that run cannot end")
    n_steps = math.ceil(ratio - 1e-9) if t_end > 0 else 0
    # every step is recorded: at least t, q, v and the energies per step (16 coordinates as a floor)
    try:
        check_fits((n_steps + 1) * 8 * 40, f"a run of {n_steps:.3g} steps (--t-end {t_end:g} s / --dt {dt:g} s)")
    except ValueError as exc:
        raise UsageError(one_line(exc)) from None
    return int(n_steps)


def _resume_file(out):
    """The saved state to continue in ``out``: result.npz or checkpoint.npz, whichever reaches further."""
    from ...io.result import Result

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


def _write_run_outputs(scene, result, sinks, out, plots=True):
    """result.npz, probes.csv and plots (unless ``plots`` is False; what the run reached); {key: path} of
    the files written."""
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
        raise OutputWriteError(exc) from None
    files["summary"] = out / "summary.json"
    if not plots:
        return files
    from ...io.plots import save_plots
    try:
        for k, p in save_plots(scene, result, out).items():
            files[f"plot_{k}"] = p
    except (OSError, ValueError, OverflowError) as exc:           # a diverged run may not plot
        print(f"skfem-flex: warning: plots not written: {one_line(exc)}", file=sys.stderr)
    files["summary"] = out / "summary.json"
    return files


def add_run(sub):
    """Add the ``run`` subcommand to the subparsers ``sub``."""
    from ...schemes import SCHEMES as INTEGRATORS

    p = sub.add_parser("run", help="run a catalogue scene and write VTK series, plots and a summary",
                       description="Run a catalogue scene; write the VTK time series (.vtu + .pvd), "
                                   "PNG plots, result.npz, probes.csv and summary.json into --out.")
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help=f"scene name from 'skfem-flex list' (default: {DEFAULT_SCENE})")
    p.add_argument("--set", action="extend", nargs="+", metavar="KEY=VALUE", default=[],
                   help="scene parameter, converted to the type of its default (repeatable)")
    p.add_argument("--t-end", type=number, default=None, metavar="T",
                   help=f"end time, s (default: the scene's, else {FALLBACK_T_END:g})")
    p.add_argument("--dt", type=number, default=None, metavar="DT",
                   help=f"time step, s (default: the scene's, else {FALLBACK_DT:g})")
    p.add_argument("--integrator", choices=sorted(INTEGRATORS), default=None,
                   help="time integrator (default: energy-momentum)")
    p.add_argument("--rho-inf", type=number, default=None, metavar="R",
                   help="spectral radius of generalized-alpha (default 0.9)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default: results/SCENE)")
    p.add_argument("--every", type=positive_int, default=None, metavar="N",
                   help=f"write a VTK file every N steps (default: at most about {MAX_FRAMES} files)")
    p.add_argument("--no-vtk", action="store_true", help="skip the VTK series")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots (about 0.2 s each)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no report")
    p.add_argument("--checkpoint-every", type=positive_number, default=CHECKPOINT_EVERY, metavar="S",
                   help=f"save the histories to {CHECKPOINT} every S seconds of wall time (default {CHECKPOINT_EVERY:g})")
    p.add_argument("--resume", default=None, metavar="DIR",
                   help=f"continue the interrupted or killed run in DIR from its last saved state (result.npz or "
                        f"{CHECKPOINT}), with its own settings; --t-end may extend it")
    p.set_defaults(func=_cmd_run)
