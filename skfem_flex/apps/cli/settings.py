"""Scene settings as typed on the command line: the catalogue scene by name, ``--set key=value`` and
``--vary NAME=VALUES`` converted to the types of the scene's parameters."""
from __future__ import annotations

import inspect
import math

from .errors import UsageError

__all__ = ["convert_setting", "split_setting", "scene_settings", "vary_values", "catalogue_scene", "DEFAULT_SCENE",
           "FALLBACK_T_END", "FALLBACK_DT"]

#: scene run by ``skfem-flex run`` without a SCENE argument
DEFAULT_SCENE = "spin_up_beam"
#: end time and step (s) for scenes that register no defaults of their own
FALLBACK_T_END, FALLBACK_DT = 1.0, 0.01

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


def split_setting(item, message):
    """(key, text) of a ``KEY=TEXT`` command-line item; a UsageError with ``message`` (formatted with
    ``item``) when it has no ``=`` or no key."""
    key, sep, text = item.partition("=")
    key = key.strip()
    if not sep or not key:
        raise UsageError(message.format(item=item))
    return key, text


def scene_settings(name, items):
    """{parameter: value} from ``--set`` items, converted with the defaults' types."""
    from ... import scenes

    params = {p: d for p, d, _ in scenes.parameters(name)}
    out = {}
    for item in items or ():
        key, text = split_setting(item, "--set expects key=value, got {item!r} (give the scene name before --set)")
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


def vary_values(key, text, default):
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


def catalogue_scene(name):
    """The factory of the catalogue scene ``name`` (UsageError naming the known scenes if there is none)."""
    from ... import scenes

    if name not in scenes.CATALOGUE:
        raise UsageError(f"unknown scene {name!r}; known scenes: {', '.join(sorted(scenes.CATALOGUE))}")
    return scenes.get(name)
