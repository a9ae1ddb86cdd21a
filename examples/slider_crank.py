"""Flexible slider–crank of Simeon (1996): a full revolution with three schemes, step refinement, published values.

The scene (``skfem_flex.scenes.slider_crank``) is the "crank" problem of the Test Set for IVP
Solvers (B. Simeon): rigid crank (0.15 m, 0.36 kg) driven at 150 rad/s, elastic steel
connecting rod (0.30 m, 8 × 8 mm) as a floating-frame Timoshenko beam, sliding block
(0.075552 kg), no gravity.

* ``rigid`` start (crank angle 0, rod straight, rigid-mechanism velocities): one crank
  revolution with energy-momentum, trapezoidal and generalized-α, Δt = T/400.
* Step refinement of the mid-point deflection history (energy-momentum, Δt = T/100 … T/400).
* ``testset`` start (the test set's smooth initial values): t = 0.1 s compared with the
  published reference solution of the reduced model (SIMEON_REFERENCE), with the Green–Lagrange
  and the linear axial strain.

Before each timed revolution, a run of a few steps of the same scene and scheme compiles the Numba
kernels (or loads them from numba's cache); its wall time is reported apart as "compile and start-up".

Run ``python examples/slider_crank.py [OUT_DIR]`` (default ``examples/output/``); it prints
the tables and writes PNGs. Importing the module computes the results without plotting.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): the revolution at Δt = T/100, the
step refinement from T/25 to T/200, and only the first published case (4 elements).
"""
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for
from skfem_flex.scenes.mechanisms import SIMEON_REFERENCE

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
OMEGA = 150.0
PERIOD = 2 * math.pi / OMEGA              # one crank revolution, s
SCHEMES = ("energy-momentum", "trapezoidal", "generalized-alpha")
N_ELEMENTS = 8
STEPS = 100 if QUICK else 400             # per revolution


def warm_up(scene, dt, integrator, steps=3):
    """Wall time (s) of a few steps of ``scene``: the one-off compile (or cache load) of its kernels."""
    start = time.perf_counter()
    sf.simulate(scene, steps * dt, dt, integrator=integrator)
    return time.perf_counter() - start


startup, revolution = {}, {}
for scheme in SCHEMES:
    startup[scheme] = warm_up(sf.scenes.slider_crank(n_elements=N_ELEMENTS), PERIOD / STEPS, scheme)
    revolution[scheme] = sf.simulate(sf.scenes.slider_crank(n_elements=N_ELEMENTS), PERIOD, PERIOD / STEPS,
                                     integrator=scheme)

REFINEMENT = (25, 50, 100, 200) if QUICK else (100, 200, 400, 800)
refinement = {k: sf.simulate(sf.scenes.slider_crank(n_elements=4), PERIOD, PERIOD / k) for k in REFINEMENT}

PUBLISHED_CASES = (("green-lagrange", 4, 1e-4), ("green-lagrange", 8, 1e-4), ("green-lagrange", 8, 5e-5),
                   ("green-lagrange", 16, 1e-4), ("linear", 8, 1e-4))[:1 if QUICK else None]
published = {case: sf.simulate(sf.scenes.slider_crank(start="testset", n_elements=case[1], strain=case[0]),
                               SIMEON_REFERENCE["t"], case[2])
             for case in PUBLISHED_CASES}


