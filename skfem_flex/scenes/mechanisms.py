r"""Multibody scenes with joints: pendulums, the flexible slider–crank, a free beam, a pinned spin-up.

``flexible_pendulum``
    A floating-frame beam pinned at one end, released at rest from horizontal.
``double_pendulum``
    A rigid bar pinned to the ground with a flexible beam hinged at its tip.
``slider_crank``
    The flexible slider–crank of Simeon (1996), the DAE test problem "crank".
``free_beam``
    A free floating-frame beam in zero gravity, set flying by a short force pulse.
``spin_up_pinned``
    The spin-up beam with a :class:`~skfem_flex.elements.constraints.Pin` at the hub and a
    :class:`~skfem_flex.elements.constraints.Driver` on the hub angle (instead of prescribed coordinates).
"""
from __future__ import annotations

import numpy as np

from ..fem.beam import TimoshenkoBeam, line_mesh
from ..bodies.floating.body import FloatingBeam
from ..bodies.particle import PointMass
from ..bodies.probes import CombinedProbe, LinearProbe, PointProbe
from ..bodies.rigid import RigidBody
from ..elements.constraints import Driver, Pin, Revolute, Slider
from ..elements.forces import Gravity, PointForce, half_sine_pulse
from ..elements.motion import MotionLaw, spin_up_law
from ..scene import Scene
from ..fem.section import Section
from ._registry import positive_count as _count, positive_value as _positive, register
from .links import LINK_KINDS, link
from .rotating import hub_beam

__all__ = ["flexible_pendulum", "double_pendulum", "slider_crank", "free_beam", "spin_up_pinned",
           "SIMEON_REFERENCE", "SIMEON_INIT", "chord_deflection"]

_SECTION_UNITS = dict(EA="N", EI="N m^2", kGA="N", rhoA="kg/m", rhoI="kg m", n_elements="-")


def _beam(length, section, n_elements, reference="clamped", name="beam", strain="green-lagrange", **kwargs):
    length = _positive("length", length)
    n = _count("n_elements", n_elements)
    tb = TimoshenkoBeam(line_mesh(length, n), section)
    return FloatingBeam(tb, reference=reference, strain=strain, name=name, **kwargs)


def _position_probe(body, point):
    return PointProbe(point)


def chord_deflection(body, q_body, x=None):
    """Transverse deflection (m) of the beam point at x relative to the chord through its end points.

    Positive to the left of the chord (root → tip); x defaults to mid-span.
    """
    x = 0.5 * (body.x_min + body.x_max) if x is None else x
    points = body.point(body.x_min), body.point(body.x_max), body.point(x)
    return float(_chord_deflection(np.stack([p.position(q_body) for p in points])))


def _chord_deflection(r):
    """Deflection (m) of point r[..., 2, :] from the chord r[..., 0, :] → r[..., 1, :], positive to its left
    (on a stack of records: leading axes)."""
    c = r[..., 1, :] - r[..., 0, :]
    d = r[..., 2, :] - r[..., 0, :]
    return (c[..., 0] * d[..., 1] - c[..., 1] * d[..., 0]) / np.hypot(c[..., 0], c[..., 1])


def _chord_angle(r):
    """Angle (rad) of the chord r[..., 0, :] → r[..., 1, :] against the x axis."""
    c = r[..., 1, :] - r[..., 0, :]
    return np.arctan2(c[..., 1], c[..., 0])


def _first_value(r):
    return r[..., 0, 0]


