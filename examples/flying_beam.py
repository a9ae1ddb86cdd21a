"""Free-flying flexible beam of Simo & Vu-Quoc (1986), geometrically exact beam.

J. C. Simo, L. Vu-Quoc, "On the dynamics of flexible beams under large overall motions — the plane
case: part II", J. Appl. Mech. 53 (1986) 855–863 (also Simo & Tarnow, ZAMP 43, 1992): a beam
(L = 10, EA = GA = 1e4, EI = 100, ρA = 1, ρI = 10) at rest from (6, 0) to (0, 8); at the end (6, 0)
a horizontal force 8 and a moment −80 act for 0 ≤ t ≤ 2.5 s, nothing after; no gravity. The beam
tumbles and flies off to the right with the centre of mass at 2 m/s.

At import the script runs the energy-conserving scheme (10 P1 elements, Δt = 0.05 s, 12 s) and the
trapezoidal rule (Δt = 0.1 s) and keeps the histories. ``python examples/flying_beam.py [OUT_DIR]``
prints a summary and writes ``flying_beam_snapshots.png`` (shapes every 1 s) and
``flying_beam_conservation.png`` (energy, linear and angular momentum) to OUT_DIR (default
``examples/output``).

Energy, linear and angular momentum are conserved by the energy-momentum scheme to the Newton
tolerance after the load stops (section angles advance at their Cayley rate; see
:mod:`skfem_flex.bodies.exact.strain`); the linear momentum then is the impulse of the load,
8 × 2.5 = 20 N s along x.

Before each timed run, a run of a few steps of the same scene and scheme compiles the Numba kernels
(or loads them from numba's cache); its wall time is reported apart as "compile and start-up".

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 4 s instead of 12 s (1.5 s of free
flight after the load).
"""
import os
import sys
import time
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
N_ELEMENTS = 10
T_END = 4.0 if QUICK else 12.0
DT = 0.05
DT_TRAPEZOIDAL = 0.1
T_LOAD = 2.5


def warm_up(scene, dt, integrator, steps=3):
    """Wall time (s) of a few steps of ``scene``: the one-off compile (or cache load) of its kernels."""
    start = time.perf_counter()
    sf.simulate(scene, t_end=steps * dt, dt=dt, integrator=integrator)
    return time.perf_counter() - start


scene = sf.scenes.flying_beam(n_elements=N_ELEMENTS)
body = scene.bodies[0]
startup = {"energy-momentum": warm_up(scene, DT, "energy-momentum"),
           "trapezoidal": warm_up(scene, DT_TRAPEZOIDAL, "trapezoidal")}
energy_momentum = sf.simulate(scene, t_end=T_END, dt=DT, integrator="energy-momentum")
try:
    trapezoidal = sf.simulate(scene, t_end=T_END, dt=DT_TRAPEZOIDAL, integrator="trapezoidal")
except sf.SimulationError as exc:          # recorded, not required
    trapezoidal = exc.result


def drift_after_load(res, values):
    """max |x − x(t_load⁺)| / |x(t_load⁺)| over the free flight."""
    after = res.t > T_LOAD + 1e-9
    x = np.asarray(values)[after]
    return float(np.max(np.abs(x - x[0])) / np.max(np.abs(x[0])))


def summary():
    lines = ["| scheme | Δt (s) | reached t (s) | energy drift | linear momentum after load | "
             "angular momentum drift | Newton it./step | compile and start-up (s) | wall (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for res in (energy_momentum, trapezoidal):
        p = res.linear_momentum[-1]
        lines.append(f"| {res.scheme} | {res.dt:g} | {res.t[-1]:.2f} | "
                     f"{drift_after_load(res, res.total_energy):.1e} | ({p[0]:.12g}, {p[1]:.2g}) | "
                     f"{drift_after_load(res, res.angular_momentum):.1e} | "
                     f"{res.newton_iterations[1:].mean():.2f} | {startup[res.scheme]:.1f} | {res.wall_time:.2f} |")
    return "\n".join(lines)


def plot(out_dir):
    plt, out_dir = pyplot_for(out_dir)
    res = energy_momentum
    fig, ax = plt.subplots(figsize=(11, 4.5), constrained_layout=True)
    times = np.arange(0.0, T_END + 1e-9, 1.0)
    cmap = plt.get_cmap("viridis")
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(res.t - t)))
        xy = body.nodal_positions(res.q[i])
        ax.plot(xy[:, 0], xy[:, 1], "-o", ms=2.5, color=cmap(k / max(len(times) - 1, 1)))
        ax.annotate(f"{res.t[i]:g}", xy[0], fontsize="x-small")
    ax.plot(*res.probes["centre_of_mass"].T, "k:", lw=0.8, label="centre of mass")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper left")
    ax.set_title(f"Flying beam (Simo & Vu-Quoc 1986): shapes every 1 s, labels at the loaded end; "
                 f"{N_ELEMENTS} elements, Δt = {DT} s, energy-momentum")
    fig.savefig(out_dir / "flying_beam_snapshots.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4), constrained_layout=True)
    for r, style in ((energy_momentum, "-"), (trapezoidal, "--")):
        label = f"{r.scheme}, Δt = {r.dt:g} s"
        axes[0].plot(r.t, r.total_energy, style, label=label)
        axes[1].plot(r.t, r.linear_momentum[:, 0], style, label=f"p_x, {label}")
        axes[2].plot(r.t, r.angular_momentum, style, label=label)
    axes[0].set_ylabel("total energy (J)")
    axes[1].set_ylabel("linear momentum p_x (kg m/s)")
    axes[2].set_ylabel("angular momentum about O (kg m²/s)")
    for a in axes:
        a.axvline(T_LOAD, color="0.7", lw=0.8)
        a.set_xlabel("t (s)")
        a.legend(fontsize="small")
    fig.suptitle("Flying beam: after the load stops (t = 2.5 s) energy and momenta are constants of motion")
    fig.savefig(out_dir / "flying_beam_conservation.png", dpi=110)
    plt.close(fig)
    return out_dir


if __name__ == "__main__":
    print(summary())
    out = plot(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent / "output")
    print(f"plots written to {out}")
