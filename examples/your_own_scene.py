"""Your own scene, from scratch: bodies, joints, loads, probes, statics and a run (docs/your_own_scene.md).

Two scenes built from the package's parts, everything in SI units (m, kg, s, N, rad):

1. ``cantilever``: a geometrically exact beam (1 m) welded to the ground at its root, under its
   weight and a tip force, solved for its static equilibrium. The weld's reaction balances the
   applied loads whatever the deflection (statics of the whole beam).
2. ``mechanism``: a slider–crank made of a rigid crank pinned to the ground, a flexible
   floating-frame connecting rod hinged to the crank, a point mass hinged to the rod's far end and
   sliding on a horizontal rail, a small rigid sensor welded to the middle of the rod; gravity
   and a horizontal push on the slider; released at rest and run with the energy-momentum scheme.
   Its energy balance E − E₀ = W (work of the push) holds to the Newton tolerance.

Run ``python examples/your_own_scene.py [OUT_DIR]`` (default ``examples/output/``) for the plots.
Importing the module computes the results without plotting; ``YOUR_SCENE_T_END`` (s) shortens
the run (the test suite imports it with a short one). Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``): 0.05 s.
"""
import os
import sys
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.bodies.probes import PointProbe
from skfem_flex.fem.beam import line_mesh

G = (0.0, -9.81)                                   # gravity, m/s² (y up)

# ------------------------------------------------------------------------------------------------
# 1. A cantilever: ExactBeam + Weld to the ground + Gravity + PointForce, static equilibrium
# ------------------------------------------------------------------------------------------------
#: a steel strip 20 mm × 2 mm: EA (N), EI (N m²), kGA (N), ρA (kg/m), ρI (kg m)
E, NU, RHO, WIDTH, HEIGHT = 2.1e11, 0.3, 7850.0, 0.02, 0.002
AREA, SECOND_MOMENT = WIDTH * HEIGHT, WIDTH * HEIGHT ** 3 / 12
strip = sf.Section(EA=E * AREA, EI=E * SECOND_MOMENT, kGA=5 / 6 * E / (2 * (1 + NU)) * AREA, rhoA=RHO * AREA,
                   rhoI=RHO * SECOND_MOMENT)
CANTILEVER_LENGTH, TIP_FORCE = 1.0, (0.0, -2.0)    # m, N

# an exact beam is placed by its end points (or ExactBeam(TimoshenkoBeam(...), start=, angle=));
# its point(s) is the axis point at arc length s (m) from the first end
cantilever_beam = sf.ExactBeam.from_points(strip, (0.0, 0.0), (CANTILEVER_LENGTH, 0.0), n_elements=16,
                                           name="strip")
clamp = sf.Weld(cantilever_beam.point(0.0), name="clamp")          # point_b=None: welded to the ground
cantilever = sf.Scene([cantilever_beam], constraints=[clamp],
                      forces=[sf.Gravity(G), sf.PointForce(cantilever_beam.point(CANTILEVER_LENGTH), TIP_FORCE)],
                      probes={"tip": PointProbe(cantilever_beam.point(CANTILEVER_LENGTH))}, name="cantilever")
statics = sf.static_equilibrium(cantilever)
#: (F_x, F_y, M): force (N) and moment (N m) the weld exerts on the beam
clamp_reaction = statics.reactions["clamp"]
tip_position = cantilever.evaluate_probes(0.0, statics.q, statics.v)["tip"]
beam_weight = strip.rhoA * CANTILEVER_LENGTH * np.asarray(G)         # N

# ------------------------------------------------------------------------------------------------
# 2. A slider-crank: RigidBody, FloatingBeam, PointMass; Pin, Revolute, Slider, Weld; a run
# ------------------------------------------------------------------------------------------------
CRANK, ROD, CRANK_ANGLE = 0.3, 1.0, np.radians(60.0)    # lengths (m) and the crank's start angle
crank_tip = CRANK * np.array([np.cos(CRANK_ANGLE), np.sin(CRANK_ANGLE)])
slider_x = crank_tip[0] + np.sqrt(ROD ** 2 - crank_tip[1] ** 2)      # the rod's far end on the rail y = 0
rod_angle = np.arctan2(-crank_tip[1], slider_x - crank_tip[0])

# a rigid body is placed by its centre of mass and angle; its point((sx, sy)) is the material
# point at (sx, sy) m from the centre of mass in the body frame (turning with the body)
crank = sf.RigidBody(mass=0.5, inertia=0.5 * CRANK ** 2 / 12, position=crank_tip / 2, angle=CRANK_ANGLE,
                     outline=[(-CRANK / 2, 0.0), (CRANK / 2, 0.0)], name="crank")
