"""Spatial catalogue scenes: heavy tops, a chain of rigid bars, Bricard's mechanism and the spatial slider–crank
(docs/spatial.md)."""
from __future__ import annotations

import numpy as np

from ..bodies.probes import PointProbe
from ..bodies.quaternion import QuaternionRigidBody
from ..bodies.spatial import SpatialRigidBody
from ..elements.constraints.quadratic import perpendiculars
from ..elements.constraints.spatial_joints import Revolute3D
from ..elements.forces import Gravity
from ..numerics.quaternions import rotation_vector_matrix
from ..scene import Scene
from ..numerics.resources import check_fits
from ._registry import positive_count, positive_value, register

#: peak memory per body of a spatial chain and its run, bytes (twice the 50 kB a body the scene takes)
BYTES_PER_SPATIAL_BODY = 100_000

__all__ = ["heavy_top", "rigid_chain", "bricard", "spatial_slider_crank", "BRULS_REFERENCE", "BRICARD_REFERENCE",
           "SLIDER_CRANK_REFERENCE"]

#: Euler parameters of the Brüls top at t = 0.2 s (published RK4 reference at Δt = 1e-4 s)
BRULS_REFERENCE = np.array([-0.708279152974, 0.438781088127, 0.545728396145, 0.089399752824])

_VARIANTS = ("simo-wong", "bruls")
_ROTATIONS = {"directors": SpatialRigidBody, "quaternion": QuaternionRigidBody}


@register(t_end=10.0, dt=0.009, variant="-", rotation="-")
def heavy_top(variant="simo-wong", rotation="directors"):
    """A heavy symmetric top about a fixed point (the pivot, at the origin).

    ``"simo-wong"`` (Simo & Wong 1991): inertia about the pivot diag(5, 5, 1) kg m² in body axes, centre
    of mass at 1 m on the body's third axis, m = 20 kg, g = 1 m/s² along −e₃ (m g l = 20 N m), initial
    rotation exp(skew(0.05, 0, 0)), initial body angular velocity (0, 0, 50) rad/s.

    ``"bruls"`` (Brüls & Cardona 2010): m = 15 kg, inertia about the centre of mass
    diag(0.234375, 0.46875, 0.234375) kg m², centre of mass at (0, 1, 0) m from the pivot, body and space
    axes coincide at t = 0, initial body angular velocity (0, 150, −4.61538) rad/s, g = 9.81 m/s² along
    −z; its Euler parameters at t = 0.2 s are :data:`BRULS_REFERENCE`.

    ``rotation="directors"`` (default): the top is a :class:`~skfem_flex.bodies.spatial.SpatialRigidBody`
    turning about its pivot (nine director coordinates, the faster step). ``"quaternion"``: a
    :class:`~skfem_flex.bodies.quaternion.QuaternionRigidBody` (four Euler parameters), whose energy–momentum
    step also conserves the spin about the symmetry axis to round-off (the directors keep it to O(Δt²)).
    Probes: ``"com"`` (the centre of mass, m).
    """
    if variant not in _VARIANTS:
        raise ValueError(f"heavy_top: variant must be one of {_VARIANTS}, got {variant!r}")
    if rotation not in _ROTATIONS:
        raise ValueError(f"heavy_top: rotation must be one of {tuple(_ROTATIONS)}, got {rotation!r}")
    body = _ROTATIONS[rotation]
    if variant == "simo-wong":
        top = body(20.0, [5.0, 5.0, 1.0], orientation=rotation_vector_matrix([0.05, 0.0, 0.0]),
                   body_angular_velocity=[0.0, 0.0, 50.0], pivot=[0.0, 0.0, 0.0], center_of_mass=[0.0, 0.0, 1.0],
                   size=[0.6, 0.6, 2.0], name="top")
        g = (0.0, 0.0, -1.0)
    else:
        m, c = 15.0, np.array([0.0, 1.0, 0.0])
        jc = np.diag([0.234375, 0.46875, 0.234375])
        top = body(m, jc + m * (c @ c * np.eye(3) - np.outer(c, c)), body_angular_velocity=[0.0, 150.0, -4.61538],
                   pivot=[0.0, 0.0, 0.0], center_of_mass=c, size=[0.5, 2.0, 0.5], name="top")
        g = (0.0, 0.0, -9.81)
    return Scene([top], forces=[Gravity(g)], name="heavy_top",
                 probes={"com": PointProbe(top.point(top.center))},
                 parameters=dict(variant=variant, rotation=rotation))


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
    # building the scene takes about 50 kB a body (measured at 2 000 bodies), a run of it about as much again
    check_fits(BYTES_PER_SPATIAL_BODY * n, f"a chain of {n} spatial bodies")
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


