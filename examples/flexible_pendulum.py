"""Flexible pendulum: a floating-frame beam pinned at one end, released at rest from horizontal.

Scene ``skfem_flex.scenes.flexible_pendulum`` (L = 1 m, EA = 1e6 N, ρA = 1 kg/m, 8 elements, g = 9.81):

* EI = 1e2 N m² (flexible) and EI = 1e4 N m² (nearly rigid) with the energy-conserving scheme,
  Δt = 1e-3 s, 2 s: constraint residual |Φ| after every step, energy balance against m g L/2;
* the same flexible case with generalized-α (ρ∞ = 0.9), which damps the high frequencies;
* the rigid compound pendulum θ'' = −(3g/2L) cos θ (scipy, tight tolerances) for comparison.

Before each timed run, a run of a few steps of the same scene and scheme compiles the Numba kernels
(or loads them from numba's cache); its wall time is reported apart as "compile and start-up".

Run ``python examples/flexible_pendulum.py [OUT_DIR]`` (default ``examples/output/``).
Importing the module computes the results without plotting.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 0.2 s instead of 2 s.
"""
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
G, LENGTH, RHOA, RHOI = 9.81, 1.0, 1.0, 1e-4
T_END, DT = (0.2 if QUICK else 2.0), 1e-3
E_REF = RHOA * LENGTH * G * LENGTH / 2          # m g L/2, J
CASES = {("EI = 1e2", "energy-momentum"): 1e2, ("EI = 1e4", "energy-momentum"): 1e4,
         ("EI = 1e2", "generalized-alpha"): 1e2}


def warm_up(scene, integrator, steps=3):
    """Wall time (s) of a few steps of ``scene``: the one-off compile (or cache load) of its kernels."""
    start = time.perf_counter()
    sf.simulate(scene, steps * DT, DT, integrator=integrator)
    return time.perf_counter() - start


startup, runs = {}, {}
for (case, scheme), EI in CASES.items():
    scene = sf.scenes.flexible_pendulum(EI=EI)
    startup[case, scheme] = warm_up(scene, scheme)
    runs[case, scheme] = sf.simulate(scene, T_END, DT, integrator=scheme)

J_PIVOT = RHOA * LENGTH ** 3 / 3 + RHOI * LENGTH
rigid = solve_ivp(lambda t, y: [y[1], -G * RHOA * LENGTH * LENGTH / 2 * math.cos(y[0]) / J_PIVOT],
                  (0, T_END), [0.0, 0.0], t_eval=runs[("EI = 1e2", "energy-momentum")].t, rtol=1e-12, atol=1e-12)
rigid_tip = LENGTH * np.stack([np.cos(rigid.y[0]), np.sin(rigid.y[0])], axis=1)


def summary():
    lines = ["| case | scheme | max abs Φ | max abs energy balance / (m g L/2) | max tip deflection (mm) "
             "| max tip distance to rigid bar (mm) | Newton it./step | compile and start-up (s) | wall (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (case, scheme), r in runs.items():
        lines.append(f"| {case} | {scheme} | {np.max(r.constraint_residual):.1e} "
                     f"| {np.max(np.abs(r.energy_balance_error)) / E_REF:.1e} "
                     f"| {1e3 * np.max(np.abs(r.probes['tip_deflection'][:, 1])):.2f} "
                     f"| {1e3 * np.max(np.linalg.norm(r.probes['tip'] - rigid_tip, axis=1)):.1f} "
                     f"| {np.mean(r.newton_iterations[1:]):.2f} | {startup[case, scheme]:.1f} | {r.wall_time:.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    from skfem_flex.io.plots import plot_snapshots

    print(f"Flexible pendulum, 8 elements, Δt = {DT:g} s, {T_END:g} s")
    print(summary())
    plt, output = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.5))
    ax[0].plot(rigid_tip[:, 0], rigid_tip[:, 1], "k:", label="rigid bar")
    for (case, scheme), r in runs.items():
        ax[0].plot(r.probes["tip"][:, 0], r.probes["tip"][:, 1], label=f"{case}, {scheme}", lw=0.9)
        ax[1].plot(r.t, 1e3 * r.probes["tip_deflection"][:, 1], label=f"{case}, {scheme}", lw=0.9)
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("x (m)")
    ax[0].set_ylabel("y (m)")
    ax[0].set_title("tip path")
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel("transverse tip deflection in the beam frame (mm)")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(output / "flexible_pendulum_tip.png", dpi=120)

    fig, ax = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for (case, scheme), r in runs.items():
        ax[0].semilogy(r.t[1:], np.abs(r.energy_balance_error[1:]) / E_REF + 1e-18, label=f"{case}, {scheme}")
        ax[1].plot(r.t, r.reactions["pivot"][:, 1], label=f"{case}, {scheme}", lw=0.9)
    ax[0].set_ylabel("|E − E₀| / (m g L/2)")
    ax[1].set_ylabel("vertical pin force on the beam (N)")
    ax[1].set_xlabel("t (s)")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(output / "flexible_pendulum_energy.png", dpi=120)
    plot_snapshots(sf.scenes.flexible_pendulum(), runs[("EI = 1e2", "energy-momentum")],
                   output / "flexible_pendulum_snapshots.png", count=6)
    print(f"\nPNGs written to {output}")