@register(t_end=2.0, dt=1e-3, length="m", g="m/s^2", body=" | ".join(LINK_KINDS), n_modes="-", **_SECTION_UNITS)
def flexible_pendulum(length=1.0, EA=1e6, EI=1e2, kGA=3.205e5, rhoA=1.0, rhoI=1e-4, n_elements=8, g=9.81,
                      body="beam", n_modes=3):
    """A flexible beam pinned at one end, released at rest from horizontal under gravity.

    FloatingBeam along [0, L] (clamped reference: the body frame is tangent to the root),
    root pinned to the origin by a :class:`~skfem_flex.elements.constraints.Pin`, gravity (0, −g).
    The mass centre falls by at most L/2, so m g L/2 (m = ρA L) is the natural energy scale.
    docs/scenes.md (also run with EI = 1e4, the stiffer case).

    ``body`` chooses the link (:mod:`skfem_flex.scenes.links`): ``"beam"`` (above),
    ``"beam-modal"`` (Craig–Bampton, ``n_modes`` fixed-interface modes), ``"plane-stress"``
    (a unit-thickness strip of the same EA, EI, kGA, ρA, ρI; Q2, ``n_elements`` × 2 elements)
    or ``"plane-stress-modal"`` (that strip reduced; 12 coordinates for n_modes = 3).

    Probes: ``"tip"`` = tip position in the global frame (m); ``"tip_deflection"`` =
    elastic tip displacement (u, w) in the body frame (m).
    """
    sec = Section(EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI)
    lk = link(body, length, sec, n_elements, n_modes=n_modes, name="pendulum")
    b = lk.body
    pin = Pin(lk.root, (0.0, 0.0), name="pivot")
    tip_defl = b.displacement_probe() if body == "beam" else b.displacement_probe("tip")
    return Scene([b], constraints=[pin], forces=[Gravity((0.0, -float(g)), [b])], name="flexible_pendulum",
                 probes={"tip": _position_probe(b, lk.tip), "tip_deflection": tip_defl},
                 parameters=dict(length=length, EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, g=g, body=body, n_modes=n_modes))


@register(t_end=2.0, dt=1e-3, bar_length="m", bar_mass="kg", beam_length="m", g="m/s^2", **_SECTION_UNITS)
def double_pendulum(bar_length=1.0, bar_mass=1.0, beam_length=1.0, EA=1e6, EI=1e2, kGA=3.205e5, rhoA=1.0,
                    rhoI=1e-4, n_elements=4, g=9.81):
    """Rigid–flexible double pendulum, released at rest from horizontal.

    A rigid bar (mass ``bar_mass``, slender-rod inertia m L²/12 about its centre) pinned to
    the ground at the origin, and a FloatingBeam (clamped reference) hinged to the bar's tip
    by a :class:`~skfem_flex.elements.constraints.Revolute`; both lie along +x at t = 0; gravity (0, −g).

    Probes: ``"elbow"`` = the hinge position (m), ``"tip"`` = beam tip position (m),
    ``"tip_deflection"`` = elastic tip displacement (u, w) in the beam frame (m).
    """
    bar_length = _positive("bar_length", bar_length)
    bar = RigidBody.bar(_positive("bar_mass", bar_mass), bar_length, name="bar")
    sec = Section(EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI)
    beam = _beam(beam_length, sec, n_elements, name="beam", position=(bar_length, 0.0))
    pivot = Pin(bar.point((-0.5 * bar_length, 0.0)), (0.0, 0.0), name="pivot")
    elbow = Revolute(bar.point((0.5 * bar_length, 0.0)), beam.point(0.0), name="elbow")
    return Scene([bar, beam], constraints=[pivot, elbow], forces=[Gravity((0.0, -float(g)))], name="double_pendulum",
                 probes={"elbow": _position_probe(bar, bar.point((0.5 * bar_length, 0.0))),
                         "tip": _position_probe(beam, beam.point(beam.x_max)),
                         "tip_deflection": beam.displacement_probe()},
                 parameters=dict(bar_length=bar_length, bar_mass=bar_mass, beam_length=beam_length, EA=EA, EI=EI,
                                 kGA=kGA, rhoA=rhoA, rhoI=rhoI, n_elements=n_elements, g=g))


#: Reference solution of the test-set problem "crank" at t = 0.1 s (index-2 DAE, Simeon's reduced
#: model: crank angle, rod angle, slider position, 2 transverse sine modes and 2 axial quadratic
#: nodes; linear stiffness, no damping), as distributed in the Test Set for IVP Solvers
#: (Univ. Bari, problem "crank", routine SOLN, by B. Simeon 1998). q1 is the amplitude of
#: sin(πx/L2), which is the transverse deflection of the mid-point relative to the chord.
SIMEON_REFERENCE = {
    "t": 0.1,
    "crank_angle": 15.0,                         # rad, = Ω t
    "rod_angle": -3.311734987910881e-01,         # rad
    "slider": 1.697373326718410e-01,             # m
    "midpoint": 1.893192460247178e-04,           # m (q1)
    "q2": 2.375751865617931e-05,                 # m, amplitude of sin(2πx/L2)
    "axial_mid": -5.323907988763734e-06,         # m, axial displacement at x = L2/2 (q3)
    "axial_tip": -8.363283141616840e-06,         # m, axial displacement at x = L2 (q4)
}


