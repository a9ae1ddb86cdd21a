"""A point mass kept at a fixed distance from a ground anchor (:class:`Distance`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import check_finite_vector, keeps_methods
from .base import CONTRACT, Constraint

__all__ = ["Distance"]


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