def revolution_table():
    lines = ["| scheme | max abs Φ | max abs(Φ_q v + Φ_t) | energy balance / max E | max abs mid-point (mm) "
             "| mid-point at T (mm) | Newton it./step | compile and start-up (s) | wall (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s, r in revolution.items():
        scale = np.max(np.abs(r.kinetic) + np.abs(r.potential))
        lines.append(f"| {s} | {np.max(r.constraint_residual):.1e} | {np.max(r.velocity_constraint_residual):.1e} "
                     f"| {np.max(np.abs(r.energy_balance_error)) / scale:.1e} "
                     f"| {1e3 * np.max(np.abs(r.probes['midpoint'])):.4f} | {1e3 * r.probes['midpoint'][-1]:+.4f} "
                     f"| {np.mean(r.newton_iterations[1:]):.2f} | {startup[s]:.1f} | {r.wall_time:.2f} |")
    return "\n".join(lines)


def refinement_table():
    finest = refinement[REFINEMENT[-1]].probes["midpoint"]
    lines = [f"| Δt | max abs difference of the mid-point history to Δt = T/{REFINEMENT[-1]} (m) | ratio |",
             "|---|---|---|"]
    prev = None
    for k in REFINEMENT[:-1]:
        stride = REFINEMENT[-1] // k
        d = float(np.max(np.abs(refinement[k].probes["midpoint"] - finest[::stride])))
        ratio = "" if prev is None else f"{prev / d:.2f}"
        lines.append(f"| T/{k} | {d:.3e} | {ratio} |")
        prev = d
    return "\n".join(lines)


def published_table():
    ref = SIMEON_REFERENCE
    lines = ["| model (start='testset') | slider x3 (m) | rod angle φ2 (rad) | mid-point deflection (m) |",
             "|---|---|---|---|",
             f"| published, reduced model | {ref['slider']:.10f} | {ref['rod_angle']:.10f} | {ref['midpoint']:.4e} |"]
    for case, r in published.items():
        strain, n_el, dt = case
        x, a, m = (r.probes[k][-1] for k in ("slider", "rod_angle", "midpoint"))
        lines.append(f"| ours: {strain}, {n_el} elements, Δt = {dt:g} s | {x:.10f} ({x - ref['slider']:+.1e}) "
                     f"| {a:.10f} ({a - ref['rod_angle']:+.1e}) | {m:.4e} ({m / ref['midpoint'] - 1:+.1%}) |")
    return "\n".join(lines)


EXPLANATION = """\
The published values (Test Set for IVP Solvers, problem "crank", routine SOLN) belong to Simeon's
reduced model started from the test set's smooth initial values ("init"), which start="testset" maps
onto our beam. Slider position and rod angle agree to better than 1e-6 (m, rad). The mid-point
deflection swings by about ±1.5 mm twice per revolution (the rod bends under its own inertia); at
t = 0.1 s it is 0.19 mm on a steep flank of that swing (about −0.065 mm per ms), so the point value
is sensitive: ours lies within about 20 % of the published one (a shift of well under a millisecond
or a few per cent of amplitude) and moves by that much between meshes (4, 8, 16 elements), while
halving the step changes it by under 1 %. The differences are model differences, not integration
error: (1) the reduced model has two transverse sine modes and a two-node quadratic axial field, we
use Timoshenko elements (shear, rotary inertia, all higher modes), and the initial values, smooth for
the reduced model, excite some higher-mode vibration in ours; (2) the test set's axial mass block
rho*b*h*L2*[[8, 1], [1, 2]] is 15 times the consistent mass of its own quadratic shape functions
([[8, 1], [1, 2]]/15), so its axial frequencies are about sqrt(15) lower than ours; (3) it uses the
linear axial strain (ipar(1) = 0), we default to Green–Lagrange (the linear-strain row shows the
size of that effect). The scene's default start (rigid-mechanism velocities, the test set's "init2")
adds a free bending vibration to the same swing, so it is not compared with the published values."""


if __name__ == "__main__":
    print(f"One crank revolution from the rigid-mechanism start, Δt = T/{STEPS}, {N_ELEMENTS} elements")
    print(revolution_table())
    print("\nStep refinement of the mid-point deflection (energy-momentum, 4 elements, one revolution)")
    print(refinement_table())
    print("\nPublished reference values at t = 0.1 s against ours (energy-momentum)")
    print(published_table())
    print()
    print(EXPLANATION)

    plt, output = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")

    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for s, r in revolution.items():
        ax[0].plot(r.probes["crank_angle"], 1e3 * r.probes["midpoint"], label=s)
        ax[1].plot(r.probes["crank_angle"], r.probes["slider"], label=s)
        ax[2].plot(r.probes["crank_angle"], r.reactions["crank drive"][:, 0], label=s)
    ax[0].set_ylabel("mid-point deflection (mm)")
    ax[1].set_ylabel("slider x (m)")
    ax[2].set_ylabel("driving torque (N m)")
    ax[2].set_xlabel("crank angle (rad)")
    ax[0].legend(fontsize="small")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"flexible slider–crank, rigid-mechanism start, Δt = T/{STEPS}")
    fig.tight_layout()
    fig.savefig(output / "slider_crank_revolution.png", dpi=120)

    fig, ax = plt.subplots(figsize=(7, 4))
    for k, r in refinement.items():
        ax.plot(r.t / PERIOD, 1e3 * r.probes["midpoint"], label=f"Δt = T/{k}")
    ax.set_xlabel("t / T")
    ax.set_ylabel("mid-point deflection (mm)")
    ax.set_title("step refinement (energy-momentum, 4 elements)")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(output / "slider_crank_refinement.png", dpi=120)

    fig, ax = plt.subplots(figsize=(7, 4))
    for (strain, n_el, dt), r in published.items():
        ax.plot(r.t, 1e3 * r.probes["midpoint"], label=f"ours, {strain}, {n_el} el., Δt = {dt:g} s", lw=0.8)
    ax.plot(SIMEON_REFERENCE["t"], 1e3 * SIMEON_REFERENCE["midpoint"], "k*", ms=12, label="published, t = 0.1 s")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("mid-point deflection (mm)")
    ax.set_title("test-set start: mid-point deflection against the published value")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(output / "slider_crank_published.png", dpi=120)
    print(f"\nPNGs written to {output}")
