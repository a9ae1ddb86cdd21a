r"""Constraint rows that are sums of products of two quadratic invariants: axes at floating-frame material points.

A material direction of a floating-frame body is u(q) = Σ_i t_i(y) d_i, with d_i the frame's directors and
t_i(y) = (e₀ − ê₀ Θ y)_i affine in the elastic coordinates y (the section's small elastic turn); a material
point is r = x + Σ_i ρ_i(y) d_i with ρ = X₀ + S y. Dotted with a direction or point of another moving body,
the row is cubic or quartic in q, and the plain mid-point gradient is no longer a discrete gradient.

Expanded, every such row is

.. math::  Φ(q) = φ_0(q) + Σ_m a_m(q)\, s_m(q),

where φ₀, a_m and s_m are quadratic scalars ½qᵀHq + b·q + c: a_m a factor t_i, or a product t_i t'_j of
two of them, and s_m the dot product of the two vectors they multiply (d_i·d'_j, d_i·(x_b − x_a), …). Each
quadratic scalar's mid-point gradient is exact, and the two-factor product rule

.. math::  Δ(a s) = \bar a\, Δs + \bar s\, Δa,\qquad \bar a = \tfrac12 (a(q_0) + a(q_1)),

is exact too, so

.. math::  D(q_0, q_1) = ∇φ_0(q_m) + Σ_m \bigl[\bar a_m ∇s_m(q_m) + \bar s_m ∇a_m(q_m)\bigr]

satisfies D (q₁ − q₀) = Φ(q₁) − Φ(q₀): the joint does no work in the energy–momentum step. Every factor is an
invariant of a common rotation and translation of all bodies (t_i depends on y only; s_m is a dot product of
directors or of differences of points, grouped by the t-monomial they multiply), and the gradient of an
invariant at q_m is orthogonal to the symmetry's action at q_m; D is a combination of such gradients, so
the forces of these rows conserve linear and angular momentum as well (a joint's point-coincidence rows
r_a − r_b = 0 are quadratic but no invariants: angular momentum to O(Δt²)). (The product rule applied to the vectors,
ū·∇w + w̄·∇u, is exact for the energy too, but the means ū of vectors are not the vectors at q_m, and
angular momentum drifts.)
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["QuadraticScalar", "ProductTerm", "PolynomialRows", "ProductRows", "product_dot"]


class QuadraticScalar(NamedTuple):
    """φ(q) = ½ qᵀ H q + b·q + c over the constraint's local coordinates (H symmetric (n, n), b (n,))."""

    H: np.ndarray
    b: np.ndarray
    c: float

    def value(self, q):
        """φ(q)."""
        return 0.5 * q @ self.H @ q + self.b @ q + self.c

    def gradient(self, q):
        """∇φ(q) = H q + b."""
        return self.H @ q + self.b

    def columns(self):
        """The coordinates φ depends on (boolean (n,))."""
        return np.any(self.H != 0.0, axis=0) | (self.b != 0.0)

    def restricted(self, cols):
        """φ over the coordinates ``cols`` only (the others must not be touched)."""
        return QuadraticScalar(self.H[np.ix_(cols, cols)], self.b[cols], self.c)

    def scaled(self, f):
        """f φ."""
        return QuadraticScalar(f * self.H, f * self.b, f * self.c)


class ProductTerm(NamedTuple):
    """a(q) s(q) added to equation ``row``."""

    row: int
    a: QuadraticScalar
    s: QuadraticScalar


class PolynomialRows(NamedTuple):
    """Equations ½ qᵀ H_k q + b_k·q + c_k + Σ_{m: row k} a_m s_m (the module docstring); ``products`` may be
    empty (then the rows are quadratic)."""

    H: np.ndarray
    b: np.ndarray
    c: np.ndarray
    products: tuple = ()

    def scaled(self, f):
        """The equations times f (each product term's factor a scaled)."""
        return PolynomialRows(f * self.H, f * self.b, f * self.c,
                              tuple(ProductTerm(p.row, p.a.scaled(f), p.s) for p in self.products))

    def value(self, q):
        """Every equation's value at q."""
        out = 0.5 * np.einsum("kij,i,j->k", self.H, q, q) + self.b @ q + self.c
        return out + ProductRows(self.products, out.size, q.size).value(q) if self.products else out


def _affine_dot(A, a, B, b):
    """(A q + a)·(B q + b) as a :class:`QuadraticScalar`."""
    H = A.T @ B
    return QuadraticScalar(H + H.T, a @ B + b @ A, float(a @ b))


def _factor_product(f, g):
    """t_f(q) t_g(q) of two affine scalars t = β·q + γ, a quadratic scalar."""
    (bf, cf), (bg, cg) = f, g
    H = np.outer(bf, bg)
    return QuadraticScalar(H + H.T, cf * bg + cg * bf, cf * cg)


