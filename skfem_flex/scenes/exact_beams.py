"""Scenes with geometrically exact beams (:class:`~skfem_flex.bodies.exact.body.ExactBeam`).

* :func:`flying_beam` — the free-flying beam of Simo & Vu-Quoc (1986);
* :func:`very_flexible_pendulum` — the pendulum of Berzeri & Shabana (2000);
* :func:`exact_spin_up_beam` — the spin-up manoeuvre of Simo & Vu-Quoc (1986)
  with an exact beam (the floating-frame version lives in ``rotating.py``).
"""
from __future__ import annotations

import numpy as np

from ..bodies.exact.body import ExactBeam
from ..bodies.probes import LinearProbe, PointProbe
from ..elements.forces import Gravity, NodalLoad
from ..elements.motion import MotionLaw, Prescribed, spin_up_law
from ..scene import Scene
from ..fem.section import Section
from ._registry import positive_count as _count, register

__all__ = ["flying_beam", "very_flexible_pendulum", "exact_spin_up_beam", "LoadWindow"]


class LoadWindow:
    """Time function 1 for start ≤ t ≤ stop, 0 otherwise (a named, printable step pulse)."""

    def __init__(self, start=0.0, stop=1.0):
        self.start, self.stop = float(start), float(stop)
        if not (np.isfinite(self.start) and np.isfinite(self.stop) and self.stop >= self.start):
            raise ValueError(f"load window needs finite start <= stop, got [{start!r}, {stop!r}]")

    def __call__(self, t):
        return 1.0 if self.start <= t <= self.stop else 0.0

    def __repr__(self):
        return f"LoadWindow({self.start}, {self.stop})"


def _fixed(value):
    return MotionLaw(lambda t: value, lambda t: 0.0, lambda t: 0.0)


@register(t_end=10.0, dt=0.05, n_elements="-", order="-", length="m", EA="N", GA="N", EI="N m^2", rhoA="kg/m",
          rhoI="kg m", force="N", moment="N m", t_load="s", rotation_rate="cayley | mid-point")
def flying_beam(n_elements=10, order=1, length=10.0, EA=1e4, GA=1e4, EI=100.0, rhoA=1.0, rhoI=10.0,
                force=8.0, moment=-80.0, t_load=2.5, rotation_rate="cayley"):
    """Free-flying flexible beam of Simo & Vu-Quoc (1986), planar, no gravity.

    J. C. Simo, L. Vu-Quoc, "On the dynamics of flexible beams under large
    overall motions — the plane case: part II", J. Appl. Mech. 53 (1986)
    855–863, and Simo & Tarnow, ZAMP 43 (1992): a straight beam at rest
    from (6, 0) to (0, 8) (L = 10), EA = GA = 1e4, EI = 100, ρA = 1,
    ρI = 10. At the end (6, 0) a dead horizontal force F = 8 and a moment
    M = −80 act for 0 ≤ t ≤ ``t_load`` = 2.5 s and nothing after (constant
    here; some versions of the benchmark ramp the loads as a hat function).
    The impulse is (F t_load, 0) = (20, 0): after the load the centre of mass
    moves at 2 m/s along x from (5.5, 4); with the energy-momentum scheme
    energy, linear and angular momentum stay constant to the Newton
    tolerance (``rotation_rate="cayley"``, the default; with
    ``"mid-point"`` angular momentum drifts by O(Δt²), 5e-4 relative at
    Δt = 0.1; see :mod:`skfem_flex.bodies.exact.strain`).

    ``GA`` is the shear stiffness as given in the paper (shear factor
    included). Probes: ``"end_a"`` (the loaded end), ``"end_b"`` (the other
    end) and ``"centre_of_mass"``, positions in m.
    """
    n_elements = _count("n_elements", n_elements)
    sec = Section(EA=EA, EI=EI, kGA=GA, rhoA=rhoA, rhoI=rhoI)
    if not np.isfinite(float(length)) or float(length) <= 0:
        raise ValueError(f"length must be finite and positive, got {length!r}")
    start = np.array([6.0, 0.0])
    end = start + float(length) * np.array([-0.6, 0.8])
    body = ExactBeam.from_points(sec, start, end, n_elements=n_elements, order=order, name="beam",
                                 rotation_rate=rotation_rate)
    t_load = float(t_load)
    if not np.isfinite(t_load) or t_load < 0:
        raise ValueError(f"t_load must be finite and >= 0, got {t_load!r}")
    load = NodalLoad(body, 0.0, force=(force, 0.0), moment=moment, time_function=LoadWindow(0.0, t_load),
                     name="end load")
    a, b = body.point(0.0), body.point(body.length)
    gam, c = body.mass_moment()                     # centre of mass (Γ q + c)/m: linear in q
    return Scene([body], forces=[load], name="flying_beam",
                 probes={"end_a": PointProbe(a), "end_b": PointProbe(b),
                         "centre_of_mass": LinearProbe(body, gam / body.total_mass, c / body.total_mass)},
                 parameters=dict(n_elements=n_elements, order=order, length=length, EA=EA, GA=GA, EI=EI,
                                 rhoA=rhoA, rhoI=rhoI, force=force, moment=moment, t_load=t_load,
                                 rotation_rate=rotation_rate))


