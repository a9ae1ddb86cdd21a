"""Spatial rotor scenes: the spinning cantilever ``rotating_beam_3d`` and the hub beam the floating-frame
``spin_up_3d`` turns (floating-frame beams, docs/spatial_floating_beam.md), and the meshed shaft with a disk
``rotor_3d`` (a reduced solid, docs/spatial_solids.md)."""
from __future__ import annotations

import numpy as np
import skfem

from ..bodies.floating_spatial.body import FloatingBeam3D
from ..bodies.floating_spatial.rotation import spinning_modes, steady_spin
from ..elements.constraints.spatial_joints import Revolute3D, RotationDriver
from ..elements.motion import MotionLaw
from ..fem.spatial_beam import TimoshenkoBeam3D
from ..fem.spatial_section import SpatialSection
from ..scene import Scene
from ._registry import positive_count, positive_value, register

__all__ = ["rotating_beam_3d", "floating_hub_beam_3d", "HUB_FRAME", "rotor_3d", "ROTOR_3D"]

#: the frame [d₁ d₂ d₃] of a hub beam: the beam along x (d₃), its flapwise axis d₁ along the spin axis z, and
#: d₂ = d₃ × d₁ = −y in the plane of rotation
HUB_FRAME = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])


def floating_hub_beam_3d(length, EA, EI, GJ, kGA, rhoA, rhoI, n_elements, order, strain="green-lagrange"):
    """A :class:`FloatingBeam3D` clamped to its frame at the origin, along x, spinning axis z (:data:`HUB_FRAME`);
    the same EI, kGA and ρI about both section axes."""
    sec = SpatialSection(EA=EA, GA1=kGA, GA2=kGA, GJ=GJ, EI1=EI, EI2=EI, rhoA=rhoA, rhoI1=rhoI, rhoI2=rhoI)
    n = positive_count("n_elements", n_elements)
    if order not in (1, 2) or isinstance(order, bool):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, positive_value("length", length), n + 1)), sec,
                            order=int(order))
    return FloatingBeam3D(beam, reference="clamped", strain=strain, orientation=HUB_FRAME, name="beam")


def hub_frame_displacement(body, point, length):
    """Probe of a hub beam's point: its displacement from (L, 0, 0) in the turning hub axes (x along the beam,
    y in the plane of rotation, z the spin axis): (axial, in-plane transverse, out of plane), m."""
    def probe(scene, t, q, v):
        qb = scene.coordinates(body, q)
        R = body.rotation_matrix(qb)
        rel = point.position(qb) - qb[:3]
        return np.array([R[:, 2] @ rel - length, -(R[:, 1] @ rel), R[:, 0] @ rel])
    return probe


@register(t_end=10.0, dt=0.01, omega="rad/s", length="m", EA="N", EI="N m²", GJ="N m²", kGA="N", rhoA="kg/m",
          rhoI="kg m", n_elements="-", order="-", strain="-", perturbation="m")
def rotating_beam_3d(omega=4.0, length=10.0, EA=2.8e7, EI=1.4e4, GJ=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
                     n_elements=8, order=1, strain="green-lagrange", perturbation=0.01):
    """A cantilever on a hub spinning at a constant ω about z, normal to it: the planar ``rotating_beam``'s data
    (the same EI about both section axes) plus GJ, as a spatial floating-frame beam
    (:class:`~skfem_flex.bodies.floating_spatial.body.FloatingBeam3D`, clamped to its frame, the frame on a
    hinge about z with a rotation driver).

    Starts in the stretched steady state (:func:`~skfem_flex.bodies.floating_spatial.rotation.steady_spin`)
    plus the shapes of the first flapwise (along z) and lead-lag (in the plane of rotation) modes, each
    scaled to a tip deflection of ``perturbation`` m, so that both vibrate at the frequencies
    :func:`~skfem_flex.bodies.floating_spatial.rotation.spinning_modes` gives.

    Probe ``"tip"``: the tip's displacement in the hub frame (axial, in-plane transverse, out of plane), m.
    """
    om = float(omega)
    pert = float(perturbation)
    if not (np.isfinite(om) and np.isfinite(pert)):
        raise ValueError(f"omega and perturbation must be finite, got {omega!r} and {perturbation!r}")
    body = floating_hub_beam_3d(length, EA, EI, GJ, kGA, rhoA, rhoI, n_elements, order, strain)
    y = steady_spin(body, om)
    if pert:
        modes = spinning_modes(body, om, n_modes=4)
        tip = body.beam.node_dofs[-1]
        for flap in (True, False):
            found = np.flatnonzero((modes.flapwise == flap) & (modes.omega > 0.0))
            if found.size == 0:
                raise ValueError(f"omega = {om!r} rad/s: the spinning beam has no vibrating "
                                 f"{'flapwise' if flap else 'lead-lag'} mode to perturb (it diverges at this "
                                 f"spin); give perturbation=0 or a smaller omega")
            shape = modes.shapes[:, int(found[0])]
            y = y + pert * np.real(shape / shape[tip[0 if flap else 1]])[body.free_dofs]
    body.q0[12:] = y
    body.v0[3:12] = np.cross(om * np.array([0.0, 0.0, 1.0]), HUB_FRAME.T).ravel()
    joints = [Revolute3D(body.point(0.0), axis=(0.0, 0.0, 1.0), name="hub hinge"),
              RotationDriver(body, None, (0.0, 0.0, 1.0), MotionLaw.constant_rate(om), name="hub drive")]
    return Scene([body], constraints=joints, name="rotating_beam_3d",
                 probes={"tip": hub_frame_displacement(body, body.point(body.s_tip), body.beam.length)},
                 parameters=dict(omega=omega, length=length, EA=EA, EI=EI, GJ=GJ, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, order=order, strain=strain, perturbation=perturbation))


