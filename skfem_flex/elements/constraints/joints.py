r"""Joints between body points, or between a body point and the ground: :class:`Pin`, :class:`Revolute`,
:class:`Weld`, :class:`Slider`, :class:`Prismatic`.

Joints (and the :class:`~skfem_flex.elements.constraints.driver.Driver`) are built from body
points (``body.point(locator)``, :class:`~skfem_flex.bodies.base.BodyPoint`)
through a few small *terms* (:mod:`skfem_flex.elements.point_terms`, shared with the
point force elements) — the difference of two points' positions (or
of a point and a ground point), a point's angle or a coordinate (linear), a
constant, a vector turned with a body and a dot product — each with its
value, Jacobian, Hessian product and an exact discrete gradient. Products
use Δ(f·g) = Δf·ḡ + f̄·Δg with f̄ the mean of the end values, rotations
use A(ϑ1) − A(ϑ0) = sinc(Δϑ/2) Δϑ A(ϑ_m) E, so every joint's discrete
gradient is exact to round-off, whatever the step.
"""
from __future__ import annotations

import numpy as np

from ...bodies.base import check_finite_vector
from ...bodies.rigid import E_MATRIX, rotation
from ..point_terms import Constant, Difference, Dot, PointLayout, Rotated, angle_term, linear_combination
from .base import TermConstraint

__all__ = ["Pin", "Revolute", "Weld", "Slider", "Prismatic"]


def _point_position0(point):
    return np.asarray(point.position(np.asarray(point.body.q0, dtype=float)), dtype=float)


def _point_angle0(point):
    return float(point.angle(np.asarray(point.body.q0, dtype=float)))


def _unit(name, vec):
    vec = check_finite_vector(name, vec, 2)
    nrm = float(np.hypot(*vec))
    if nrm == 0.0:
        raise ValueError(f"{name} must not be the zero vector")
    return vec / nrm


# ==================================================================== joints
class Pin(TermConstraint):
    """A body point fixed to the ground: Φ = r(q) − a = 0 (a revolute joint to the ground).

    Parameters
    ----------
    point : BodyPoint
        ``body.point(locator)``.
    anchor : array_like, shape (2,), optional
        Ground point a in m; default the point's initial position.
    name : str

    Notes
    -----
    Reaction: the force (F_x, F_y) = −λ (N) the pin exerts on the body.
    """

    reaction_labels = ("Fx", "Fy")

    def __init__(self, point, anchor=None, name="pin"):
        layout = PointLayout([point])
        self.point = point
        self.anchor = _point_position0(point) if anchor is None else check_finite_vector("anchor", anchor, 2)
        n = layout.n
        self.set_terms(layout, [Difference(n, point, layout.slices[0], anchor=self.anchor)])
        self.name = name


class Revolute(TermConstraint):
    """Two body points coincide: Φ = r_a(q) − r_b(q) = 0.

    Parameters
    ----------
    point_a, point_b : BodyPoint
        Points of two bodies (``body.point(locator)``).
    name : str

    Notes
    -----
    Reaction: the force (F_x, F_y) = −λ (N) the joint exerts on the body of
    ``point_a`` (the body of ``point_b`` receives the opposite force).
    """

    reaction_labels = ("Fx", "Fy")

    def __init__(self, point_a, point_b, name="revolute"):
        if point_a is None or point_b is None:
            raise ValueError("Revolute joins two body points; use Pin for a point fixed to the ground")
        layout = PointLayout([point_a, point_b])
        n = layout.n
        self.points = (point_a, point_b)
        self.set_terms(layout, [Difference(n, point_a, layout.slices[0], point_b, layout.slices[1])])
        self.name = name


class Weld(TermConstraint):
    """Positions and angles of two body points coincide (or one point is clamped to the ground).

    Φ = [r_a − r_b; ϑ_a − ϑ_b − ϑ_0] with ϑ_0 the relative angle at the
    start (the bodies keep their initial relative orientation).

    Parameters
    ----------
    point_a : BodyPoint
        A point with an angle (rigid body, beam section).
    point_b : BodyPoint, optional
        The other point; ``None`` welds ``point_a`` to the ground at its
        initial position and angle.
    angle : float, optional
        ϑ_0 in rad (default: the initial relative angle).
    name : str

    Notes
    -----
    Reaction: (F_x, F_y, M) = −λ, the force (N) and moment (N m) the weld
    exerts on the body of ``point_a``.
    """

    reaction_labels = ("Fx", "Fy", "M")

    def __init__(self, point_a, point_b=None, angle=None, name="weld"):
        layout = PointLayout([point_a, point_b])
        n = layout.n
        sa, sb = layout.slices
        ta = angle_term(n, point_a, sa)
        if point_b is None:
            pos = Difference(n, point_a, sa, anchor=_point_position0(point_a))
            rel0 = _point_angle0(point_a)
            ang = [ta]
        else:
            pos = Difference(n, point_a, sa, point_b, sb)
            rel0 = _point_angle0(point_a) - _point_angle0(point_b)
            ang = [ta, angle_term(n, point_b, sb)]
        self.angle0 = rel0 if angle is None else float(check_finite_vector("angle", angle, 1)[0])
        ang_term = linear_combination(n, ang, [1.0, -1.0][:len(ang)], self.angle0)
        self.points = (point_a, point_b)
        self.set_terms(layout, [pos, ang_term])
        self.name = name


