"""Studies: error against run time (work–precision) and stability on stiff and extreme cases.

Both studies run catalogue scenes through :func:`~skfem_flex.run.simulate.simulate`
as the cases of a sweep (:mod:`skfem_flex.apps.sweep`: in this process by default,
on a Dask cluster with ``client=``, resumable with ``store=``), catch every
failure (a failed run is a row with its message and the time it happened,
never a crash) and return plain tables that the command line writes as
Markdown, CSV and PNG.

With exudyn installed (:func:`skfem_flex.apps.peer.peer_available`), the work–precision
study also runs the peer code's model of the flexible pendulum and the spin-up
(:mod:`skfem_flex.apps.peer`) at the same steps and measures its error in the same way
against the same reference (rows with scheme :data:`PEER_SCHEME`).
"""
from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import ellipj, ellipk, gamma

from . import peer as _peer
from ..run.simulate import simulate

__all__ = ["WorkPrecisionRow", "StabilityRow", "StudyRows", "work_precision", "stability", "write_table",
           "plot_work_precision", "plot_stability", "WORK_PRECISION_CASES", "STABILITY_CASES", "oscillator_period",
           "pendulum_period", "upward_crossings", "period_error", "history_error", "PEER_SCHEME"]

SCHEMES = ("energy-momentum", "trapezoidal", "generalized-alpha")
#: the scheme label of the peer code's rows in the work–precision study (exudyn's generalized-α, ρ∞ = 0.9)
PEER_SCHEME = "exudyn generalized-alpha"


# --------------------------------------------------------------- references
def oscillator_period(exponent=2.0, m=1.0, k=1.0, u0=1.0):
    """Exact period of m ü + n k u^(2n−1) = 0 from rest at u0 > 0 (V = ½ k u^(2n), 2n even).

    T = 4 ∫₀^u0 du / sqrt(2 (V(u0) − V(u))/m) = 4 sqrt(m/k) u0^(1−n) ∫₀¹ (1 − s^(2n))^(−1/2) ds,
    and ∫₀¹ (1 − s^p)^(−1/2) ds = Γ(1/p) Γ(1/2) / (p Γ(1/p + 1/2)).
    """
    p = 2.0 * exponent
    if abs(p - round(p)) > 1e-12 or round(p) % 2:
        raise ValueError(f"oscillator_period needs an even power 2n (bounded potential), got exponent {exponent!r}")
    integral = gamma(1.0 / p) * math.sqrt(math.pi) / (p * gamma(1.0 / p + 0.5))
    return 4.0 * math.sqrt(m / k) * u0 ** (1.0 - exponent) * integral


def pendulum_period(length=0.5, v0=1.695, g=9.81):
    """Exact period of a pendulum started at the bottom with speed v0: 4 sqrt(l/g) K(sin²(θ0/2))."""
    k2 = v0 ** 2 / (4.0 * g * length)          # sin²(θ0/2) = (1 − cos θ0)/2
    if k2 >= 1.0:
        raise ValueError(f"v0 = {v0} makes the pendulum go over the top: no period")
    return 4.0 * math.sqrt(length / g) * ellipk(k2)


def pendulum_position(t, length=0.5, v0=1.695, g=9.81):
    """Exact motion of the pendulum started at the bottom with horizontal speed v0, m.

    sin(θ/2) = k sn(√(g/l) t | k²) with k = v0 / (2√(g l)) (k < 1: it swings, never over the top);
    position l (sin θ, −cos θ), shape (len(t), 2).
    """
    k = v0 / (2.0 * math.sqrt(g * length))
    if k >= 1.0:
        raise ValueError(f"v0 = {v0} makes the pendulum go over the top: no swinging motion")
    theta = 2.0 * np.arcsin(k * ellipj(math.sqrt(g / length) * np.asarray(t, dtype=float), k * k)[0])
    return length * np.stack([np.sin(theta), -np.cos(theta)], axis=-1)


