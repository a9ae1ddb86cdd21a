"""Spatial beam catalogue scenes: the 45° bend, the right-angle frame and the 3D flying beam
(docs/spatial_beams.md)."""
from __future__ import annotations

import numpy as np

from ..bodies.exact.spatial_body import SpatialExactBeam
from ..bodies.probes import PointProbe
from ..bodies.spatial import SpatialRigidBody
from ..elements.constraints.spatial_joints import Revolute3D, RotationDriver, Weld3D
from ..elements.forces.spatial import SpatialMoment, SpatialPointForce
from ..elements.motion import spin_up_law
from ..fem.spatial_section import SpatialSection
from ..scene import Scene
from ._registry import positive_count, positive_value, register
from .spatial_rotors import floating_hub_beam_3d, hub_frame_displacement

__all__ = ["bend_45", "right_angle_frame", "flying_spaghetti_3d", "spin_up_3d", "BEND_45_REFERENCE", "hat_pulse"]

#: tip displacement (m, in the scene's global axes) of the 45° bend under the tip load 600: the spectrally
#: converged single-element result of Kynema's Legendre spectral element (identical for 15 and 18 nodes), with
#: the same stiffnesses as :func:`bend_45`
BEND_45_REFERENCE = np.array([-23.64597160, -13.72080060, 53.57764506])


def _order(order):
    if order not in (1, 2) or isinstance(order, bool):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    return int(order)


def hat_pulse(peak, rise):
    """h(t): 0 → ``peak`` linearly over [0, rise], back to 0 over [rise, 2 rise], 0 after."""
    peak, rise = float(peak), float(rise)

    def h(t):
        return peak * max(0.0, 1.0 - abs(t - rise) / rise) if 0.0 <= t <= 2.0 * rise else 0.0
    return h


@register(t_end=1.0, dt=0.1, n_elements="-", order="-", interpolation="-")
def bend_45(n_elements=8, order=1, interpolation=None):
    """The Bathe–Bolourchi 45° bend: a cantilever curved on a radius of 100 through 45° in the x–y plane
    (root at the origin, tangent along x, the arc turning towards +y), unit square section, E = 1e7,
    ν = 0 (G = 5e6): EA = 1e7, kGA = 4.16667e6 (k = 5/6), EI = 8.3333e5 about both axes,
    GJ = 8.3333e5 (J = 1/6), density 1 (ρA = 1, ρI = 1/12); a dead tip force of 600 along +z, normal to
    the plane of the bend. Clamped at the root by a weld.

    Static: ``static_equilibrium(scene)`` or ``simulate(..., start="static")``. Probe ``"tip"`` (its
    position, m); :data:`BEND_45_REFERENCE` is the converged tip displacement. ``interpolation``: of the
    beam's elements (:class:`~skfem_flex.bodies.exact.spatial_body.SpatialExactBeam`; by default rotations for
    P1, directors for P2).
    """
    n = positive_count("n_elements", n_elements)
    E, G, R = 1e7, 5e6, 100.0
    sec = SpatialSection(EA=E, GA1=5.0 / 6.0 * G, GA2=5.0 / 6.0 * G, GJ=G / 6.0, EI1=E / 12.0, EI2=E / 12.0,
                         rhoA=1.0, rhoI1=1.0 / 12.0, rhoI2=1.0 / 12.0)

    def placement(s):
        th = s / R
        d3 = np.array([np.cos(th), np.sin(th), 0.0])
        d1 = np.array([0.0, 0.0, 1.0])
        return np.array([R * np.sin(th), R * (1.0 - np.cos(th)), 0.0]), np.column_stack([d1, np.cross(d3, d1), d3])

    beam = SpatialExactBeam(sec, R * np.pi / 4.0, placement, n_elements=n, order=_order(order), name="bend",
                            interpolation=interpolation)
    tip = beam.point(beam.length)
    return Scene([beam], constraints=[Weld3D(beam.point(0.0), name="clamp")],
                 forces=[SpatialPointForce(tip, (0.0, 0.0, 600.0), name="tip load")], name="bend_45",
                 probes={"tip": PointProbe(tip)},
                 parameters=dict(n_elements=n, order=order, interpolation=beam.interpolation))


