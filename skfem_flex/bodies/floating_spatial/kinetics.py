r"""Kinetic energy of a spatial floating-frame beam on its inertia invariants.

The coordinates are q = (x, d₁, d₂, d₃, y): the frame's origin x, its directors d_i (the columns of
D = [d₁ d₂ d₃]) and the elastic coordinates y. A point of the axis is at r = x + D ρ(s), ρ = X₀ + S y, so

.. math::

    \dot r = \dot x + \sum_i ρ_i \dot d_i + \sum_k d_k\, S_k \dot y ,

and with the invariants of ``inertia.py`` (the sections' turning adds to I₀, P and N only)

.. math::

    a^T M(q)\, b = m\, a_x\!\cdot b_x + \sum_i s_i (a_x\!\cdot b_i + a_i\!\cdot b_x)
      + a_x\!\cdot D\bar S b_y + b_x\!\cdot D\bar S a_y + \sum_{ij} J_{ij}\, a_i\!\cdot b_j
      + \sum_{ik} \big[(a_i\!\cdot d_k)\, c_{ik}\!\cdot b_y + (b_i\!\cdot d_k)\, c_{ik}\!\cdot a_y\big]
      + \sum_{kl} (d_k\!\cdot d_l)\, a_y^T N_{kl}\, b_y ,

    s = S_0 + \bar S y,\quad J_{ij} = I_{0,ij} + (P_{ij} + P_{ji})\!\cdot y + y^T N_{ij} y,\quad
    c_{ik} = P_{ik} + N_{ik}^T y .

M(q) is a polynomial of degree two in q, and aᵀM(q)b is invariant when x, the d_i, a and b turn together
(y does not turn). Hence:

- the mid-point gradient of G(q) = ½ v₀ᵀM(q)v₁ is its exact discrete gradient, and it turns with the
  state (the energy–momentum scheme needs nothing else);
- DM(q)[w] = (M(q + hw) − M(q − hw))/(2h) holds exactly for every h;
- the Hessian of aᵀM(q)b in q does not depend on q.

Writing B(q, a) = ∂(M(q) a)/∂q (so ∇_q aᵀM(q)b = B(q, a)ᵀ b) and H(a, b) = ∇²_q aᵀM(q)b, the
quadratic-velocity force Q_v = ∂T/∂q − Ṁ v and its derivatives are

.. math::

    Q_v = B(q, v)^T v/2 − B(q, v) v,\quad
    ∂Q_v/∂q = H(v, v)/2 − (B(v, v) − B(0, v)),\quad
    ∂Q_v/∂v = B(q, v)^T − B(q, v) − DM(q)[v],

where B(v, v) − B(0, v) is the part of B(·, v) linear in the configuration, evaluated at v.
"""
from __future__ import annotations

import numpy as np

__all__ = ["split", "mass_matrix", "momentum_jacobian", "kinetic_hessian", "mass_derivative",
           "quadratic_velocity_force", "kinetic_discrete_gradient"]

_D = slice(3, 12)


def split(q):
    """(x (3,), D (3, 3) with the directors as columns, y) of a coordinate (or velocity) vector."""
    q = np.asarray(q, dtype=float)
    return q[:3], q[_D].reshape(3, 3).T, q[12:]


def _configuration(inv, y):
    """s (3,), J (3, 3), C (3, 3, n_f) at the elastic coordinates y (module docstring)."""
    s = inv.S0 + inv.Sbar @ y
    Py = inv.P @ y
    J = inv.I0 + Py + Py.T + np.einsum("ijab,a,b->ij", inv.N, y, y)
    C = inv.P + np.einsum("ikml,m->ikl", inv.N, y)
    return s, J, C


def _blocks(n_f):
    """Slices of x, each director and y in a vector of 12 + n_f."""
    return slice(0, 3), [slice(3 + 3 * i, 6 + 3 * i) for i in range(3)], slice(12, 12 + n_f)


def mass_matrix(inv, q):
    """M(q), (12 + n_f) × (12 + n_f), kg (module docstring)."""
    x, D, y = split(q)
    nf = y.size
    s, J, C = _configuration(inv, y)
    X, Ds, Y = _blocks(nf)
    eye = np.eye(3)
    M = np.zeros((12 + nf, 12 + nf))
    M[X, X] = inv.mass * eye
    M[X, Y] = D @ inv.Sbar
    for i in range(3):
        M[X, Ds[i]] = M[Ds[i], X] = s[i] * eye
        for j in range(3):
            M[Ds[i], Ds[j]] = J[i, j] * eye
        M[Ds[i], Y] = D @ C[i]
        M[Y, Ds[i]] = M[Ds[i], Y].T
    M[Y, X] = M[X, Y].T
    M[Y, Y] = np.einsum("kl,klab->ab", D.T @ D, inv.N)
    return M