def product_dot(u, w, value=0.0):
    """u·w − value as one :class:`PolynomialRows` equation.

    u·w = P_u·P_w + Σ_k t'_k (P_u·W'_k q) + Σ_j t_j (W_j q·P_w) + Σ_jk t_j t'_k (W_j q·W'_k q) with P = A₀q + a₀:
    the first is the quadratic part, each other sum a product term (factor, dot product). For u·u the terms
    that are equal are taken once, with weight 2.

    Parameters
    ----------
    u, w : tuple
        Vectors in *factored form* (A₀ (3, n), a₀ (3,), terms): v(q) = A₀ q + a₀ + Σ_j t_j(q) W_j q with terms
        ((β_j (n,), γ_j, W_j (3, n)), ...), t_j = β_j·q + γ_j an invariant scalar (elastic coordinates only).
    value : float
        The constant subtracted.

    Returns
    -------
    PolynomialRows
        One equation.
    """
    (Au, au, tu), (Aw, aw, tw) = u, w
    same = u is w
    n = Au.shape[1]
    base = _affine_dot(Au, au, Aw, aw)
    zero = np.zeros(3)
    products = []
    if not same:
        for beta, gamma, W in tw:
            a = QuadraticScalar(np.zeros((n, n)), beta, gamma)
            products.append(ProductTerm(0, a, _affine_dot(Au, au, W, zero)))
    for j, (beta, gamma, W) in enumerate(tu):
        a = QuadraticScalar(np.zeros((n, n)), beta, gamma)
        products.append(ProductTerm(0, a.scaled(2.0) if same else a, _affine_dot(W, zero, Aw, aw)))
        for k, (beta2, gamma2, W2) in enumerate(tw):
            if same and k < j:
                continue
            a2 = _factor_product((beta, gamma), (beta2, gamma2))
            products.append(ProductTerm(0, a2.scaled(2.0) if same and k > j else a2, _affine_dot(W, zero, W2, zero)))
    return PolynomialRows(base.H[None], base.b[None], np.array([base.c - float(value)]), tuple(products))


class ProductRows:
    """The product terms of a set of ``m`` equations over ``n`` local coordinates, with their values,
    derivatives and discrete gradient (the module docstring)."""

    def __init__(self, products, m, n):
        self.terms = tuple(products)
        self.m, self.n = int(m), int(n)

    def columns(self):
        """The coordinates the terms touch (boolean (n,))."""
        cols = np.zeros(self.n, dtype=bool)
        for p in self.terms:
            cols |= p.a.columns() | p.s.columns()
        return cols

    def restricted(self, cols):
        """The same terms over the coordinates ``cols`` only (the others must not be touched)."""
        cols = np.asarray(cols)
        return ProductRows([ProductTerm(p.row, p.a.restricted(cols), p.s.restricted(cols)) for p in self.terms],
                           self.m, cols.size)

    def without_rows(self, keep):
        """Only the equations ``keep`` (sorted indices), renumbered."""
        where = {int(k): i for i, k in enumerate(keep)}
        return ProductRows([p._replace(row=where[p.row]) for p in self.terms if p.row in where], len(where), self.n)

    def value(self, q):
        """Σ a s per equation at q."""
        out = np.zeros(self.m)
        for p in self.terms:
            out[p.row] += p.a.value(q) * p.s.value(q)
        return out

    def jacobian(self, q):
        """∇(a s) = a ∇s + s ∇a, (m, n)."""
        return self.jacobians(np.asarray(q, dtype=float)[None])[0]

    def jacobians(self, Q):
        """∇(a s) = a ∇s + s ∇a at many states Q (N, n) at once: (N, m, n)."""
        out = np.zeros((Q.shape[0], self.m, self.n))
        for p in self.terms:
            ga, gs = Q @ p.a.H + p.a.b, Q @ p.s.H + p.s.b                      # H symmetric
            va = 0.5 * np.einsum("Ni,Ni->N", Q, ga + p.a.b) + p.a.c
            vs = 0.5 * np.einsum("Ni,Ni->N", Q, gs + p.s.b) + p.s.c
            out[:, p.row] += va[:, None] * gs + vs[:, None] * ga
        return out

    def hessian_product(self, q, mu):
        """Σ_k μ_k ∇²Φ_k: ∇²(a s) = a H_s + s H_a + ∇a ∇sᵀ + ∇s ∇aᵀ."""
        out = np.zeros((self.n, self.n))
        for p in self.terms:
            w = float(mu[p.row])
            if w:
                ga, gs = p.a.gradient(q), p.s.gradient(q)
                g = np.outer(ga, gs)
                out += w * (p.a.value(q) * p.s.H + p.s.value(q) * p.a.H + g + g.T)
        return out

    def velocity_jacobian(self, q, v):
        """Row k: ∇²Φ_k v."""
        out = np.zeros((self.m, self.n))
        for p in self.terms:
            ga, gs = p.a.gradient(q), p.s.gradient(q)
            out[p.row] += (p.a.value(q) * (p.s.H @ v) + p.s.value(q) * (p.a.H @ v) + ga * (gs @ v)
                           + gs * (ga @ v))
        return out

    def discrete_gradient(self, q0, q1):
        """Σ [ā ∇s(q_m) + s̄ ∇a(q_m)] per row: exact (module docstring)."""
        qm = 0.5 * (q0 + q1)
        out = np.zeros((self.m, self.n))
        for p in self.terms:
            abar = 0.5 * (p.a.value(q0) + p.a.value(q1))
            sbar = 0.5 * (p.s.value(q0) + p.s.value(q1))
            out[p.row] += abar * p.s.gradient(qm) + sbar * p.a.gradient(qm)
        return out

    def discrete_gradient_jacobian(self, q0, q1, mu):
        """∂(Dᵀμ)/∂q₁ = Σ μ [ā ½H_s + s̄ ½H_a + ∇s(q_m) ½∇a(q₁)ᵀ + ∇a(q_m) ½∇s(q₁)ᵀ]."""
        qm = 0.5 * (q0 + q1)
        out = np.zeros((self.n, self.n))
        for p in self.terms:
            w = float(mu[p.row])
            if w:
                abar = 0.5 * (p.a.value(q0) + p.a.value(q1))
                sbar = 0.5 * (p.s.value(q0) + p.s.value(q1))
                out += w * (0.5 * (abar * p.s.H + sbar * p.a.H) + 0.5 * np.outer(p.s.gradient(qm), p.a.gradient(q1))
                            + 0.5 * np.outer(p.a.gradient(qm), p.s.gradient(q1)))
        return out
