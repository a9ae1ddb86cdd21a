"""A constraint given by your own callables (:class:`UserConstraint`)."""
from __future__ import annotations

import numpy as np

from .base import Constraint

__all__ = ["UserConstraint"]


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
