"""Registry of scene factories with parameter units."""
from __future__ import annotations

import inspect

import math

__all__ = ["CATALOGUE", "register", "get", "parameters", "positive_count", "positive_value"]

#: name -> scene factory
CATALOGUE = {}


def register(t_end=None, dt=None, **units):
    """Decorator adding a scene factory to the catalogue.

    Parameters
    ----------
    t_end, dt : float, optional
        Default end time and step (s) of ``skfem-flex run SCENE``, stored in
        ``fn.defaults`` (only the ones given); the CLI falls back to its own
        defaults for the others.
    **units
        Parameter name -> unit, shown by ``skfem-flex list``.
    """
    defaults = {k: float(v) for k, v in (("t_end", t_end), ("dt", dt)) if v is not None}

    def deco(fn):
        fn.units = dict(units)
        fn.defaults = dict(defaults)
        CATALOGUE[fn.__name__] = fn
        return fn
    return deco


def get(name):
    """The factory of scene ``name``; ``ValueError`` listing the known scenes otherwise."""
    if name not in CATALOGUE:
        raise ValueError(f"unknown scene {name!r}; known scenes: {', '.join(sorted(CATALOGUE))}")
    return CATALOGUE[name]


def parameters(name):
    """[(parameter, default, unit)] of scene ``name``."""
    fn = get(name)
    out = []
    for p in inspect.signature(fn).parameters.values():
        out.append((p.name, p.default, fn.units.get(p.name, "")))
    return out


def positive_count(name, value):
    """``value`` as a positive int, or ``ValueError`` naming the scene parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def positive_value(name, value):
    """``value`` as a finite positive float, or ``ValueError`` naming the scene parameter."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite positive number, got {value!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be finite and positive, got {value!r}")
    return value
