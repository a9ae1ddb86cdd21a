"""A spring on one body coordinate, V = ½ k u^(2n) (:class:`NonlinearSpring`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import keeps_methods
from .base import CONSERVATIVE, ForceElement

__all__ = ["NonlinearSpring", "MAX_SPRING_EXPONENT"]

#: largest exponent n of a NonlinearSpring (V = ½ k u^(2n))
MAX_SPRING_EXPONENT = 100


class NonlinearSpring(ForceElement):
    """Spring on one coordinate with strain ε = u^n and energy V = ½ k ε².

    Parameters
    ----------
    body : Body
        The body whose coordinate stretches the spring.
    stiffness : float
        k in N/m^(2n−1) (N/m for n = 1), finite and positive.
    exponent : float
        n with 2n a positive integer, so that V = ½ k u^(2n) is a polynomial
        defined for all u: n = 1 linear, n = 2 gives m ü + 2 k u³ = 0, n = 1.5
        gives V = ½ k u³ (unbounded below; Lee & Yun, §4).
    coordinate : int or str
        Which coordinate of the body is u (default 0).

    Notes
    -----
    Discrete gradient (Lee & Yun, eq. 25a generalised): the exact
    divided difference (V(u1) − V(u0))/(u1 − u0) = ½ k Σ_j u1^j u0^(2n−1−j),
    free of cancellation; for n = 2 it equals k (u0² + u1²)/2 · (u0 + u1),
    the stress at the mean strain times the strain difference.
    """

    conservative = True
    name = "spring"

    def __init__(self, body, stiffness, exponent=1.0, coordinate=0):
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        n = float(exponent)
        two_n = 2.0 * n
        if not np.isfinite(n) or n <= 0 or abs(two_n - round(two_n)) > 1e-12:
            raise ValueError(f"exponent must be positive with 2*exponent an integer (1, 1.5, 2, ...), got {exponent!r}")
        if two_n > 2 * MAX_SPRING_EXPONENT:
            # u^(2n) of any u ≠ ±1 leaves double precision long before; the discrete gradient sums 2n terms
            raise ValueError(f"exponent must be at most {MAX_SPRING_EXPONENT}, got {exponent!r}")
        self.k, self.exponent, self.power = k, n, int(round(two_n))
        self.bodies = (body,)
        self.index = body.coordinate_index(coordinate)
        self.n = body.n_dofs

    def _u(self, q):
        return float(q[self.index])

    def potential_energy(self, q):
        return 0.5 * self.k * self._u(q) ** self.power

    def potential_gradient(self, q):
        g = np.zeros(self.n)
        p = self.power
        g[self.index] = 0.5 * self.k * p * self._u(q) ** (p - 1)
        return g

    def potential_hessian(self, q):
        h = np.zeros((self.n, self.n))
        p = self.power
        h[self.index, self.index] = 0.5 * self.k * p * (p - 1) * self._u(q) ** (p - 2) if p >= 2 else 0.0
        return h

    def potential_discrete_gradient(self, q0, q1):
        u0, u1, p = self._u(q0), self._u(q1), self.power
        j = np.arange(p)
        g = np.zeros(self.n)
        g[self.index] = 0.5 * self.k * np.sum(u1 ** j * u0 ** (p - 1 - j))
        h = np.zeros((self.n, self.n))
        if p >= 2:
            j = np.arange(1, p)
            h[self.index, self.index] = 0.5 * self.k * np.sum(j * u1 ** (j - 1) * u0 ** (p - 1 - j))
        return g, h

    def compiled_form(self):
        if not keeps_methods(self, NonlinearSpring, CONSERVATIVE):
            return None
        return "coordinate spring", self.index, self.k, self.power

