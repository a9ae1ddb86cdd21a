r"""The arithmetic of a rigid body turned by a quaternion: its mass matrix, its Hamiltonian energy–momentum
step and its Newmark terms (the one implementation: the compiled family and the body's Python methods both
call these functions).

With the Euler parameters e = (e₀, e₁, e₂, e₃) and the 4×4 matrix E(e) = [eᵀ; G(e)] whose last three rows
give the body angular velocity Ω = 2 G(e) ė (E(e) E(e)ᵀ = (e·e) I), the kinetic energy of the rotation is

.. math::  T = 2\, (E(e)\dot e)^T J_4\, (E(e)\dot e) = \tfrac12 \dot e^T M(e) \dot e,\qquad
           M(e) = 4 E(e)^T J_4 E(e),\quad J_4 = \operatorname{diag}(j_0, J),

with J the inertia tensor in body axes; j₀ > 0 only makes M regular along e, where the constraint
½(e·e − 1) = 0 holds the motion (it does no work there). M is a polynomial of degree two in e.
On e·e = 1 its inverse is A(e) = ¼ E(e)ᵀ J₄⁻¹ E(e), also of degree two, and the Hamiltonian is
T(e, π) = ½ πᵀ A(e) π with π = M(e) ė.

**Energy–momentum step** (a discrete gradient built on invariants, as Gonzalez builds his). With
b = E(e)π (four numbers, unchanged when space turns: e → l∘e, π → l∘π) and b·b = (e·e)(π·π),

.. math::

    T = \tfrac18 \Bigl[c_0\, s_0^2 + λ_r\, P\,Q + \sum_i c_i\, s_i^2\Bigr],\quad
    s_0 = e\cdot π,\; P = e\cdot e,\; Q = π\cdot π,\; s_i = u_i \cdot b,

where λ_i, u_i are the eigenvalues and eigenvectors of J⁻¹ (u_i padded with a leading zero), λ_r one of
them (a repeated one if J has an axis of symmetry), c₀ = 1/j₀ − λ_r and c_i = λ_i − λ_r (only the nonzero
ones kept: none for a spherical J, one, along the symmetry axis k, for a symmetric one). Each of s₀, P, Q,
s_i is quadratic in z = (e, π), so its mid-point gradient is exact, and the discrete gradient

.. math::

    D_T = \tfrac18 \Bigl[2 c_0 \bar s_0 ∇s_0(z_m) + λ_r \bigl(\bar Q ∇P(z_m) + \bar P ∇Q(z_m)\bigr)
          + \sum_i 2 c_i \bar s_i ∇s_i(z_m)\Bigr]

(bars: means of the two end values) has D_T·Δz = ΔT exactly. The step from (e₀, π₀) to (e₁, π₁) is

.. math::

    Δe = Δt\, D_{T,π},\qquad π_1 - π_0 + Δt\, D_{T,e} + Δt\, ∇V(e_m) + μ\, e_m = 0,\qquad ½(e_1\cdot e_1 - 1) = 0 .

Every invariant above is unchanged by a turn of space, and s₀, P, Q and s_k also by a turn of the body
about its symmetry axis k: their mid-point gradients are orthogonal to those turns' generators at z_m,
so the step conserves the energy, the angular momentum components the loads leave free, and for a
symmetric body the spin about its axis, to round-off. (The director formulation's six rigidity equations
are invariant under a turn about the body axis only as a set, and its mid-point step keeps the body-axis
momentum only to O(Δt²).)

The unknown is Δe: the first equation is linear in π₁, which is solved for; ė₁ = A(e₁) π₁ is the
velocity kept for output and for the next step's π₀ = M(e₀) ė₀.
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["E_UNITS", "e_matrix", "mass", "inverse_mass", "mass_jacobian", "quadratic_velocity_force",
           "em_terms", "invariant_terms", "newmark_terms", "omega_matrix", "space_matrix", "rotation_momentum",
           "gravity_quadratic", "moment_rate"]


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


@numba.njit(cache=True)
def space_matrix(e):
    """Ḡ(e) (3, 4): the space angular velocity ω = 2 Ḡ(e) ė, and the angular momentum of the rotation
    about the body's reference point ½ Ḡ(e) π (kg m²/s)."""
    out = np.empty((3, 4))
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = -e[1], e[0], -e[3], e[2]
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = -e[2], e[3], e[0], -e[1]
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = -e[3], -e[2], e[1], e[0]
    return out


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
def rotation_momentum(J4, e, edot):
    """The rotation's angular momentum about the body's reference point, ½ Ḡ(e) M(e) ė (kg m²/s; R J Ω
    on e·e = 1)."""
    p = _times(mass(J4, e), edot)
    G = space_matrix(e)
    out = np.zeros(3)
    for i in range(3):
        for j in range(4):
            out[i] += 0.5 * G[i, j] * p[j]
    return out