#: The test set's smooth initial values ``init`` ("close to smooth motion"): rod angle rate,
#: slider position and rate, and the reduced model's elastic coordinates (q1, q2: amplitudes
#: of sin(πξ), sin(2πξ) transverse; q3, q4: axial displacement at ξ = ½ and 1 with the
#: quadratic shape functions 4ξ(1 − ξ) and ξ(2ξ − 1), ξ = x/L2) and their rates.
SIMEON_INIT = {
    "rod_rate": -7.49957670e+01, "slider": 4.50016933e-01, "slider_rate": -2.68938672e-06,
    "q": (0.0, 0.0, 1.03339863e-05, 1.69327969e-05),
    "qdot": (4.44896105e-01, 4.63434311e-03, -1.78591076e-06, -2.68938672e-06),
}


def _simeon_fields(length, q):
    """Nodal fields (u, w, φ) as callables of x for the test set's reduced coordinates q1..q4."""
    q1, q2, q3, q4 = map(float, q)
    k = np.pi / length

    def u(x):
        xi = np.asarray(x) / length
        return q3 * 4.0 * xi * (1.0 - xi) + q4 * xi * (2.0 * xi - 1.0)

    def w(x):
        return q1 * np.sin(k * np.asarray(x)) + q2 * np.sin(2.0 * k * np.asarray(x))

    def phi(x):
        return k * (q1 * np.cos(k * np.asarray(x)) + 2.0 * q2 * np.cos(2.0 * k * np.asarray(x)))
    return dict(u=u, w=w, theta=phi)


@register(t_end=0.1, dt=1e-4, crank_length="m", crank_mass="kg", crank_inertia="kg m^2", rod_length="m", E="Pa", nu="-",
          rho="kg/m^3", width="m", height="m", slider_mass="kg", omega="rad/s", n_elements="-", strain="-",
          start="-", crank_angle="rad", body=" | ".join(LINK_KINDS), n_modes="-", n_across="-", mesh="path")
