"""The force-element contract: what every gravity field, spring, damper and load provides.

A force element names the ``bodies`` whose coordinates it reads; the scene
hands it the concatenation of those bodies' coordinate blocks (``q_loc``) in
that order. A conservative element provides a potential with gradient,
Hessian and discrete gradient; a non-conservative one a generalized force
(f, ∂f/∂q, ∂f/∂v) at (q, v, t), whose work the integrators record as
external work.
"""
from __future__ import annotations

import numpy as np

__all__ = ["ForceElement", "split_blocks", "CONSERVATIVE", "check_nonnegative"]


def split_blocks(bodies, q_loc):
    """Split a concatenated local vector into one view per body."""
    out, start = [], 0
    for b in bodies:
        out.append(q_loc[start:start + b.n_dofs])
        start += b.n_dofs
    return out


#: the methods of a conservative element's compiled form (a subclass redefining one runs in Python)
CONSERVATIVE = ("potential_energy", "potential_gradient", "potential_hessian", "potential_discrete_gradient")


class ForceElement:
    """Base class. ``conservative`` selects which half of the interface applies."""

    bodies: tuple = ()
    conservative: bool = True
    name: str = "force"

    # conservative elements
    def potential_energy(self, q):
        raise NotImplementedError

    def potential_gradient(self, q):
        raise NotImplementedError

    def potential_hessian(self, q):
        raise NotImplementedError

    def potential_discrete_gradient(self, q0, q1):
        """(g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0)."""
        raise NotImplementedError

    def compiled_form(self):
        """How the compiled mechanism loop (the element families of :mod:`skfem_flex.compiled.families`) evaluates this element,
        or None (the default: the scene runs on the Python path).

        ``("gravity", g)``; ``("coordinate spring", i, k, p)`` for V = ½ k q_i^p (i over the element's
        own coordinates); ``("point force", point, F)`` for Q = r_qᵀ F(t) (F in the global frame);
        ``("generalized force", G, F)`` for Q = Gᵀ F(t) (G constant, (k, the element's coordinates),
        F(t) of k values); ``("follower force", point, g, c, F)`` for Q = r_qᵀ A(g · q + c) F(t);
        ``("quadratic spring", g, c, k)`` for V = ½ k (g · q + c)²; ``("linear damper", g, c)`` for
        Q = −c (g · v) g; ``("two-point spring", a, b, anchor, k, l₀)`` for V = ½ k (‖r_a − r_b‖ − l₀)²
        and ``("two-point damper", a, b, anchor, c)`` for the damper along r_a − r_b (b None: the
        ground point ``anchor``). Vectors g are over the element's own coordinates.
        """
        return None

    # non-conservative elements
    def generalized_force(self, q, v, t):
        """(f, ∂f/∂q, ∂f/∂v) at time t (s)."""
        raise NotImplementedError



def check_nonnegative(name, value):
    """``value`` as a float, or ``ValueError`` unless it is finite and non-negative."""
    value = float(value)
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
    return value
