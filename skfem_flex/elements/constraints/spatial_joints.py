r"""Spatial joints between the points of spatial bodies, or a body point and the ground.

Every joint is a :class:`~.quadratic.QuadraticConstraint`: its equations are differences of points
(linear) and dot products of points and body-fixed directions (quadratic), so its mid-point Jacobian is
an exact discrete gradient (``docs/spatial.md``). At a floating-frame body's material point a dot product
with a moving direction, or of a difference of points, is cubic or quartic: product rows with the product
rule's exact discrete gradient (:mod:`.product_rows`, ``docs/spatial_floating_beam.md``). Axes are given in **space axes at the initial state**
and fixed in each body from there; a joint must hold at the initial state (the scene's consistent start
projects small misfits away).

=========================  =================================================  ==========
joint                      equations                                          equations
=========================  =================================================  ==========
:class:`Spherical`         r_a − r_b = 0                                      3
:class:`Revolute3D`        spherical; n₁ᵃ·e_b = n₂ᵃ·e_b = 0                   5
:class:`Universal`         spherical; u_a·w_b = 0                             4
:class:`Cylindrical`       n₁ᵃ·e_b = n₂ᵃ·e_b = 0; (r_b − r_a)·n_iᵃ = 0        4
:class:`Prismatic3D`       orientation lock (3); (r_b − r_a)·n_iᵃ = 0         5
:class:`Weld3D`            spherical; orientation lock (3)                    6
:class:`Distance3D`        ½(‖r_a − r_b‖² − l²) = 0                           1
:class:`TranslationDriver` (r_a − r_b)·e_a − s₀ − s(t) = 0                    1
:class:`RotationDriver`    cos θ(t) (u·n₂) − sin θ(t) (u·n₁) = 0              1
=========================  =================================================  ==========

e is the joint axis, n₁, n₂ two directions perpendicular to it (fixed in body a, or in space for the
ground); the orientation lock is u₁·a₂ = u₁·a₃ = u₂·a₃ = 0 with a_i directions of body a and u_i the
directions of body b that coincide with them at the start. Every joint's reaction is the force (N) and
moment (N m, about its point on body a) it exerts on body a, in space axes.
"""
from __future__ import annotations

import numpy as np

from ...bodies.base import BodyPoint, check_finite_vector, keeps_methods
from ..point_terms import PointLayout
from ..motion import MotionLaw
from .base import CONTRACT, Constraint
from .quadratic import (Affine, QuadraticConstraint, hinge_directions, perpendiculars, spatial_reaction, stack,
                        unit_vector)

__all__ = ["Spherical", "Revolute3D", "Universal", "Cylindrical", "Prismatic3D", "Weld3D", "Distance3D",
           "TranslationDriver", "RotationDriver"]

_LABELS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")


def _spatial_point(name, point):
    if not isinstance(point, BodyPoint) or getattr(point, "dimension", 2) != 3:
        raise ValueError(f"{name} must be a point of a spatial body (body.point(...)), got {point!r}")
    return point