def slider_crank(crank_length=0.15, crank_mass=0.36, crank_inertia=0.002727, rod_length=0.30, E=2e11, nu=0.3,
                 rho=7870.0, width=0.008, height=0.008, slider_mass=0.075552, omega=150.0, n_elements=8,
                 strain="green-lagrange", start="rigid", crank_angle=0.0, body="beam", n_modes=3, n_across=2,
                 mesh=None):
    """Flexible slider–crank of Simeon (1996), the "crank" problem of the DAE test set.

    B. Simeon, *Modelling a flexible slider crank mechanism by a mixed system of DAEs and
    PDEs*, Math. Modelling of Systems 2 (1996) 1–18; data as in the Test Set for IVP Solvers
    (Univ. Bari, problem "crank", B. Simeon 1998): rigid crank L1 = 0.15 m, M1 = 0.36 kg,
    J1 = 0.002727 kg m² (about the crank pivot: the test set's mass matrix entry is
    J1 + M2 L1²), driven at constant speed Ω = 150 rad/s by the constraint φ1 = Ω t;
    elastic connecting rod L2 = 0.30 m, steel E = 2e11 Pa, ν = 0.3, ρ = 7870 kg/m³, square
    8 × 8 mm section; sliding block M3 = 0.075552 kg; no gravity.

    Model here: the crank is a :class:`RigidBody` (centre at L1/2, inertia J1 − M1 (L1/2)² about
    it) pinned to the origin and driven by a :class:`Driver` on its angle; the rod is a
    :class:`FloatingBeam` with the ``"pinned"`` reference condition (chord frame: its angle is
    the rod angle φ2 of the test set), hinged to the crank tip and to the slider (a point mass)
    by :class:`Revolute` joints; the slider moves on the x axis (:class:`Slider`). It starts at
    crank angle 0 with the rod straight and undeformed and the velocities of the rigid
    mechanism (the test set's ``init2``: φ̇1 = 150, φ̇2 = −75 rad/s, slider at rest), which
    excites the rod's bending vibration strongly. ``start="testset"`` starts instead from the
    test set's smooth initial values ``init`` (:data:`SIMEON_INIT`: small axial stretch, lateral
    mode rates; default data only), mapped onto the beam's nodes through the test set's shape
    functions — the start to which the published reference values belong.
    ``crank_angle`` (rad, ``start="rigid"`` only) starts the mechanism at that crank angle, the
    driver law φ1 = crank_angle + Ω t; with ``omega=0`` the crank is held there (for statics and
    modes at a crank angle, e.g. a Campbell diagram over it).

    Probes: ``"slider"`` = slider x (m), ``"rod_angle"`` = angle of the rod's chord (rad),
    ``"midpoint"`` = transverse deflection of the rod's mid-point relative to its chord (m,
    positive to the left of the chord from crank to slider), ``"crank_angle"`` (rad).
    :data:`SIMEON_REFERENCE` holds the published reference values at t = 0.1 s (of the reduced
    model started from the test set's smooth initial values ``init``, not from ``init2``).

    ``body`` chooses the rod (:mod:`skfem_flex.scenes.links`): ``"beam"`` (above),
    ``"beam-modal"`` (Craig–Bampton with ``n_modes`` fixed-interface modes, frame attached to the
    crank end), ``"plane-stress"`` (a strip ``height`` high and ``width`` thick, Q2, ``n_elements``
    × ``n_across`` elements, unreduced and linear) or ``"plane-stress-modal"`` (that strip
    reduced). ``mesh`` replaces the strip by a meshed rod read from a gmsh file, with physical
    groups ``big_end`` and ``small_end`` around its holes (centres at (0, 0) and (L2, 0); e.g.
    ``examples/meshes/conrod.msh``, thickness ``width``). ``start="testset"`` needs ``body="beam"``.
    """
    l1, l2 = _positive("crank_length", crank_length), _positive("rod_length", rod_length)
    m1 = _positive("crank_mass", crank_mass)
    j1 = _positive("crank_inertia", crank_inertia)
    jc = j1 - m1 * (0.5 * l1) ** 2
    if jc <= 0:
        raise ValueError(f"crank_inertia {j1!r} (about the pivot) is below M1 (L1/2)² = {m1 * (0.5 * l1) ** 2:.6g}")
    om = float(omega)
    if not np.isfinite(om):
        raise ValueError(f"omega must be finite, got {omega!r}")
    if start not in ("rigid", "testset"):
        raise ValueError(f"start must be 'rigid' or 'testset', got {start!r}")
    phi1 = float(crank_angle)
    if not np.isfinite(phi1):
        raise ValueError(f"crank_angle must be finite, got {crank_angle!r}")
    if start == "testset" and phi1 != 0.0:
        raise ValueError(f"start='testset' begins at crank angle 0, got crank_angle={crank_angle!r}")
    if start == "testset" and body != "beam":
        raise ValueError(f"start='testset' maps the test set's beam modes onto a FloatingBeam: it needs body='beam', "
                         f"got {body!r}")
    c1, s1 = np.cos(phi1), np.sin(phi1)
    if l1 >= l2:
        raise ValueError(f"crank_length {l1!r} must be shorter than rod_length {l2!r} (the crank must turn)")
    crank = RigidBody(m1, jc, (0.5 * l1 * c1, 0.5 * l1 * s1), phi1, velocity=(-0.5 * l1 * om * s1, 0.5 * l1 * om * c1),
                      angular_velocity=om, outline=[[-0.5 * l1, 0.0], [0.5 * l1, 0.0]], name="crank")
    sec = Section.rectangle(E=E, nu=nu, b=width, h=height, rho=rho)
    # rigid mechanism at φ1: l1 sin φ1 + l2 sin φ2 = 0 (slider on the x axis), and its rates
    phi2 = float(np.arcsin(-l1 * s1 / l2))
    c2 = np.cos(phi2)
    w_rod = -l1 * om * c1 / (l2 * c2)
    lk = link(body, l2, sec, n_elements, n_modes=n_modes, n_across=n_across, reference="pinned", strain=strain,
              material=(E, nu, rho, height, width), mesh=mesh, name="rod", position=(l1 * c1, l1 * s1), angle=phi2,
              velocity=(-l1 * om * s1, l1 * om * c1), angular_velocity=w_rod)
    rod = lk.body
    x_slider = l1 * c1 + l2 * c2
    v_slider = -l1 * om * s1 - l2 * w_rod * np.sin(phi2)
    if start == "testset":
        ini = SIMEON_INIT
        rod.q0[3:] = rod.elastic_vector(**_simeon_fields(l2, ini["q"]))
        rod.v0[3:] = rod.elastic_vector(**_simeon_fields(l2, ini["qdot"]))
        rod.v0[2] = ini["rod_rate"]
        x_slider, v_slider = ini["slider"], ini["slider_rate"]
    slider = PointMass(_positive("slider_mass", slider_mass), [x_slider, 0.0], [v_slider, 0.0], name="slider")
    cons = [Pin(crank.point((-0.5 * l1, 0.0)), (0.0, 0.0), name="crank pivot"),
            Driver(crank, MotionLaw.constant_rate(om, start=phi1), coordinate="theta", name="crank drive"),
            Revolute(crank.point((0.5 * l1, 0.0)), lk.root, name="crank pin"),
            Revolute(lk.tip, slider.point(), name="wrist pin"),
            Slider(slider.point(), (1.0, 0.0), (0.0, 0.0), name="guide")]
    root, tip = lk.root, lk.tip

    # recorded by the compiled loop as positions, combined over a whole chunk at once
    probes = {"slider": CombinedProbe([PointProbe(slider.point())], _first_value),
              "rod_angle": CombinedProbe([PointProbe(root), PointProbe(tip)], _chord_angle),
              "midpoint": CombinedProbe([PointProbe(root), PointProbe(tip), PointProbe(lk.mid)], _chord_deflection),
              "crank_angle": CombinedProbe([LinearProbe(crank, [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])], _first_value)}
    return Scene([crank, rod, slider], constraints=cons, name="slider_crank", probes=probes,
                 parameters=dict(crank_length=crank_length, crank_mass=crank_mass, crank_inertia=crank_inertia,
                                 rod_length=rod_length, E=E, nu=nu, rho=rho, width=width, height=height,
                                 slider_mass=slider_mass, omega=omega, n_elements=n_elements, strain=strain,
                                 start=start, crank_angle=crank_angle, body=body, n_modes=n_modes,
                                 n_across=n_across, mesh=mesh))


