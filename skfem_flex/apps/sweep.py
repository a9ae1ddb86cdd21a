"""Parameter sweeps: many runs of one model as Dask tasks, results as an xarray Dataset in Zarr.

A *case* is one call of :func:`~skfem_flex.run.simulate.simulate` on a scene built
from a factory with some parameters, under some run settings (end time,
step, integrator, ...). :func:`sweep` expands a grid (``vary``) or a list
(``cases``) into cases, runs each case as one task on a Dask cluster (a local
cluster of worker processes it starts itself, or any cluster a
``dask.distributed.Client`` points at), and collects the results into one
:class:`xarray.Dataset` with dimensions ``case`` and ``time``.

Store (``store=PATH``, a directory) in one of two layouts, chosen by the name:

* ``PATH`` ending in ``.zarr``: a Zarr (format 2) group, one child group
  ``PATH/<key>/`` per finished case; the whole store opens with
  ``xarray.open_datatree(PATH, engine="zarr")``;
* any other name: ``PATH/<key>.nc``, one netCDF file per finished case
  (``xarray.open_dataset``); about ten times faster to write and read than a
  Zarr group of the same case, which matters for many short cases.

Either way a marker (``.zattrs`` or ``sweep-store.json``) says it is a
sweep store, and the driver writes a finished case into
``PATH.parent/.PATH.name.partial/`` and then renames it into ``PATH`` with a
single ``rename(2)``, atomic on a POSIX file system: a reader (or a rerun)
sees either the whole case or none of it, whatever moment the driver is
killed at (SIGKILL included), so the store opens with xarray at every
moment. Only the driver writes, so workers need no shared file system.
:func:`open_sweep` joins the cases into one Dataset.

A case's *key* is a SHA-256 hash of (scene name, parameters, settings,
recorded groups, measure names); with ``resume=True`` a case whose key is
already in the store is read back instead of run, so a killed sweep restarts
where it stopped, and changing any setting (``dt``, ``t_end``,
``integrator``, ``rho_inf``, ...) makes new cases instead of reusing old ones.

Cases of different lengths (another ``dt`` or ``t_end``, or a run that stopped
early) share the ``time`` dimension as the index of the recorded step: shorter
cases are padded with NaN, ``n_times`` holds each case's own length and the
variable ``t`` (case, time) its times. When every case has the same times they
also become the ``time`` coordinate. Other dimensions that differ between
cases (``q_dof`` of meshes with more or fewer elements) are padded the same way.
"""
from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import inspect
import itertools
import json
import logging
import math
import os
import shutil
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SimulationError

__all__ = ["sweep", "plan", "run_cases", "open_sweep", "probe_extremes", "local_cluster", "connect", "CaseSpec",
           "BudgetExceeded", "WallClockBudget", "RUN_SETTINGS", "RECORD_GROUPS", "DEFAULT_RECORD", "STATUSES",
           "LOCAL_CLUSTER_CONFIG"]

#: run settings a case may vary like a scene parameter (``vary={"dt": [...]}``)
RUN_SETTINGS = ("t_end", "dt", "integrator")
#: further keyword arguments of :func:`~skfem_flex.run.simulate.simulate` a sweep passes on (part of the key;
#: a case may vary them too)
SIMULATE_OPTIONS = ("rho_inf", "newton", "max_halvings", "project", "compiled")
#: time series a case can store: group -> Result attributes
RECORD_GROUPS = {
    "probes": (),
    "energy": ("kinetic", "potential", "total_energy", "external_work", "energy_balance_error"),
    "residuals": ("constraint_residual", "velocity_constraint_residual"),
    "newton": ("newton_iterations",),
    "state": ("q", "v"),
}
DEFAULT_RECORD = ("probes", "energy", "residuals", "newton")
#: ``status`` of a case: ran to t_end / stopped by a SimulationError (history kept up to there) /
#: stopped by its wall-clock budget / raised before or outside the time loop (bad parameters: no history) /
#: lost with its worker more often than the cluster allows (not stored, so a rerun retries it)
STATUSES = ("completed", "failed", "stopped", "error", "lost")
_FORMAT = "skfem_flex.apps.sweep/1"
#: per-case scalar variables written by the sweep (measures may not use these names)
_RESERVED = {"status", "message", "wall_time", "run_time", "steps", "halvings", "newton_total", "newton_per_step",
             "t_reached", "n_times", "max_energy_balance_error", "relative_energy_error", "max_constraint_residual",
             "worker", "t", "scene", "label", "case"}