#: P3 of the Bricard mechanism (square-section rods) at t = 0.5, 1, 2, 10 s, m: a reduced (one-coordinate)
#: Lagrange model integrated by DOP853 (rtol 1e-11), which exudyn's converged run matches to 3.4e-7 m
BRICARD_REFERENCE = {0.5: (0.774718, -0.979815, -0.199906), 1.0: (0.274481, -0.886708, -0.462330),
                     2.0: (-0.778135, -0.980353, -0.197253), 10.0: (0.999731, -1.000000, -0.000269)}


@register(t_end=10.0, dt=1e-3, side="m")
def bricard(side=0.1):
    """Bricard's mechanism (IFToMM multibody benchmark A04): five rods of 1 m and 1 kg (square section of
    ``side`` = 0.1 m, the inertia of that cuboid), six hinges in a closed loop at A (0, 0, 0) about y, B (1, 0, 0) about z, C (1, −1, 0) about x,
    D (1, −1, 1) about y, E (0, −1, 1) about z and F (0, 0, 1) about x, the loop closed through the ground
    from F to A; gravity 9.81 m/s² along −y; released at rest, 10 s.

    Grübler's count gives no mobility, but the loop moves with one degree of freedom: its 30 hinge equations
    have rank 29 everywhere along the motion. The scene drops the dependent one
    (:func:`~skfem_flex.scene_initial.drop_redundant_constraints`, a warning says which: the 5th equation of
    hinge F). Probe ``"P3"``: the point C, m (:data:`BRICARD_REFERENCE`, for side = 0.1 m).
    """
    from ..scene_initial import drop_redundant_constraints

    side = positive_value("side", side)
    if side >= 1.0:
        raise ValueError(f"side must be below the rods' length 1 m, got {side!r} m")
    points = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1.0]])
    axes = np.eye(3)[[1, 2, 0, 1, 2, 0]]
    mass = 1.0
    axial, transverse = mass * 2 * side ** 2 / 12.0, mass * (1.0 + side ** 2) / 12.0
    links = []
    for k in range(5):
        e = points[k + 1] - points[k]
        inertia = transverse * np.eye(3) + (axial - transverse) * np.outer(e, e)
        links.append(SpatialRigidBody(mass, inertia, position=0.5 * (points[k] + points[k + 1]),
                                      size=np.abs(e) + side * (1 - np.abs(e)), name=f"link {k + 1}"))

    def at(body, k):
        return body.point(body.body_coordinates(points[k]))

    hinges = [Revolute3D(at(links[0], 0), None, axis=axes[0], name="A")]
    hinges += [Revolute3D(at(links[k - 1], k), at(links[k], k), axis=axes[k], name="BCDE"[k - 1]) for k in range(1, 5)]
    hinges.append(Revolute3D(at(links[4], 5), None, axis=axes[5], name="F"))
    scene = Scene(links, hinges, [Gravity((0.0, -9.81, 0.0))], name="bricard",
                  probes={"P3": PointProbe(at(links[1], 2))}, parameters=dict(side=side))
    return drop_redundant_constraints(scene)[0]


#: the IFToMM spatial slider–crank (crank's centre of mass at mid-crank, the cross of the universal joint
#: along x on the slider): (slider position x_C m, crank angle θ rad unwrapped) at t = 0.1, 0.5, 1, 2, 3 s
#: from a reduced one-coordinate Lagrange model integrated by DOP853 (rtol 1e-12)
SLIDER_CRANK_REFERENCE = {0.1: (0.226787189, 0.560031482), 0.5: (0.184952630, 5.583762553),
                          1.0: (0.211721661, 10.913590729), 2.0: (0.289085197, 21.072744514),
                          3.0: (0.228484813, 32.008327751)}


