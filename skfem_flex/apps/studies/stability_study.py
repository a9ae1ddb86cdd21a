"""The stability study: every stiff or extreme case under every scheme, each run bounded or not, under a
wall-clock budget."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .references import oscillator_period
from .rows import SCHEMES, compiled_first, study_rows

__all__ = ["StabilityRow", "StabilityCase", "stability", "plot_stability", "STABILITY_CASES", "QUICK_STEPS",
           "QUICK_BUDGET"]


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
    from ...scenes import spring_mass
    period = oscillator_period(2.0)
    return StabilityCase(spring_mass, 50 * period, period / fraction, f"quartic oscillator, Δt = T/{fraction}")


def _upright_pendulum():
    from ...scenes import pendulum
    # v0 just below the speed that reaches the top (2 sqrt(g l)): released near the upright position
    v0 = 0.9999 * 2.0 * math.sqrt(9.81 * 0.5)
    return StabilityCase(lambda: pendulum(v0=v0), 10.0, 0.02, "pendulum reaching 179° (near upright), Δt = 0.02 s")


def _long_pendulum():
    from ...scenes import pendulum
    return StabilityCase(pendulum, 1000.0, 0.01, "pendulum, 10⁵ steps, Δt = 0.01 s")


def _spin_up_stability(omega, dt):
    from ...scenes import spin_up_beam
    return StabilityCase(lambda: spin_up_beam(omega=omega), 30.0, dt,
                         f"spin-up ω = {omega:g} rad/s, 8 elements, Δt = {dt:g} s, 30 s")


def _slender_beam():
    from ...scenes import rotating_beam
    h = 0.01                     # m: L/h = 1000 for L = 10 m
    ea = 2.8e7
    return StabilityCase(lambda: rotating_beam(0.0, EI=ea * h * h / 12.0, rhoI=1.2 * h * h / 12.0, n_elements=16,
                                               perturbation=0.5),
                         2.0, 0.01, "slender cantilever (L/h = 1000, 16 elements) in free vibration, Δt = 0.01 s, "
                                    "25× its shortest period, 2 s")


def _free_beam():
    from ...scenes import free_beam
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
    from ..sweep import plan

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
        specs += plan(compiled_first(case.scene, case.dt, schemes), vary={"integrator": list(schemes)},
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
    return study_rows(specs, row, store, client, resume, n_workers)


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
