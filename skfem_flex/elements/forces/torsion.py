"""Torsion springs and dampers on the relative angle of two body points, or on a point's angle to the
ground (:class:`RotationalSpring`, :class:`RotationalDamper`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import BodyPoint, check_finite_vector, keeps_methods
from ..point_terms import PointLayout, angle_term
from .base import CONSERVATIVE, ForceElement, check_nonnegative

__all__ = ["RotationalSpring", "RotationalDamper"]


class _Rotational(ForceElement):
    def _setup(self, point_a, point_b, what):
        if not isinstance(point_a, BodyPoint):
            raise ValueError(f"{what} needs a body point (body.point(...)), got {point_a!r}")
        if point_b is not None and not isinstance(point_b, BodyPoint):
            raise ValueError(f"{what}: the second end must be a body point or None (ground), got {point_b!r}")
        self.layout = PointLayout([point_a, point_b])
        n = self.layout.n
        sa, sb = self.layout.slices
        ta = angle_term(n, point_a, sa)
        if point_b is None:
            self.grad = ta.grad.copy()
            self._angle = ta.fun
        else:
            tb = angle_term(n, point_b, sb)
            self.grad = ta.grad - tb.grad
            self._angle = lambda q: ta.fun(q) - tb.fun(q)
        self.bodies = self.layout.bodies
        self.points = (point_a, point_b)
        self.n = n

    def relative_angle(self, q):
        """ϑ_a − ϑ_b (ϑ_b = 0 for the ground), rad."""
        return float(self._angle(q))


class RotationalSpring(_Rotational):
    """Torsion spring on the relative angle of two body points (or a point's angle to the ground).

    V = ½ k (ϑ_a − ϑ_b − ϑ₀)². The angles are linear in q, so V is quadratic
    and the midpoint gradient k (ϑ̄ − ϑ₀) ∇ϑ is its exact discrete gradient.

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint or None
        ``None``: the ground (angle 0).
    stiffness : float
        k in N m/rad (> 0).
    rest_angle : float, optional
        ϑ₀ in rad; default the initial relative angle.
    name : str
    """

    conservative = True

    def __init__(self, point_a, point_b=None, stiffness=1.0, rest_angle=None, name="torsion spring"):
        self._setup(point_a, point_b, "RotationalSpring")
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        self.k = k
        a0 = self.relative_angle(self.layout.initial())
        self.rest_angle = a0 if rest_angle is None else float(check_finite_vector("rest_angle", rest_angle, 1)[0])
        self.name = name

    def potential_energy(self, q):
        return 0.5 * self.k * (self.relative_angle(q) - self.rest_angle) ** 2

    def potential_gradient(self, q):
        return self.k * (self.relative_angle(q) - self.rest_angle) * self.grad

    def potential_hessian(self, q):
        return self.k * np.outer(self.grad, self.grad)

    def potential_discrete_gradient(self, q0, q1):
        mean = 0.5 * (self.relative_angle(q0) + self.relative_angle(q1))
        return self.k * (mean - self.rest_angle) * self.grad, 0.5 * self.k * np.outer(self.grad, self.grad)

    def compiled_form(self):
        # the angles are linear in q: ϑ_a − ϑ_b − ϑ₀ = g · q + c with c its value at q = 0
        if not keeps_methods(self, RotationalSpring, CONSERVATIVE + ("relative_angle",)):
            return None
        return ("quadratic spring", self.grad.copy(), self.relative_angle(np.zeros(self.n)) - self.rest_angle,
                self.k)


class RotationalDamper(_Rotational):
    """Torsion damper: moment −c (ϑ̇_a − ϑ̇_b) on point a (the opposite on b).

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint or None
        ``None``: the ground.
    damping : float
        c in N m s/rad (≥ 0).
    name : str
    """

    conservative = False

    def __init__(self, point_a, point_b=None, damping=0.0, name="torsion damper"):
        self._setup(point_a, point_b, "RotationalDamper")
        self.c = check_nonnegative("damping", damping)
        self.name = name

    def generalized_force(self, q, v, t):
        rate = float(self.grad @ v)
        return -self.c * rate * self.grad, None, -self.c * np.outer(self.grad, self.grad)

    def compiled_form(self):
        if not keeps_methods(self, RotationalDamper, ("generalized_force",)):
            return None
        return "linear damper", self.grad.copy(), self.c

