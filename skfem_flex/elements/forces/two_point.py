"""Springs and dampers along the line of two body points, or of a body point and a ground point
(:class:`LinearSpring`, :class:`LinearDamper`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import BodyPoint, check_finite_vector, keeps_methods
from ..point_terms import Difference, Dot, PointLayout
from .base import CONSERVATIVE, ForceElement, check_nonnegative

__all__ = ["LinearSpring", "LinearDamper"]


def _other(point_b, point_a, what):
    """(BodyPoint or None, ground anchor or None) from the second argument of a two-point element."""
    if point_b is None:
        return None, np.asarray(point_a.position(np.asarray(point_a.body.q0, dtype=float)), dtype=float)
    if isinstance(point_b, BodyPoint):
        return point_b, None
    return None, check_finite_vector(f"{what} ground anchor", point_b, 2)



class _TwoPoint(ForceElement):
    """Shared set-up of elements between a body point and another point or the ground."""

    def _setup(self, point_a, point_b, what):
        if not isinstance(point_a, BodyPoint):
            raise ValueError(f"{what} needs a body point (body.point(...)) as its first end, got {point_a!r}")
        pb, anchor = _other(point_b, point_a, what)
        self.layout = PointLayout([point_a, pb])
        n = self.layout.n
        sa, sb = self.layout.slices
        self.points, self.anchor = (point_a, pb), anchor
        self.bodies = self.layout.bodies
        self.n = n
        self._d = Difference(n, point_a, sa, pb, sb, None if pb is not None else anchor)    # d = r_a − r_b
        self._s = Dot(n, self._d, self._d)                                                 # s = |d|²


class LinearSpring(_TwoPoint):
    """Linear spring between two body points, or a body point and a ground point.

    V = ½ k (l − l₀)² with l = ‖r_a − r_b‖.

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint, array_like (2,) or None
        The other end: a body point, a ground point (m), or ``None`` for the
        ground point where ``point_a`` starts.
    stiffness : float
        k in N/m (> 0).
    rest_length : float, optional
        l₀ in m (≥ 0); default the initial length.
    name : str

    Notes
    -----
    Exact discrete gradient in closed form (Simo & Tarnow's "stress at the
    mean strain" for a spring): with s = l², the divided difference of
    V(s) = ½ k (√s − l₀)² is (V1 − V0)/(s1 − s0) = ½ k (1 − 2 l₀/(l_0 + l_1)),
    free of cancellation, times the exact discrete gradient of s (the product
    rule Δ(d·d) = 2 d̄·Δd on the points' exact position gradients).
    """

    conservative = True

    def __init__(self, point_a, point_b, stiffness, rest_length=None, name="spring"):
        self._setup(point_a, point_b, "LinearSpring")
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        self.k = k
        q0 = self.layout.initial()
        l_init = float(np.sqrt(self._s.value(q0)[0]))
        self.rest_length = l_init if rest_length is None else check_nonnegative("rest_length", rest_length)
        self.name = name

    def length(self, q):
        """l = ‖r_a − r_b‖ in m."""
        return float(np.sqrt(self._s.value(q)[0]))

    def tension(self, q):
        """k (l − l₀) in N (positive when stretched)."""
        return self.k * (self.length(q) - self.rest_length)

    def potential_energy(self, q):
        return 0.5 * self.k * (self.length(q) - self.rest_length) ** 2

    def _dvds(self, s):
        if self.rest_length == 0.0:
            return 0.5 * self.k, 0.0
        ln = np.sqrt(s)
        return 0.5 * self.k * (1.0 - self.rest_length / ln), 0.25 * self.k * self.rest_length / (s * ln)

    def potential_gradient(self, q):
        s = self._s.value(q)[0]
        return self._dvds(s)[0] * self._s.jacobian(q)[0]

    def potential_hessian(self, q):
        s = self._s.value(q)[0]
        d1, d2 = self._dvds(s)
        js = self._s.jacobian(q)[0]
        return d2 * np.outer(js, js) + self._s.hessian(q, np.array([d1]))

    def potential_discrete_gradient(self, q0, q1):
        l0, l1 = self.length(q0), self.length(q1)
        lr = self.rest_length
        ssum = l0 + l1
        kappa = 0.5 * self.k * (1.0 - 2.0 * lr / ssum) if lr > 0.0 else 0.5 * self.k
        ds = self._s.dgrad(q0, q1)[0]
        g = kappa * ds
        h = self._s.dgrad_jacobian(q0, q1, np.array([kappa]))
        if lr > 0.0:
            h = h + (self.k * lr / (2.0 * l1 * ssum ** 2)) * np.outer(ds, self._s.jacobian(q1)[0])
        return g, h

    def compiled_form(self):
        if not keeps_methods(self, LinearSpring, CONSERVATIVE + ("length", "_dvds")):
            return None
        return "two-point spring", self.points[0], self.points[1], self.anchor, self.k, self.rest_length


class LinearDamper(_TwoPoint):
    """Linear damper along the line of two body points (or a body point and the ground).

    Force on point a: F = −c (u · (ṙ_a − ṙ_b)) u with u = (r_a − r_b)/l, the
    opposite on b; generalized force Q = J_dᵀ F (J_d = ∂(r_a − r_b)/∂q).

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint, array_like (2,) or None
        As for :class:`LinearSpring`.
    damping : float
        c in N s/m (≥ 0).
    name : str

    Notes
    -----
    Non-conservative: the energy scheme evaluates it at the midpoint
    q_m with v̄ = Δq/Δt, so its work −c Δt (u·J v̄)² ≤ 0 enters
    ``Result.external_work`` exactly.
    """

    conservative = False

    def __init__(self, point_a, point_b, damping, name="damper"):
        self._setup(point_a, point_b, "LinearDamper")
        self.c = check_nonnegative("damping", damping)
        self.name = name

    def generalized_force(self, q, v, t):
        d = self._d.value(q)
        jd = self._d.jacobian(q)
        ln = float(np.hypot(*d))
        if ln == 0.0:
            raise ValueError(f"damper {self.name!r}: its two points coincide, the direction is undefined")
        u = d / ln
        w = jd @ v
        rate = float(u @ w)
        jtu = jd.T @ u
        f = -self.c * rate * jtu
        du = (np.eye(2) - np.outer(u, u)) @ jd / ln              # ∂u/∂q
        dw = np.vstack([self._d.hessian(q, e) @ v for e in np.eye(2)])   # ∂(J_d v)/∂q
        drate = w @ du + u @ dw
        fq = -self.c * (np.outer(jtu, drate) + rate * (self._d.hessian(q, u) + jd.T @ du))
        fv = -self.c * np.outer(jtu, jtu)
        return f, fq, fv

    def compiled_form(self):
        if not keeps_methods(self, LinearDamper, ("generalized_force",)):
            return None
        return "two-point damper", self.points[0], self.points[1], self.anchor, self.c

