r"""The arithmetic of a rigid body turned by a quaternion: its mass matrix, its Hamiltonian energy–momentum
step and its Newmark terms (the one implementation: the compiled family and the body's Python methods both
call these functions).

With the Euler parameters e = (e₀, e₁, e₂, e₃) and the 4×4 matrix E(e) = [eᵀ; G(e)] whose last three rows
give the body angular velocity Ω = 2 G(e) ė (E(e) E(e)ᵀ = |e|² I), the kinetic energy of the rotation is

.. math::  T = 2\, (E(e)\dot e)^T J_4\, (E(e)\dot e) = \tfrac12 \dot e^T M(e) \dot e,\qquad
           M(e) = 4 E(e)^T J_4 E(e),\quad J_4 = \operatorname{diag}(j_0, J),

with J the inertia tensor in body axes; j₀ > 0 only makes M regular along e, where the constraint
½(e·e − 1) = 0 holds the motion (it does no work there). M is a polynomial of degree two in e.
On |e| = 1 its inverse is A(e) = ¼ E(e)ᵀ J₄⁻¹ E(e), also of degree two, and the Hamiltonian is
T(e, π) = ½ πᵀ A(e) π with π = M(e) ė.

**Energy–momentum step** (Betsch & Siebert's partitioned discrete gradient). From (e₀, π₀) to (e₁, π₁):

.. math::

    \frac{Δe}{Δt} = K\, π_m,\quad K = \tfrac12 (A(e_0) + A(e_1)),\quad π_m = \tfrac12(π_0 + π_1),

    π_1 - π_0 + Δt\, \tfrac12 \bigl(∇_e T(e_m, π_0) + ∇_e T(e_m, π_1)\bigr) + Δt\, ∇V(e_m) + μ\, e_m = 0 .

T is quadratic in e for fixed π and in π for fixed e, so the two half-sums are exact discrete gradients
and the step conserves T + V. A turn of the body about a symmetry axis of J (right multiplication
e → e∘r) and a turn of space about an axis its loads leave free (left multiplication) are orthogonal
linear maps of R⁴ that keep |e| and T: every term above is equivariant under them, so the step also
conserves the body's angular momentum about its symmetry axis and the spatial one about the free axis,
to round-off. (The director formulation's six rigidity equations are invariant under a turn about the
body axis only as a set, and its mid-point step keeps the body-axis momentum only to O(Δt²).)

The unknown is Δe: π₁ = 2 K⁻¹ Δe/Δt − π₀, and ė₁ = A(e₁) π₁ is the velocity kept for output and for the
next step's π₀ = M(e₀) ė₀.
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["E_UNITS", "e_matrix", "mass", "inverse_mass", "mass_jacobian", "quadratic_velocity_force",
           "hamiltonian_gradient", "em_terms", "newmark_terms", "omega_matrix", "space_matrix"]


def _units():
    """E(u_k) for the four unit vectors: E(e) = Σ e_k E_k (E is linear in e)."""
    out = np.zeros((4, 4, 4))
    for k in range(4):
        e = np.zeros(4)
        e[k] = 1.0
        e0, e1, e2, e3 = e
        out[k] = [[e0, e1, e2, e3], [-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]]
    return out


#: E(u_k), k = 0..3
E_UNITS = _units()


@numba.njit(cache=True)
def e_matrix(e):
    """E(e) = [eᵀ; G(e)] (4, 4): Ω = 2 G(e) ė is the body angular velocity."""
    out = np.zeros((4, 4))
    for k in range(4):
        for i in range(4):
            for j in range(4):
                out[i, j] += e[k] * E_UNITS[k, i, j]
    return out


def omega_matrix(e):
    """G(e) (3, 4): the body angular velocity Ω = 2 G(e) ė (rad/s)."""
    return e_matrix(np.asarray(e, dtype=float))[1:]


def space_matrix(e):
    """Ḡ(e) (3, 4): the space angular velocity ω = 2 Ḡ(e) ė, and the angular momentum of the rotation
    about the body's reference point ½ Ḡ(e) π (kg m²/s)."""
    e0, e1, e2, e3 = (float(a) for a in e)
    return np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])


@numba.njit(cache=True)
def _sandwich(J, e, scale):
    """scale · E(e)ᵀ J E(e) in plain loops (a 4×4 product is cheaper without a BLAS call)."""
    E = e_matrix(e)
    JE = np.zeros((4, 4))
    for i in range(4):
        for k in range(4):
            for j in range(4):
                JE[i, j] += J[i, k] * E[k, j]
    out = np.zeros((4, 4))
    for i in range(4):
        for k in range(4):
            for j in range(4):
                out[i, j] += E[k, i] * JE[k, j]
    for i in range(4):
        for j in range(4):
            out[i, j] *= scale
    return out


@numba.njit(cache=True)
def _times(A, x):
    """A x for a 4×4 A, in plain loops."""
    out = np.zeros(4)
    for i in range(4):
        for j in range(4):
            out[i] += A[i, j] * x[j]
    return out


@numba.njit(cache=True)
def mass(J4, e):
    """M(e) = 4 E(e)ᵀ J₄ E(e) (kg m²)."""
    return _sandwich(J4, e, 4.0)


@numba.njit(cache=True)
def inverse_mass(J4i, e):
    """A(e) = ¼ E(e)ᵀ J₄⁻¹ E(e), the inverse of M(e) on |e| = 1 (1/(kg m²))."""
    return _sandwich(J4i, e, 0.25)


