"""Energy conservation: the figures of Lee & Yun (docs/scenes.md, references), reproduced.

* Spring–mass systems with strain ε = u^n, V = ½ k ε² (m = k = 1, u0 = 1, v0 = 0):
  n = 1 (linear), n = 2 (m ü + 2u³ = 0) and n = 1.5 (V = ½ u³, unbounded below),
  each under the trapezoidal rule and the energy-conserving scheme (paper, figs. 1–5).
* The simple pendulum with the constraint C = (x·x − l²)/2 = 0, l = 0.5 m,
  v0 = 1.695 m/s (paper, fig. 6): trajectory, multiplier λ(t) and total energy.

Run ``python examples/energy_conservation.py [OUT_DIR]``; it prints a summary
table and writes PNGs (default ``examples/output``).
"""
import sys
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.run.plots import pyplot_for

DT = 0.1            # s, the spring–mass step
T_END = 40.0        # s
SCHEMES = ("trapezoidal", "energy-momentum")
EXPONENTS = (1.0, 2.0, 1.5)


def run(scene, **kwargs):
    """simulate(), returning the partial result when the motion escapes (exponent 1.5)."""
    try:
        return sf.simulate(scene, **kwargs), ""
    except sf.ConvergenceError as exc:
        return exc.result, str(exc)


spring_runs = {(n, s): run(sf.scenes.spring_mass(exponent=n), t_end=T_END, dt=DT, integrator=s)
               for n in EXPONENTS for s in SCHEMES}
pendulum_runs = {dt: sf.simulate(sf.scenes.pendulum(), t_end=10.0, dt=dt) for dt in (0.01, 0.05)}


def summary():
    lines = ["| system | scheme | completed | t reached (s) | max rel. energy error |", "|---|---|---|---|---|"]
    for (n, s), (res, msg) in spring_runs.items():
        err = np.max(np.abs(res.total_energy - res.total_energy[0])) / abs(res.total_energy[0])
        lines.append(f"| spring–mass n = {n:g} | {s} | {res.completed} | {res.t[-1]:.2f} | {err:.2e} |")
    for dt, res in pendulum_runs.items():
        err = np.max(np.abs(res.total_energy - res.total_energy[0])) / res.kinetic[0]
        lines.append(f"| pendulum, dt = {dt:g} s | energy-momentum | {res.completed} | {res.t[-1]:.2f} | {err:.2e} "
                     f"(max abs Φ {np.max(res.constraint_residual):.1e}, min λ {np.min(res.lam):.2f} N/m) |")
    return "\n".join(lines)


def plot(out_dir):
    plt, out_dir = pyplot_for(out_dir)
    fig, axes = plt.subplots(len(EXPONENTS), 3, figsize=(13, 9), constrained_layout=True)
    for row, n in enumerate(EXPONENTS):
        for s, style in zip(SCHEMES, ("--", "-")):
            res, msg = spring_runs[(n, s)]
            label = s + (" (escaped)" if msg else "")
            axes[row, 0].plot(res.t, res.q[:, 0], style, label=label)
            axes[row, 1].plot(res.t, res.v[:, 0], style, label=label)
            axes[row, 2].plot(res.t, res.total_energy, style, label=label)
        axes[row, 0].set_ylabel(f"n = {n:g}\nu (m)")
        axes[row, 1].set_ylabel("v (m/s)")
        axes[row, 2].set_ylabel("total energy (J)")
        if n == 1.5:
            for ax in axes[row]:
                ax.set_yscale("symlog")
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
            print(f"n = {n:g}, {s}: {msg}")
    where = plot(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    print(f"PNGs written to {where}")
