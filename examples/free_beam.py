"""Free-flying floating-frame beam in zero gravity, set in motion by a short force pulse.

Scene ``skfem_flex.scenes.free_beam`` (L = 10 m, EA = 2.8e7 N, EI = 1.4e4 N m², ρA = 1.2 kg/m,
8 elements, no joints, no gravity): a half-sine pulse of 100 N peak and 0.05 s acts at the tip along
global +y. After the pulse, energy, linear and angular momentum must stay constant (docs/scenes.md).
Energy-momentum and generalized-α, Δt = 5e-3 s, 4 s.

Run ``python examples/free_beam.py [OUT_DIR]`` (default ``examples/output/``).
Importing the module computes the results without plotting.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 0.5 s instead of 4 s.
"""
import math
import os
import sys
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
FORCE, DURATION = 100.0, 0.05
T_END, DT = (0.5 if QUICK else 4.0), 5e-3
scene = sf.scenes.free_beam(force=FORCE, duration=DURATION)
runs = {s: sf.simulate(scene, T_END, DT, integrator=s) for s in ("energy-momentum", "generalized-alpha")}


def summary():
    lines = ["| scheme | impulse p_y after the pulse (N s) | exact 2τF/π | drift of E after the pulse (J) "
             "| drift of p (N s) | drift of angular momentum (N m s) | Newton it./step |",
             "|---|---|---|---|---|---|---|"]
    for s, r in runs.items():
        after = r.t > DURATION + 1e-9
        p, h, e = r.linear_momentum[after], r.angular_momentum[after], r.total_energy[after]
        lines.append(f"| {s} | {p[0, 1]:.6f} | {2 * DURATION * FORCE / math.pi:.6f} | {np.ptp(e):.1e} "
                     f"| {np.max(np.ptp(p, axis=0)):.1e} | {np.ptp(h):.1e} | {np.mean(r.newton_iterations[1:]):.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    from skfem_flex.io.plots import plot_snapshots

    print(f"Free beam after a {FORCE:g} N, {DURATION:g} s half-sine pulse at the tip, Δt = {DT:g} s, {T_END:g} s")
    print(summary())
    plt, output = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")

    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for s, r in runs.items():
        ax[0].plot(r.t, r.total_energy, label=s)
        ax[1].plot(r.t, r.angular_momentum, label=s)
        ax[2].plot(r.t, 1e3 * r.probes["tip_deflection"][:, 1], lw=0.8, label=s)
    ax[0].set_ylabel("total energy (J)")
    ax[1].set_ylabel("angular momentum (N m s)")
    ax[2].set_ylabel("tip deflection, beam frame (mm)")
    ax[2].set_xlabel("t (s)")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(output / "free_beam.png", dpi=120)
    plot_snapshots(scene, runs["energy-momentum"], output / "free_beam_snapshots.png", count=6)
    print(f"\nPNGs written to {output}")
