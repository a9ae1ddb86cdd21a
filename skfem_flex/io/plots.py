"""Plots of a run with matplotlib, without a display.

Every function builds a :class:`matplotlib.figure.Figure` directly (no
``pyplot``, no GUI backend, no global state), saves it as PNG when ``path`` is
given, and returns it. :func:`save_plots` writes the standard set a run of
``skfem-flex run`` produces.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_energy", "plot_probes", "plot_constraints", "plot_snapshots", "save_plots", "pyplot_for",
           "plot_campbell", "plot_sweep_extremes", "probe_units"]


def pyplot_for(directory):
    """(``matplotlib.pyplot`` on the display-free Agg backend, ``directory`` as a Path, created).

    For scripts (the examples) that draw their own figures with pyplot and save them as PNG.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return plt, directory


def _figure(rows=1, cols=1, size=(7.0, 4.0), **kw):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, cols, squeeze=False, **kw)
    return fig, axes


def _finish(fig, path, dpi=110):
    if path is not None:
        fig.savefig(Path(path), dpi=dpi)
    return fig


def plot_energy(result, path=None):
    """Kinetic, potential and total energy, external work, and the energy balance error against time.

    Top: T, V, E = T + V, the external work W (J) and E₀ + W, which E follows
    when the balance holds. Bottom: the balance error E − E₀ − W (J).
    """
    fig, ax = _figure(2, 1, size=(7.0, 5.5), sharex=True)
    t = result.t
    top, bottom = ax[0, 0], ax[1, 0]
    top.plot(t, result.kinetic, label="kinetic T")
    top.plot(t, result.potential, label="potential V")
    top.plot(t, result.total_energy, label="total E = T + V", lw=2)
    top.plot(t, result.external_work, label="external work W")
    top.plot(t, result.total_energy[0] + result.external_work, "k:", label="E₀ + W")
    top.set_ylabel("energy (J)")
    top.legend(fontsize="small", ncols=2)
    top.grid(alpha=0.3)
    bottom.plot(t, result.energy_balance_error, color="C3")
    bottom.set_ylabel("E − E₀ − W (J)")
    bottom.set_xlabel("t (s)")
    bottom.grid(alpha=0.3)
    fig.suptitle(f"energy ({result.scheme}, Δt = {result.dt:.3g} s)" if result.scheme else "energy")
    return _finish(fig, path)


def probe_units(scene):
    """{probe name: unit} of a scene's probes, for axis labels.

    A probe's own ``unit`` attribute when it has one; "m" for the position probes of
    :mod:`skfem_flex.bodies.probes` (:class:`~skfem_flex.bodies.probes.PointProbe`: a point's
    global position; :class:`~skfem_flex.bodies.probes.LinearProbe`: positions and
    displacements linear in the coordinates, as the beams' ``displacement_probe``); "SI" for
    any other callable, whose value the package cannot know more of than that it is in SI units.
    """
    from ..bodies.probes import LinearProbe, PointProbe

    out = {}
    for name, probe in getattr(scene, "probes", {}).items():
        unit = getattr(probe, "unit", None)
        if not isinstance(unit, str) or not unit:
            unit = "m" if isinstance(probe, (PointProbe, LinearProbe)) else "SI"
        out[name] = unit
    return out


def plot_probes(result, path=None, units=None):
    """One panel per probe against time (every component of a vector probe).

    ``units`` ({probe name: unit}, e.g. from :func:`probe_units`) labels the y axes, "name (unit)";
    probes without an entry are labelled "name (SI)".
    """
    units = units or {}
    names = list(result.probes)
    if not names:
        fig, ax = _figure(1, 1, size=(7.0, 2.0))
        ax[0, 0].text(0.5, 0.5, "no probes", ha="center", va="center")
        ax[0, 0].set_axis_off()
        return _finish(fig, path)
    fig, ax = _figure(len(names), 1, size=(7.0, 1.2 + 2.2 * len(names)), sharex=True)
    for a, k in zip(ax[:, 0], names):
        val = np.asarray(result.probes[k], dtype=float).reshape(len(result.t), -1)
        for i in range(val.shape[1]):
            a.plot(result.t, val[:, i], label=f"{k}[{i}]" if val.shape[1] > 1 else k)
        a.set_ylabel(f"{k} ({units.get(k, 'SI')})")
        a.grid(alpha=0.3)
        if val.shape[1] > 1:
            a.legend(fontsize="small")
    ax[-1, 0].set_xlabel("t (s)")
    return _finish(fig, path)


