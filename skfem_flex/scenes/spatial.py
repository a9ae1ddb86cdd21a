"""Spatial catalogue scenes: heavy tops and a chain of rigid bars (docs/spatial.md)."""
from __future__ import annotations

import numpy as np

from ..bodies.probes import PointProbe
from ..bodies.spatial import SpatialRigidBody
from ..elements.constraints.spatial_joints import Revolute3D
from ..elements.forces import Gravity
from ..numerics.quaternions import rotation_vector_matrix
from ..scene import Scene
from ._registry import positive_count, positive_value, register

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


@register(t_end=2.0, dt=0.005, n_bodies="-", length="m", mass="kg", g="m/s^2")
def rigid_chain(n_bodies=10, length=1.0, mass=1.0, g=9.81):
    """A chain of slender rigid bars under gravity, joined by hinges whose axes alternate (y, z, y, …).

    Bar k (length ``length``, mass ``mass``, a 0.05 m square section) starts along +x from x = k l; the
    first is hinged to the ground at the origin about y, each next to the end of the one before about z
    or y in turn, so the chain swings and folds in space; gravity along −z. Probes: ``"tip"`` (the free end
    of the last bar, m).
    """
    n = positive_count("n_bodies", n_bodies)
    length = positive_value("length", length)
    mass = positive_value("mass", mass)
    a = 0.05
    jx = mass * 2 * a * a / 12.0
    jt = mass * (length ** 2 + a * a) / 12.0
    bodies, joints = [], []
    for k in range(n):
        bar = SpatialRigidBody(mass, [jx, jt, jt], position=[(k + 0.5) * length, 0.0, 0.0], size=[length, a, a],
                               name=f"bar {k + 1}")
        start = bar.point([-0.5 * length, 0.0, 0.0])
        axis = (0.0, 1.0, 0.0) if k % 2 == 0 else (0.0, 0.0, 1.0)
        if k == 0:
            joints.append(Revolute3D(start, None, axis=axis, name="hinge 1"))
        else:
            joints.append(Revolute3D(bodies[-1].point([0.5 * length, 0.0, 0.0]), start, axis=axis,
                                     name=f"hinge {k + 1}"))
        bodies.append(bar)
    return Scene(bodies, joints, [Gravity((0.0, 0.0, -float(g)))], name="rigid_chain",
                 probes={"tip": PointProbe(bodies[-1].point([0.5 * length, 0.0, 0.0]))},
                 parameters=dict(n_bodies=n, length=length, mass=mass, g=g))

