"""``skfem-flex list``: the catalogue's scenes with their parameters, defaults and units."""
from __future__ import annotations

import inspect

from .settings import DEFAULT_SCENE, FALLBACK_DT, FALLBACK_T_END

__all__ = ["add_list"]


def _cmd_list(args):
    from ... import scenes

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


def add_list(sub):
    """Add the ``list`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser("list", help="list the scenes with their parameters, defaults and units",
                       description="List the catalogue scenes with their parameters, defaults and units.")
    p.set_defaults(func=_cmd_list)