@register(t_end=4.0, dt=5e-3, length="m", force="N", duration="s", **_SECTION_UNITS)
def free_beam(length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4, n_elements=8, force=100.0,
              duration=0.05):
    """A free floating-frame beam in zero gravity, set flying by a short transverse force pulse.

    FloatingBeam along [0, L] (clamped reference), no joints, no gravity. A half-sine pulse
    F(t) = force · sin(π t/τ), 0 ≤ t ≤ τ = ``duration``, acts at the tip along global +y
    (:class:`~skfem_flex.elements.forces.PointForce` with :func:`~skfem_flex.elements.forces.half_sine_pulse`);
    its impulse is 2 τ force/π. Afterwards energy, linear and angular momentum are constant
    (docs/scenes.md), and ``Result.external_work`` holds the work of the pulse.

    Probes: ``"tip"`` = tip position (m), ``"tip_deflection"`` = elastic tip displacement
    (u, w) in the body frame (m).
    """
    sec = Section(EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI)
    body = _beam(length, sec, n_elements, name="beam")
    tip = body.point(body.x_max)
    pulse = PointForce(tip, half_sine_pulse(np.array([0.0, float(force)]), _positive("duration", duration)),
                       name="pulse")
    return Scene([body], forces=[pulse], name="free_beam",
                 probes={"tip": _position_probe(body, tip), "tip_deflection": body.displacement_probe()},
                 parameters=dict(length=length, EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, force=force, duration=duration))


@register(t_end=30.0, dt=1e-2, omega="rad/s", T="s", length="m", order="-", strain="-", **_SECTION_UNITS)
def spin_up_pinned(omega=4.0, T=15.0, length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
                   n_elements=8, order=1, strain="green-lagrange"):
    """The spin-up beam (Simo & Vu-Quoc 1986) with joints instead of prescribed coordinates.

    Same beam and hub law as :func:`~skfem_flex.scenes.spin_up_beam`, but the root is held at
    the origin by a :class:`~skfem_flex.elements.constraints.Pin` and the hub angle θ follows
    :func:`~skfem_flex.elements.motion.spin_up_law` through a :class:`~skfem_flex.elements.constraints.Driver`,
    so the coordinates stay unknowns and the driving torque is the driver's reaction −λ
    (``Result.reactions["hub drive"]``), equal to the generalized force that the prescribed
    version records in ``Result.prescribed_force``.

    Probes: ``"tip"`` = tip displacement in the hub frame (axial, transverse), m.
    """
    body = hub_beam(length, EA, EI, kGA, rhoA, rhoI, n_elements, order, strain)
    cons = [Pin(body.point(body.x_min), (0.0, 0.0), name="hub pin"),
            Driver(body, spin_up_law(omega, T), coordinate="theta", name="hub drive")]
    return Scene([body], constraints=cons, name="spin_up_pinned", probes={"tip": body.displacement_probe()},
                 parameters=dict(omega=omega, T=T, length=length, EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, order=order, strain=strain))
