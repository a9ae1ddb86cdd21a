"""Registry of scene factories with parameter units."""
from __future__ import annotations

import inspect

__all__ = ["CATALOGUE", "register", "get", "parameters"]

#: name -> scene factory
CATALOGUE = {}


def register(**units):
    """Decorator adding a scene factory to the catalogue; ``units`` maps parameter names to units."""
    def deco(fn):
        fn.units = dict(units)
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
