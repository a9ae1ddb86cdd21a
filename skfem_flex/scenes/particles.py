"""Point-mass scenes of the Lee & Yun: spring–mass systems and the simple pendulum."""
from __future__ import annotations

from ..bodies.particle import PointMass
from ..bodies.probes import PointProbe
from ..elements.constraints import Distance
from ..elements.forces import Gravity, NonlinearSpring
from ..scene import Scene
from ._registry import register

__all__ = ["spring_mass", "pendulum"]


@register(t_end=20.0, dt=0.05, exponent="-", m="kg", k="N/m^(2n-1)", u0="m", v0="m/s")
def spring_mass(exponent=2.0, m=1.0, k=1.0, u0=1.0, v0=0.0):
    """One-dof spring–mass system with strain ε = u^n and V = ½ k ε².

    Lee & Yun, §4: n = 1 is the linear oscillator, n = 2
    gives m ü + 2 k u³ = 0 (quartic potential), n = 1.5 gives V = ½ k u³,
    unbounded below, whose motion escapes to −∞.

    Probes: ``"u"`` (displacement, m).
    """
    body = PointMass(m, [u0], [v0], name="mass")
    spring = NonlinearSpring(body, k, exponent)
    return Scene([body], forces=[spring], name="spring_mass",
                 probes={"u": lambda s, t, q, v: q[0]},
                 parameters=dict(exponent=exponent, m=m, k=k, u0=u0, v0=v0))


@register(t_end=5.0, dt=0.01, length="m", mass="kg", v0="m/s", g="m/s^2")
def pendulum(length=0.5, mass=1.0, v0=1.695, g=9.81):
    """Simple pendulum in Cartesian coordinates with the constraint C = (x·x − l²)/2 = 0.

    Lee & Yun, §4 and eqs. (26a–c): pivot at the origin,
    y up, gravity along −y; the mass starts at the bottom (0, −l) with
    horizontal speed v0 along +x (l = 0.5 m, v0 = 1.695 m/s in the paper).

    Probes: ``"position"`` (x, y in m).
    """
    body = PointMass(mass, [0.0, -float(length)], [v0, 0.0], name="bob")
    rod = Distance(body, (0.0, 0.0), length, name="rod")
    return Scene([body], constraints=[rod], forces=[Gravity((0.0, -g))], name="pendulum",
                 probes={"position": PointProbe(body.point())},
                 parameters=dict(length=length, mass=mass, v0=v0, g=g))