@numba.njit(cache=True)
def _polarized(J, e, a, inverse):
    """∂(M(e) a)/∂e (or of A(e) a with J = J₄⁻¹): column k is c (E_kᵀ J E(e) a + E(e)ᵀ J E_k a), c = 4 or ¼."""
    c = 0.25 if inverse else 4.0
    E = e_matrix(e)
    b = _times(J, _times(E, a))
    out = np.zeros((4, 4))
    for k in range(4):
        Eka = np.zeros(4)
        for i in range(4):
            for j in range(4):
                Eka[i] += E_UNITS[k, i, j] * a[j]
        JEka = _times(J, Eka)
        for i in range(4):
            s = 0.0
            for j in range(4):
                s += E_UNITS[k, j, i] * b[j] + E[j, i] * JEka[j]
            out[i, k] = c * s
    return out


@numba.njit(cache=True)
def mass_jacobian(J4, e, a):
    """B(e, a) = ∂(M(e) a)/∂e (4, 4)."""
    return _polarized(J4, e, a, False)


@numba.njit(cache=True)
def _qv(J4, e, v):
    """Q_v = ∂T/∂e − Ṁ v with T = ½ vᵀM(e)v: ½ B(e, v)ᵀ v − B(e, v) v."""
    B = mass_jacobian(J4, e, v)
    return 0.5 * _times(B.T.copy(), v) - _times(B, v)


@numba.njit(cache=True)
def quadratic_velocity_force(J4, e, v):
    """(Q_v, ∂Q_v/∂e, ∂Q_v/∂v) of the rotation (N m per unit of e). Q_v is linear in e and quadratic in v,
    so both derivatives are exact differences."""
    f = _qv(J4, e, v)
    fe, fv = np.zeros((4, 4)), np.zeros((4, 4))
    z = np.zeros(4)
    for k in range(4):
        u = np.zeros(4)
        u[k] = 1.0
        col = _qv(J4, u, v) - _qv(J4, z, v)          # Q_v(e, v) = L(v) e: column k of L(v)
        d = _qv(J4, e, v + u) - _qv(J4, e, v - u)
        for i in range(4):
            fe[i, k] = col[i]
            fv[i, k] = 0.5 * d[i]
    return f, fe, fv


@numba.njit(cache=True)
def hamiltonian_gradient(J4i, e, p):
    """∇_e T(e, π) with T = ½ πᵀ A(e) π: component k is ¼ (E_k π)·J₄⁻¹ (E(e) π)."""
    b = _times(J4i, _times(e_matrix(e), p))
    out = np.zeros(4)
    for k in range(4):
        s = 0.0
        for i in range(4):
            ek = 0.0
            for j in range(4):
                ek += E_UNITS[k, i, j] * p[j]
            s += ek * b[i]
        out[k] = 0.25 * s
    return out


@numba.njit(cache=True)
def _hamiltonian_hessian(J4i, p):
    """∂²T/∂e² (constant in e: T is quadratic in e)."""
    out = np.zeros((4, 4))
    for k in range(4):
        u = np.zeros(4)
        u[k] = 1.0
        col = hamiltonian_gradient(J4i, u, p)
        for i in range(4):
            out[i, k] = col[i]
    return out


@numba.njit(cache=True)
def em_terms(J4, J4i, e0, e1, v0, h):
    r"""The rotation's part of one energy–momentum step (module docstring) at the end e₁.

    Returns
    -------
    p1 : ndarray (4,)
        π₁ = 2 K⁻¹ Δe/Δt − π₀, with π₀ = M(e₀) ė₀.
    gk : ndarray (4,)
        −½ (∇_e T(e_m, π₀) + ∇_e T(e_m, π₁)) (the residual takes −Δt g_k).
    dp, dgk : ndarray (4, 4)
        Their derivatives with respect to e₁ (Δe).
    v1 : ndarray (4,)
        ė₁ = A(e₁) π₁.
    """
    p0 = _times(mass(J4, e0), v0)
    K = 0.5 * (inverse_mass(J4i, e0) + inverse_mass(J4i, e1))
    vm = (e1 - e0) / h
    pm = np.linalg.solve(K, vm)
    p1 = 2.0 * pm - p0
    # K π_m = Δe/Δt: δπ_m = K⁻¹ (δ/Δt − ½ ∂(A(e₁) π_m)/∂e₁ δ)
    rhs = np.eye(4) / h - 0.5 * _polarized(J4i, e1, pm, True)
    dp = 2.0 * np.linalg.solve(K, rhs)
    em = 0.5 * (e0 + e1)
    gk = -0.5 * (hamiltonian_gradient(J4i, em, p0) + hamiltonian_gradient(J4i, em, p1))
    # ∂∇_eT(e, π)/∂π = (∂(A(e)π)/∂e)ᵀ
    Dm = _polarized(J4i, em, p1, True)
    DmT_dp = np.zeros((4, 4))
    for i in range(4):
        for k in range(4):
            for j in range(4):
                DmT_dp[i, j] += Dm[k, i] * dp[k, j]
    dgk = -(0.25 * (_hamiltonian_hessian(J4i, p0) + _hamiltonian_hessian(J4i, p1)) + 0.5 * DmT_dp)
    v1 = _times(inverse_mass(J4i, e1), p1)
    return p1, gk, dp, dgk, v1


@numba.njit(cache=True)
def newmark_terms(J4, e1, v1, a1):
    """The rotation's Newmark terms at the end of the step: (M(e₁), M(e₁) a₁, ∂(M a₁)/∂e₁, Q_v, ∂Q_v/∂e,
    ∂Q_v/∂v)."""
    M1 = mass(J4, e1)
    f, fe, fv = quadratic_velocity_force(J4, e1, v1)
    return M1, _times(M1, a1), mass_jacobian(J4, e1, a1), f, fe, fv