# ------------------------------------------------------------------ budget
class BudgetExceeded(SimulationError):
    """A run stopped because it used up its wall-clock budget (``result`` keeps its history)."""


class WallClockBudget:
    """Output sink that stops a run once it has used ``seconds`` of wall time.

    The clock starts at the first record (the initial state), after the run has compiled what it
    needs, so a cold cache does not eat the budget. It raises :class:`BudgetExceeded` at the first
    recorded step past the budget; :func:`~skfem_flex.run.simulate.simulate` then attaches the
    history so far to the exception.
    """

    def __init__(self, seconds):
        self.seconds, self.start = float(seconds), None

    def write(self, scene, t, q, v):
        now = time.perf_counter()
        if self.start is None:
            self.start = now
        if now - self.start > self.seconds:
            raise BudgetExceeded(f"stopped: wall-clock budget of {self.seconds:g} s used up at t = {t:.6g} s")

    def close(self):
        pass


# ------------------------------------------------------------------- cases
@dataclass
class CaseSpec:
    """One run of a sweep (plain data, shipped to a worker as it is).

    Attributes
    ----------
    scene : str or callable
        Catalogue name or a factory returning a :class:`~skfem_flex.Scene`.
    scene_name : str
        Name of the scene in the store and in the key.
    params : dict
        Keyword arguments of the factory.
    settings : dict
        ``t_end``, ``dt`` (s), ``integrator``, ``record_every``, ``budget``
        (s or None) and the simulate options given (``rho_inf``, ``newton``, ...).
    record : tuple of str
        Groups of :data:`RECORD_GROUPS` stored as time series.
    measures : dict of str to callable
        ``name -> fn(result) -> float``, evaluated on the worker on the
        (possibly partial) Result and stored per case.
    label : str
        Free text stored as the ``label`` coordinate (not part of the key).
    index : int
        Position in the plan (orders the cases of :func:`open_sweep`).
    """

    scene: object
    scene_name: str
    params: dict
    settings: dict
    record: tuple = DEFAULT_RECORD
    measures: dict = field(default_factory=dict)
    label: str = ""
    index: int = 0

    @property
    def key(self):
        """Stable hash of (scene name, parameters, settings, record, measure names): 20 hex digits."""
        text = json.dumps({"scene": self.scene_name, "params": _canonical(self.params),
                           "settings": _canonical(self.settings), "record": sorted(self.record),
                           "measures": sorted(self.measures)}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    @property
    def task_name(self):
        """Readable Dask task key: the varied values, then the hash."""
        shown = ",".join(f"{k}={_short(v)}" for k, v in self.params.items())
        return f"case-{self.label or self.scene_name}-{shown}-{self.key}".replace(" ", "_")


def _short(v):
    return f"{v:g}" if isinstance(v, float) else str(v)


def _plain(value):
    """numpy scalars as Python scalars."""
    return value.item() if isinstance(value, np.generic) else value


def _canonical(value):
    """A JSON-able, order-independent image of ``value`` for hashing (TypeError if it has none)."""
    value = _plain(value)
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return {"float": value.hex()}       # exact; plan() turns ints given for float parameters into floats
    if isinstance(value, dict):
        return {str(k): _canonical(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"dataclass": type(value).__qualname__, "fields": _canonical(dataclasses.asdict(value))}
    raise TypeError(f"sweep values must be numbers, strings, booleans, None, lists, dicts or dataclasses "
                    f"(to be keyed and stored), got {type(value).__name__} {value!r}")


def _factory(scene, name):
    """(factory, scene name, {parameter: default} or None when it takes **kwargs)."""
    from .. import scenes

    if isinstance(scene, str):
        factory = scenes.get(scene)
        return factory, scene, {p: d for p, d, _ in scenes.parameters(scene)}
    if not callable(scene):
        raise TypeError(f"scene must be a catalogue name or a factory returning a Scene, got {scene!r}")
    if name is None:
        qual = getattr(scene, "__qualname__", "")
        if not qual or "<lambda>" in qual or "<locals>" in qual:
            raise ValueError(f"give name=... for the factory {scene!r}: a lambda or local function has no "
                             f"stable name to key its cases by")
        name = f"{scene.__module__}.{qual}"
    sig = inspect.signature(scene).parameters.values()
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in sig):
        return scene, str(name), None
    return scene, str(name), {p.name: p.default for p in sig}


def plan(scene, vary=None, cases=None, *, fixed=None, t_end=None, dt=None, integrator="energy-momentum",
         record=DEFAULT_RECORD, record_every=1, budget=None, measures=None, name=None, label="", **options):
    """The list of :class:`CaseSpec` a sweep runs (nothing is run).

    Parameters: as :func:`sweep`. Cases come out in the order of
    ``itertools.product`` over ``vary`` (the last name varies fastest) or in
    the order of ``cases``.

    Raises
    ------
    ValueError
        Unknown scene or parameter, a missing required parameter, an empty
        list of values, both ``vary`` and ``cases``, an unknown record group,
        a measure named like a sweep variable, or no ``t_end``/``dt``.
    TypeError
        A value that cannot be stored or keyed, an unknown simulate option.
    """
    from ..schemes import SCHEMES as INTEGRATORS

    factory, scene_name, defaults = _factory(scene, name)
    unknown = sorted(set(options) - set(SIMULATE_OPTIONS))
    if unknown:
        raise TypeError(f"sweep got unexpected option(s) {', '.join(unknown)}; simulate options it passes on: "
                        f"{', '.join(SIMULATE_OPTIONS)}")
    if vary is not None and cases is not None:
        raise ValueError("give vary= (a grid) or cases= (a list of parameter dicts), not both")
    if vary is not None:
        if not isinstance(vary, dict):
            raise TypeError(f"vary must be a dict of name -> list of values, got {type(vary).__name__}")
        lists = {}
        for k, values in vary.items():
            if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
                raise TypeError(f"vary[{k!r}] must be a list of values, got {values!r}")
            lists[k] = [_plain(v) for v in values]
            if not lists[k]:
                raise ValueError(f"vary[{k!r}] is empty")
        rows = [dict(zip(lists, combo)) for combo in itertools.product(*lists.values())]
    elif cases is not None:
        rows = [dict(c) for c in cases]
        if not rows:
            raise ValueError("cases is empty")
    else:
        rows = [{}]
    if isinstance(record_every, bool) or not isinstance(record_every, int) or record_every < 1:
        raise ValueError(f"record_every must be a positive integer, got {record_every!r}")
    if budget is not None and not (isinstance(budget, (int, float)) and math.isfinite(budget) and budget > 0):
        raise ValueError(f"budget must be a positive number of seconds or None, got {budget!r}")
    record = tuple(record)
    bad = [g for g in record if g not in RECORD_GROUPS]
    if bad:
        raise ValueError(f"unknown record group(s) {bad}; known: {', '.join(RECORD_GROUPS)}")
    measures = dict(measures or {})
    for k, fn in measures.items():
        if k in _RESERVED or k in RECORD_GROUPS["energy"] + RECORD_GROUPS["residuals"]:
            raise ValueError(f"measure name {k!r} is taken by a sweep variable")
        if not callable(fn):
            raise TypeError(f"measure {k!r} must be a callable(result) -> float, got {fn!r}")
    base = {"t_end": t_end, "dt": dt, "integrator": integrator}
    registered = getattr(factory, "defaults", {}) or {}
    specs = []
    for i, row in enumerate(rows):
        row = {k: _plain(v) for k, v in {**(fixed or {}), **row}.items()}
        params = {k: v for k, v in row.items() if k not in RUN_SETTINGS + SIMULATE_OPTIONS}
        run = {k: row.get(k, base[k]) for k in RUN_SETTINGS}
        for k in ("t_end", "dt"):
            if run[k] is None:
                run[k] = registered.get(k)
            if run[k] is None:
                raise ValueError(f"give {k}= (the scene {scene_name!r} registers no default {k})")
        if not isinstance(run["integrator"], str) or run["integrator"] not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {run['integrator']!r}")
        if defaults is not None:
            for k in params:
                if k not in defaults:
                    raise ValueError(f"scene {scene_name!r} has no parameter {k!r}; it has: "
                                     f"{', '.join(defaults) or 'none'}")
            missing = [k for k, d in defaults.items() if d is inspect.Parameter.empty and k not in params]
            if missing:
                raise ValueError(f"scene {scene_name!r} needs the parameter {missing[0]!r}")
            # an int given for a float parameter builds the same scene: key it as the float
            params = {k: float(v) if isinstance(defaults[k], float) and isinstance(v, int)
                      and not isinstance(v, bool) else v for k, v in params.items()}
        settings = {**run, "record_every": record_every, "budget": budget,
                    **{k: row.get(k, options.get(k)) for k in SIMULATE_OPTIONS if k in row or k in options}}
        spec = CaseSpec(factory if not isinstance(scene, str) else scene_name, scene_name, params, settings,
                        record, measures, label, i)
        spec.key                # raises TypeError now for values that cannot be keyed
        specs.append(spec)
    return specs


# ------------------------------------------------------------------- a task
def run_case(spec):
    """Run one case (the Dask task): build the scene, :func:`simulate`, measure; returns its Dataset.

    Never raises for a bad case: exceptions become ``status`` and
    ``message`` (see :data:`STATUSES`).
    """
    from .. import scenes
    from ..run.simulate import simulate

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
        status, message, result = "stopped", _one_line(exc), exc.result
    except SimulationError as exc:
        status, message, result = "failed", _one_line(exc), exc.result
    except Exception as exc:        # a bad case is a row of the results, never the end of the sweep
        status, message = "error", f"{type(exc).__name__}: {_one_line(exc)}"
    if result is not None:
        for k, fn in spec.measures.items():
            try:
                measured[k] = float(fn(result))
            except Exception as exc:
                measured[k] = math.nan
                message = "; ".join(filter(None, [message, f"measure {k}: {type(exc).__name__}: {_one_line(exc)}"]))
    return _case_dataset(spec, status, message, result, run_time, measured)


def _one_line(text):
    return " ".join(str(text).split())


def _case_dataset(spec, status, message, result, run_time, measured):
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
    attrs = {"format": _FORMAT, "key": spec.key, "scene": spec.scene_name, "label": spec.label,
             "index": spec.index, "parameters": json.dumps(spec.params), "settings": json.dumps(_settings_attr(spec)),
             "record": ",".join(spec.record)}
    return xr.Dataset(data, attrs=attrs)


def _settings_attr(spec):
    """Settings as readable JSON (Newton settings and other dataclasses as dicts)."""
    out = {}
    for k, v in spec.settings.items():
        out[k] = dataclasses.asdict(v) if dataclasses.is_dataclass(v) and not isinstance(v, type) else v
    return out


# ------------------------------------------------------------------- store
def _partial_dir(root):
    return root.parent / f".{root.name}.partial"


class _Layout:
    """How one case is a file system entry: a netCDF file (``<key>.nc``) or a Zarr group (``<key>/``)."""

    def __init__(self, kind):
        self.kind = kind
        self.suffix = ".nc" if kind == "netcdf" else ""

    def write(self, ds, path):
        import dask

        # the Dataset is in memory: with a distributed Client as the default scheduler xarray would
        # take a cluster-wide lock per variable (a scheduler round trip each, ~0.4 s a case)
        with dask.config.set(scheduler="synchronous"):
            if self.kind == "netcdf":
                ds.to_netcdf(str(path), engine="scipy", format="NETCDF3_64BIT")
            else:
                ds.to_zarr(str(path), mode="w", zarr_format=2, consolidated=False)

    def read(self, path):
        import xarray as xr

        if self.kind == "netcdf":
            with xr.open_dataset(str(path), engine="scipy") as ds:
                return ds.load()
        with xr.open_zarr(str(path), consolidated=False) as ds:
            return ds.load()

    def keys(self, root):
        """Keys of the finished cases (temporary entries never live in the root)."""
        if self.kind == "netcdf":
            return sorted(p.name[:-3] for p in root.iterdir() if p.name.endswith(".nc") and p.is_file())
        return sorted(d.name for d in root.iterdir() if (d / ".zgroup").is_file())

    def path(self, root, key):
        return root / f"{key}{self.suffix}"


_MARKER = "sweep-store.json"     # the netCDF layout's root marker (the Zarr layout keeps it in .zattrs)


def _open_store(path, create):
    """(root directory, layout); a missing store is created when ``create`` (Zarr if the name ends in .zarr)."""
    root = Path(path)
    if root.exists():
        marker = root / (".zattrs" if (root / ".zgroup").is_file() else _MARKER)
        try:
            fmt = json.loads(marker.read_text()).get("format")
        except (OSError, ValueError, AttributeError):
            fmt = None
        if not root.is_dir() or fmt != _FORMAT:
            raise ValueError(f"{str(root)!r} exists but is not a skfem_flex sweep store (no {_FORMAT!r} "
                             f"marker in it); choose another store path")
        return root, _Layout("zarr" if marker.name == ".zattrs" else "netcdf")
    if not create:
        raise FileNotFoundError(f"no sweep store at {str(root)!r}")
    kind = "zarr" if root.suffix == ".zarr" else "netcdf"
    root.parent.mkdir(parents=True, exist_ok=True)
    partial = _partial_dir(root)
    partial.mkdir(exist_ok=True)
    tmp = partial / f"root-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    if kind == "zarr":
        import zarr
        zarr.open_group(str(tmp), mode="w", zarr_format=2, attributes={"format": _FORMAT})
    else:
        tmp.mkdir()
        (tmp / _MARKER).write_text(json.dumps({"format": _FORMAT}) + "\n")
    try:
        os.rename(tmp, root)
    except OSError:                  # another driver created it first
        shutil.rmtree(tmp, ignore_errors=True)
        return _open_store(path, create=False)
    return root, _Layout(kind)


def _clean_partial(root):
    """Remove leftovers of drivers that died while writing (their process no longer exists)."""
    partial = _partial_dir(root)
    if not partial.is_dir():
        return
    for d in partial.iterdir():
        try:
            pid = int(d.name.split("-")[1])
            os.kill(pid, 0)
        except (IndexError, ValueError, ProcessLookupError):
            shutil.rmtree(d, ignore_errors=True) if d.is_dir() else d.unlink(missing_ok=True)
        except PermissionError:      # alive, another user's
            pass


_TEMP_NAMES = itertools.count()


def _write_case(root, layout, ds):
    """Write one case under a temporary name outside the root, then rename it into the root (atomic)."""
    key = ds.attrs["key"]
    partial = _partial_dir(root)
    partial.mkdir(exist_ok=True)
    tmp = partial / f"case-{os.getpid()}-{next(_TEMP_NAMES)}-{key}{layout.suffix}"
    layout.write(ds, tmp)
    final = layout.path(root, key)
    if final.exists():               # resume=False: replace the old case
        old = partial / f"old-{os.getpid()}-{next(_TEMP_NAMES)}-{key}{layout.suffix}"
        os.rename(final, old)
        os.rename(tmp, final)
        shutil.rmtree(old, ignore_errors=True) if old.is_dir() else old.unlink()
    else:
        os.rename(tmp, final)
    return final


def open_sweep(store):
    """All cases in a sweep store as one Dataset (dimensions ``case``, ``time``), in plan order.

    Safe to call while a sweep is writing: it sees the cases finished so far.
    The data are loaded into memory; for very large stores open the Zarr
    hierarchy lazily with ``xarray.open_datatree(store, engine="zarr")``.

    Raises
    ------
    FileNotFoundError
        No store at that path.
    ValueError
        The path is not a sweep store.
    """
    root, layout = _open_store(store, create=False)
    cases = []
    for key in layout.keys(root):
        try:
            cases.append(layout.read(layout.path(root, key)))
        except FileNotFoundError:    # replaced by a resume=False rerun between listing and reading
            continue
    cases.sort(key=lambda ds: (ds.attrs.get("index", 0), ds.attrs["key"]))
    return _combine(cases, attrs={"store": str(root)})


def _column(values):
    """One coordinate from per-case values (None = the case has no such parameter)."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present) and len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([math.nan if v is None else float(v) for v in values])
    return np.array(["" if v is None else str(v) for v in values])


def _combine(cases, attrs=None):
    """Concatenate per-case Datasets along ``case`` (time padded with NaN, parameters as coordinates)."""
    import xarray as xr

    if not cases:
        return xr.Dataset(coords={"case": np.array([], dtype=str)}, attrs=dict(attrs or {}))
    # time (and any other dimension: q of different meshes) padded with NaN to the longest case
    size = {}
    for ds in cases:
        for d, n in ds.sizes.items():
            size[d] = max(size.get(d, 0), n)
    padded = []
    for ds in cases:
        short = {d: (0, size[d] - n) for d, n in ds.sizes.items() if n < size[d]}
        bare = (ds.pad(short) if short else ds).copy(deep=False)
        bare.attrs = {}              # (Dataset.drop_attrs rebuilds every variable: slow)
        padded.append(bare)
    out = xr.concat(padded, dim="case", join="outer", data_vars="all", coords="different", compat="equals")
    params = [json.loads(ds.attrs["parameters"]) for ds in cases]
    settings = [json.loads(ds.attrs["settings"]) for ds in cases]
    coords = {"case": [ds.attrs["key"] for ds in cases], "scene": _column([ds.attrs["scene"] for ds in cases]),
              "label": _column([ds.attrs.get("label", "") for ds in cases])}
    for k in RUN_SETTINGS + tuple(k for k in SIMULATE_OPTIONS if any(k in s for s in settings)):
        coords[k] = _column([s.get(k) for s in settings])
    for k in dict.fromkeys(k for p in params for k in p):
        coords[k] = _column([p.get(k) for p in params])
    out = out.assign_coords({k: ("case", v) if k != "case" else v for k, v in coords.items()})
    ts = [ds["t"].values for ds in cases]
    if all(len(t) == len(ts[0]) and np.array_equal(t, ts[0]) for t in ts):
        out = out.assign_coords(time=ts[0])
    out.attrs.update(attrs or {})
    out.attrs["settings"] = json.dumps(settings[0]) if all(s == settings[0] for s in settings) else ""
    return out


def probe_extremes(ds, probe):
    """The signed extreme (the value of largest magnitude over time) of a probe, per case and component.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep's Dataset.
    probe : str
        Probe name (the variable ``probe_<name>``).

    Returns
    -------
    xarray.DataArray
        Dimensions ``case`` and the probe's component dimension (if any);
        NaN for cases without a history.

    Raises
    ------
    ValueError
        When the Dataset has no such probe (the message lists the probes it has).
    """
    var = f"probe_{probe}".replace("/", "_")
    if var not in ds:
        have = [k[len("probe_"):] for k in ds.data_vars if k.startswith("probe_")]
        raise ValueError(f"the sweep recorded no probe {probe!r}; it has: {', '.join(have) or 'none'}")
    x = ds[var]
    where = abs(x).fillna(-1.0).argmax("time")
    return x.isel(time=where).where(ds["n_times"] > 0).drop_vars("time", errors="ignore")


# ------------------------------------------------------------------- run
def _default_workers():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def run_cases(specs, store=None, client=None, resume=True, n_workers=None, progress=False, on_case=None):
    """Run cases (from :func:`plan`) on Dask and return their Dataset; see :func:`sweep`.

    ``on_case(spec, ds)``, if given, is called in the driver with each case's
    Dataset as it finishes (cases read from the store first).
    """
    import xarray as xr  # noqa: F401  (fail here, not on a worker, when xarray is missing)

    specs = list(specs)
    keys = [s.key for s in specs]
    seen = {}
    for s, k in zip(specs, keys):
        if k in seen:
            raise ValueError(f"cases {seen[k]} and {s.index} of the plan are the same run (key {k})")
        seen[k] = s.index
    root, layout = _open_store(store, create=True) if store is not None else (None, None)
    results = {}
    if root is not None:
        _clean_partial(root)
        if resume:
            stored = set(layout.keys(root))
            for s, k in zip(specs, keys):
                if k in stored:
                    results[k] = layout.read(layout.path(root, k))
                    if on_case is not None:
                        on_case(s, results[k])
    skipped = len(results)
    todo = [s for s, k in zip(specs, keys) if k not in results]
    by_key = {k: s for s, k in zip(specs, keys)}
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(specs), initial=skipped, unit="case", desc="sweep", dynamic_ncols=True)

    def finished(ds):
        if root is not None and ds["status"].item() != "lost":
            _write_case(root, layout, ds)
        results[ds.attrs["key"]] = ds
        if on_case is not None:
            on_case(by_key[ds.attrs["key"]], ds)
        if bar is not None:
            bar.set_postfix_str(f"last: {ds['status'].item()}", refresh=False)
            bar.update(1)
    try:
        if todo and isinstance(client, str) and client == "serial":
            for s in todo:
                finished(run_case(s))
        elif todo:
            _run_on_dask(todo, client, n_workers, finished)
    finally:
        if bar is not None:
            bar.close()
    out = _combine([results[k] for k in keys],
                   attrs={"store": str(root) if root is not None else "", "computed": len(todo), "skipped": skipped})
    return out


#: Dask settings of the local clusters a sweep starts itself (:func:`local_cluster`)
LOCAL_CLUSTER_CONFIG = {
    # the statistical profiler samples every thread's stack every 10 ms: several per cent of a GIL-bound time loop
    "distributed.worker.profile.enabled": False,
    # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536 (freed memory goes back to the system at
    # once). Setting it also stops glibc from adapting its mmap threshold, and the time loop's many
    # short-lived arrays then cost page faults: some 20 000-40 000 per spin-up case instead of a few hundred,
    # and about 10 % more CPU time per case with two workers at once. The workers of our clusters keep
    # glibc's defaults (a value set in the environment still wins: Dask's precedence).
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    # every process of the cluster (scheduler and nannies in the driver, each worker) measures its event
    # loop's delay every 20 ms, for diagnostics only: a few per cent of a core each, taken from the
    # workers on a machine with one core per worker
    "distributed.admin.tick.interval": "200ms",
}


def local_cluster(n_workers=None, **kwargs):
    """The local Dask cluster a sweep starts when no ``client`` is given (the caller closes it).

    ``n_workers`` worker processes (default one per core), one thread each,
    no dashboard, with :data:`LOCAL_CLUSTER_CONFIG`; ``kwargs`` go to
    ``distributed.LocalCluster`` (e.g. ``env={...}`` for the workers).
    Start a cluster that stays up for several sweeps with it
    (``Client(local_cluster(2))``) so that its workers run cases as fast as
    the sweep's own.

    Raises
    ------
    ValueError
        ``n_workers`` is not a positive integer.
    """
    import dask
    from distributed import LocalCluster

    n = _default_workers() if n_workers is None else n_workers
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n_workers must be a positive integer, got {n_workers!r}")
    options = {"threads_per_worker": 1, "processes": True, "dashboard_address": None,
               "silence_logs": logging.ERROR, **kwargs}
    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        return LocalCluster(n_workers=int(n), **options)


@contextlib.contextmanager
def connect(client=None, n_workers=None):
    """Where cases run, as :func:`run_cases` takes it, for the length of a ``with`` block.

    ``"serial"`` and a ``distributed.Client`` are yielded as they are; a
    scheduler address yields a Client connected to it; None starts
    :func:`local_cluster` (``n_workers``) and yields its Client. What was
    opened here is closed at the end of the block. Several sweeps (a study
    over several scenes) run on one cluster this way.

    Raises
    ------
    TypeError
        ``client`` is none of these.
    ValueError
        A bad ``n_workers``.
    """
    from distributed import Client

    if isinstance(client, str) and client == "serial":
        yield client
        return
    if client is not None and not isinstance(client, (str, Client)):
        raise TypeError(f"client must be None, 'serial', a scheduler address or a distributed.Client, "
                        f"got {client!r}")
    if isinstance(client, Client):
        yield client
        return
    with contextlib.ExitStack() as stack:
        if client is None:
            cluster = stack.enter_context(local_cluster(n_workers))
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(Client(client))
        yield client


def _run_on_dask(specs, client, n_workers, finished):
    from distributed import as_completed

    with connect(client, n_workers) as client:
        _warm_up(client, specs)
        futures = {client.submit(run_case, s, key=s.task_name, pure=False): s for s in specs}
        for fut in as_completed(futures):
            s = futures.pop(fut)
            try:
                ds = fut.result()
            except Exception as exc:     # KilledWorker and the like: the case is lost, not failed
                ds = _case_dataset(s, "lost", f"{type(exc).__name__}: {_one_line(exc)}", None, math.nan, {})
            fut.release()
            finished(ds)


def _kernel_set(spec):
    """What decides which compiled units a case needs: the build key of its scene under its scheme
    (:func:`skfem_flex.compiled.pack.build_key`: families, storage, solver), read from the packed scene
    itself. A case whose scene cannot be built gets a key of its own (it fails in its task, not here)."""
    from .. import scenes
    from ..compiled.pack import build_key

    try:
        factory = scenes.get(spec.scene) if isinstance(spec.scene, str) else spec.scene
        return build_key(factory(**spec.params), spec.settings["integrator"],
                         python_only=spec.settings.get("compiled") is False)
    except Exception as exc:          # reported by the case itself
        return ("unbuilt", spec.task_name, type(exc).__name__)


def _warm_worker(specs, first, dask_worker=None):
    """The warm-up on one worker (``client.run``; unpickling this function imported the package there).
    The first worker of a machine runs the one-step ``specs`` one after another; the others import what
    a case needs meanwhile, and no kernel (they would compile it at the same time). Nothing comes back."""
    if dask_worker is not None and dask_worker.address in first:
        for spec in specs:               # one step each: compiles what is not cached, loads the rest
            run_case(spec)
    else:
        import xarray  # noqa: F401


def _warm_up(client, specs):
    """Before the cases start, run one step of one case per kernel set (:func:`_kernel_set`) on one worker
    per machine, one after another, so that every Numba kernel the sweep needs is compiled once per machine
    (into numba's on-disk cache) rather than by every worker at once; the other workers of the machine
    then load it from the cache. Machines with a single worker need no warm-up."""
    hosts = {}
    for addr, info in client.scheduler_info(n_workers=-1)["workers"].items():
        hosts.setdefault(info.get("host", addr), []).append(addr)
    first = [addrs[0] for addrs in hosts.values() if len(addrs) > 1]
    if not first:
        return
    shorts = {}
    for spec in specs:
        shorts.setdefault(_kernel_set(spec), dataclasses.replace(
            spec, settings={**spec.settings, "t_end": spec.settings["dt"]}, measures={}))
    try:
        client.run(_warm_worker, list(shorts.values()), first)
    except Exception:                # only a warm-up: the cases themselves report any failure
        pass


def sweep(scene, vary=None, cases=None, *, t_end=None, dt=None, integrator="energy-momentum", record=DEFAULT_RECORD,
          store=None, client=None, resume=True, fixed=None, record_every=1, budget=None, measures=None, name=None,
          n_workers=None, progress=False, **options):
    """Run a scene over a grid or list of parameters, one Dask task per case.

    Each case calls ``simulate(factory(**params), t_end, dt, integrator=...,
    record_every=..., **options)`` exactly as a serial call would, so the
    numbers are the same bit for bit.

    Parameters
    ----------
    scene : str or callable
        Catalogue name (``skfem-flex list``) or a factory returning a Scene
        (it must pickle; a lambda needs ``name``).
    vary : dict of str to list, optional
        Grid: every combination of the values (``itertools.product``, last
        name fastest). Names are factory parameters, the run settings
        ``t_end``, ``dt``, ``integrator`` or the simulate options (below).
    cases : list of dict, optional
        Explicit cases instead of a grid (same names as ``vary``).
    t_end, dt : float, optional
        End time and step, s, for cases that do not set them (default: the
        scene's registered defaults).
    integrator : str
        ``"energy-momentum"``, ``"trapezoidal"`` or ``"generalized-alpha"``.
    record : sequence of str
        Time series stored per case: groups of :data:`RECORD_GROUPS`
        (``"state"`` adds q and v, which can be large).
    store : path, optional
        Directory of the store: a Zarr hierarchy if the name ends in
        ``.zarr``, else one netCDF file per case (see the module notes).
        None keeps the results in memory only.
    client : None, "serial", str or distributed.Client
        None: start a local cluster of ``n_workers`` worker processes
        (:func:`local_cluster`: one thread each, default one per core) and
        close it at the end. A Client or a scheduler address: run on that
        cluster. ``"serial"``: run the cases one after another in this
        process (same code path). On a cluster, one worker per machine first
        runs one step of one case per scene, integrator, compiled-or-not and
        non-numeric parameters, so that the Numba kernels are compiled once
        per machine.
    resume : bool
        Read cases already in the store instead of running them; False
        recomputes and replaces them.
    fixed : dict, optional
        Parameters given to every case.
    record_every : int
        As in ``simulate``.
    budget : float, optional
        Wall-clock seconds one case may spend in its time loop; then it is
        stopped with status ``"stopped"`` and its history kept.
    measures : dict of str to callable, optional
        ``name -> fn(result) -> float`` evaluated on the worker; stored per case.
    name : str, optional
        Scene name for the key and the store (needed for lambdas).
    n_workers : int, optional
        Worker processes of the local cluster (client=None only).
    progress : bool
        tqdm progress bar over cases on stderr.
    **options
        ``rho_inf``, ``newton``, ``max_halvings``, ``project``, ``compiled``:
        passed to ``simulate`` (and part of the key).

    Returns
    -------
    xarray.Dataset
        Dimensions ``case`` (coordinate: the case key) and ``time`` (step
        index; times when all cases share them). Coordinates along ``case``:
        ``scene``, ``label``, ``t_end``, ``dt``, ``integrator`` and every
        parameter given. Per case and time: ``t`` (s), ``probe_<name>``,
        ``kinetic``, ``potential``, ``total_energy``, ``external_work``,
        ``energy_balance_error`` (J), ``constraint_residual``,
        ``velocity_constraint_residual``, ``newton_iterations`` (NaN past
        ``n_times``). Per case: ``status`` (:data:`STATUSES`), ``message``,
        ``wall_time`` (time loop, s), ``run_time`` (simulate call, s),
        ``steps``, ``halvings``, ``newton_total``, ``newton_per_step``,
        ``t_reached``, ``n_times``, ``max_energy_balance_error`` (J),
        ``relative_energy_error``, ``max_constraint_residual``, ``worker``
        and the measures. ``attrs``: ``computed`` and ``skipped`` (read from
        the store) case counts, ``store``.

    Raises
    ------
    ValueError, TypeError
        For a bad plan (see :func:`plan`) before anything runs. Cases that
        fail are not errors: they are rows with their status and message.
    """
    specs = plan(scene, vary, cases, fixed=fixed, t_end=t_end, dt=dt, integrator=integrator, record=record,
                 record_every=record_every, budget=budget, measures=measures, name=name, **options)
    return run_cases(specs, store=store, client=client, resume=resume, n_workers=n_workers, progress=progress)
