r"""Algebraic constraints Φ(q, t) = 0 adjoined with Lagrange multipliers.

Sign convention of the equations of motion::

    M(q) q̈ + ∇V(q) + Φ_q(q, t)ᵀ λ = Q(q, q̇, t),     Φ(q, t) = 0

so the generalized force a constraint exerts is −Φ_qᵀ λ. A constraint names
the ``bodies`` it reads; the scene hands it the concatenated coordinates of
those bodies. Besides Φ, Φ_q and Φ_t each constraint provides a *discrete
gradient* D(q0, q1) with D (q1 − q0) = Φ(q1) − Φ(q0) exactly, which the
energy-conserving scheme uses so that constraint forces do no work (Lee & Yun,
§3.1: the constraint is enforced at the end of each step,
Φ(q_{n+1}) = 0, and the discrete constraint work (Φ_f − Φ_i) λ_m vanishes).

Joints (:class:`Pin`, :class:`Revolute`, :class:`Slider`,
:class:`Prismatic`, :class:`Weld`, :class:`Driver`) are built from body
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

from ..bodies.base import BodyPoint, check_finite_vector, keeps_methods, zero_matrix
from ..bodies.rigid import E_MATRIX, rotation
from .motion import MotionLaw
# PointLayout is re-exported here (it was defined in this module and is part of its public names)
from .point_terms import (Constant, Difference, Dot, PointLayout, Rotated, angle_term, coordinate_term,
                          linear_combination)

__all__ = ["Constraint", "Distance", "UserConstraint", "Pin", "Revolute", "Slider", "Prismatic", "Weld",
           "Driver", "PointLayout"]




# ============================================================ the base class
#: the methods a constraint's compiled form stands for (a subclass redefining one runs in Python)
CONTRACT = ("value", "jacobian", "hessian_product", "time_derivative", "time_terms", "velocity_jacobian",
            "acceleration_rhs", "discrete_gradient", "discrete_gradient_jacobian")


class Constraint:
    """Base class of holonomic constraints.

    Subclasses set ``bodies``, ``n_equations`` and ``name`` and implement
    :meth:`value`, :meth:`jacobian` and :meth:`hessian_product`. Rheonomic
    constraints (drivers) also override :meth:`time_derivative` and
    :meth:`time_terms`.
    """

    bodies: tuple = ()
    n_equations: int = 0
    name: str = "constraint"
    #: True when Φ depends explicitly on t
    rheonomic: bool = False
    #: True when Φ is at most quadratic in q: then the midpoint gradient is exact
    quadratic: bool = False
    #: what :meth:`reaction` returns, one label per entry
    reaction_labels: tuple = ()

    def value(self, q, t):
        """Φ(q, t), shape (n_equations,)."""
        raise NotImplementedError

    def jacobian(self, q, t):
        """Φ_q(q, t), shape (n_equations, len(q))."""
        raise NotImplementedError

    def hessian_product(self, q, mu, t):
        """∂(Φ_qᵀ μ)/∂q, shape (len(q), len(q))."""
        raise NotImplementedError

    def time_derivative(self, q, t):
        """Φ_t(q, t); zero for scleronomic constraints."""
        return np.zeros(self.n_equations)

    def time_terms(self, q, v, t):
        """2 Φ_qt v + Φ_tt, the explicit-time part of the acceleration equation."""
        return np.zeros(self.n_equations)

    def velocity_jacobian(self, q, v, t):
        """∂(Φ_q v)/∂q at fixed v, shape (n_equations, len(q)).

        Row i is vᵀ ∂²Φ_i/∂q² (the Hessian of a scalar is symmetric), taken
        from :meth:`hessian_product` with μ = e_i.
        """
        # H v, not vᵀ H: the same row for a symmetric H, and a sparse H stays sparse
        rows = [np.asarray(self.hessian_product(q, e, t) @ v, dtype=float).ravel() for e in np.eye(self.n_equations)]
        return np.asarray(rows, dtype=float).reshape(self.n_equations, len(q))

    def acceleration_rhs(self, q, v, t):
        """γ with Φ_q q̈ = γ: γ = −(Φ_q v)_q v − 2 Φ_qt v − Φ_tt."""
        return -(self.velocity_jacobian(q, v, t) @ v) - self.time_terms(q, v, t)

    def discrete_gradient(self, q0, q1, t):
        """D with D (q1 − q0) = Φ(q1, t) − Φ(q0, t).

        Quadratic constraints use the midpoint Jacobian, exact for them;
        others add Gonzalez's correction row by row.
        """
        qm = 0.5 * (q0 + q1)
        d = self.jacobian(qm, t)
        if self.quadratic:
            return d
        dq = q1 - q0
        nrm2 = float(dq @ dq)
        if nrm2 > 0.0:
            jump = self.value(q1, t) - self.value(q0, t)
            d = d + np.outer((jump - d @ dq) / nrm2, dq)
        return d

    def discrete_gradient_jacobian(self, q0, q1, mu, t):
        """∂(Dᵀ μ)/∂q1 (the Gonzalez correction's own derivative is left out)."""
        return 0.5 * self.hessian_product(0.5 * (q0 + q1), mu, t)

    def compiled_form(self):
        """How the compiled mechanism loop (:mod:`skfem_flex.compiled.scene_loop`) evaluates this constraint,
        or None (the default: the scene runs on the Python path).

        ``("rows", [(term, law), ...])``: the equations in order, each block the ``compiled_form()`` of a
        :class:`~skfem_flex.elements.point_terms.Term` minus a motion law x(t) (``law`` None: no time term);
        ``("distance", point, a, l)`` for Φ = ½(‖r − a‖² − l²).
        """
        return None

    def reaction(self, q, lam):
        """What the constraint exerts, from its multipliers λ at coordinates q.

        The base class returns −λ, the generalized reaction per equation
        (−Φ_qᵀλ projected on each equation's own gradient); joints override
        it with forces (N) and moments (N m) in the global frame.
        """
        return -np.asarray(lam, dtype=float)

    def reaction_history(self, q, lam):
        """:meth:`reaction` at many states at once (the recorded steps of a compiled loop).

        Parameters
        ----------
        q : ndarray (N, n_local)
        lam : ndarray (N, n_equations)

        Returns
        -------
        ndarray (N, k)
            Row i is ``reaction(q[i], lam[i])``: −λ, vectorized, when the class keeps the base
            :meth:`reaction`; otherwise row by row, unless the class vectorizes it too.
        """
        lam = np.asarray(lam, dtype=float)
        if type(self).reaction is Constraint.reaction:
            return -lam
        if lam.shape[0] == 0:
            return np.zeros((0, len(self.reaction_labels) or self.n_equations))
        rows = [np.atleast_1d(np.asarray(self.reaction(qi, li), dtype=float)) for qi, li in zip(q, lam)]
        return np.array(rows).reshape(lam.shape[0], -1)


class _TermConstraint(Constraint):
    """A constraint whose equations are terms (rows stacked in order); exact discrete gradient."""

    def _set_terms(self, layout, terms):
        self.layout = layout
        self.bodies = layout.bodies
        self._terms = list(terms)
        rows, r = [], 0
        for t in self._terms:
            rows.append(slice(r, r + t.size))
            r += t.size
        self._rows = rows
        self.n_equations = r
        self.quadratic = all(t.linear for t in self._terms)

    def value(self, q, t):
        if len(self._terms) == 1:
            return self._terms[0].value(q)
        return np.concatenate([term.value(q) for term in self._terms])

    def jacobian(self, q, t):
        if len(self._terms) == 1:
            return self._terms[0].jacobian(q)
        return np.vstack([term.jacobian(q) for term in self._terms])

    def hessian_product(self, q, mu, t):
        mu = np.asarray(mu, dtype=float)
        out = zero_matrix(self.layout.n)
        for term, r in zip(self._terms, self._rows):
            if not term.linear:
                out = out + term.hessian(q, mu[r])
        return out

    def discrete_gradient(self, q0, q1, t):
        if len(self._terms) == 1:
            return self._terms[0].dgrad(q0, q1)
        return np.vstack([term.dgrad(q0, q1) for term in self._terms])

    def discrete_gradient_jacobian(self, q0, q1, mu, t):
        mu = np.asarray(mu, dtype=float)
        out = zero_matrix(self.layout.n)
        for term, r in zip(self._terms, self._rows):
            if not term.linear:
                out = out + term.dgrad_jacobian(q0, q1, mu[r])
        return out

    def compiled_form(self):
        if self.rheonomic or not keeps_methods(self, _TermConstraint, CONTRACT):
            return None
        forms = [term.compiled_form() for term in self._terms]
        if any(f is None or f[0] == "constant" for f in forms):
            return None
        return "rows", [(f, None) for f in forms]


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
class Pin(_TermConstraint):
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
        self._set_terms(layout, [Difference(n, point, layout.slices[0], anchor=self.anchor)])
        self.name = name



class Revolute(_TermConstraint):
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
        self._set_terms(layout, [Difference(n, point_a, layout.slices[0], point_b, layout.slices[1])])
        self.name = name



class Weld(_TermConstraint):
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
        self._set_terms(layout, [pos, ang_term])
        self.name = name



class Slider(_TermConstraint):
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
        self._set_terms(layout, terms)

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


class Driver(_TermConstraint):
    """A coordinate, an angle or a relative angle prescribed as a function of time.

    Φ = s(q) − x(t) = 0 with s a body coordinate, the angle ϑ of a body point,
    or the relative angle ϑ_a − ϑ_b of two points (all linear in q, so the
    discrete gradient is the constant gradient of s). Unlike
    :class:`~skfem_flex.elements.motion.Prescribed`, the coordinate stays an unknown
    and the driving force is the multiplier: generalized force −λ.

    Parameters
    ----------
    target : Body or BodyPoint
        A body (then ``coordinate`` names the driven coordinate) or a body
        point whose angle is driven.
    law : MotionLaw
        x(t), ẋ(t), ẍ(t).
    coordinate : str or int, optional
        For a body target: the coordinate's name or index (e.g. ``"theta"``).
    relative_to : BodyPoint, optional
        For a point target: drive ϑ_target − ϑ_relative_to.
    name : str

    Notes
    -----
    Φ_t = −ẋ(t), acceleration equation Φ_q q̈ = ẍ(t). Reaction: the
    generalized force −λ the driver exerts on s (N m for angles, N for
    lengths); its power is −λ ṡ.
    """

    rheonomic = True
    reaction_labels = ("Q",)

    def __init__(self, target, law, coordinate=None, relative_to=None, name="driver"):
        if not isinstance(law, MotionLaw):
            raise ValueError(f"Driver needs a MotionLaw (position, velocity, acceleration), got {law!r}")
        self.law = law
        if isinstance(target, BodyPoint):
            if coordinate is not None:
                raise ValueError("coordinate applies to a body target, not to a body point (whose angle is driven)")
            layout = PointLayout([target, relative_to])
            n = layout.n
            term = angle_term(n, target, layout.slices[0])
            if relative_to is not None:
                term = linear_combination(n, [term, angle_term(n, relative_to, layout.slices[1])], [1.0, -1.0])
        else:
            if relative_to is not None:
                raise ValueError("relative_to applies to a body-point (angle) target")
            if coordinate is None:
                raise ValueError(f"Driver on body {getattr(target, 'name', target)!r} needs coordinate=...")
            index = target.coordinate_index(coordinate)
            layout = PointLayout.of_bodies([target])
            term = coordinate_term(layout.n, index)
        self._s = term
        self._set_terms(layout, [term])
        self.quadratic = True
        self.name = name

    def driven_value(self, q):
        """s(q), the driven quantity."""
        return float(self._s.value(q)[0])

    def value(self, q, t):
        return self._s.value(q) - float(self.law.position(t))

    def time_derivative(self, q, t):
        return np.array([-float(self.law.velocity(t))])

    def compiled_form(self):
        form = self._s.compiled_form()
        if form is None or not keeps_methods(self, Driver, CONTRACT):
            return None
        return "rows", [(form, self.law)]

    def time_terms(self, q, v, t):
        return np.array([-float(self.law.acceleration(t))])

    def acceleration_rhs(self, q, v, t):
        return np.array([float(self.law.acceleration(t))])



# ============================================================ point masses
class Distance(Constraint):
    """Keeps a planar point mass at a fixed distance from a ground anchor.

    Φ = (‖x − a‖² − l²)/2 = 0 (Lee & Yun, §4: the simple pendulum).

    Parameters
    ----------
    body : PointMass
        A two-dimensional point mass.
    anchor : array_like, shape (2,)
        Ground point a in m.
    length : float
        Distance l in m, finite and positive.

    Notes
    -----
    Reaction: the force −λ (x − a) (N) on the mass (the rod's tension).
    """

    n_equations = 1
    quadratic = True
    reaction_labels = ("Fx", "Fy")

    def __init__(self, body, anchor=(0.0, 0.0), length=1.0, name="distance"):
        if body.n_dofs != 2:
            raise ValueError(f"Distance needs a planar point mass (2 coordinates), body {body.name!r} "
                             f"has {body.n_dofs}")
        length = float(length)
        if not np.isfinite(length) or length <= 0:
            raise ValueError(f"length must be finite and positive, got {length!r}")
        self.bodies = (body,)
        self.anchor = check_finite_vector("anchor", anchor, 2)
        self.length = length
        self.name = name

    def value(self, q, t):
        d = q - self.anchor
        return np.array([0.5 * (d @ d - self.length ** 2)])

    def jacobian(self, q, t):
        return (q - self.anchor)[None, :]

    def hessian_product(self, q, mu, t):
        return mu[0] * np.eye(2)

    def compiled_form(self):
        if not keeps_methods(self, Distance, CONTRACT):
            return None
        return "distance", self.bodies[0].point(), self.anchor, self.length

    def reaction(self, q, lam):
        return -float(lam[0]) * (np.asarray(q, dtype=float) - self.anchor)

    def reaction_history(self, q, lam):
        if not keeps_methods(self, Distance, ("reaction",)):
            return super().reaction_history(q, lam)
        return -np.asarray(lam, dtype=float)[:, :1] * (np.asarray(q, dtype=float) - self.anchor[None, :])


class UserConstraint(Constraint):
    """A constraint given by callables.

    Parameters
    ----------
    bodies : sequence of Body
        Bodies whose concatenated coordinates q the callables receive.
    value : callable (q, t) -> array (m,)
        Φ(q, t).
    jacobian : callable (q, t) -> array (m, len(q))
        Φ_q(q, t).
    hessian_product : callable (q, mu, t) -> array (len(q), len(q)), optional
        ∂(Φ_qᵀ μ)/∂q. If omitted it is taken by central differences of the
        Jacobian (a Newton tangent only; Φ itself stays exact).
    time_derivative : callable (q, t) -> array (m,), optional
        Φ_t for rheonomic constraints.
    time_terms : callable (q, v, t) -> array (m,), optional
        2 Φ_qt v + Φ_tt for rheonomic constraints.
    discrete_gradient : callable (q0, q1, t) -> array (m, len(q)), optional
        An exact discrete gradient. Without it the midpoint Jacobian with
        Gonzalez's correction is used, which is exact too (the correction
        makes D (q1 − q0) = Φ(q1) − Φ(q0) hold by construction).
    name : str

    Notes
    -----
    Reaction: −λ, the generalized reaction per equation.
    """

    def __init__(self, bodies, value, jacobian, hessian_product=None, time_derivative=None,
                 time_terms=None, discrete_gradient=None, name="user"):
        self.bodies = tuple(bodies)
        if not callable(value) or not callable(jacobian):
            raise ValueError("UserConstraint needs callables value(q, t) and jacobian(q, t)")
        for label, fn in (("hessian_product", hessian_product), ("time_derivative", time_derivative),
                          ("time_terms", time_terms), ("discrete_gradient", discrete_gradient)):
            if fn is not None and not callable(fn):
                raise ValueError(f"UserConstraint: {label} must be callable, got {fn!r}")
        self._value, self._jac = value, jacobian
        self._hess, self._phit, self._tt, self._dg = hessian_product, time_derivative, time_terms, discrete_gradient
        self.rheonomic = time_derivative is not None
        n = sum(b.n_dofs for b in self.bodies)
        q = np.concatenate([b.q0 for b in self.bodies]) if self.bodies else np.zeros(0)
        phi = np.atleast_1d(np.asarray(value(q, 0.0), dtype=float))
        jac = np.atleast_2d(np.asarray(jacobian(q, 0.0), dtype=float))
        if jac.shape != (phi.size, n):
            raise ValueError(f"jacobian must have shape ({phi.size}, {n}), got {jac.shape}")
        self.n_equations = phi.size
        self.reaction_labels = tuple(f"Q{i}" for i in range(phi.size))
        self.name = name

    def value(self, q, t):
        return np.atleast_1d(np.asarray(self._value(q, t), dtype=float))

    def jacobian(self, q, t):
        return np.atleast_2d(np.asarray(self._jac(q, t), dtype=float))

    def hessian_product(self, q, mu, t):
        if self._hess is not None:
            return np.asarray(self._hess(q, mu, t), dtype=float)
        h = 1e-6 * max(1.0, float(np.max(np.abs(q))) if q.size else 1.0)
        out = np.empty((q.size, q.size))
        for k in range(q.size):
            e = np.zeros(q.size)
            e[k] = h
            out[:, k] = (self.jacobian(q + e, t).T @ mu - self.jacobian(q - e, t).T @ mu) / (2 * h)
        return out

    def time_derivative(self, q, t):
        return np.zeros(self.n_equations) if self._phit is None else np.atleast_1d(self._phit(q, t))

    def time_terms(self, q, v, t):
        return np.zeros(self.n_equations) if self._tt is None else np.atleast_1d(self._tt(q, v, t))

    def discrete_gradient(self, q0, q1, t):
        if self._dg is not None:
            return np.atleast_2d(np.asarray(self._dg(q0, q1, t), dtype=float))
        return super().discrete_gradient(q0, q1, t)
