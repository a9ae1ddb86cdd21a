"""Very flexible pendulum of Berzeri & Shabana (2000), geometrically exact beam.

M. Berzeri, A. A. Shabana, "Development of simple models for the elastic forces in the absolute
nodal co-ordinate formulation", J. Sound Vib. 235 (2000) 539–565: a beam L = 1.2 m,
A = 0.0018 m², I = 1.215e-8 m⁴, ρ = 5540 kg/m³, E = 0.7 MPa, ν = 0.3, κ = 5/6, pinned at one end,
released at rest, straight and horizontal, under gravity g = 9.81 m/s². So soft that it sags,
whips and coils as it swings down.

At import the script runs the energy-conserving scheme for 1 s on 8, 16 and 32 P1 elements
(Δt = 2e-3 s) and keeps the histories. ``python examples/very_flexible_pendulum.py [OUT_DIR]``
prints the energy balance and the mesh convergence of the tip trajectory and writes
``very_flexible_pendulum.png`` (shapes every 0.1 s, tip paths, energies) to OUT_DIR (default
``examples/output``). Before each timed run, a run of a few steps of the same scene compiles the
Numba kernels (or loads them from numba's cache); its wall time is reported apart as "compile and
start-up".

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 4 and 8 elements, 0.3 s.
"""
import os
import sys
import time
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
MESHES = (4, 8) if QUICK else (8, 16, 32)
T_END = 0.3 if QUICK else 1.0
DT = 2e-3


def warm_up(scene, steps=3):
    """Wall time (s) of a few steps of ``scene``: the one-off compile (or cache load) of its kernels."""
    start = time.perf_counter()
    sf.simulate(scene, t_end=steps * DT, dt=DT)
    return time.perf_counter() - start


scenes = {n: sf.scenes.very_flexible_pendulum(n_elements=n) for n in MESHES}
startup = {n: warm_up(scene) for n, scene in scenes.items()}
runs = {n: sf.simulate(scene, t_end=T_END, dt=DT) for n, scene in scenes.items()}
finest = MESHES[-1]
# distance of each tip path from the finest one, max over the run (m)
tip_difference = {n: float(np.max(np.linalg.norm(runs[n].probes["tip"] - runs[finest].probes["tip"], axis=1)))
                  for n in MESHES[:-1]}


def summary():
    lines = [f"| elements | energy balance error (rel.) | max tip distance from {finest} el. (m) "
             f"| tip at {T_END:g} s (m) | Newton it./step | compile and start-up (s) | wall (s) |",
             "|---|---|---|---|---|---|---|"]
    for n, res in runs.items():
        tip = res.probes["tip"][-1]
        lines.append(f"| {n} | {res.relative_energy_error():.1e} | {tip_difference.get(n, 0.0):.4f} | "
                     f"({tip[0]:.4f}, {tip[1]:.4f}) | {res.newton_iterations[1:].mean():.2f} | "
                     f"{startup[n]:.1f} | {res.wall_time:.2f} |")
    return "\n".join(lines)


def plot(out_dir):
    plt, out_dir = pyplot_for(out_dir)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), constrained_layout=True)
    res, body = runs[finest], scenes[finest].bodies[0]
    cmap = plt.get_cmap("viridis")
    times = np.arange(0.0, T_END + 1e-9, 0.1)
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(res.t - t)))
        xy = body.nodal_positions(res.q[i])
        axes[0].plot(xy[:, 0], xy[:, 1], "-", color=cmap(k / max(len(times) - 1, 1)), lw=1.2)
    axes[0].set_title(f"shapes every 0.1 s ({finest} elements)")
    for n, r in runs.items():
        axes[1].plot(*r.probes["tip"].T, label=f"{n} elements")
    axes[1].set_title("tip trajectory")
    for a in axes[:2]:
        a.set_aspect("equal")
        a.set_xlabel("x (m)")
        a.set_ylabel("y (m)")
        a.plot(0.0, 0.0, "k^")
    axes[1].legend(fontsize="small")
    axes[2].plot(res.t, res.kinetic, label="kinetic")
    axes[2].plot(res.t, res.potential, label="potential (strain + gravity)")
    axes[2].plot(res.t, res.total_energy, "k", label="total")
    axes[2].set_xlabel("t (s)")
    axes[2].set_ylabel("energy (J)")
    axes[2].legend(fontsize="small")
    axes[2].set_title(f"energies, balance error {res.relative_energy_error():.1e}")
    fig.suptitle(f"Very flexible pendulum (Berzeri & Shabana 2000), exact beam, Δt = {DT} s, energy-momentum")
    fig.savefig(out_dir / "very_flexible_pendulum.png", dpi=110)
    plt.close(fig)
    return out_dir


if __name__ == "__main__":
    print(summary())
    out = plot(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent / "output")
    print(f"plots written to {out}")