def momentum_jacobian(inv, q, a):
    """B(q, a) = ∂(M(q) a)/∂q (module docstring)."""
    _, D, y = split(q)
    ax, A, ay = split(a)
    nf = y.size
    _, _, C = _configuration(inv, y)
    X, Ds, Y = _blocks(nf)
    eye = np.eye(3)
    Wa = np.einsum("ikl,l->ik", C, ay)                       # c_ik · a_y
    Na = np.einsum("ikab,b->ika", inv.N, ay)                 # N_ik a_y
    Sa = inv.Sbar @ ay
    Py = inv.P + inv.P.transpose(1, 0, 2)
    gradJ = Py + np.einsum("ijab,b->ija", inv.N, y) + np.einsum("ijba,b->ija", inv.N, y)
    B = np.zeros((12 + nf, 12 + nf))
    B[X, Y] = A @ inv.Sbar
    for i in range(3):
        B[X, Ds[i]] = Sa[i] * eye
        for k in range(3):
            B[Ds[i], Ds[k]] = Wa[i, k] * eye
        B[Ds[i], Y] = np.outer(ax, inv.Sbar[i]) + A @ gradJ[i] + D @ Na[i]
        k = i
        B[Y, Ds[k]] = (np.outer(inv.Sbar[k], ax) + C[:, k, :].T @ A.T
                       + (Na[k, :, :] + Na[:, k, :]).T @ D.T)
    B[Y, Y] = np.einsum("ik,ikab->ba", A.T @ D, inv.N)
    return B


def kinetic_hessian(inv, a, b):
    """H(a, b) = ∇²_q aᵀM(q)b (constant in q)."""
    _, A, ay = split(a)
    _, Bv, by = split(b)
    nf = ay.size
    _, Ds, Y = _blocks(nf)
    eye = np.eye(3)
    alpha = np.einsum("a,klab,b->kl", ay, inv.N, by)
    Na = np.einsum("ikab,b->ika", inv.N, ay)
    Nb = np.einsum("ikab,b->ika", inv.N, by)
    T = A.T @ Bv
    H = np.zeros((12 + nf, 12 + nf))
    for k in range(3):
        for ell in range(3):
            H[Ds[k], Ds[ell]] = (alpha[k, ell] + alpha[ell, k]) * eye
        H[Ds[k], Y] = A @ Nb[:, k, :] + Bv @ Na[:, k, :]
        H[Y, Ds[k]] = H[Ds[k], Y].T
    NT = np.einsum("ijab,ij->ab", inv.N, T)
    H[Y, Y] = NT + NT.T
    return H


def mass_derivative(inv, q, w):
    """DM(q)[w] = Σ_k w_k ∂M/∂q_k, exact by the central difference of a quadratic (module docstring)."""
    q, w = np.asarray(q, dtype=float), np.asarray(w, dtype=float)
    wn = float(np.abs(w).max())
    if wn == 0.0:
        return np.zeros((q.size, q.size))
    h = max(float(np.abs(q).max()), 1.0) / wn
    return (mass_matrix(inv, q + h * w) - mass_matrix(inv, q - h * w)) / (2.0 * h)


def quadratic_velocity_force(inv, q, v):
    """(Q_v, ∂Q_v/∂q, ∂Q_v/∂v) (module docstring)."""
    Bq = momentum_jacobian(inv, q, v)
    f = 0.5 * (Bq.T @ v) - Bq @ v
    fq = 0.5 * kinetic_hessian(inv, v, v) - (momentum_jacobian(inv, v, v) - momentum_jacobian(inv, np.zeros_like(v), v))
    fv = Bq.T - Bq - mass_derivative(inv, q, v)
    return f, fq, fv


def kinetic_discrete_gradient(inv, q0, q1, v0, v1):
    """(g, ∂g/∂q1, ∂g/∂v1) of G(q) = ½ v₀ᵀM(q)v₁: the gradient at the mid-point, exact for a quadratic."""
    qm = 0.5 * (np.asarray(q0, dtype=float) + np.asarray(q1, dtype=float))
    Bm = momentum_jacobian(inv, qm, v0)
    return 0.5 * (Bm.T @ v1), 0.25 * kinetic_hessian(inv, v0, v1), 0.5 * Bm.T
