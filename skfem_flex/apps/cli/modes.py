"""``skfem-flex modes`` and ``skfem-flex campbell``: the modes of a scene about a static, steady or
initial state, and its frequencies against one parameter (a Campbell diagram)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from .arguments import positive_int
from .errors import UsageError, one_line
from .outputs import jsonable, prepare_out
from .settings import catalogue_scene, scene_settings, vary_values

__all__ = ["add_modes", "add_campbell"]


def _analysis(name, compute):
    """``compute()``; bad input becomes a UsageError (exit 2), an equilibrium that cannot be found
    (a SimulationError) is reported in one line and gives None (exit 1)."""
    from ...errors import SimulationError

    try:
        return compute()
    except SimulationError as exc:
        print(f"skfem-flex: error: {one_line(exc)}", file=sys.stderr)
        return None
    except (ValueError, TypeError) as exc:
        msg = one_line(exc)
        raise UsageError(msg if msg.startswith(f"scene {name!r}") else f"scene {name!r}: {msg}") from None


def _cmd_modes(args):
    from ...analysis import modes, write_mode_series
    from ...io.files import write_text_atomically

    factory = catalogue_scene(args.scene)
    params = scene_settings(args.scene, args.set)
    out = Path(args.out) if args.out is not None else Path("results") / f"{args.scene}-modes"
    scene = _analysis(args.scene, lambda: factory(**params))
    result = None if scene is None else _analysis(args.scene, lambda: modes(scene, about=args.about,
                                                                          n_modes=args.n))
    if result is None:
        return 1
    prepare_out(out)
    rows = result.table()
    lines = ["mode,omega_rad_s,frequency_hz,damping_ratio,growth_rate_1_s"]
    lines += [f"{r['mode']},{r['omega_rad_s']!r},{r['frequency_hz']!r},{r['damping_ratio']!r},"
              f"{r['growth_rate_1_s']!r}" for r in rows]
    write_text_atomically(out / "modes.csv", "\n".join(lines) + "\n")
    pvds = [] if args.no_vtk else write_mode_series(scene, result, out, frames=args.frames)
    summary = {"scene": args.scene, "parameters": dict(scene.parameters) or params, "about": result.about,
               "modes": rows, "stable": result.stable, "vtk": [str(p) for p in pvds]}
    write_text_atomically(out / "summary.json", json.dumps(jsonable(summary), indent=2) + "\n")
    if not args.quiet:
        print(f"{args.scene}: {len(rows)} modes about the {result.about} state"
              f"{'' if result.stable else ' (UNSTABLE: a mode grows)'}")
        print(f"{'mode':>4} {'omega (rad/s)':>15} {'f (Hz)':>13} {'damping ratio':>14} {'growth (1/s)':>13}")
        for r in rows:
            print(f"{r['mode']:>4} {r['omega_rad_s']:>15.8g} {r['frequency_hz']:>13.8g} "
                  f"{r['damping_ratio']:>14.4g} {r['growth_rate_1_s']:>13.4g}")
        print(f"outputs in {out.resolve()}/: modes.csv, summary.json"
              + (f", {len(pvds)} VTK series (one .pvd per mode, a cycle from t = 0 to 1)" if pvds else ""))
    return 0


def _cmd_campbell(args):
    import inspect as _inspect

    from ...analysis import campbell
    from ... import scenes

    factory = catalogue_scene(args.scene)
    params = scene_settings(args.scene, args.set)
    key, sep, text = args.vary.partition("=")
    key = key.strip()
    known = {p: d for p, d, _ in scenes.parameters(args.scene)}
    if not sep or not key:
        raise UsageError(f"--vary expects NAME=VALUES, got {args.vary!r}")
    if key not in known:
        raise UsageError(f"scene {args.scene!r} has no parameter {key!r}; it has: {', '.join(known) or 'none'}")
    default = None if known[key] is _inspect.Parameter.empty else known[key]
    if isinstance(default, (bool, str)):
        raise UsageError(f"--vary {key}: only numeric parameters can be varied, {key} is {type(default).__name__}")
    values = vary_values(key, text.strip(), default)
    params.pop(key, None)
    out = Path(args.out) if args.out is not None else Path("results") / f"{args.scene}-campbell"
    diagram = _analysis(args.scene, lambda: campbell(factory, key, values, n_modes=args.n, about=args.about,
                                                     **params))
    if diagram is None:
        return 1
    prepare_out(out)
    csv_path, md_path = diagram.write_table(out / "campbell")
    png = out / "campbell.png"
    diagram.plot(png)
    if not args.quiet:
        print(md_path.read_text(), end="")
        print(f"wrote {md_path}, {csv_path} and {png}")
    return 0


def _add_analysis_options(p, about_default):
    p.add_argument("scene", metavar="SCENE", help="scene name from 'skfem-flex list'")
    p.add_argument("--set", action="extend", nargs="+", metavar="KEY=VALUE", default=[],
                   help="scene parameter, converted to the type of its default (repeatable)")
    p.add_argument("--n", type=positive_int, default=6, metavar="N", help="number of modes (default 6)")
    p.add_argument("--about", choices=["static", "steady", "initial"], default=about_default,
                   help=f"state to linearize about (default: {about_default})")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory")
    p.add_argument("--quiet", action="store_true", help="no table on stdout")


def add_modes(sub):
    """Add the ``modes`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser("modes", help="modes of a scene about its static, steady or initial state",
                       description="Linearize a catalogue scene about its static equilibrium, its steady "
                                   "motion or its initial state and write the lowest modes (modes.csv, "
                                   "summary.json) and one VTK series per mode animating it (default "
                                   "results/SCENE-modes).")
    _add_analysis_options(p, "static")
    p.add_argument("--frames", type=positive_int, default=24, metavar="F",
                   help="frames per cycle of each mode's VTK series (default 24)")
    p.add_argument("--no-vtk", action="store_true", help="skip the VTK series")
    p.set_defaults(func=_cmd_modes)


def add_campbell(sub):
    """Add the ``campbell`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser("campbell", help="Campbell diagram: frequencies against a scene parameter",
                       description="Frequencies of a catalogue scene against one parameter, each point "
                                   "linearized about its own steady (or static/initial) state; writes "
                                   "campbell.csv, campbell.md and campbell.png (default results/SCENE-campbell).")
    _add_analysis_options(p, "steady")
    p.add_argument("--vary", required=True, metavar="NAME=VALUES",
                   help="parameter and its values: a comma list (0,4,8) or START:STOP:COUNT")
    p.set_defaults(func=_cmd_campbell)