# a floating-frame beam: its frame sits at the root (mesh x = 0) at `position`, its axis along
# `angle`; its point(x) is the axis point at x (m) along the beam, whatever the deformation
rod_section = sf.Section(EA=1e6, EI=50.0, kGA=3e5, rhoA=1.0, rhoI=1e-4)
rod = sf.FloatingBeam(sf.TimoshenkoBeam(line_mesh(ROD, 6), rod_section), reference="clamped",
                      position=crank_tip, angle=rod_angle, name="rod")
# a point mass has a single point: point() (no locator)
slider = sf.PointMass(0.3, position=(slider_x, 0.0), name="slider")
# a rigid sensor (20 g) whose centre sits on the rod's axis at mid-length, welded there
mid = crank_tip + 0.5 * ROD * np.array([np.cos(rod_angle), np.sin(rod_angle)])
sensor = sf.RigidBody(mass=0.02, inertia=1e-5, position=mid, angle=rod_angle, name="sensor")

joints = [
    sf.Pin(crank.point((-CRANK / 2, 0.0)), anchor=(0.0, 0.0), name="bearing"),   # body point, ground point
    sf.Revolute(crank.point((CRANK / 2, 0.0)), rod.point(0.0), name="crank_pin"),
    sf.Revolute(rod.point(ROD), slider.point(), name="wrist_pin"),
    # Slider(point, direction, anchor): the point moves along the line through anchor along direction
    sf.Slider(slider.point(), direction=(1.0, 0.0), anchor=(0.0, 0.0), name="rail"),
    sf.Weld(sensor.point(), rod.point(0.5 * ROD), name="sensor_mount"),
]
PUSH = (-1.5, 0.0)                                  # N on the slider, towards the crank
mechanism = sf.Scene([crank, rod, slider, sensor], constraints=joints,
                     forces=[sf.Gravity(G), sf.PointForce(slider.point(), PUSH, name="push")],
                     probes={"slider": PointProbe(slider.point()),                       # (x, y), m
                             "crank_angle": lambda scene, t, q, v: q[scene.index(crank, "theta")]},  # rad
                     name="mechanism")

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
T_END = float(os.environ.get("YOUR_SCENE_T_END", "0.05" if QUICK else "1.0"))         # s
DT = 1e-3                                                         # s
result = sf.simulate(mechanism, T_END, DT)
#: E − E₀ − W over the run, J, and the scale it is judged against
balance_error = np.abs(result.energy_balance_error).max()
energy_scale = np.max(np.abs(result.kinetic) + np.abs(result.potential))


def summary():
    """The two scenes' numbers, as text."""
    fx, fy, m = clamp_reaction
    lines = [f"cantilever: tip at ({tip_position[0]:.5f}, {tip_position[1]:.5f}) m; clamp reaction "
             f"({fx:.5g} N, {fy:.5g} N, {m:.5g} N m) against applied loads "
             f"({TIP_FORCE[0] + beam_weight[0]:.5g} N, {TIP_FORCE[1] + beam_weight[1]:.5g} N)",
             f"mechanism: {result.steps} steps of {DT:g} s to t = {result.t[-1]:g} s; slider from "
             f"{result.probes['slider'][0, 0]:.4f} m to {result.probes['slider'][-1, 0]:.4f} m; crank angle "
             f"{np.degrees(result.probes['crank_angle'][-1]):.2f} deg",
             f"  energy balance |E - E0 - W| = {balance_error:.2e} J of max(|T| + |V|) = {energy_scale:.3g} J; "
             f"max |constraint| {result.constraint_residual.max():.1e}; largest bearing force "
             f"{np.linalg.norm(result.reactions['bearing'], axis=1).max():.3g} N"]
    return "\n".join(lines)


if __name__ == "__main__":
    from skfem_flex.io.plots import plot_snapshots, pyplot_for

    print(summary())
    plt, output = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    fig, ax = plt.subplots(2, 2, figsize=(11, 7))
    ax[0, 0].plot(result.t, result.probes["slider"][:, 0])
    ax[0, 0].set_ylabel("slider x (m)")
    ax[0, 1].plot(result.t, np.degrees(result.probes["crank_angle"]))
    ax[0, 1].set_ylabel("crank angle (deg)")
    ax[1, 0].plot(result.t, result.total_energy - result.total_energy[0], label="E − E₀")
    ax[1, 0].plot(result.t, result.external_work, "--", label="W (push)")
    ax[1, 0].set_ylabel("energy (J)")
    ax[1, 0].legend(fontsize="small")
    for name in ("bearing", "crank_pin", "wrist_pin"):
        ax[1, 1].plot(result.t, np.linalg.norm(result.reactions[name], axis=1), label=name)
    ax[1, 1].set_ylabel("joint force (N)")
    ax[1, 1].legend(fontsize="small")
    for a in ax.ravel():
        a.grid(alpha=0.3)
        a.set_xlabel("t (s)")
    fig.tight_layout()
    fig.savefig(output / "your_own_scene.png", dpi=120)
    plot_snapshots(mechanism, result, output / "your_own_scene_snapshots.png", count=6)
    print(f"PNGs written to {output}")