def upward_crossings(t, x, xdot):
    """Times at which x crosses zero upwards, by cubic Hermite interpolation within each step."""
    out = []
    for i in np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]:
        h = t[i + 1] - t[i]
        c = [x[i], xdot[i] * h, x[i + 1], xdot[i + 1] * h]
        # Hermite cubic in s ∈ [0, 1] written as a polynomial, roots by numpy
        poly = np.array([2 * c[0] + c[1] - 2 * c[2] + c[3], -3 * c[0] - 2 * c[1] + 3 * c[2] - c[3], c[1], c[0]])
        roots = [r.real for r in np.roots(poly) if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
        if roots:
            out.append(t[i] + min(roots) * h)
    return np.array(out)


def period_error(exact, coordinate=0):
    """An error function: |measured mean period − exact| / exact from upward zero crossings."""
    def err(result):
        tc = upward_crossings(result.t, result.q[:, coordinate], result.v[:, coordinate])
        if tc.size < 2:
            return float("nan")
        return abs((tc[-1] - tc[0]) / (tc.size - 1) - exact) / exact
    return err


def history_error(reference, probe):
    """An error function: max over time of |probe − reference| / max |reference|.

    ``reference`` is a Result (interpolated with cubic splines onto the
    run's times) or a callable t -> value.
    """
    if callable(reference):
        ref_fn = reference
    else:
        ref_fn = CubicSpline(reference.t, reference.probes[probe], axis=0)

    def err(result):
        ref = np.asarray(ref_fn(result.t))
        val = result.probes[probe]
        return float(np.max(np.abs(val - ref)) / max(np.max(np.abs(ref)), 1e-300))
    return err


# --------------------------------------------------------------- work–precision
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
    from ..scenes import pendulum
    return WorkPrecisionCase(pendulum, 5 * pendulum_period(), (0.05, 0.02, 0.01, 0.005, 0.002),
                             error=period_error(pendulum_period()),
                             description="period error against 4 sqrt(l/g) K(k²)")


def _quartic_case():
    from ..scenes import spring_mass
    period = oscillator_period(2.0)
    return WorkPrecisionCase(spring_mass, 10 * period, tuple(period / f for f in (10, 20, 40, 80, 160)),
                             error=period_error(period),
                             description="period error against the Gamma-function period")


def _spin_up_case():
    from ..scenes import spin_up_beam
    return WorkPrecisionCase(spin_up_beam, 10.0, (0.05, 0.02, 0.01, 0.005), probe="tip", reference_dt=0.005 / 8,
                             description="tip history (hub frame) against a run at Δt/8, ω = 4 rad/s, 8 elements, "
                                         "first 10 s",
                             peer=lambda dt, t_end: _peer.spin_up(n_elements=8, dt=dt, t_end=t_end, omega=4.0, T=15.0))


def _flexible_pendulum_case():
    from ..scenes import flexible_pendulum
    return WorkPrecisionCase(flexible_pendulum, 2.0, (0.01, 0.005, 0.002, 0.001), probe="tip",
                             reference_dt=0.001 / 8,
                             description="tip position (global frame) history against a run at Δt/8, 8 elements, "
                                         "released horizontal, first 2 s",
                             peer=lambda dt, t_end: _peer.flexible_pendulum(n_elements=8, dt=dt, t_end=t_end))


def _rotating_beam_case():
    from ..scenes import rotating_beam, rotating_beam_frequencies
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


class StudyRows(list):
    """A study's rows (a list, in the order of its cases) with the counts of the sweep that made them.

    Attributes
    ----------
    computed : int
        Runs made now.
    skipped : int
        Runs read back from the store (``resume=True``), timings included.
    """

    computed = 0
    skipped = 0


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
    from .sweep import plan

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
    specs = plan(_compiled_first(case.scene, min(dts), schemes), vary={"integrator": list(schemes),
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
    rows = _study_rows(specs, row, store, client, resume, n_workers)
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


def _study_rows(specs, row, store, client, resume, n_workers):
    """Run a study's cases as a sweep; ``row(spec, case Dataset)`` makes each table row (in plan order)."""
    from .sweep import run_cases

    rows = {}
    ds = run_cases(specs, store=store, client=client, resume=resume, n_workers=n_workers,
                   on_case=lambda s, c: rows.update({s.index: row(s, c)}))
    out = StudyRows(rows[s.index] for s in specs)
    out.computed, out.skipped = int(ds.attrs["computed"]), int(ds.attrs["skipped"])
    return out


def _reference(case, out_dir, name):
    """A fine energy-momentum run (loaded from out_dir if saved there before)."""
    from ..io.result import Result
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


# --------------------------------------------------------------- stability
@dataclass
class StabilityRow:
    """One case × scheme cell of the stability matrix."""

    case: str
    scheme: str
    bounded: bool
    completed: bool
    t_reached: float
    max_energy_error: float
    max_constraint_residual: float
    newton_per_step: float
    wall_time: float
    message: str = ""


@dataclass
class StabilityCase:
    """A scene factory run to t_end with step dt; ``energy_scale`` callable(result) -> J (default max T+|V|)."""

    scene: Callable
    t_end: float
    dt: float
    description: str = ""
    energy_scale: Callable = None
    bound: float = 10.0


def _quartic_stability(fraction):
    from ..scenes import spring_mass
    period = oscillator_period(2.0)
    return StabilityCase(spring_mass, 50 * period, period / fraction, f"quartic oscillator, Δt = T/{fraction}")


def _upright_pendulum():
    from ..scenes import pendulum
    # v0 just below the speed that reaches the top (2 sqrt(g l)): released near the upright position
    v0 = 0.9999 * 2.0 * math.sqrt(9.81 * 0.5)
    return StabilityCase(lambda: pendulum(v0=v0), 10.0, 0.02, "pendulum reaching 179° (near upright), Δt = 0.02 s")


def _long_pendulum():
    from ..scenes import pendulum
    return StabilityCase(pendulum, 1000.0, 0.01, "pendulum, 10⁵ steps, Δt = 0.01 s")


def _spin_up_stability(omega, dt):
    from ..scenes import spin_up_beam
    return StabilityCase(lambda: spin_up_beam(omega=omega), 30.0, dt,
                         f"spin-up ω = {omega:g} rad/s, 8 elements, Δt = {dt:g} s, 30 s")


def _slender_beam():
    from ..scenes import rotating_beam
    h = 0.01                     # m: L/h = 1000 for L = 10 m
    ea = 2.8e7
    return StabilityCase(lambda: rotating_beam(0.0, EI=ea * h * h / 12.0, rhoI=1.2 * h * h / 12.0, n_elements=16,
                                               perturbation=0.5),
                         2.0, 0.01, "slender cantilever (L/h = 1000, 16 elements) in free vibration, Δt = 0.01 s, "
                                    "25× its shortest period, 2 s")


def _free_beam():
    from ..scenes import free_beam
    return StabilityCase(free_beam, 20.0, 5e-3, "free-flying beam after a tip pulse, Δt = 5 ms, 20 s")


#: name (a plain identifier) -> callable returning a StabilityCase; the label says what it is
STABILITY_CASES = {
    "quartic_T2": lambda: _quartic_stability(2),
    "quartic_T4": lambda: _quartic_stability(4),
    "quartic_T10": lambda: _quartic_stability(10),
    "quartic_T50": lambda: _quartic_stability(50),
    "pendulum_near_upright": _upright_pendulum,
    "pendulum_1e5_steps": _long_pendulum,
    **{f"spin_up_omega{w:g}_dt{1000 * dt:g}ms": (lambda w=w, dt=dt: _spin_up_stability(w, dt))
       for w in (4.0, 10.0) for dt in (0.005, 0.01, 0.02, 0.05)},
    "slender_beam": _slender_beam,
    "free_beam": _free_beam,
}

#: ``quick`` runs (a smoke test of the study): at most this many steps and seconds of wall time per run
QUICK_STEPS, QUICK_BUDGET = 100, 1.0


def _energy_error(scale_fn):
    """A measure: max |energy balance error| / scale (scale_fn(result), default max(|T| + |V|))."""
    def measure(res):
        scale = scale_fn(res) if scale_fn else float(np.max(np.abs(res.kinetic) + np.abs(res.potential)))
        return float(np.max(np.abs(res.energy_balance_error))) / max(scale, 1e-300)
    return measure


def _finite_state(res):
    return float(np.all(np.isfinite(res.q)))


#: (scene factory, schemes) already run once in this process by :func:`_compiled_first`
_WARMED = set()


def _compiled_first(factory, dt, schemes):
    """``factory`` that, the first time in a process, runs one step of its scene under every scheme, so
    that the kernels are compiled (cold Numba cache) or loaded from the cache (about 0.05 s per loop)
    before the case starts: the sweep builds the scene before it starts a case's wall-clock budget and
    run time, so neither counts against the first step size's run."""
    def build(**params):
        scene = factory(**params)
        key = (getattr(factory, "__qualname__", repr(factory)), tuple(schemes), tuple(sorted(params.items())))
        if key not in _WARMED:
            _WARMED.add(key)
            for scheme in schemes:
                try:
                    simulate(factory(**params), dt, dt, integrator=scheme, handle_signals=False)
                except Exception:        # only a warm-up: the case itself reports any failure
                    pass
        return scene
    return build


def stability(cases=None, schemes=SCHEMES, progress=None, quick=False, budget=300.0, store=None, client="serial",
              resume=True, n_workers=None):
    """The stability matrix: every case under every scheme.

    Parameters
    ----------
    cases : sequence of str, optional
        Names in ``STABILITY_CASES`` (default: all).
    schemes : sequence of str
    progress : callable(str), optional
    quick : bool
        Shorten every run to 1/20 of its length and at most ``QUICK_STEPS`` steps, with at
        most ``QUICK_BUDGET`` s of wall time each (a smoke test of the study).
    budget : float
        Wall-clock seconds a single run may use; a slower run is stopped and
        reported as not completed, with the time it reached. The compile of
        the Numba kernels on a cold cache is not counted: it happens before.
    store, client, resume, n_workers
        As in :func:`skfem_flex.apps.sweep.sweep`: every case × scheme is a case
        of one sweep (keyed ``stability:<case>``), in this process by default.

    Returns
    -------
    StudyRows of StabilityRow
        A run is *bounded* when it completed, its state stayed finite and its
        energy error stayed below ``bound`` times the energy scale. A failure
        is a row with ``completed = False``, the time reached and the message.
        ``computed`` and ``skipped`` count the runs made now and read from
        the store.
    """
    from .sweep import plan

    names = list(STABILITY_CASES) if cases is None else list(cases)
    for n in names:
        if n not in STABILITY_CASES:
            raise ValueError(f"no stability case {n!r}; known: {', '.join(STABILITY_CASES)}")
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not math.isfinite(budget) or budget <= 0:
        raise ValueError(f"budget must be a positive number of seconds, got {budget!r}")
    if quick:
        budget = min(budget, QUICK_BUDGET)
    specs, bounds = [], {}
    for n in names:
        case = STABILITY_CASES[n]()
        t_end = min(case.t_end / 20.0, QUICK_STEPS * case.dt) if quick else case.t_end
        bounds[n] = case.bound
        specs += plan(_compiled_first(case.scene, case.dt, schemes), vary={"integrator": list(schemes)},
                      t_end=t_end, dt=case.dt, budget=budget,
                      record=(), measures={"energy_error": _energy_error(case.energy_scale),
                                           "finite": _finite_state},
                      name=f"stability:{n}", label=n)
    for i, spec in enumerate(specs):
        spec.index = i

    def row(spec, c):
        n, scheme = spec.label, spec.settings["integrator"]
        e_err = float(c["energy_error"]) if "energy_error" in c else float("nan")
        completed = c["status"].item() == "completed"
        bounded = bool(completed and "finite" in c and float(c["finite"]) == 1.0 and e_err < bounds[n])
        steps = int(c["steps"])
        r = StabilityRow(n, scheme, bounded, completed, float(c["t_reached"]), e_err,
                         float(c["max_constraint_residual"]), float(c["newton_total"]) / max(steps, 1),
                         float(c["run_time"]), str(c["message"].item()))
        if progress:
            progress(f"{n} / {scheme}: {'bounded' if bounded else 'NOT bounded'}, energy error {e_err:.2g}")
        return r
    return _study_rows(specs, row, store, client, resume, n_workers)


def plot_stability(rows, path):
    """The stability matrix as a picture: log10 of the energy error, crossed where not bounded."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r.case for r in rows))
    schemes = list(dict.fromkeys(r.scheme for r in rows))
    grid = np.full((len(cases), len(schemes)), np.nan)
    fig, ax = plt.subplots(figsize=(2.2 + 1.8 * len(schemes), 1.2 + 0.45 * len(cases)), constrained_layout=True)
    for r in rows:
        i, j = cases.index(r.case), schemes.index(r.scheme)
        grid[i, j] = np.log10(max(r.max_energy_error, 1e-17)) if np.isfinite(r.max_energy_error) else 2.0
        if r.bounded:
            label = f"{r.max_energy_error:.1e}"
        elif r.message.startswith("stopped:"):
            label = f"stopped at\nt = {r.t_reached:.3g} s"     # wall-clock budget, not a failure
        else:
            label = f"failed at\nt = {r.t_reached:.3g} s" if not r.completed else "unbounded"
        ax.text(j, i, label, ha="center", va="center", fontsize=8,
                color="black" if r.bounded else "red", fontweight="normal" if r.bounded else "bold")
    im = ax.imshow(grid, cmap="viridis", vmin=-16, vmax=1, aspect="auto")
    ax.set_xticks(range(len(schemes)), schemes)
    ax.set_yticks(range(len(cases)), cases)
    fig.colorbar(im, ax=ax, label="log10 max relative energy error")
    ax.set_title("stability matrix")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ---------------------------------------------------------------- tables
def write_table(rows, stem):
    """Write rows (dataclasses) as ``stem.csv`` and ``stem.md``; returns the two paths."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    dicts = [asdict(r) for r in rows]
    cols = list(dicts[0]) if dicts else []
    with open(stem.with_suffix(".csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(dicts)

    def fmt(v):
        if isinstance(v, float):
            return f"{v:.3g}"
        return str(v).replace("|", "/").replace("\n", " ")
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(fmt(d[c]) for c in cols) + " |" for d in dicts]
    stem.with_suffix(".md").write_text("\n".join(lines) + "\n")
    return stem.with_suffix(".csv"), stem.with_suffix(".md")