@numba.njit(cache=True)
def gravity_quadratic(Qc, g):
    """W (4, 4) with −g·(m R(e) c) = eᵀ W e, from the first moment's quadratics Qc (m Q_i(c)) and g (m/s²)."""
    W = np.zeros((4, 4))
    for i in range(3):
        for a in range(4):
            for b in range(4):
                W[a, b] -= g[i] * Qc[i, a, b]
    return W


@numba.njit(cache=True)
def moment_rate(Qc, e, edot):
    """d/dt (m R(e) c) = 2 Σ Qc_i e · ė (3,), kg m/s: a pivoted body's linear momentum."""
    out = np.zeros(3)
    for i in range(3):
        for a in range(4):
            for b in range(4):
                out[i] += 2.0 * Qc[i, a, b] * edot[a] * e[b]
    return out


@numba.njit(cache=True)
def mass(J4, e):
    """M(e) = 4 E(e)ᵀ J₄ E(e) (kg m²)."""
    return _sandwich(J4, e, 4.0)


@numba.njit(cache=True)
def inverse_mass(J4i, e):
    """A(e) = ¼ E(e)ᵀ J₄⁻¹ E(e), the inverse of M(e) on e·e = 1 (1/(kg m²))."""
    return _sandwich(J4i, e, 0.25)


@numba.njit(cache=True)
def _polarized(J, e, a, inverse):
    """∂(M(e) a)/∂e (or of A(e) a with J = J₄⁻¹): column k is c (E_kᵀ J E(e) a + E(e)ᵀ J E_k a), c = 4 or ¼."""
    c = 0.25 if inverse else 4.0
    E = e_matrix(e)
    b = _times(J, _times(E, a))
    out = np.zeros((4, 4))
    Eka, JEka = np.zeros(4), np.zeros(4)
    for k in range(4):
        for i in range(4):
            t = 0.0
            for j in range(4):
                t += E_UNITS[k, i, j] * a[j]
            Eka[i] = t
        for i in range(4):
            t = 0.0
            for j in range(4):
                t += J[i, j] * Eka[j]
            JEka[i] = t
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
def _qv_of(B, v):
    """Q_v = ∂T/∂e − Ṁ v with T = ½ vᵀM(e)v, from B = B(e, v): ½ Bᵀ v − B v."""
    out = np.zeros(4)
    for i in range(4):
        for j in range(4):
            out[i] += 0.5 * B[j, i] * v[j] - B[i, j] * v[j]
    return out


@numba.njit(cache=True)
def quadratic_velocity_force(J4, e, v):
    """(Q_v, ∂Q_v/∂e, ∂Q_v/∂v) of the rotation (N m per unit of e). B(e, a) is linear in e and in a, so Q_v
    is linear in e (column k of ∂Q_v/∂e is Q_v(u_k, v)) and, with B_k = B(e, u_k),
    ∂Q_v/∂v_k = ½ (B_kᵀ v + B(e, v)ᵀ u_k) − (B_k v + B(e, v) u_k)."""
    B = mass_jacobian(J4, e, v)
    f = _qv_of(B, v)
    fe, fv = np.zeros((4, 4)), np.zeros((4, 4))
    u = np.zeros(4)
    for k in range(4):
        u[:] = 0.0
        u[k] = 1.0
        col = _qv_of(mass_jacobian(J4, u, v), v)
        Bk = mass_jacobian(J4, e, u)
        for i in range(4):
            fe[i, k] = col[i]
            s = 0.5 * B[k, i] - B[i, k]
            for j in range(4):
                s += 0.5 * Bk[j, i] * v[j] - Bk[i, j] * v[j]
            fv[i, k] = s
    return f, fe, fv