@register(t_end=5.0, dt=1e-3, omega="rad/s", body="-", n_modes="-")
def spatial_slider_crank(omega=6.0, body="rigid", n_modes=6):
    """The IFToMM benchmark "spatial rigid slider–crank mechanism": a crank (0.08 m, 0.12 kg) hinged about x
    at A = (0, 0.1, 0.12) m, a rod (0.3 m, 0.5 kg) on a ball joint at the crank's end B and a cross (universal)
    joint at C on a slider (2 kg) that slides along the x axis; gravity 9.81 m/s² along −z; the crank starts
    upright turning at ``omega`` = 6 rad/s about +x (the other velocities consistent), 5 s.

    Inertias about the centres of mass: crank 1e-4 kg m² about x and about y, 1e-5 about its axis; rod 4e-4
    about its axis and 4e-3 across; slider 1e-4. The crank's centre of mass is at mid-crank and the cross's
    slider arm is along x (the rod's arm perpendicular to the rod and to x): the published data leave these
    two choices open. Probes: ``"slider"`` (x_C, m) and ``"crank angle"`` (θ, rad, in (−π, π]);
    :data:`SLIDER_CRANK_REFERENCE` (for omega = 6 rad/s).

    ``body="solid-modal"`` makes the rod a meshed steel bar (:func:`meshed_rod_3d`: 0.3 m, square section of
    the rod's mass, P2 tetrahedra) reduced by Craig–Bampton to ``n_modes`` modes: its frame is clamped at the
    C end, where the cross joint needs an orientation, and the ball joint holds its B end face (a rigid
    interface). Its inertia is the bar's, not the benchmark's rod's.
    """
    from ..elements.constraints.spatial_joints import Prismatic3D, Spherical, Universal

    rate = float(omega)
    if not np.isfinite(rate) or abs(rate) > 1e4:
        raise ValueError(f"omega must be finite and at most 1e4 rad/s in size, got {omega!r}")
    scale = rate / 6.0            # one degree of freedom: every velocity is proportional to the crank's
    A, B, C = np.array([0.0, 0.1, 0.12]), np.array([0.0, 0.1, 0.2]), np.array([0.2, 0.0, 0.0])
    omega = np.array([rate, 0.0, 0.0])
    crank = SpatialRigidBody(0.12, [1e-4, 1e-4, 1e-5], position=0.5 * (A + B), velocity=np.cross(omega, 0.5 * (B - A)),
                             angular_velocity=omega, size=[0.01, 0.01, 0.08], name="crank")
    e = (C - B) / np.linalg.norm(C - B)
    rod_velocity, rod_omega = scale * np.array([0.12, -0.24, 0.0]), scale * np.array([1.92, -0.96, 0.48])
    if body not in ("rigid", "solid-modal"):
        raise ValueError(f"body must be 'rigid' or 'solid-modal', got {body!r}")
    if body == "rigid":
        rod = SpatialRigidBody(0.5, 4e-3 * np.eye(3) + (4e-4 - 4e-3) * np.outer(e, e), position=0.5 * (B + C),
                               velocity=rod_velocity, angular_velocity=rod_omega, name="rod")
        rod_b, rod_c = rod.point(rod.body_coordinates(B)), rod.point(rod.body_coordinates(C))
    else:
        rod = meshed_rod_3d(C, B, n_modes, velocity=rod_velocity + np.cross(rod_omega, C - 0.5 * (B + C)),
                            angular_velocity=rod_omega)
        rod_b, rod_c = rod.point("B"), rod.point("frame")
    slider = SpatialRigidBody(2.0, [1e-4, 1e-4, 1e-4], position=C, velocity=[0.24 * scale, 0.0, 0.0], size=[0.05] * 3,
                              name="slider")
    cross = np.cross(e, [1.0, 0.0, 0.0])
    joints = [Revolute3D(crank.point(crank.body_coordinates(A)), None, axis=(1.0, 0.0, 0.0), name="crank hinge"),
              Spherical(crank.point(crank.body_coordinates(B)), rod_b, name="ball"),
              Universal(rod_c, slider.point(), axis_a=cross, axis_b=(1.0, 0.0, 0.0), name="cross"),
              Prismatic3D(slider.point(), None, axis=(1.0, 0.0, 0.0), name="guide")]

    def crank_angle(scene, t, q, v):
        d3 = scene.coordinates(crank, q)[9:12]
        return float(np.arctan2(-d3[1], d3[2]))

    return Scene([crank, rod, slider], joints, [Gravity((0.0, 0.0, -9.81))], name="spatial_slider_crank",
                 probes={"slider": lambda scene, t, q, v: float(scene.coordinates(slider, q)[0]),
                         "crank angle": crank_angle}, parameters=dict(omega=rate, body=body, n_modes=n_modes))


def meshed_rod_3d(start, end, n_modes, velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), mass=0.5,
                  n_elements=12):
    """A steel bar from ``start`` to ``end`` (m) of square section with the given ``mass`` (kg), P2 tetrahedra
    (``n_elements`` hexahedra along, each split in six), reduced by Craig–Bampton (``n_modes``) to a
    :class:`~skfem_flex.bodies.floating_spatial.solid.FloatingSolid3D`: its frame clamped at the ``start`` face
    (its origin the face's centre), the ``end`` face the rigid interface ``"B"``; the frame's first axis along
    the bar. ``velocity`` is the start face centre's, ``angular_velocity`` the bar's (space axes)."""
    import skfem

    from ..bodies.floating_spatial.solid import FloatingSolid3D
    from ..fem.elasticity3d import ElasticSolid3D
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    length = float(np.linalg.norm(end - start))
    rho = 7800.0
    side = np.sqrt(mass / (rho * length))
    mesh = skfem.MeshHex.init_tensor(np.linspace(0.0, length, n_elements + 1), np.linspace(-side / 2, side / 2, 2),
                                     np.linspace(-side / 2, side / 2, 2)).to_meshtet()
    solid = ElasticSolid3D(mesh, E=2e11, nu=0.3, rho=rho, name="rod")
    axis = (end - start) / length
    R = np.column_stack([axis, *perpendiculars(axis)])
    return FloatingSolid3D(solid, lambda X: np.isclose(X[0], 0.0), int(n_modes),
                           interfaces={"B": lambda X: np.isclose(X[0], length)}, position=start, orientation=R,
                           velocity=velocity, angular_velocity=angular_velocity, name="rod")