@register(t_end=30.0, dt=0.05, n_elements="-", order="-", interpolation="-")
def right_angle_frame(n_elements=10, order=1, interpolation=None):
    """The Simo–Vu-Quoc right-angle cantilever: two legs of 10 in the x–y plane, the first from the
    clamped root at the origin to the elbow at (0, 10, 0), the second from the elbow to the tip at
    (−10, 10, 0), welded at the elbow; EA = GA = 1e6, EI = GJ = 1e3, ρA = 1, ρI = diag(20, 10, 10) (polar,
    about d₁, about d₂); a force at the elbow along +z rising linearly to 50 at t = 1 and back to 0 at
    t = 2. ``n_elements`` per leg (``interpolation`` as for :func:`bend_45`). Probes ``"elbow"`` and ``"tip"``
    (positions, m).
    """
    n = positive_count("n_elements", n_elements)
    sec = SpatialSection(EA=1e6, GA1=1e6, GA2=1e6, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=10.0, rhoI2=10.0)
    p = _order(order)
    leg1 = SpatialExactBeam.straight(sec, (0.0, 0.0, 0.0), (0.0, 10.0, 0.0), n_elements=n, order=p,
                                     normal=(0.0, 0.0, 1.0), name="leg 1", interpolation=interpolation)
    leg2 = SpatialExactBeam.straight(sec, (0.0, 10.0, 0.0), (-10.0, 10.0, 0.0), n_elements=n, order=p,
                                     normal=(0.0, 0.0, 1.0), name="leg 2", interpolation=interpolation)
    elbow = leg1.point(leg1.length)
    return Scene([leg1, leg2],
                 constraints=[Weld3D(leg1.point(0.0), name="clamp"), Weld3D(elbow, leg2.point(0.0), name="elbow")],
                 forces=[SpatialPointForce(elbow, lambda t: np.array([0.0, 0.0, hat_pulse(50.0, 1.0)(t)]),
                                           name="elbow load")],
                 name="right_angle_frame", probes={"elbow": PointProbe(elbow), "tip": PointProbe(leg2.point(10.0))},
                 parameters=dict(n_elements=n, order=order, interpolation=leg1.interpolation))


@register(t_end=30.0, dt=0.1, n_elements="-", order="-", interpolation="-")
def flying_spaghetti_3d(n_elements=10, order=1, interpolation=None):
    """Simo and Vu-Quoc's flying beam in space: a free beam from (6, 0, 0) to (0, 0, 8) (length 10),
    EA = GA = 1e4, EI = GJ = 500, ρA = 1, ρI = diag(20, 10, 10); at the (6, 0, 0) end a force
    F_x = 0.1 h(t) and moments M_y = h(t), M_z = 0.5 h(t), fixed in space, with the hat pulse h rising
    from 0 to 200 at t = 2.5 and back to 0 at t = 5. After t = 5 the beam flies free: its linear momentum is
    the impulse (50, 0, 0) kg m/s, and energy and angular momentum are constant. ``interpolation`` as for
    :func:`bend_45`. Probe ``"tip"`` (the (0, 0, 8) end, m).
    """
    n = positive_count("n_elements", n_elements)
    sec = SpatialSection(EA=1e4, GA1=1e4, GA2=1e4, GJ=500.0, EI1=500.0, EI2=500.0, rhoA=1.0, rhoI1=10.0,
                         rhoI2=10.0)
    beam = SpatialExactBeam.straight(sec, (6.0, 0.0, 0.0), (0.0, 0.0, 8.0), n_elements=n, order=_order(order),
                                     normal=(0.0, 1.0, 0.0), name="beam", interpolation=interpolation)
    end = beam.point(0.0)
    h = hat_pulse(200.0, 2.5)
    return Scene([beam], forces=[SpatialPointForce(end, lambda t: np.array([0.1 * h(t), 0.0, 0.0]), name="force"),
                                 SpatialMoment(end, lambda t: np.array([0.0, h(t), 0.5 * h(t)]), name="moment")],
                 name="flying_spaghetti_3d", probes={"tip": PointProbe(beam.point(beam.length))},
                 parameters=dict(n_elements=n, order=order, interpolation=beam.interpolation))


@register(t_end=30.0, dt=0.01, omega="rad/s", T="s", length="m", EA="N", EI="N m²", GJ="N m²", kGA="N",
          rhoA="kg/m", rhoI="kg m", tip_load="N", n_elements="-", order="-", body="-")
