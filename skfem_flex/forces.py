"""Force elements: gravity, springs and loads that act on the coordinates of bodies.

A force element names the ``bodies`` whose coordinates it reads; the scene
hands it the concatenation of those bodies' coordinate blocks (``q_loc``) in
that order. A conservative element provides a potential with gradient,
Hessian and discrete gradient; a non-conservative one a generalized force
(f, ∂f/∂q, ∂f/∂v) at (q, v, t), whose work the integrators record as
external work.
"""
from __future__ import annotations

import numpy as np

from .bodies.base import check_finite_vector

__all__ = ["ForceElement", "Gravity", "NonlinearSpring", "split_blocks"]


def split_blocks(bodies, q_loc):
    """Split a concatenated local vector into one view per body."""
    out, start = [], 0
    for b in bodies:
        out.append(q_loc[start:start + b.n_dofs])
        start += b.n_dofs
    return out


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

    # non-conservative elements
    def generalized_force(self, q, v, t):
        """(f, ∂f/∂q, ∂f/∂v) at time t (s)."""
        raise NotImplementedError


class Gravity(ForceElement):
    """Uniform gravity field acting on bodies.

    Parameters
    ----------
    g : array_like, shape (2,)
        Acceleration of gravity in m/s², default (0, −9.81) (y up).
    bodies : sequence of Body, optional
        Bodies it acts on; ``None`` (default) means every body of the scene.

    Notes
    -----
    V = −g · ∫ r dm, summed over the bodies; each body supplies its own
    :meth:`~skfem_flex.bodies.base.Body.gravity_potential`. For bodies whose
    positions are linear in q the gradient is constant and is built once.
    """

    conservative = True
    name = "gravity"

    def __init__(self, g=(0.0, -9.81), bodies=None):
        self.g = check_finite_vector("g", g, 2)
        self.bodies = None if bodies is None else tuple(bodies)
        if self.bodies is None:
            return
        self._slices, self._const_grad, start = [], [], 0
        for b in self.bodies:
            self._slices.append(slice(start, start + b.n_dofs))
            start += b.n_dofs
            try:
                gam, _ = b.mass_moment()
                self._const_grad.append(-(self.g @ gam))
            except NotImplementedError:
                self._const_grad.append(None)
        self._n = start
        self._linear = all(c is not None for c in self._const_grad)

    def on(self, bodies):
        """The same field acting on ``bodies`` (used by the scene for ``bodies=None``)."""
        return Gravity(self.g, bodies)

    def potential_energy(self, q):
        return sum(b.gravity_potential(q[s], self.g)[0] for b, s in zip(self.bodies, self._slices))

    def potential_gradient(self, q):
        out = np.empty(self._n)
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            out[s] = c if c is not None else b.gravity_potential(q[s], self.g)[1]
        return out

    def potential_hessian(self, q):
        if self._linear:
            return None
        out = np.zeros((self._n, self._n))
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            if c is None:
                out[s, s] = _dense(b.gravity_potential(q[s], self.g)[2])
        return out

    def potential_discrete_gradient(self, q0, q1):
        if self._linear:
            return self.potential_gradient(q0), None
        g = np.empty(self._n)
        h = np.zeros((self._n, self._n))
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            if c is not None:
                g[s] = c
            else:
                gb, hb = b.gravity_discrete_gradient(q0[s], q1[s], self.g)
                g[s] = gb
                h[s, s] = _dense(hb)
        return g, h


def _dense(a):
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


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
        gives V = ½ k u³ (unbounded below; seed paper on energy schemes, §4).
    coordinate : int or str
        Which coordinate of the body is u (default 0).

    Notes
    -----
    Discrete gradient (second seed paper, eq. 25a generalised): the exact
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
