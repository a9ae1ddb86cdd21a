"""Spatial catalogue scenes: heavy tops and a chain of rigid bars (docs/spatial.md)."""
from __future__ import annotations

import numpy as np

from ..bodies.probes import PointProbe
from ..bodies.spatial import SpatialRigidBody
from ..elements.constraints.spatial_joints import Revolute3D
from ..elements.forces import Gravity
from ..numerics.quaternions import rotation_vector_matrix
from ..scene import Scene
from ._registry import positive_count, register

__all__ = ["heavy_top", "rigid_chain", "BRULS_REFERENCE"]

#: Euler parameters of the Brüls top at t = 0.2 s (published RK4 reference at Δt = 1e-4 s)
BRULS_REFERENCE = np.array([-0.708279152974, 0.438781088127, 0.545728396145, 0.089399752824])

_VARIANTS = ("simo-wong", "bruls")


@register(t_end=10.0, dt=0.009, variant="-")
def heavy_top(variant="simo-wong"):
    """A heavy symmetric top about a fixed point (the pivot, at the origin).

    ``"simo-wong"`` (Simo & Wong 1991): inertia about the pivot diag(5, 5, 1) kg m² in body axes, centre
    of mass at 1 m on the body's third axis, m = 20 kg, g = 1 m/s² along −e₃ (m g l = 20 N m), initial
    rotation exp(skew(0.05, 0, 0)), initial body angular velocity (0, 0, 50) rad/s.

    ``"bruls"`` (Brüls & Cardona 2010): m = 15 kg, inertia about the centre of mass
    diag(0.234375, 0.46875, 0.234375) kg m², centre of mass at (0, 1, 0) m from the pivot, body and space
    axes coincide at t = 0, initial body angular velocity (0, 150, −4.61538) rad/s, g = 9.81 m/s² along
    −z; its Euler parameters at t = 0.2 s are :data:`BRULS_REFERENCE`.

    The top is a :class:`~skfem_flex.bodies.spatial.SpatialRigidBody` turning about its pivot (nine
    director coordinates). Probes: ``"com"`` (the centre of mass, m).
    """
    if variant not in _VARIANTS:
        raise ValueError(f"heavy_top: variant must be one of {_VARIANTS}, got {variant!r}")
    if variant == "simo-wong":
        top = SpatialRigidBody(20.0, [5.0, 5.0, 1.0], orientation=rotation_vector_matrix([0.05, 0.0, 0.0]),
                               body_angular_velocity=[0.0, 0.0, 50.0], pivot=[0.0, 0.0, 0.0],
                               center_of_mass=[0.0, 0.0, 1.0], size=[0.6, 0.6, 2.0], name="top")
        g = (0.0, 0.0, -1.0)
    else:
        m, c = 15.0, np.array([0.0, 1.0, 0.0])
        jc = np.diag([0.234375, 0.46875, 0.234375])
        top = SpatialRigidBody(m, jc + m * (c @ c * np.eye(3) - np.outer(c, c)),
                               body_angular_velocity=[0.0, 150.0, -4.61538], pivot=[0.0, 0.0, 0.0],
                               center_of_mass=c, size=[0.5, 2.0, 0.5], name="top")
        g = (0.0, 0.0, -9.81)
    return Scene([top], forces=[Gravity(g)], name="heavy_top",
                 probes={"com": PointProbe(top.point(top.center))}, parameters=dict(variant=variant))


@register(t_end=1.0, dt=1e-3, n_bodies="-")
def rigid_chain(n_bodies=10):
    """A spatial chain of rigid bars on hinges under gravity: the layout of exudyn's 3D rigid-body
    performance test (``perf3DRigidBodies``, 400 bars there).

    Bars of 0.4 m × 0.1 m × 0.1 m, density 1000 kg/m³ (m = 4 kg, the cuboid's inertia), placed end to end:
    bar k + 1 is turned against bar k by R_x(δ) R_z(2δ), δ = 0.01π, so the chain starts as a helix-like
    curve; each bar is hinged at its start about its own third axis, the first to the ground at the
    origin; gravity 9.81 m/s² along −z; released at rest. Probes: ``"tip"`` (the free end of the last
    bar, m).
    """
    n = positive_count("n_bodies", n_bodies)
    length, width, density = 0.4, 0.1, 1000.0
    mass = density * length * width * width
    inertia = [mass * 2 * width ** 2 / 12.0] + [mass * (length ** 2 + width ** 2) / 12.0] * 2
    delta = 0.01 * np.pi
    turn = rotation_vector_matrix([delta, 0.0, 0.0]) @ rotation_vector_matrix([0.0, 0.0, 2 * delta])
    R, start = np.eye(3), np.zeros(3)
    bodies, joints = [], []
    for k in range(n):
        bar = SpatialRigidBody(mass, inertia, position=start + R @ [0.5 * length, 0.0, 0.0], orientation=R,
                               size=[length, width, width], name=f"bar {k + 1}")
        near = bar.point([-0.5 * length, 0.0, 0.0])
        previous = None if k == 0 else bodies[-1].point([0.5 * length, 0.0, 0.0])
        # the hinge: the end of the bar before (or the ground) and this bar's start, about this bar's e₃
        if previous is None:
            joints.append(Revolute3D(near, None, axis=R[:, 2], name="hinge 1"))
        else:
            joints.append(Revolute3D(previous, near, axis=R[:, 2], name=f"hinge {k + 1}"))
        bodies.append(bar)
        start = start + R @ [length, 0.0, 0.0]
        R = R @ turn
    return Scene(bodies, joints, [Gravity((0.0, 0.0, -9.81))], name="rigid_chain",
                 probes={"tip": PointProbe(bodies[-1].point([0.5 * length, 0.0, 0.0]))},
                 parameters=dict(n_bodies=n))
