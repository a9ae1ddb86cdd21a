"""Algebraic constraints Φ(q, t) = 0 adjoined with Lagrange multipliers.

Sign convention of the equations of motion::

    M(q) q̈ + ∇V(q) + Φ_q(q, t)ᵀ λ = Q(q, q̇, t),     Φ(q, t) = 0

A constraint names the ``bodies`` it reads; the scene hands it the
concatenated coordinates of those bodies. Besides Φ, Φ_q and Φ_t each
constraint provides a *discrete gradient* D(q0, q1) with
D (q1 − q0) = Φ(q1) − Φ(q0) exactly, which the energy-conserving scheme uses
so that constraint forces do no work (second seed paper, §3.1).
"""
from __future__ import annotations

import numpy as np

from .bodies.base import check_finite_vector

__all__ = ["Constraint", "Distance", "UserConstraint"]


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

    def acceleration_rhs(self, q, v, t):
        """γ with Φ_q q̈ = γ: γ = −(Φ_q v)_q v − 2 Φ_qt v − Φ_tt."""
        rows = [v @ self.hessian_product(q, e, t) @ v for e in np.eye(self.n_equations)]
        return -np.asarray(rows, dtype=float) - self.time_terms(q, v, t)

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


class Distance(Constraint):
    """Keeps a planar point mass at a fixed distance from a ground anchor.

    Φ = (|x − a|² − l²)/2 = 0 (second seed paper, §4: the simple pendulum).

    Parameters
    ----------
    body : PointMass
        A two-dimensional point mass.
    anchor : array_like, shape (2,)
        Ground point a in m.
    length : float
        Distance l in m, finite and positive.
    """

    n_equations = 1
    quadratic = True

    def __init__(self, body, anchor=(0.0, 0.0), length=1.0, name="distance"):
        if body.n_dofs != 2:
            raise ValueError(f"Distance needs a planar point mass (2 coordinates), body {body.name!r} has {body.n_dofs}")
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
    name : str
    """

    def __init__(self, bodies, value, jacobian, hessian_product=None, time_derivative=None,
                 time_terms=None, name="user"):
        self.bodies = tuple(bodies)
        if not callable(value) or not callable(jacobian):
            raise ValueError("UserConstraint needs callables value(q, t) and jacobian(q, t)")
        self._value, self._jac = value, jacobian
        self._hess, self._phit, self._tt = hessian_product, time_derivative, time_terms
        self.rheonomic = time_derivative is not None
        n = sum(b.n_dofs for b in self.bodies)
        q = np.concatenate([b.q0 for b in self.bodies]) if self.bodies else np.zeros(0)
        phi = np.atleast_1d(np.asarray(value(q, 0.0), dtype=float))
        jac = np.atleast_2d(np.asarray(jacobian(q, 0.0), dtype=float))
        if jac.shape != (phi.size, n):
            raise ValueError(f"jacobian must have shape ({phi.size}, {n}), got {jac.shape}")
        self.n_equations = phi.size
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
