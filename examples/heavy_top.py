"""Heavy tops in space: the conservation laws of the energy-momentum scheme, and the Brüls top's convergence.

Scenes ``skfem_flex.scenes.heavy_top("simo-wong")`` and ``heavy_top("bruls")`` (docs/spatial.md):

* Simo–Wong top, 10 s at Δt = 0.009 s and 0.05 s under energy-momentum, the trapezoidal rule and
  generalized-α (ρ∞ = 0.9, at velocity level; at position level its velocities oscillate), with the top's
  rotation carried by directors (the default) and by a unit quaternion (``rotation="quaternion"``): the
  largest relative error of the energy, of the angular momentum about the vertical e₃, of the spin about
  the body's symmetry axis, and the rotation matrix's orthonormality;
* Brüls top: the Euler parameters at t = 0.2 s against the published reference for Δt = 4e-4 … 5e-5 s under
  the three schemes (generalized-α at position level, as published), with the observed orders, plotted to
  ``heavy_top_convergence.png``.

Run ``python examples/heavy_top.py [OUT_DIR]`` (default ``examples/output/``). Importing the module computes
the results without plotting. Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 1 s of the
Simo–Wong top and two steps sizes of the Brüls top.
"""
import os
import sys
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for
from skfem_flex.scenes.spatial import BRULS_REFERENCE

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
T_TOP = 1.0 if QUICK else 10.0
TOP_STEPS = (0.009, 0.05)
BRULS_STEPS = (2e-4, 1e-4) if QUICK else (4e-4, 2e-4, 1e-4, 5e-5)
SCHEMES = {"energy-momentum": sf.EnergyMomentum(), "trapezoidal": sf.Trapezoidal(),
           "generalized-alpha": sf.GeneralizedAlpha(constraint_level="velocity")}


def top_errors(result, top):
    """Largest relative errors of E, L₃ and the body spin Ω₃, and max |RᵀR − I|."""
    E, L3 = result.total_energy, result.angular_momentum[:, 2]
    spin = np.array([top.body_angular_velocity(q, v)[2] for q, v in zip(result.q, result.v)])
    orth = max(np.abs(top.rotation_matrix(q).T @ top.rotation_matrix(q) - np.eye(3)).max() for q in result.q)
    return (np.abs(E - E[0]).max() / abs(E[0]), np.abs(L3 - L3[0]).max() / abs(L3[0]),
            np.abs(spin - spin[0]).max() / abs(spin[0]), orth)


ROTATIONS = ("directors", "quaternion")
simo_wong = {}
for rotation in ROTATIONS:
    for dt in TOP_STEPS:
        for name, scheme in SCHEMES.items():
            scene = sf.scenes.heavy_top("simo-wong", rotation=rotation)
            res = sf.simulate(scene, T_TOP, dt, scheme=scheme)
            steps = len(res.t) - 1
            simo_wong[(rotation, name, dt)] = top_errors(res, scene.bodies[0]) + (1e6 * res.wall_time / steps,)

bruls = {}
for name in SCHEMES:
    scheme = sf.GeneralizedAlpha() if name == "generalized-alpha" else SCHEMES[name]
    for dt in BRULS_STEPS:
        scene = sf.scenes.heavy_top("bruls")
        res = sf.simulate(scene, 0.2, dt, scheme=scheme)
        e = scene.bodies[0].euler_parameters(res.q[-1], BRULS_REFERENCE)
        bruls[(name, dt)] = float(np.abs(e - BRULS_REFERENCE).max())


def orders(name):
    errs = [bruls[(name, dt)] for dt in BRULS_STEPS]
    return [float(np.log(a / b) / np.log(h / k)) for a, b, h, k in zip(errs, errs[1:], BRULS_STEPS, BRULS_STEPS[1:])]


def summary():
    lines = [f"Simo–Wong top, {T_TOP:g} s", "",
             "| rotation | scheme | Δt (s) | energy | L₃ | body spin Ω₃ | max abs(RᵀR − I) | µs a step |",
             "|---|---|---|---|---|---|---|---|"]
    for (rotation, name, dt), (e, l3, spin, orth, wall) in simo_wong.items():
        lines.append(f"| {rotation} | {name} | {dt:g} | {e:.2e} | {l3:.2e} | {spin:.2e} | {orth:.1e} | {wall:.0f} |")
    lines += ["", "Brüls top: max abs(e(0.2 s) − e_ref)", "",
              "| scheme | " + " | ".join(f"Δt = {dt:g}" for dt in BRULS_STEPS) + " | observed orders |",
              "|---|" + "---|" * (len(BRULS_STEPS) + 1)]
    for name in SCHEMES:
        lines.append(f"| {name} | " + " | ".join(f"{bruls[(name, dt)]:.2e}" for dt in BRULS_STEPS)
                     + " | " + ", ".join(f"{o:.2f}" for o in orders(name)) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    plt, out = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    print(summary())
    fig, ax = plt.subplots(figsize=(5, 4))
    for name in SCHEMES:
        ax.loglog(BRULS_STEPS, [bruls[(name, dt)] for dt in BRULS_STEPS], "o-", label=name)
    ax.loglog(BRULS_STEPS, [2e4 * dt ** 2 for dt in BRULS_STEPS], "k:", label="Δt²")
    ax.set_xlabel("Δt (s)")
    ax.set_ylabel("max |e(0.2 s) − e_ref|")
    ax.set_title("Brüls heavy top")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "heavy_top_convergence.png", dpi=120)
    print(f"wrote {out / 'heavy_top_convergence.png'}")