def plot_constraints(result, path=None):
    """Constraint residuals max |Φ| and max |Φ_q v + Φ_t| against time (log scale)."""
    fig, ax = _figure(1, 1)
    a = ax[0, 0]
    for arr, label in [(result.constraint_residual, "max |Φ(q, t)|"),
                       (result.velocity_constraint_residual, "max |Φ_q v + Φ_t|")]:
        arr = np.abs(np.asarray(arr, dtype=float))
        if np.any(arr > 0):
            # exact zeros cannot be shown on a log scale: they are left out (gaps)
            a.semilogy(result.t, np.where(arr > 0, arr, np.nan), ".-", ms=2, lw=0.8, label=label)
        else:
            a.plot(result.t, arr, label=f"{label} (zero throughout)")
    a.set_xlabel("t (s)")
    a.set_ylabel("residual")
    a.grid(alpha=0.3, which="both")
    a.legend(fontsize="small")
    return _finish(fig, path)


def _draw_geometry(a, geom, color):
    from matplotlib.collections import LineCollection, PolyCollection

    pts = np.asarray(geom.points, dtype=float)
    xy = np.zeros((len(pts), 2))
    xy[:, : min(2, pts.shape[1])] = pts[:, :2]
    for ctype, conn in geom.cells:
        conn = np.asarray(conn, dtype=int)
        if conn.ndim == 1:
            conn = conn[:, None]
        if ctype == "vertex":
            a.plot(xy[conn[:, 0], 0], xy[conn[:, 0], 1], "o", color=color, ms=5)
        elif ctype.startswith("line"):
            if conn.shape[1] == 3:          # meshio/VTK line3: end, end, middle
                conn = conn[:, [0, 2, 1]]
            a.add_collection(LineCollection([xy[c] for c in conn], colors=color, linewidths=1.8))
            a.plot(xy[np.unique(conn), 0], xy[np.unique(conn), 1], ".", color=color, ms=2.5)
        else:                               # polygons, triangles, quads: outlines
            a.add_collection(PolyCollection([xy[c] for c in conn], facecolors=color, edgecolors=color,
                                            alpha=0.35, linewidths=1.2))
    return xy


def plot_snapshots(scene, result, path=None, count=6):
    """A strip of ``count`` snapshots of the deformed system at equally spaced recorded times.

    Uses ``body.geometry`` (global frame) of every body of ``scene`` at
    ``result.q``/``result.v``; all panels share the same limits and an equal
    aspect ratio; colours distinguish bodies.
    """
    n = len(result.t)
    count = max(1, min(int(count), n))
    idx = np.unique(np.round(np.linspace(0, n - 1, count)).astype(int))
    geoms = []
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    for i in idx:
        q, v = result.q[i], result.v[i]
        geoms.append([b.geometry(q[scene.slice(b)], v[scene.slice(b)]) for b in scene.bodies])
        for g in geoms[-1]:
            xy = np.asarray(g.points, dtype=float)[:, :2]
            if len(xy):
                lo, hi = np.minimum(lo, xy.min(axis=0)), np.maximum(hi, xy.max(axis=0))
    if np.all(np.isfinite(lo)):
        span = max(float(np.max(hi - lo)), 1e-9)
        mid = 0.5 * (lo + hi)
        half = 0.5 * np.maximum(hi - lo, 0.4 * span) + 0.08 * span
    else:
        mid, half = np.zeros(2), np.ones(2)
    width = min(2.4 * len(idx), 16.0)
    height = float(np.clip(width / len(idx) * half[1] / half[0] + 0.9, 2.0, 6.0))
    fig, ax = _figure(1, len(idx), size=(width, height), sharex=True, sharey=True)
    for a, i, gs in zip(ax[0], idx, geoms):
        for bid, g in enumerate(gs):
            _draw_geometry(a, g, f"C{bid % 10}")
        a.set_title(f"t = {result.t[i]:.4g} s", fontsize="small")
        a.set_aspect("equal", adjustable="box")
        a.grid(alpha=0.3)
        a.tick_params(labelsize="x-small")
    ax[0, 0].set_xlim(mid[0] - half[0], mid[0] + half[0])
    ax[0, 0].set_ylim(mid[1] - half[1], mid[1] + half[1])
    ax[0, 0].set_xlabel("x (m)", fontsize="small")
    ax[0, 0].set_ylabel("y (m)", fontsize="small")
    fig.suptitle(scene.name)
    return _finish(fig, path)


