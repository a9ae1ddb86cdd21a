"""Energy conservation: the figures of Lee & Yun (docs/scenes.md, references), reproduced.

* Spring–mass systems with strain ε = u^n, V = ½ k ε² (m = k = 1, u0 = 1, v0 = 0):
  n = 1 (linear), n = 2 (m ü + 2u³ = 0) and n = 1.5 (V = ½ u³, unbounded below),
  each under the trapezoidal rule and the energy-conserving scheme (paper, figs. 1–5).
* The simple pendulum with the constraint C = (x·x − l²)/2 = 0, l = 0.5 m,
  v0 = 1.695 m/s (paper, fig. 6): trajectory, multiplier λ(t) and total energy.

The n = 1.5 runs end early, as they must: V = ½ k u³ is unbounded below, and the exact motion
runs off to u → −∞ in the finite time (energy E = ½ k u0³, ½ m u̇² = E − V(u))

    t* = ∫_{−∞}^{u0} du / √(k (u0³ − u³)/m) ≈ 4.2065 s.

Both schemes stop near t*, each in its own way, and the table reports how (a result, not a
failure of the example):

* the trapezoidal rule does not conserve energy: as the stiffness 3 k u grows along the escape, its
  energy error grows without bound (0.5 J at the start, about 1e9 J at t = 4.1 s), and ``simulate``'s
  divergence guard stops it with a ``DivergenceError``;
* the energy-conserving scheme keeps E = 0.5 J to the Newton tolerance (1e-9 relative at u ≈ −1500)
  up to its last step; Newton then fails as u runs away within one step (``ConvergenceError``,
  after halving the step).

Run ``python examples/energy_conservation.py [OUT_DIR]``; it prints a summary
table and writes PNGs (default ``examples/output``).

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): the spring–mass runs end at
10 s instead of 40 s (after the escape at t*), the pendulum runs at 2 s instead of 10 s.
"""
import os
import sys
from pathlib import Path

import numpy as np
from scipy.integrate import quad

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
DT = 0.1                                # s, the spring–mass step
T_END = 10.0 if QUICK else 40.0         # s
PENDULUM_T_END = 2.0 if QUICK else 10.0  # s
SCHEMES = ("trapezoidal", "energy-momentum")
EXPONENTS = (1.0, 2.0, 1.5)


def escape_time(m=1.0, k=1.0, u0=1.0):
    """Time (s) at which the exact motion of V = ½ k u³, released at rest from u0 > 0, reaches u = −∞.

    t* = ∫_{−∞}^{u0} du / √(k (u0³ − u³)/m), split at u = 0; the tail is finite because the
    integrand falls as |u|^(−3/2).
    """
    rate = np.sqrt(k / m)
    near = quad(lambda u: 1.0 / np.sqrt(u0 ** 3 - u ** 3), 0.0, u0)[0]
    tail = quad(lambda u: 1.0 / np.sqrt(u0 ** 3 + u ** 3), 0.0, np.inf)[0]
    return (near + tail) / rate


ESCAPE_TIME = escape_time()


def run(scene, **kwargs):
    """simulate(); a run that breaks off returns its partial result and why it stopped.

    Returns (result, ""), or (partial result, "ConvergenceError: ...") when Newton failed, or
    (partial result, "DivergenceError: ...") when ``simulate``'s guard stopped a run whose energy
    grew by orders of magnitude.
    """
    try:
        return sf.simulate(scene, **kwargs), ""
    except sf.SimulationError as exc:
        return exc.result, f"{type(exc).__name__}: {exc}"


spring_runs = {(n, s): run(sf.scenes.spring_mass(exponent=n), t_end=T_END, dt=DT, integrator=s)
               for n in EXPONENTS for s in SCHEMES}
pendulum_runs = {dt: sf.simulate(sf.scenes.pendulum(), t_end=PENDULUM_T_END, dt=dt) for dt in (0.01, 0.05)}


