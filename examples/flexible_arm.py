"""A flexible two-link arm in space: a hinge between two floating-frame beams at material points.

The first link, a spatial floating-frame beam with the Green–Lagrange axis (8 elements reduced to 6
clamped modes with their stiffening derivatives and centrifugal shapes), is clamped to a hub that a
rotation driver spins up about the vertical z (the spin-up law of Simo and Vu-Quoc, to 2 rad/s in 2 s). The
second link, a floating-frame beam in its chord frame (8 elements, 6 free-interface modes), hangs on an elbow hinge at the first link's tip: the
hinge's axis is the first link's section direction normal to its axis and to z, so the elbow turns with the
first link's bending and twisting. Under gravity the second link falls and swings about the elbow while
the hub turns it round: bending in both planes, torsion, Coriolis forces.

The elbow's rows couple two material points (their positions and section directions are quadratic in q, the
rows quartic): sums of products of two quadratic invariants with the product rule's exact discrete gradient
(``docs/spatial_floating_beam.md``, "Joints at points of the axis"). The energy–momentum step therefore
closes the energy balance E − E₀ = W (W the driver's work) to round-off.

Printed per scheme (energy–momentum, the trapezoidal rule, generalized-α at velocity level): the largest
energy-balance error relative to the largest energy, the largest elbow-row residual, the lowest height of
the second link's tip, the CPU time per step.

Run ``python examples/flexible_arm.py``. Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests):
0.3 s instead of 4 s.
"""
import os
import time

import numpy as np
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating_spatial.body import FloatingBeam3D
from skfem_flex.bodies.floating_spatial.reduction import reduction_basis
from skfem_flex.elements.motion import spin_up_law
from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D
from skfem_flex.scenes.spatial_rotors import HUB_FRAME

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
T_END, DT = (0.3 if QUICK else 4.0), 0.01
#: an aluminium tube of 30 mm diameter and 2 mm wall, roughly: N, N m², kg/m, kg m
SECTION = sf.SpatialSection(EA=1.2e7, GA1=2e6, GA2=2e6, GJ=650.0, EI1=500.0, EI2=500.0, rhoA=0.47, rhoI1=2.4e-5,
                            rhoI2=2.4e-5)
LINK_1, LINK_2 = 1.0, 0.8                                    # m


def link(length, n_elements, reference, strain, position, name, n_modes=6):
    """A link of ``n_elements`` two-node elements reduced to ``n_modes`` modes (clamped: Craig–Bampton at the root,
    with the stiffening derivatives and centrifugal shapes of the Green–Lagrange axis; chord: free-interface)."""
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, length, n_elements + 1)), SECTION, order=1)
    full = FloatingBeam3D(beam, reference=reference, strain=strain, orientation=HUB_FRAME, name=name)
    return FloatingBeam3D(beam, reference=reference, strain=strain, orientation=HUB_FRAME, position=position,
                          basis=reduction_basis(full, n_modes), name=name)


def arm():
    """The scene (module docstring): the hub's hinge and driver, the elbow hinge between the links' material
    points, gravity; probe ``"tip"``: the second link's free end, m."""
    first = link(LINK_1, 8, "clamped", "green-lagrange", (0.0, 0.0, 0.0), "upper arm")
    second = link(LINK_2, 8, "chord", "linear", (LINK_1, 0.0, 0.0), "forearm")
    z = np.array([0.0, 0.0, 1.0])
    elbow = sf.Revolute3D(first.point(LINK_1), second.point(0.0), axis=(0.0, 1.0, 0.0), name="elbow")
    tip = second.point(LINK_2)
    return sf.Scene([first, second], forces=[sf.Gravity((0.0, 0.0, -9.81))],
                    constraints=[sf.Revolute3D(first.point(0.0), axis=z, name="hub"),
                                 sf.RotationDriver(first, None, z, spin_up_law(2.0, 2.0), name="hub drive"), elbow],
                    probes={"tip": lambda scene, t, q, v: tip.position(scene.coordinates(second, q))},
                    name="flexible arm")


SCHEMES = {"energy-momentum": sf.EnergyMomentum(), "trapezoidal": sf.Trapezoidal(),
           "generalized-alpha": sf.GeneralizedAlpha(constraint_level="velocity")}
results = {}
for name, scheme in SCHEMES.items():
    scene = arm()
    sf.simulate(scene, 2 * DT, DT, scheme=scheme)           # compile (or load) the kernels first
    start = time.process_time()
    res = sf.simulate(scene, T_END, DT, scheme=scheme)
    cpu = (time.process_time() - start) / (res.t.size - 1)
    elbow = [c for c in scene.constraints if c.name == "elbow"][0]
    rows = scene.constraint_layout[scene.constraints.index(elbow)][1]
    residual = float(np.abs(np.asarray([scene.constraint_value(q, t)[rows] for t, q in zip(res.t, res.q)])).max())
    results[name] = dict(energy=res.relative_energy_error(), elbow=residual,
                         lowest=float(res.probes["tip"][:, 2].min()), work=float(np.abs(res.external_work).max()),
                         us_per_step=1e6 * cpu, python=res.run_path["python_elements"])

if __name__ == "__main__":
    print(f"flexible two-link arm, {T_END:g} s at Δt = {DT:g} s")
    print(f"{'scheme':<20}{'energy balance':>16}{'elbow rows':>12}{'lowest tip z (m)':>18}{'µs/step':>9}")
    for name, r in results.items():
        print(f"{name:<20}{r['energy']:>16.1e}{r['elbow']:>12.1e}{r['lowest']:>18.3f}{r['us_per_step']:>9.0f}")
