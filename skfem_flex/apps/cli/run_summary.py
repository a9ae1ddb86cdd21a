"""What a run reports: its ``summary.json`` (settings, how far it got, energy balance, Newton work, the
code path that ran and the compile time) and the lines printed at its end."""
from __future__ import annotations

import math
from pathlib import Path

from .outputs import jsonable

__all__ = ["run_summary", "print_report", "ENERGY_WARNING"]

#: relative energy balance error above which a run's summary carries a warning (conservative schemes)
ENERGY_WARNING = 0.01


def run_summary(name, scene, params, integrator, rho_inf, t_end, dt, result, error, files, wall):
    """The run's summary (strict JSON): its settings, whether it completed and why not, and, for a run that
    recorded something, how far it got, the code path that ran (``run_path``: loop, solver, storage, the
    elements that ran through Python and why), its compile time, energy balance, constraint residuals and
    Newton work; ``files`` are the outputs written, ``wall`` the seconds of the whole run."""
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
            "compile_time_s": float(result.compile_time), "run_path": result.run_path,
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
    return jsonable(s)


def _energy_warnings(integrator, rho_inf, relative_error):
    """A warning when a scheme meant to keep the energy balance misses it by more than ENERGY_WARNING.

    Generalized-α with ρ∞ < 1 dissipates high frequencies by design and gets none."""
    dissipative = integrator == "generalized-alpha" and (rho_inf is None or rho_inf < 1.0)
    if dissipative or not math.isfinite(relative_error) or relative_error <= ENERGY_WARNING:
        return [] if math.isfinite(relative_error) else ["the energy balance error is not finite"]
    return [f"energy balance error {100 * relative_error:.3g} % of the energy scale with {integrator} "
            f"(above {100 * ENERGY_WARNING:g} %): a smaller --dt, or the energy-momentum scheme, keeps it"]


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


def _path_text(run_path):
    """The code that ran, in words: loop, solver, Newton matrix storage, and the elements that ran through
    Python with why (``result.run_path``)."""
    python = run_path.get("python_elements") or []
    elements = f"through Python: {'; '.join(python)}" if python else "every element compiled"
    return (f"{run_path.get('loop', '?')} loop, {run_path.get('solver', '?')} solver, "
            f"{run_path.get('storage', '?')} Newton matrix; {elements}")


def print_report(name, summary, files, out):
    """The lines printed at the end of a completed run: steps, time, compile time, the code path that ran,
    energy balance, constraints, Newton work, and the outputs written into ``out``."""
    e = summary.get("energy", {})
    nw = summary.get("newton", {})
    compile_time = summary.get("compile_time_s", 0.0)
    print(f"{name}: {_steps_text(summary)} to t = {summary.get('t_reached', summary['t_end']):.4g} s "
          f"with {summary['integrator']} in {summary['wall_time_s']:.2f} s, of which {compile_time:.2f} s compiling"
          + (" (once per machine)" if compile_time > 0 else ""))
    if summary.get("run_path"):
        print(f"  code path: {_path_text(summary['run_path'])}")
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