class _Joint(QuadraticConstraint):
    """Set-up shared by the joints: the local layout, affine points and directions of a and b."""

    reaction_labels = _LABELS

    def _setup(self, point_a, point_b, anchor):
        self.point_a = _spatial_point("point_a", point_a)
        self.point_b = None if point_b is None else _spatial_point("point_b", point_b)
        if self.point_b is not None and self.point_b.body is self.point_a.body:
            raise ValueError("a joint needs points of two different bodies (or point_b=None for the ground)")
        self._layout = PointLayout([self.point_a] if self.point_b is None else [self.point_a, self.point_b])
        n = self._layout.n
        self.ra = Affine.of(self.point_a, self._layout.slices[0], n)
        if self.point_b is None:
            r0 = self.point_a.position(np.asarray(self.point_a.body.q0, dtype=float))
            self.anchor = r0 if anchor is None else check_finite_vector("anchor", anchor, 3)
            self.rb = Affine.constant(self.anchor, n)
        else:
            if anchor is not None:
                raise ValueError("anchor is the ground point: give it only with point_b=None")
            self.rb = Affine.of(self.point_b, self._layout.slices[1], n)
        return n

    def _direction(self, which, e_space):
        """A direction given in space at the start, fixed in body a or b (or in space for the ground)."""
        point = self.point_a if which == "a" else self.point_b
        n = self._layout.n
        if point is None:
            return Affine.constant(e_space, n)
        if point.triad is None and getattr(point, "Theta", None) is None:
            raise ValueError(f"this point of body {point.body.name!r} has no orientation of its own (a point mass, "
                             f"or a node of a floating frame's elastic body): it cannot carry a "
                             f"joint axis")
        sl = self._layout.slices[0 if which == "a" else 1]
        return Affine.of(point.direction(e_space), sl, n)

    def _finish(self, parts, name, laws=None):
        rows = stack(parts)
        QuadraticConstraint.__init__(self, self._layout.bodies, rows.H, rows.b, rows.c, laws=laws, name=name,
                                     products=rows.products)

    def _check_initial(self):
        q0 = self._layout.initial()
        res = np.abs(self.value(q0, 0.0))
        scale = max(1.0, float(np.abs(q0).max(initial=0.0)))
        if res.size and float(res.max()) > 1e-6 * scale:
            raise ValueError(f"joint {self.name!r} does not hold at the initial state: |Φ| = {res.max():.3g} "
                             f"(points or axes that do not meet)")

    def _lock(self):
        """u₁·a₂ = u₁·a₃ = u₂·a₃ = 0: b turns with a (three equations)."""
        a = [self._direction("a", e) for e in np.eye(3)]
        u = [self._direction("b", e) for e in np.eye(3)]
        return [u[0].dot(a[1]), u[0].dot(a[2]), u[1].dot(a[2])]

    def _ground_lock(self):
        """Body a must not turn (point_b is the ground): a₁·e₂ = a₁·e₃ = a₂·e₃ = 0, a_i = e_i at the start."""
        a = [self._direction("a", e) for e in np.eye(3)]
        n = self._layout.n
        e = [Affine.constant(v, n) for v in np.eye(3)]
        return [a[0].dot(e[1]), a[0].dot(e[2]), a[1].dot(e[2])]

    def _axis_alignment(self, axis):
        e = unit_vector("axis", axis)
        n1, n2 = perpendiculars(e)
        eb = self._direction("b", e)
        return e, n1, n2, [self._direction("a", n1).dot(eb), self._direction("a", n2).dot(eb)]

    def reaction(self, q, lam):
        return spatial_reaction(self, self.point_a.body, self._layout.slices[0], self.point_a, q, lam)

    def reaction_history(self, q, lam):
        return spatial_reaction(self, self.point_a.body, self._layout.slices[0], self.point_a, q, lam)


class Spherical(_Joint):
    """A ball joint: r_a = r_b (or r_a = anchor for ``point_b=None``).

    Parameters
    ----------
    point_a : SpatialPoint
    point_b : SpatialPoint or None
    anchor : array_like (3,), optional
        The ground point, m (default: the initial position of ``point_a``).
    name : str
    """

    def __init__(self, point_a, point_b=None, anchor=None, name="spherical"):
        self._setup(point_a, point_b, anchor)
        self._finish([self.ra.equals(self.rb)], name)
        self._check_initial()


class Revolute3D(_Joint):
    """A hinge: the points coincide and body b turns about ``axis`` fixed in body a (5 equations).

    Parameters
    ----------
    point_a, point_b : SpatialPoint (``point_b`` None: the ground)
    axis : array_like (3,)
        The hinge axis in space axes at the initial state (any length but zero).
    anchor : array_like (3,), optional
        The ground point for ``point_b=None``.
    name : str
    """

    def __init__(self, point_a, point_b=None, axis=(0.0, 0.0, 1.0), anchor=None, name="revolute"):
        self._setup(point_a, point_b, anchor)
        self.axis = unit_vector("axis", axis)
        _, _, _, align = self._axis_alignment(self.axis)
        self._finish([self.ra.equals(self.rb)] + align, name)
        self._check_initial()