class Slider(TermConstraint):
    """A body point moves along a line fixed to the ground or to another body.

    Φ = n · (r_P − r_L) = 0 with n the unit normal of the line and r_L a point
    on it. On the ground, n and r_L are constant; on a body, r_L is a point
    of that body and n = A(ϑ_L) n_loc turns with its frame, so the exact
    discrete gradient combines the product rule with the rotation identity.

    Parameters
    ----------
    point : BodyPoint
        The sliding point P.
    direction : array_like, shape (2,)
        Direction of the line in the global frame at the initial configuration.
    anchor : array_like, shape (2,), optional
        A ground point of the line (m); default the initial position of P.
        Only for a ground line.
    on : BodyPoint, optional
        A point of the guiding body, on the line; its frame carries the line.
    name : str

    Notes
    -----
    Reaction: (F_x, F_y) = −λ n, the normal force (N) on the body of P.
    """

    reaction_labels = ("Fx", "Fy")

    def __init__(self, point, direction=(1.0, 0.0), anchor=None, on=None, name="slider"):
        self._build(point, direction, anchor, on, lock=False)
        self.name = name

    def _build(self, point, direction, anchor, on, lock):
        d = _unit("direction", direction)
        normal = E_MATRIX @ d
        layout = PointLayout([point, on])
        n = layout.n
        sp, so = layout.slices
        self.point, self.on = point, on
        terms = []
        if on is None:
            a = _point_position0(point) if anchor is None else check_finite_vector("anchor", anchor, 2)
            self.anchor = a
            self._normal = Constant(n, normal)
            terms.append(Dot(n, self._normal, Difference(n, point, sp, anchor=a)))
        else:
            if anchor is not None:
                raise ValueError("anchor applies to a ground line only; a line on a body passes through `on`")
            theta = angle_term(n, on, so)
            local = rotation(-_point_angle0(on)) @ normal
            self._normal = Rotated(n, theta, local)
            terms.append(Dot(n, self._normal, Difference(n, point, sp, on, so)))
        if lock:
            tp = angle_term(n, point, sp)
            if on is None:
                rel0 = _point_angle0(point)
                terms.append(linear_combination(n, [tp], [1.0], rel0))
            else:
                rel0 = _point_angle0(point) - _point_angle0(on)
                terms.append(linear_combination(n, [tp, angle_term(n, on, so)], [1.0, -1.0], rel0))
        self.set_terms(layout, terms)

    def normal(self, q):
        """Unit normal n of the line at local coordinates q."""
        return self._normal.value(q)

    def reaction(self, q, lam):
        return -float(lam[0]) * self.normal(q)

    def reaction_history(self, q, lam):
        lam = np.asarray(lam, dtype=float)
        if self.on is not None or type(self).normal is not Slider.normal or \
                type(self).reaction not in (Slider.reaction, Prismatic.reaction):
            # the normal turns with the guiding body (or a subclass computes the reaction its own way)
            return super().reaction_history(q, lam)
        f = -lam[:, :1] * self.normal(None)[None, :]          # a ground line's constant normal
        return f if lam.shape[1] == 1 else np.column_stack([f, -lam[:, 1]])


class Prismatic(Slider):
    """A slider whose relative angle is locked: the point moves along the line without turning.

    Φ = [n · (r_P − r_L); ϑ_P − ϑ_L − ϑ_0] (ϑ_L = 0 for a ground line,
    ϑ_0 the initial relative angle). Parameters as :class:`Slider`; the point
    must have an angle (rigid body or beam section).

    Notes
    -----
    Reaction: (F_x, F_y, M) = (−λ_0 n, −λ_1) on the body of P.
    """

    reaction_labels = ("Fx", "Fy", "M")

    def __init__(self, point, direction=(1.0, 0.0), anchor=None, on=None, name="prismatic"):
        self._build(point, direction, anchor, on, lock=True)
        self.name = name

    def reaction(self, q, lam):
        f = -float(lam[0]) * self.normal(q)
        return np.array([f[0], f[1], -float(lam[1])])