def plot_campbell(diagram, path=None, orders=None):
    """Campbell diagram: frequencies (Hz) against the parameter, one line per mode order.

    ``diagram`` is a :class:`~skfem_flex.analysis.CampbellDiagram`. Points of growing modes
    (Re s > 0) are marked with a red ×. ``orders``: excitation orders n drawn as lines
    f = n · value/2π (for a spin rate in rad/s); default (1,) when the parameter's unit is
    rad/s, none otherwise.
    """
    fig, ax = _figure(1, 1, size=(7.0, 4.5))
    a = ax[0, 0]
    values = np.asarray(diagram.values, dtype=float)
    f = diagram.frequency_hz
    for k in range(f.shape[1]):
        a.plot(values, f[:, k], ".-", label=f"mode {k + 1}")
        bad = diagram.growth_rate[:, k] > 1e-9 * np.maximum(np.abs(diagram.omega[:, k]), 1.0)
        if np.any(bad):
            a.plot(values[bad], f[bad, k], "x", color="C3", ms=8)
    if orders is None:
        orders = (1,) if diagram.unit == "rad/s" else ()
    for n in orders:
        a.plot(values, n * values / (2 * np.pi), "k--", lw=0.8, label=f"{n}× excitation")
    a.set_xlabel(f"{diagram.parameter} ({diagram.unit})" if diagram.unit else diagram.parameter)
    a.set_ylabel("frequency (Hz)")
    a.set_title(f"Campbell diagram: {diagram.scene_name} (about the {diagram.about} state; × growing)")
    a.grid(alpha=0.3)
    a.legend(fontsize="small", ncols=2)
    return _finish(fig, path)


def save_plots(scene, result, directory, prefix=""):
    """Write the standard plots of a run as PNG files into ``directory``.

    ``energy.png`` and ``snapshots.png`` always, ``probes.png`` when the
    scene has probes, ``constraints.png`` when it has constraints.

    Returns
    -------
    dict of str to Path
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    out = {}
    jobs = [("energy", lambda p: plot_energy(result, p))]
    if result.probes:
        jobs.append(("probes", lambda p: plot_probes(result, p, probe_units(scene))))
    if scene.n_constraints:
        jobs.append(("constraints", lambda p: plot_constraints(result, p)))
    jobs.append(("snapshots", lambda p: plot_snapshots(scene, result, p)))
    for name, job in jobs:
        p = directory / f"{prefix}{name}.png"
        job(p)
        out[name] = p
    return out


def plot_sweep_extremes(extremes, parameters, path=None, title=""):
    """A probe's extreme against the varied parameters of a sweep: one panel per component.

    Parameters
    ----------
    extremes : array (n_cases,) or (n_cases, n_components)
        Signed extreme of the probe per case (see :func:`skfem_flex.apps.sweep.probe_extremes`).
    parameters : dict of str to array (n_cases,)
        The varied parameters. The first one is the x axis; every
        combination of the others is a line of its own. Cases whose extreme
        is NaN (failed before recording) are left out.
    """
    ext = np.asarray(extremes, dtype=float).reshape(len(np.asarray(next(iter(parameters.values())))), -1)
    names = list(parameters)
    x = np.asarray(parameters[names[0]])
    others = [np.asarray(parameters[k]) for k in names[1:]]
    groups = list(dict.fromkeys(zip(*others))) if others else [()]
    fig, ax = _figure(ext.shape[1], 1, size=(7.0, 1.4 + 2.6 * ext.shape[1]), sharex=True)
    numeric = np.issubdtype(x.dtype, np.number)
    for c, a in enumerate(ax[:, 0]):
        for g, combo in enumerate(groups):
            sel = np.array([tuple(o[i] for o in others) == combo for i in range(len(x))], dtype=bool)
            sel &= np.isfinite(ext[:, c])
            order = np.argsort(x[sel], kind="stable") if numeric else np.arange(sel.sum())
            label = ", ".join(f"{k} = {v}" for k, v in zip(names[1:], combo)) or None
            a.plot(x[sel][order], ext[sel, c][order], "o-", color=f"C{g % 10}", label=label)
        a.set_ylabel(f"extreme [{c}]" if ext.shape[1] > 1 else "extreme")
        a.grid(alpha=0.3)
        if others:
            a.legend(fontsize="small")
    ax[-1, 0].set_xlabel(names[0])
    if title:
        fig.suptitle(title)
    return _finish(fig, path)