class Universal(_Joint):
    """A cross (Cardan) joint: the points coincide and ``axis_a`` (fixed in a) stays perpendicular to
    ``axis_b`` (fixed in b); the two must be perpendicular at the start (4 equations)."""

    def __init__(self, point_a, point_b=None, axis_a=(1.0, 0.0, 0.0), axis_b=(0.0, 1.0, 0.0), anchor=None,
                 name="universal"):
        self._setup(point_a, point_b, anchor)
        ea, eb = unit_vector("axis_a", axis_a), unit_vector("axis_b", axis_b)
        if abs(float(ea @ eb)) > 1e-9:
            raise ValueError(f"universal joint {name!r}: axis_a and axis_b must be perpendicular, "
                             f"their cosine is {float(ea @ eb):.3g}")
        self._finish([self.ra.equals(self.rb), self._direction("a", ea).dot(self._direction("b", eb))], name)
        self._check_initial()


class Cylindrical(_Joint):
    """Body b slides along and turns about ``axis`` fixed in body a through ``point_a`` (4 equations)."""

    def __init__(self, point_a, point_b=None, axis=(0.0, 0.0, 1.0), anchor=None, name="cylindrical"):
        self._setup(point_a, point_b, anchor)
        self.axis, n1, n2, align = self._axis_alignment(axis)
        d = self.rb - self.ra
        self._finish(align + [d.dot(self._direction("a", n1)), d.dot(self._direction("a", n2))], name)
        self._check_initial()


class Prismatic3D(_Joint):
    """Body b slides along ``axis`` fixed in body a without turning relative to it (5 equations)."""

    def __init__(self, point_a, point_b=None, axis=(1.0, 0.0, 0.0), anchor=None, name="prismatic"):
        self._setup(point_a, point_b, anchor)
        self.axis = e = unit_vector("axis", axis)
        n1, n2 = perpendiculars(e)
        d = self.rb - self.ra
        lock = self._lock() if self.point_b is not None else self._ground_lock()
        self._finish(lock + [d.dot(self._direction("a", n1)), d.dot(self._direction("a", n2))], name)
        self._check_initial()



class Weld3D(_Joint):
    """Bodies a and b (or a and the ground) move as one: the points coincide, no relative turn (6)."""

    def __init__(self, point_a, point_b=None, anchor=None, name="weld"):
        self._setup(point_a, point_b, anchor)
        lock = self._lock() if self.point_b is not None else self._ground_lock()
        self._finish([self.ra.equals(self.rb)] + lock, name)
        self._check_initial()


class Distance3D(_Joint):
    """Two points (or a point and a ground point) at a fixed distance: ½(‖r_a − r_b‖² − l²) = 0.

    ``length`` defaults to the initial distance, which must not be zero (a direction is needed)."""

    reaction_labels = ("tension",)

    def __init__(self, point_a, point_b=None, length=None, anchor=None, name="distance"):
        self._setup(point_a, point_b, anchor)
        d = self.ra - self.rb
        l0 = float(np.linalg.norm(d.value(self._layout.initial())))
        length = l0 if length is None else float(length)
        if not np.isfinite(length) or length <= 0.0:
            raise ValueError(f"distance {name!r}: the length must be finite and positive (the points must not "
                             f"coincide), got {length!r} m")
        self.length = length
        self._finish([d.dot(d, length ** 2).scaled(0.5)], name)

    def reaction(self, q, lam):
        """The tension N (positive pulls the points together)."""
        return np.atleast_1d(-self.length * np.asarray(lam, dtype=float))

    def reaction_history(self, q, lam):
        return -self.length * np.asarray(lam, dtype=float).reshape(-1, 1)


class TranslationDriver(_Joint):
    """The offset of ``point_a`` from ``point_b`` along ``axis`` (fixed in body a) follows s₀ + s(t).

    Parameters
    ----------
    point_a, point_b : SpatialPoint (``point_b`` None: the ground; then the axis is fixed in space)
    axis : array_like (3,)
        In space axes at the initial state.
    law : MotionLaw
        s(t), ṡ(t), s̈(t) in m: the displacement from the initial distance s₀.
    """

    def __init__(self, point_a, point_b=None, axis=(1.0, 0.0, 0.0), law=None, anchor=None,
                 name="translation driver"):
        self._setup(point_a, point_b, anchor)
        if law is None:
            raise ValueError("a translation driver needs a law (MotionLaw)")
        e = unit_vector("axis", axis)
        d = self.ra - self.rb
        row = d.dot(self._direction("a", e))
        s0 = float(row.value(self._layout.initial())[0])
        self._finish([row._replace(c=row.c - s0)], name, laws=[law])