def ended_by(msg):
    """How a spring–mass run ended, in words."""
    if not msg:
        return "completed"
    kind = msg.split(":", 1)[0]
    return {"DivergenceError": "energy blew up (DivergenceError)",
            "ConvergenceError": "Newton failed (ConvergenceError)"}.get(kind, kind)


def summary():
    lines = [f"Spring–mass n = 1.5: the exact motion escapes to u = −∞ at t* = {ESCAPE_TIME:.4f} s.", "",
             "| system | scheme | ended | t reached (s) | max rel. energy error |", "|---|---|---|---|---|"]
    for (n, s), (res, msg) in spring_runs.items():
        err = np.max(np.abs(res.total_energy - res.total_energy[0])) / abs(res.total_energy[0])
        lines.append(f"| spring–mass n = {n:g} | {s} | {ended_by(msg)} | {res.t[-1]:.2f} | {err:.2e} |")
    for dt, res in pendulum_runs.items():
        err = np.max(np.abs(res.total_energy - res.total_energy[0])) / res.kinetic[0]
        lines.append(f"| pendulum, dt = {dt:g} s | energy-momentum | {ended_by('')} | {res.t[-1]:.2f} | {err:.2e} "
                     f"(max abs Φ {np.max(res.constraint_residual):.1e}, min λ {np.min(res.lam):.2f} N/m) |")
    return "\n".join(lines)


def plot(out_dir):
    plt, out_dir = pyplot_for(out_dir)
    fig, axes = plt.subplots(len(EXPONENTS), 3, figsize=(13, 9), constrained_layout=True)
    for row, n in enumerate(EXPONENTS):
        for s, style in zip(SCHEMES, ("--", "-")):
            res, msg = spring_runs[(n, s)]
            label = s + (f" ({ended_by(msg)})" if msg else "")
            axes[row, 0].plot(res.t, res.q[:, 0], style, label=label)
            axes[row, 1].plot(res.t, res.v[:, 0], style, label=label)
            axes[row, 2].plot(res.t, res.total_energy, style, label=label)
        axes[row, 0].set_ylabel(f"n = {n:g}\nu (m)")
        axes[row, 1].set_ylabel("v (m/s)")
        axes[row, 2].set_ylabel("total energy (J)")
        if n == 1.5:
            for ax in axes[row]:
                ax.set_yscale("symlog")
                ax.axvline(ESCAPE_TIME, color="0.6", lw=0.8, ls=":")
        axes[row, 2].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    fig.suptitle(f"Spring–mass systems, ε = u^n, Δt = {DT} s: trapezoidal rule vs energy-conserving scheme")
    fig.savefig(out_dir / "spring_mass.png", dpi=110)
    plt.close(fig)

    res = pendulum_runs[0.01]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), constrained_layout=True)
    axes[0].plot(res.q[:, 0], res.q[:, 1])
    axes[0].set_aspect("equal")
    axes[0].set_xlabel("x (m)")
    axes[0].set_ylabel("y (m)")
    axes[0].set_title("trajectory")
    axes[1].plot(res.t, res.lam[:, 0])
    axes[1].set_xlabel("t (s)")
    axes[1].set_ylabel("λ (N/m)")
    axes[1].set_title("multiplier: never vanishes")
    for dt, r in pendulum_runs.items():
        axes[2].plot(r.t, (r.total_energy - r.total_energy[0]) / r.kinetic[0], label=f"Δt = {dt} s")
    axes[2].set_xlabel("t (s)")
    axes[2].set_ylabel("(E − E0)/T0")
    axes[2].set_title("energy error (round-off)")
    axes[2].legend()
    fig.suptitle("Simple pendulum, l = 0.5 m, v0 = 1.695 m/s, energy-conserving scheme")
    fig.savefig(out_dir / "pendulum.png", dpi=110)
    plt.close(fig)
    return out_dir


if __name__ == "__main__":
    print(summary())
    for (n, s), (res, msg) in spring_runs.items():
        if msg:
            print(f"n = {n:g}, {s}, stopped at t = {res.t[-1]:.2f} s (escape at t* = {ESCAPE_TIME:.2f} s): {msg}")
    where = plot(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    print(f"PNGs written to {where}")
