"""A sweep's plan: the cases (:class:`CaseSpec`, plain data keyed by a hash) from a grid or a list.

:func:`plan` expands ``vary`` (a grid) or ``cases`` (a list) into cases, checks every name and value
against the scene's factory before anything runs, and gives each case its key: a SHA-256 hash of
(scene name, parameters, settings, recorded groups, measure names).
"""
from __future__ import annotations

import dataclasses
import hashlib
import inspect
import itertools
import json
import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["CaseSpec", "plan", "RUN_SETTINGS", "SIMULATE_OPTIONS", "RECORD_GROUPS", "DEFAULT_RECORD"]

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
#: per-case scalar variables written by the sweep (measures may not use these names)
_RESERVED = {"status", "message", "wall_time", "run_time", "steps", "halvings", "newton_total", "newton_per_step",
             "t_reached", "n_times", "max_energy_balance_error", "relative_energy_error", "max_constraint_residual",
             "worker", "t", "scene", "label", "case"}


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
    from ... import scenes

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
    from ...schemes import SCHEMES as INTEGRATORS

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