@register(t_end=1.0, dt=1e-3, n_elements="-", order="-", length="m", A="m^2", I="m^4", rho="kg/m^3", E="Pa",
          nu="-", k="-", g="m/s^2")
def very_flexible_pendulum(n_elements=16, order=1, length=1.2, A=0.0018, I=1.215e-8, rho=5540.0, E=0.7e6,
                           nu=0.3, k=5.0 / 6.0, g=9.81):
    """Very flexible pendulum of Berzeri & Shabana (2000), exact beam.

    M. Berzeri, A. A. Shabana, "Development of simple models for the elastic
    forces in the absolute nodal co-ordinate formulation", J. Sound Vib. 235
    (2000) 539–565: L = 1.2 m, A = 0.0018 m², I = 1.215e-8 m⁴,
    ρ = 5540 kg/m³, E = 0.7 MPa, ν = 0.3, shear factor κ = 5/6
    (G = E/(2(1 + ν))). Pinned at the origin (the position of node 0 is
    prescribed constant; its section angle is free), released at rest,
    straight and horizontal along +x, under gravity g along −y.

    Probes: ``"tip"`` (position of the free end, m).
    """
    n_elements = _count("n_elements", n_elements)
    nu = float(nu)
    if not np.isfinite(nu) or not -1.0 < nu < 0.5:
        raise ValueError(f"nu must lie in (-1, 0.5), got {nu!r}")
    sec = Section.from_material(E=E, G=float(E) / (2.0 * (1.0 + nu)), A=A, I=I, rho=rho, k=k)
    if not np.isfinite(float(length)) or float(length) <= 0:
        raise ValueError(f"length must be finite and positive, got {length!r}")
    g = float(g)
    if not np.isfinite(g):
        raise ValueError(f"g must be finite, got {g!r}")
    body = ExactBeam.from_points(sec, (0.0, 0.0), (float(length), 0.0), n_elements=n_elements, order=order,
                                 name="pendulum")
    pin = [Prescribed(body, "ux0", _fixed(0.0)), Prescribed(body, "uy0", _fixed(0.0))]
    tip = body.point(body.length)
    return Scene([body], forces=[Gravity((0.0, -g))], prescribed=pin, name="very_flexible_pendulum",
                 probes={"tip": PointProbe(tip)},
                 parameters=dict(n_elements=n_elements, order=order, length=length, A=A, I=I, rho=rho, E=E,
                                 nu=nu, k=k, g=g))


def exact_spin_up_beam(omega=4.0, T=15.0, length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
                       n_elements=8, order=1):
    """Spin-up manoeuvre of Simo & Vu-Quoc (1986) with a geometrically exact beam.

    J. C. Simo, L. Vu-Quoc, "On the dynamics of flexible beams under large
    overall motions — the plane case: part II", J. Appl. Mech. 53 (1986):
    a beam clamped to a hub at the origin whose angle follows
    θ(t) = (ω/T)(t²/2 + (T/2π)²(cos(2πt/T) − 1)) for t < T and ω(t − T/2)
    after (:func:`~skfem_flex.elements.motion.spin_up_law`). The root node's position
    is held at the origin and its section angle is prescribed to θ(t)
    (the clamp), both through :class:`~skfem_flex.elements.motion.Prescribed`.

    Probe ``"tip"``: tip displacement in the hub frame (axial, transverse),
    A(θ)ᵀ(r_tip − r_root) − (L, 0), m.
    """
    n_elements = _count("n_elements", n_elements)
    sec = Section(EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI)
    length = float(length)
    if not np.isfinite(length) or length <= 0:
        raise ValueError(f"length must be finite and positive, got {length!r}")
    body = ExactBeam.from_points(sec, (0.0, 0.0), (length, 0.0), n_elements=n_elements, order=order, name="beam")
    law = spin_up_law(omega, T)
    clamp = [Prescribed(body, "ux0", _fixed(0.0)), Prescribed(body, "uy0", _fixed(0.0)),
             Prescribed(body, "psi0", law)]
    root, tip = body.point(0.0), body.point(length)

    def probe_tip(s, t, q, v):
        qb = s.coordinates(body, q)
        th = root.angle(qb)
        d = tip.position(qb) - root.position(qb)
        c, sn = np.cos(th), np.sin(th)
        return np.array([c * d[0] + sn * d[1] - length, -sn * d[0] + c * d[1]])

    return Scene([body], prescribed=clamp, name="spin_up_beam", probes={"tip": probe_tip},
                 parameters=dict(body="exact", omega=omega, T=T, length=length, EA=EA, EI=EI, kGA=kGA,
                                 rhoA=rhoA, rhoI=rhoI, n_elements=n_elements, order=order))
