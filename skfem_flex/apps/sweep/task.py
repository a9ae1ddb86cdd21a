"""One case as a Dask task: build the scene, :func:`~skfem_flex.run.simulate.simulate`, measure, and
return the case as a small xarray Dataset (the recorded groups and per-case scalars, not the Result,
so only what is stored travels back to the driver)."""
from __future__ import annotations

import dataclasses
import json
import math
import os
import socket
import time

import numpy as np

from ...errors import SimulationError
from .budget import BudgetExceeded, WallClockBudget
from .cases import RECORD_GROUPS, SIMULATE_OPTIONS
from .store import STORE_FORMAT

__all__ = ["run_case", "case_dataset", "one_line", "STATUSES"]

#: ``status`` of a case: ran to t_end / stopped by a SimulationError (history kept up to there) /
#: stopped by its wall-clock budget / raised before or outside the time loop (bad parameters: no history) /
#: lost with its worker more often than the cluster allows (not stored, so a rerun retries it)
STATUSES = ("completed", "failed", "stopped", "error", "lost")


def run_case(spec):
    """Run one case (the Dask task): build the scene, :func:`simulate`, measure; returns its Dataset.

    Never raises for a bad case: exceptions become ``status`` and
    ``message`` (see :data:`STATUSES`).
    """
    from ... import scenes
    from ...run.simulate import simulate

    s = spec.settings
    status, message, result, run_time, measured = "completed", "", None, math.nan, {}
    try:
        factory = scenes.get(spec.scene) if isinstance(spec.scene, str) else spec.scene
        scene = factory(**spec.params)
        sinks = [WallClockBudget(s["budget"])] if s.get("budget") is not None else []
        options = {k: s[k] for k in SIMULATE_OPTIONS if k in s}
        start = time.perf_counter()
        try:
            result = simulate(scene, s["t_end"], s["dt"], integrator=s["integrator"], record_every=s["record_every"],
                              output=sinks, **options)
        finally:
            run_time = time.perf_counter() - start
    except BudgetExceeded as exc:
        status, message, result = "stopped", one_line(exc), exc.result
    except SimulationError as exc:
        status, message, result = "failed", one_line(exc), exc.result
    except Exception as exc:        # a bad case is a row of the results, never the end of the sweep
        status, message = "error", f"{type(exc).__name__}: {one_line(exc)}"
    if result is not None:
        for k, fn in spec.measures.items():
            try:
                measured[k] = float(fn(result))
            except Exception as exc:
                measured[k] = math.nan
                message = "; ".join(filter(None, [message, f"measure {k}: {type(exc).__name__}: {one_line(exc)}"]))
    return case_dataset(spec, status, message, result, run_time, measured)


def one_line(text):
    """``text`` (an exception's message) on one line: runs of white space, newlines included, as one space."""
    return " ".join(str(text).split())


def case_dataset(spec, status, message, result, run_time, measured):
    """The Dataset of one case: its recorded groups along ``time``, its scalars (status, message, timings,
    counts, measures) and, in ``attrs``, its key, scene, parameters and settings (``result`` None: no history)."""
    import xarray as xr

    data, nan = {}, math.nan
    n = 0 if result is None else len(result.t)
    data["t"] = ("time", np.asarray(result.t if result is not None else [], dtype=float))
    if result is not None:
        for group in spec.record:
            if group == "probes":
                for k, val in result.probes.items():
                    val = np.asarray(val)
                    name = f"probe_{k}".replace("/", "_")
                    data[name] = (("time",) + tuple(f"{name}_dim{d}" for d in range(1, val.ndim)), val)
            for k in RECORD_GROUPS[group]:
                val = getattr(result, k)
                data[k] = (("time",) + (f"{k}_dof",) * (np.ndim(val) - 1), np.asarray(val))
    its = np.asarray(result.newton_iterations) if result is not None else np.zeros(0)
    steps = int(result.steps) if result is not None else 0
    scalars = {
        "status": status, "message": message,
        "wall_time": float(result.wall_time) if result is not None else nan,
        "run_time": float(run_time),
        "steps": steps, "halvings": int(result.halvings) if result is not None else 0,
        "newton_total": int(its.sum()), "newton_per_step": float(its.sum()) / steps if steps else nan,
        "t_reached": float(result.t[-1]) if n else nan, "n_times": n,
        "max_energy_balance_error": float(np.max(np.abs(result.energy_balance_error))) if n else nan,
        "relative_energy_error": result.relative_energy_error() if n else nan,
        "max_constraint_residual": float(np.max(result.constraint_residual)) if n else nan,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
        **measured,
    }
    for k, v in scalars.items():
        data[k] = ((), v)
    attrs = {"format": STORE_FORMAT, "key": spec.key, "scene": spec.scene_name, "label": spec.label,
             "index": spec.index, "parameters": json.dumps(spec.params), "settings": json.dumps(_settings_attr(spec)),
             "record": ",".join(spec.record)}
    return xr.Dataset(data, attrs=attrs)


def _settings_attr(spec):
    """Settings as readable JSON (Newton settings and other dataclasses as dicts)."""
    out = {}
    for k, v in spec.settings.items():
        out[k] = dataclasses.asdict(v) if dataclasses.is_dataclass(v) and not isinstance(v, type) else v
    return out