@numba.njit(cache=True)
def _solve4(A, b):
    """x with A x = b for a 4×4 A by Gaussian elimination with partial pivoting (A, b kept)."""
    M = A.copy()
    x = b.copy()
    for c in range(4):
        piv = c
        for r in range(c + 1, 4):
            if abs(M[r, c]) > abs(M[piv, c]):
                piv = r
        if piv != c:
            for k in range(4):
                M[c, k], M[piv, k] = M[piv, k], M[c, k]
            x[c], x[piv] = x[piv], x[c]
        for r in range(c + 1, 4):
            f = M[r, c] / M[c, c]
            for k in range(c, 4):
                M[r, k] -= f * M[c, k]
            x[r] -= f * x[c]
    for c in range(3, -1, -1):
        t = x[c]
        for k in range(c + 1, 4):
            t -= M[c, k] * x[k]
        x[c] = t / M[c, c]
    return x


@numba.njit(cache=True)
def em_terms(J4, J4i, kin, U, cu, e0, e1, v0, h):
    r"""The rotation's part of one energy–momentum step (module docstring) at the end e₁.

    ``kin`` = (c₀, λ_r), ``U`` (n_u, 4) the rows u_i and ``cu`` (n_u,) the c_i of the invariants.

    Returns
    -------
    p1 : ndarray (4,)
        π₁ (π₀ = M(e₀) ė₀), from K π₁ = Δe/Δt − (the π₀ part of D_{T,π}).
    gk : ndarray (4,)
        −D_{T,e} (the residual takes −Δt g_k).
    dp, dgk : ndarray (4, 4)
        Their derivatives with respect to e₁ (Δe): dπ₁ = K⁻¹(∂rhs − ∂K π₁) and
        dD_{T,e} = ∂_{e₁}D_{T,e} + ∂_{π₁}D_{T,e} dπ₁.
    v1 : ndarray (4,)
        ė₁ = A(e₁) π₁.
    """
    c0, lr = kin[0], kin[1]
    p0 = _times(mass(J4, e0), v0)
    em = 0.5 * (e0 + e1)
    E0, E1, Em = e_matrix(e0), e_matrix(e1), e_matrix(em)
    P = 0.5 * (np.sum(e0 * e0) + np.sum(e1 * e1))
    s00 = np.sum(e0 * p0)
    b0 = _times(E0, p0)
    na = U.shape[0]
    W, W1 = np.zeros((na, 4)), np.zeros((na, 4))      # E(e_m)ᵀu_a, E(e₁)ᵀu_a
    sa0 = np.zeros(na)
    for a in range(na):
        for i in range(4):
            sa0[a] += U[a, i] * b0[i]
            for j in range(4):
                W[a, j] += Em[i, j] * U[a, i]
                W1[a, j] += E1[i, j] * U[a, i]
    # K π₁ = rhs (D_{T,π} = Δe/Δt, linear in π₁)
    K = np.zeros((4, 4))
    rhs = (e1 - e0) / h
    for i in range(4):
        K[i, i] += 0.125 * lr * P
        rhs[i] -= 0.125 * (c0 * s00 * em[i] + lr * P * p0[i])
        for j in range(4):
            K[i, j] += 0.125 * c0 * em[i] * e1[j]
    for a in range(na):
        for i in range(4):
            rhs[i] -= 0.125 * cu[a] * sa0[a] * W[a, i]
            for j in range(4):
                K[i, j] += 0.125 * cu[a] * W[a, i] * W1[a, j]
    p1 = _solve4(K, rhs)
    pm = 0.5 * (p0 + p1)
    Q = 0.5 * (np.sum(p0 * p0) + np.sum(p1 * p1))
    s0 = s00 + np.sum(e1 * p1)
    w1p = np.zeros(na)                                 # E(e₁)ᵀu_a · π₁
    for a in range(na):
        for j in range(4):
            w1p[a] += W1[a, j] * p1[j]
    sa = sa0 + w1p
    # E_kᵀu_a per (a, k), and T_a = C(π_m)ᵀu_a, (T_a)_k = (E_kᵀu_a)·π_m; ∂s_a/∂e₁_k = (E_kᵀu_a)·π₁
    EkU = np.zeros((na, 4, 4))
    Ta, dsa = np.zeros((na, 4)), np.zeros((na, 4))
    for a in range(na):
        for k in range(4):
            col = _times(E_UNITS[k].T, U[a])
            for j in range(4):
                EkU[a, k, j] = col[j]
                Ta[a, k] += col[j] * pm[j]
                dsa[a, k] += col[j] * p1[j]
    De = np.zeros(4)
    for k in range(4):
        De[k] = 0.125 * (c0 * s0 * pm[k] + 2.0 * lr * Q * em[k])
        for a in range(na):
            De[k] += 0.125 * cu[a] * sa[a] * Ta[a, k]
    # dπ₁/de₁ = K⁻¹ (∂rhs/∂e₁ − (∂K/∂e₁) π₁)
    R = np.zeros((4, 4))
    e1p = np.sum(e1 * p1)
    for i in range(4):
        R[i, i] += 1.0 / h - 0.125 * 0.5 * c0 * s00
        for k in range(4):
            R[i, k] -= 0.125 * lr * p0[i] * e1[k]                      # ∂P/∂e₁ = e₁
            R[i, k] -= 0.125 * lr * e1[k] * p1[i]                      # (∂K/∂e₁_k) π₁: λ_r e₁_k π₁
            R[i, k] -= 0.125 * c0 * em[i] * p1[k]                      # c₀ e_m (u_k·π₁)
        R[i, i] -= 0.125 * c0 * 0.5 * e1p                              # c₀ ½u_k (e₁·π₁)
    for a in range(na):
        for i in range(4):
            for k in range(4):
                R[i, k] -= 0.125 * cu[a] * 0.5 * EkU[a, k, i] * (sa0[a] + w1p[a])
                R[i, k] -= 0.125 * cu[a] * W[a, i] * dsa[a, k]
    dp = np.zeros((4, 4))
    for k in range(4):
        col = _solve4(K, R[:, k].copy())
        for i in range(4):
            dp[i, k] = col[i]
    # D_{T,e}: its partial derivatives in e₁ (π₁ fixed) and in π₁
    De_e, De_p = np.zeros((4, 4)), np.zeros((4, 4))
    for i in range(4):
        De_e[i, i] += 0.125 * lr * Q
        De_p[i, i] += 0.125 * 0.5 * c0 * s0
        for k in range(4):
            De_e[i, k] += 0.125 * c0 * pm[i] * p1[k]
            De_p[i, k] += 0.125 * (c0 * pm[i] * e1[k] + 2.0 * lr * em[i] * p1[k])
    for a in range(na):
        for i in range(4):
            for k in range(4):
                De_e[i, k] += 0.125 * cu[a] * Ta[a, i] * dsa[a, k]
                De_p[i, k] += 0.125 * cu[a] * (Ta[a, i] * W1[a, k] + 0.5 * sa[a] * EkU[a, i, k])
    dgk = np.zeros((4, 4))
    for i in range(4):
        for k in range(4):
            t = De_e[i, k]
            for j in range(4):
                t += De_p[i, j] * dp[j, k]
            dgk[i, k] = -t
    return p1, -De, dp, dgk, _times(inverse_mass(J4i, e1), p1)


