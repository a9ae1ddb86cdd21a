"""Registry of scene factories with parameter units."""
from __future__ import annotations

import inspect

__all__ = ["CATALOGUE", "register", "get", "parameters"]

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
