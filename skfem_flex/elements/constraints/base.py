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

This module holds the contract (:class:`Constraint`, with the default discrete gradient) and
:class:`TermConstraint`, the constraint whose equations are stacked point terms (every joint and
the driver).
"""
from __future__ import annotations

import numpy as np

from ...bodies.base import keeps_methods, zero_matrix

__all__ = ["Constraint", "TermConstraint", "CONTRACT"]


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

    def time_derivative_jacobian(self, q, t):
        """Φ_qt = ∂Φ_t/∂q, shape (n_equations, len(q)): zero unless Φ_t depends on q (a rotation driver). The
        velocity rows Φ_q v + Φ_t of the trapezoidal rule take it into their Newton matrix."""
        return np.zeros((self.n_equations, len(q)))

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
        """How the compiled mechanism loop (the element families of :mod:`skfem_flex.compiled.families`) evaluates this constraint,
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


class TermConstraint(Constraint):
    """A constraint whose equations are terms (rows stacked in order); exact discrete gradient.

    Subclasses build their terms (:mod:`skfem_flex.elements.point_terms`) and call :meth:`set_terms`.
    """

    def set_terms(self, layout, terms):
        """Take the equations ``terms`` (stacked in order) over the points of ``layout`` (a PointLayout)."""
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
        if self.rheonomic or not keeps_methods(self, TermConstraint, CONTRACT):
            return None
        forms = [term.compiled_form() for term in self._terms]
        if any(f is None or f[0] == "constant" for f in forms):
            return None
        return "rows", [(f, None) for f in forms]