def invariant_terms(J, j0):
    """``(kin, U, cu)`` of :func:`em_terms` for the inertia J (3, 3) and j₀ (module docstring): λ_r a repeated
    eigenvalue of J⁻¹ when there is one (to 1e-12 relative), else the middle one."""
    lam, vec = np.linalg.eigh(np.linalg.inv(np.asarray(J, dtype=float)))
    tol = 1e-12 * float(np.abs(lam).max())
    lr = float(lam[1])
    for a, b in ((0, 1), (1, 2), (0, 2)):
        if abs(lam[a] - lam[b]) <= tol:
            lr = float(lam[a])
    U, cu = np.zeros((3, 4)), np.zeros(3)
    for i in range(3):
        if abs(lam[i] - lr) > tol:
            U[i, 1:] = vec[:, i]
            cu[i] = lam[i] - lr
    return np.array([1.0 / float(j0) - lr, lr]), U, cu


@numba.njit(cache=True)
def newmark_terms(J4, e1, v1, a1):
    """The rotation's Newmark terms at the end of the step: (M(e₁), M(e₁) a₁, ∂(M a₁)/∂e₁, Q_v, ∂Q_v/∂e,
    ∂Q_v/∂v)."""
    M1 = mass(J4, e1)
    f, fe, fv = quadratic_velocity_force(J4, e1, v1)
    return M1, _times(M1, a1), mass_jacobian(J4, e1, a1), f, fe, fv
