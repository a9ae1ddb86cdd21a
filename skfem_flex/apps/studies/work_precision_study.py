"""The work–precision study: error against run time for every scheme and step, with the peer code's
rows when exudyn is installed (:data:`PEER_SCHEME`)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .. import peer as _peer
from ...run.simulate import simulate
from .references import history_error, oscillator_period, pendulum_period, period_error, upward_crossings
from .rows import SCHEMES, compiled_first, study_rows

__all__ = ["WorkPrecisionRow", "WorkPrecisionCase", "work_precision", "plot_work_precision", "WORK_PRECISION_CASES",
           "PEER_SCHEME"]

#: the scheme label of the peer code's rows in the work–precision study (exudyn's generalized-α, ρ∞ = 0.9)
PEER_SCHEME = "exudyn generalized-alpha"


@dataclass
class WorkPrecisionRow:
    """One run of a work–precision study."""

    case: str
    scheme: str
    dt: float
    steps: int
    wall_time: float
    error: float
    newton_per_step: float
    message: str = ""


@dataclass
class WorkPrecisionCase:
    """A scene factory with a run length and a way to measure the error of a run.

    ``error`` is either a callable(result) -> float, or None: then a
    reference run at ``reference_dt`` with the energy-momentum scheme is
    made (and saved when the study has an output folder) and the error is
    the history error of ``probe`` against it.

    ``peer``, for such history cases, is None or callable(dt, t_end) -> run,
    the same problem in the peer code (a model of :mod:`skfem_flex.apps.peer`,
    whose ``run()`` returns (t, probe, seconds) with the probe as our scene's
    ``probe``): its error is the same history error against the same reference.
    """

    scene: Callable
    t_end: float
    dts: tuple
    error: Callable = None
    probe: str = ""
    reference_dt: float = 0.0
    description: str = ""
    peer: Callable = None


def _pendulum_case():
    from ...scenes import pendulum
    return WorkPrecisionCase(pendulum, 5 * pendulum_period(), (0.05, 0.02, 0.01, 0.005, 0.002),
                             error=period_error(pendulum_period()),
                             description="period error against 4 sqrt(l/g) K(k²)")


def _quartic_case():
    from ...scenes import spring_mass
    period = oscillator_period(2.0)
    return WorkPrecisionCase(spring_mass, 10 * period, tuple(period / f for f in (10, 20, 40, 80, 160)),
                             error=period_error(period),
                             description="period error against the Gamma-function period")


def _spin_up_case():
    from ...scenes import spin_up_beam
    return WorkPrecisionCase(spin_up_beam, 10.0, (0.05, 0.02, 0.01, 0.005), probe="tip", reference_dt=0.005 / 8,
                             description="tip history (hub frame) against a run at Δt/8, ω = 4 rad/s, 8 elements, "
                                         "first 10 s",
                             peer=lambda dt, t_end: _peer.spin_up(n_elements=8, dt=dt, t_end=t_end, omega=4.0, T=15.0))


def _flexible_pendulum_case():
    from ...scenes import flexible_pendulum
    return WorkPrecisionCase(flexible_pendulum, 2.0, (0.01, 0.005, 0.002, 0.001), probe="tip",
                             reference_dt=0.001 / 8,
                             description="tip position (global frame) history against a run at Δt/8, 8 elements, "
                                         "released horizontal, first 2 s",
                             peer=lambda dt, t_end: _peer.flexible_pendulum(n_elements=8, dt=dt, t_end=t_end))


def _rotating_beam_case():
    from ...scenes import rotating_beam, rotating_beam_frequencies
    omega = 4.0
    period = 2.0 * math.pi / float(rotating_beam_frequencies(omega, n_modes=1)[0])

    def err(result):
        tc = upward_crossings(result.t, result.probes["tip"][:, 1], np.gradient(result.probes["tip"][:, 1], result.t))
        if tc.size < 2:
            return float("nan")
        return abs((tc[-1] - tc[0]) / (tc.size - 1) - period) / period
    return WorkPrecisionCase(lambda: rotating_beam(omega), 8 * period, tuple(period / f for f in (10, 20, 40, 80)),
                             error=err, description="period of the first in-plane bending mode at ω = 4 rad/s "
                                                    "against the linearised modal analysis")


#: name -> callable returning a WorkPrecisionCase (built lazily so that imports stay light)
WORK_PRECISION_CASES = {"spring_mass": _quartic_case, "pendulum": _pendulum_case, "spin_up_beam": _spin_up_case,
                        "rotating_beam": _rotating_beam_case, "flexible_pendulum": _flexible_pendulum_case}


def work_precision(case, schemes=SCHEMES, dts=None, out_dir=None, name="case", progress=None, store=None,
                   client="serial", resume=True, n_workers=None, peer=True):
    """Error against run time for every scheme and step.

    Parameters
    ----------
    case : WorkPrecisionCase or str
        A case or the name of one in ``WORK_PRECISION_CASES``.
    schemes : sequence of str
    dts : sequence of float, optional
        Steps (s); default the case's.
    out_dir : path, optional
        Where a reference run is saved (``reference_<name>.npz``) and reused.
    progress : callable(str), optional
        Called with a line per run.
    store, client, resume, n_workers
        As in :func:`skfem_flex.apps.sweep.sweep`: the runs are the cases of a
        sweep (scheme × dt) keyed ``work-precision:<name>``. The default
        client ``"serial"`` runs them one after another in this process, so
        that their wall times are not disturbed by each other; with a
        ``store`` a rerun reuses the runs already there (timings included).

    Returns
    -------
    StudyRows of WorkPrecisionRow
        Failed runs have ``error = nan`` and their message; ``computed`` and
        ``skipped`` count the runs made now and read from the store.

        With ``peer`` true, exudyn importable (:func:`skfem_flex.apps.peer.peer_available`)
        and a case that has a peer model (``flexible_pendulum``, ``spin_up_beam``),
        rows with scheme :data:`PEER_SCHEME` follow: the peer's model of the
        same problem at each Δt, in this process after our runs (never from the
        store; counted in ``computed``), its error the same history error of the
        same probe against the same reference run, its wall time exudyn's solve
        (its model set-up excluded, as our scene's build is), its ``steps`` the
        steps exudyn took.
    peer : bool
        False leaves the peer out even when exudyn is installed.
    """
    from ..sweep import plan

    if isinstance(case, str):
        if case not in WORK_PRECISION_CASES:
            raise ValueError(f"no work-precision case {case!r}; known: {sorted(WORK_PRECISION_CASES)}")
        name, case = case, WORK_PRECISION_CASES[case]()
    dts = tuple(case.dts if dts is None else dts)
    if not dts or any((not np.isfinite(d)) or d <= 0 for d in dts):
        raise ValueError(f"dts must be positive steps, got {dts!r}")
    error_fn = case.error
    if error_fn is None:
        ref = _reference(case, out_dir, name)
        error_fn = history_error(ref, case.probe)
    with_peer = bool(peer) and case.peer is not None and case.error is None and _peer.peer_available()
    specs = plan(compiled_first(case.scene, min(dts), schemes), vary={"integrator": list(schemes),
                                                                        "dt": [float(d) for d in dts]}, t_end=case.t_end,
                 record=(), measures={"error": error_fn}, name=f"work-precision:{name}", label=name)

    def row(spec, c):
        err, msg = float(c["error"]) if "error" in c else float("nan"), str(c["message"].item())
        if c["status"].item() != "completed":
            err = float("nan")
        elif not np.isfinite(err) and not msg:
            msg = "error not measurable (no full period)"
        steps = int(c["steps"])
        r = WorkPrecisionRow(name, spec.settings["integrator"], float(spec.settings["dt"]), steps,
                             float(c["wall_time"]), err, float(c["newton_total"]) / max(steps, 1), msg)
        if progress:
            progress(f"{name} {r.scheme} dt={r.dt:.3g}: error {r.error:.3g}, {r.wall_time:.3g} s")
        return r
    rows = study_rows(specs, row, store, client, resume, n_workers)
    if with_peer:
        for dt in dts:
            rows.append(_peer_row(case, name, float(dt), error_fn, progress))
            rows.computed += 1
    return rows


def _peer_row(case, name, dt, error_fn, progress):
    """One run of the case's peer model at ``dt``, measured by ``error_fn`` (a history error) as ours are."""
    from types import SimpleNamespace

    run = case.peer(dt, case.t_end)
    try:
        t, probe, seconds = run()
        err = float(error_fn(SimpleNamespace(t=np.asarray(t), probes={case.probe: np.asarray(probe)})))
        msg = "" if np.isfinite(err) else "error not measurable"
    except Exception as exc:              # a failed peer run is a row, as ours are
        seconds, err, msg = float("nan"), float("nan"), f"{type(exc).__name__}: {str(exc).strip()}".splitlines()[0]
    stats = getattr(run, "stats", {})
    steps = int(stats.get("steps", round(case.t_end / dt)))
    newton = stats.get("newton", float("nan"))
    r = WorkPrecisionRow(name, PEER_SCHEME, dt, steps, float(seconds), err, float(newton) / max(steps, 1), msg)
    if progress:
        progress(f"{name} {r.scheme} dt={r.dt:.3g}: error {r.error:.3g}, {r.wall_time:.3g} s")
    return r


def _reference(case, out_dir, name):
    """A fine energy-momentum run (loaded from out_dir if saved there before)."""
    from ...io.result import Result
    path = Path(out_dir) / f"reference_{name}.npz" if out_dir else None
    if path is not None and path.exists() and hasattr(Result, "load"):
        return Result.load(path)
    dt = case.reference_dt or min(case.dts) / 8.0
    ref = simulate(case.scene(), case.t_end, dt, integrator="energy-momentum")
    if path is not None and hasattr(ref, "save"):
        path.parent.mkdir(parents=True, exist_ok=True)
        ref.save(path)
    return ref


def plot_work_precision(rows, path, title="work–precision"):
    """Log–log error against wall time: one panel per case, one line per scheme; returns the path.

    Our schemes are solid lines with circles; the peer code's rows (scheme starting with
    ``"exudyn"``) dashed black lines with squares."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r.case for r in rows))
    schemes = list(dict.fromkeys(r.scheme for r in rows))
    ncol = min(2, len(cases))
    nrow = (len(cases) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 3.8 * nrow), constrained_layout=True, squeeze=False)
    ours = [s for s in schemes if not s.startswith("exudyn")]
    peers = [s for s in schemes if s.startswith("exudyn")]
    style = {s: dict(fmt="o-", color=f"C{k}") for k, s in enumerate(ours)}
    style.update({s: dict(fmt="s--", color=("k", "0.45", "0.7")[k % 3], markerfacecolor="none")
                  for k, s in enumerate(peers)})
    for ax, case in zip(axes.flat, cases):
        for scheme in schemes:
            sel = [r for r in rows if r.case == case and r.scheme == scheme]
            if not sel:
                continue
            good = [r for r in sel if np.isfinite(r.error) and r.error > 0]
            kw = dict(style[scheme])
            line, = ax.loglog([r.wall_time for r in good], [r.error for r in good], kw.pop("fmt"), label=scheme,
                              **kw)
            failed = [r for r in sel if not np.isfinite(r.error)]
            if failed:
                line.set_label(f"{scheme} ({len(failed)} run(s) failed)")
        ax.set_title(case)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(cases):]:
        ax.set_visible(False)
    fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