class RotationDriver(Constraint):
    """The angle of a hinge follows a law: θ(t) about ``axis`` between body b and body a (or body a and the
    ground), one equation

    Φ = cos θ(t) (u·n₂) − sin θ(t) (u·n₁) = 0,

    with n₁, n₂ directions of body a (or of space) perpendicular to the axis and u the direction of the
    turning body that coincides with n₁ at the start: u = cos θ n₁ + sin θ n₂ satisfies it. Use it beside a
    :class:`Revolute3D` about the same axis. At fixed t it is quadratic in q (an exact mid-point gradient);
    Φ_t = −θ̇ (sin θ (u·n₂) + cos θ (u·n₁)).

    Parameters
    ----------
    body_a : SpatialRigidBody
    body_b : SpatialRigidBody or None
        The body that turns against a; None: body a turns against the ground.
    axis : array_like (3,)
        In space axes at the initial state.
    law : MotionLaw
        θ(t), θ̇(t), θ̈(t) in rad (θ(0) = 0 at the start).
    name : str

    Notes
    -----
    Reaction: the moment (N m) about the axis that drives the turning body.
    """

    quadratic = True
    rheonomic = True
    reaction_labels = ("moment",)

    def __init__(self, body_a, body_b, axis, law, name="rotation driver"):
        if not isinstance(law, MotionLaw):
            raise ValueError(f"a rotation driver needs a MotionLaw θ(t), got {law!r}")
        self.layout, u, a1, a2 = hinge_directions(body_a, body_b, axis)
        self.bodies = self.layout.bodies
        (self.Hx, self.bx, self.cx), (self.Hy, self.by, self.cy) = ([p[0][0], p[1][0], float(p[2][0])]
                                                                      for p in (u.dot(a1), u.dot(a2)))
        self.law = law
        self.n_equations = 1
        self.name = name

    def _xy(self, q):
        x = 0.5 * q @ self.Hx @ q + self.bx @ q + self.cx
        y = 0.5 * q @ self.Hy @ q + self.by @ q + self.cy
        return x, y, self.Hx @ q + self.bx, self.Hy @ q + self.by

    def value(self, q, t):
        th = self.law(t)[0]
        x, y, _, _ = self._xy(q)
        return np.array([np.cos(th) * y - np.sin(th) * x])

    def jacobian(self, q, t):
        th = self.law(t)[0]
        _, _, gx, gy = self._xy(q)
        return (np.cos(th) * gy - np.sin(th) * gx)[None, :]

    def hessian_product(self, q, mu, t):
        th = self.law(t)[0]
        return float(np.asarray(mu).ravel()[0]) * (np.cos(th) * self.Hy - np.sin(th) * self.Hx)

    def time_derivative(self, q, t):
        th, w, _ = self.law(t)
        x, y, _, _ = self._xy(q)
        return np.array([-w * (np.sin(th) * y + np.cos(th) * x)])

    def time_derivative_jacobian(self, q, t):
        """Φ_qt = −θ̇ (sin θ ∇(u·n₂) + cos θ ∇(u·n₁))."""
        th, w, _ = self.law(t)
        _, _, gx, gy = self._xy(q)
        return (-w * (np.sin(th) * gy + np.cos(th) * gx))[None, :]

    def time_terms(self, q, v, t):
        th, w, acc = self.law(t)
        x, y, gx, gy = self._xy(q)
        s, c = np.sin(th), np.cos(th)
        phi_qt_v = -w * (s * (gy @ v) + c * (gx @ v))
        phi_tt = -acc * (s * y + c * x) - w * w * (c * y - s * x)
        return np.array([2.0 * phi_qt_v + phi_tt])

    def reaction(self, q, lam):
        return np.atleast_1d(np.asarray(lam, dtype=float)).copy()

    def reaction_history(self, q, lam):
        return np.asarray(lam, dtype=float).reshape(-1, 1).copy()

    def compiled_form(self):
        """``("rotation driver", H_X, b_X, c_X, H_Y, b_Y, c_Y, law)``: the rotation-driver family packs it; None
        for a subclass that changes the equation (it runs through its own methods)."""
        if not keeps_methods(self, RotationDriver, CONTRACT + ("time_derivative_jacobian", "_xy")):
            return None
        return "rotation driver", self.Hx, self.bx, self.cx, self.Hy, self.by, self.cy, self.law