def spin_up_3d(omega=4.0, T=15.0, length=10.0, EA=2.8e7, EI=1.4e4, GJ=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
               tip_load=10.0, n_elements=8, order=1, body="exact"):
    """The spin-up manoeuvre of Simo and Vu-Quoc in space: the planar spin-up beam (its hub angle
    :func:`~skfem_flex.elements.motion.spin_up_law`, length, EA, EI, kGA, ρA, ρI; here EI and ρI the same
    about both section axes, and GJ) as a :class:`~skfem_flex.bodies.exact.spatial_body.SpatialExactBeam`
    welded to a hub that turns about z on a hinge with a rotation driver, with an out-of-plane tip load
    along z growing with the spin, ``tip_load`` · min(t/T, 1) (N). With ``tip_load`` = 0 it moves in the
    plane of the planar scene. ``body="floating"`` builds the same manoeuvre with a spatial floating-frame beam
    (:func:`~skfem_flex.scenes.spatial_rotors.floating_hub_beam_3d`) whose frame is the hub.

    Probe ``"tip"``: the tip's displacement in the hub frame, R_hubᵀ (r_tip − r_root) − (L, 0, 0) (axial,
    in-plane transverse, out of plane), m.
    """
    n = positive_count("n_elements", n_elements)
    length = positive_value("length", length)
    T = positive_value("T", T)
    load = float(tip_load)
    if not np.isfinite(load):
        raise ValueError(f"tip_load must be finite, got {tip_load!r}")
    params = dict(omega=omega, T=T, length=length, EA=EA, EI=EI, GJ=GJ, kGA=kGA, rhoA=rhoA, rhoI=rhoI, tip_load=load,
                  n_elements=n, order=order, body=body)

    def load_law(t):
        return np.array([0.0, 0.0, load * min(max(t, 0.0) / T, 1.0)])
    if body not in ("exact", "floating"):
        raise ValueError(f"body must be 'exact' or 'floating', got {body!r}")
    if body == "floating":
        ffr = floating_hub_beam_3d(length, EA, EI, GJ, kGA, rhoA, rhoI, n, _order(order))
        axis = (0.0, 0.0, 1.0)
        tip = ffr.point(length)
        return Scene([ffr], constraints=[Revolute3D(ffr.point(0.0), axis=axis, name="hub hinge"),
                                         RotationDriver(ffr, None, axis, spin_up_law(positive_value("omega", omega), T),
                                                        name="hub drive")],
                     forces=[SpatialPointForce(tip, load_law, name="tip load")], name="spin_up_3d",
                     probes={"tip": hub_frame_displacement(ffr, tip, length)}, parameters=params)
    sec = SpatialSection(EA=EA, GA1=kGA, GA2=kGA, GJ=GJ, EI1=EI, EI2=EI, rhoA=rhoA, rhoI1=rhoI, rhoI2=rhoI)
    beam = SpatialExactBeam.straight(sec, (0.0, 0.0, 0.0), (length, 0.0, 0.0), n_elements=n, order=_order(order),
                                     normal=(0.0, 1.0, 0.0), name="beam")
    hub = SpatialRigidBody(1.0, [0.1, 0.1, 0.1], name="hub")
    joints = [Revolute3D(hub.point([0.0, 0.0, 0.0]), axis=(0.0, 0.0, 1.0), name="hub hinge"),
              RotationDriver(hub, None, (0.0, 0.0, 1.0), spin_up_law(positive_value("omega", omega), T),
                             name="hub drive"),
              Weld3D(beam.point(0.0), hub.point([0.0, 0.0, 0.0]), name="clamp")]
    tip, root = beam.point(length), beam.point(0.0)

    def probe_tip(scene, t, q, v):
        qb, qh = scene.coordinates(beam, q), scene.coordinates(hub, q)
        return hub.rotation_matrix(qh).T @ (tip.position(qb) - root.position(qb)) - [length, 0.0, 0.0]

    force = SpatialPointForce(tip, load_law, name="tip load")
    return Scene([hub, beam], constraints=joints, forces=[force], name="spin_up_3d", probes={"tip": probe_tip},
                 parameters=params)