#: the rotor of :func:`rotor_3d`: shaft length and square side, disk thickness and square side (m), steel
ROTOR_3D = dict(length=0.6, shaft=0.02, disk_thickness=0.04, disk=0.2, E=2e11, nu=0.3, rho=7800.0)


@register(t_end=1.0, dt=1e-3, torque="N m", T="s", unbalance="kg", n_modes="-")
def rotor_3d(torque=20.0, T=1.0, unbalance=0.01, n_modes=8):
    """A steel shaft with a disk at mid-span (:data:`ROTOR_3D`: square sections, P2 tetrahedra) on two ball
    bearings, spun up from rest about its axis x by a ``torque`` (N m) on the disk during [0, T], with an
    ``unbalance`` (a point mass, kg) on the disk's rim: the classical whirl test. The rotor is a
    :class:`~skfem_flex.bodies.floating_spatial.solid.FloatingSolid3D` reduced to ``n_modes`` modes: its frame
    clamped to the disk (the disk moves rigidly with it, as in the Jeffcott model), the shaft's end faces rigid
    interfaces on the ball joints. The first critical speed is the first bending pair on the bearings
    (237 rad/s by :func:`skfem_flex.modes` at rest; the Jeffcott estimate √(48EI/(L³m)) with the disk's mass
    alone gives about 200 rad/s), which the default spin-up reaches at t ≈ 0.99 s.

    Probes: ``"disk"``, the disk centre's displacement off the axis (y, z), m; ``"spin"``, the disk's rate
    about x, rad/s.
    """
    from ..bodies.floating_spatial.solid import FloatingSolid3D
    from ..bodies.spatial import SpatialPointMass
    from ..elements.constraints.spatial_joints import Spherical
    from ..elements.forces.spatial import SpatialMoment
    from ..fem.elasticity3d import ElasticSolid3D

    c = ROTOR_3D
    moment, duration = float(torque), positive_value("T", T)
    mass = float(unbalance)
    if not (np.isfinite(moment) and np.isfinite(mass)) or mass < 0.0:
        raise ValueError(f"torque must be finite and unbalance finite and ≥ 0 kg, got {torque!r} and {unbalance!r}")
    L, a, h, D = c["length"], c["shaft"], c["disk_thickness"], c["disk"]
    across = np.array([-D / 2, -D / 2 + (D - a) / 6, -D / 2 + (D - a) / 3, -a / 2, a / 2, a / 2 + (D - a) / 6,
                       a / 2 + (D - a) / 3, D / 2])
    grid = skfem.MeshHex.init_tensor(np.linspace(0.0, L, 16), across, across)
    centre = grid.p[:, grid.t].mean(axis=1)
    shaft = (np.abs(centre[1]) < a / 2) & (np.abs(centre[2]) < a / 2)
    disk = np.abs(centre[0] - L / 2) < h / 2
    mesh = grid.remove_elements(np.flatnonzero(~(shaft | disk))).to_meshtet()
    solid = ElasticSolid3D(mesh, c["E"], c["nu"], c["rho"], name="shaft")
    body = FloatingSolid3D(solid, lambda X: np.abs(X[0] - L / 2) <= h / 2 + 1e-9, positive_count("n_modes", n_modes),
                           interfaces={"driven end": lambda X: np.isclose(X[0], 0.0),
                                       "far end": lambda X: np.isclose(X[0], L)}, name="rotor")
    joints = [Spherical(body.point("driven end"), name="bearing 1"), Spherical(body.point("far end"),
                                                                                name="bearing 2")]
    bodies = [body]
    if mass > 0.0:
        rim = body.frame_point((0.0, D / 2, 0.0))
        weight = SpatialPointMass(mass, position=rim.position(body.q0), name="unbalance")
        bodies.append(weight)
        joints.append(Spherical(weight.point(), rim, name="unbalance mount"))
    drive = SpatialMoment(body, lambda t: np.array([moment if 0.0 <= t <= duration else 0.0, 0.0, 0.0]),
                          name="drive torque")

    def disk_probe(scene, t, q, v):
        return scene.coordinates(body, q)[1:3] - body.q0[1:3]

    def spin_probe(scene, t, q, v):
        return float(body.body_angular_velocity(scene.coordinates(body, q), scene.coordinates(body, v))[0])

    return Scene(bodies, constraints=joints, forces=[drive], name="rotor_3d",
                 probes={"disk": disk_probe, "spin": spin_probe},
                 parameters=dict(torque=torque, T=T, unbalance=unbalance, n_modes=n_modes))
