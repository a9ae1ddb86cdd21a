r"""Compiled kinetic terms of a spatial floating-frame body: M(q) and its derivatives, as products with vectors
and as one weighted matrix.

The compiled twin of ``kinetics.py`` (held to it at round-off by ``tests/test_family_spatial_floating_frame.py``).
The coordinates are q = (x, d₁, d₂, d₃, y); D[c, k] = q[3 + 3k + c] (the directors as columns), and for any
vector a of the same layout a_x, A (its director parts as columns) and a_y. With the invariants of
``inertia.py`` and s = S₀ + S̄y, J_ij = I₀,ij + (P_ij + P_ji)·y + yᵀN_ij y, C_ik = P_ik + N_ikᵀ y (as (3, 3, n_f)
arrays C[i, k, e]) and their y-derivative gJ[i, j, e] = ∂J_ij/∂y_e, the kinetic bilinear form is

.. math::

    a^T M(q)\, b = m\, a_x\!\cdot b_x + \sum_i s_i (a_x\!\cdot b_i + a_i\!\cdot b_x)
      + a_x\!\cdot D\bar S b_y + b_x\!\cdot D\bar S a_y + \sum_{ij} J_{ij}\, a_i\!\cdot b_j
      + \sum_{ik} \big[(a_i\!\cdot d_k)\, c_{ik}\!\cdot b_y + (b_i\!\cdot d_k)\, c_{ik}\!\cdot a_y\big]
      + \sum_{kl} (d_k\!\cdot d_l)\, a_y^T N_{kl}\, b_y .

Why a module of its own, and why these shapes: a Newton step of a reduced body needs M(q₁), B(q, a) =
∂(M(q)a)/∂q, its transpose, DM(q)[w] and H(a, b) = ∇²_q aᵀM(q)b, each once and each only inside one weighted
sum. Every one of them has an elastic block (y, y) of the form Σ_ik W_ik N_ik, N_ik = ∫ρ S_iᵀS_k (n_f × n_f):
the blocks are gathered as one 3 × 3 weight W and contracted with N once (:func:`add_elastic_block`), the
costliest loop of the body, instead of once per term. B is linear in its vector argument, so terms at the same
configuration share one pass (B(q, c₁a + c₂b)); the other blocks are written straight into the sum. The
residual needs only products with vectors (:func:`mass_times`, :func:`form_gradient`, :func:`derivative_times`),
which are formed without any matrix.

Every ``add_*`` function adds ``c`` times its term to ``out`` outside the elastic block and ``c`` times the
term's weight to ``W``; :func:`add_elastic_block` then adds Σ_ik W_ik N_ik once.
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["directors", "contract_into", "configuration", "mass_times", "form_gradient", "derivative_times",
           "add_mass", "add_jacobian", "add_velocity_force_derivative", "add_mass_derivative", "add_hessian",
           "add_elastic_block"]


@numba.njit(cache=True, inline="always")
def directors(q):
    """D (3, 3), the director parts of a coordinate (or velocity) vector as columns."""
    D = np.empty((3, 3))
    for k in range(3):
        for c in range(3):
            D[c, k] = q[3 + 3 * k + c]
    return D


@numba.njit(cache=True)
def contract_into(Nt, u, out):
    """out[i, k, e] = Σ_f N_ikef u_f with u_f = u[12 + f]: N_ik applied to the elastic part of u."""
    nf = Nt.shape[0]
    flat = out.reshape(9 * nf)
    for r in range(9 * nf):
        flat[r] = 0.0
    for b in range(nf):
        ub = u[12 + b]
        if ub != 0.0:
            for r in range(9 * nf):
                flat[r] += Nt[b, r] * ub


@numba.njit(cache=True)
def configuration(S0, Sbar, I0, P, q, Nq):
    """(D, s, J, C, gJ) at q (module docstring); ``Nq`` the contraction of N with q (:func:`contract_into`)."""
    nf = Sbar.shape[1]
    D = directors(q)
    s = S0.copy()
    J = I0.copy()
    C = np.empty((3, 3, nf))
    gJ = np.empty((3, 3, nf))
    for i in range(3):
        for e in range(nf):
            s[i] += Sbar[i, e] * q[12 + e]
        for j in range(3):
            acc = 0.0
            for e in range(nf):
                pij = P[i, j, e] + P[j, i, e]
                acc += (pij + Nq[i, j, e]) * q[12 + e]
                C[i, j, e] = P[i, j, e] + Nq[j, i, e]
                gJ[i, j, e] = pij + Nq[i, j, e] + Nq[j, i, e]
            J[i, j] += acc
    return D, s, J, C, gJ


@numba.njit(cache=True, inline="always")
def _sbar_times(Sbar, u):
    """S̄ u_y (3,)."""
    nf = Sbar.shape[1]
    out = np.zeros(3)
    for k in range(3):
        for e in range(nf):
            out[k] += Sbar[k, e] * u[12 + e]
    return out


@numba.njit(cache=True, inline="always")
def _c_times(C, u):
    """Σ_e C[i, k, e] u_y,e (3, 3)."""
    nf = C.shape[2]
    out = np.zeros((3, 3))
    for i in range(3):
        for k in range(3):
            acc = 0.0
            for e in range(nf):
                acc += C[i, k, e] * u[12 + e]
            out[i, k] = acc
    return out


@numba.njit(cache=True)
def mass_times(mass, Sbar, D, s, J, C, b, Nb, out):
    """out += M(q) b at the configuration (D, s, J, C) (:func:`configuration`), without the matrix; ``Nb`` N
    applied to b (:func:`contract_into`)."""
    nf = Sbar.shape[1]
    Bm = directors(b)
    Sb = _sbar_times(Sbar, b)
    Cb = _c_times(C, b)
    DtD = np.zeros((3, 3))
    DtB = np.zeros((3, 3))
    Dtx = np.zeros(3)
    for k in range(3):
        for c in range(3):
            Dtx[k] += D[c, k] * b[c]
            for i in range(3):
                DtD[k, i] += D[c, k] * D[c, i]
                DtB[k, i] += D[c, k] * Bm[c, i]
    for c in range(3):
        acc = mass[0] * b[c]
        for i in range(3):
            acc += s[i] * Bm[c, i] + D[c, i] * Sb[i]
        out[c] += acc
        for i in range(3):
            acc = s[i] * b[c]
            for j in range(3):
                acc += J[i, j] * Bm[c, j] + D[c, j] * Cb[i, j]
            out[3 + 3 * i + c] += acc
    for e in range(nf):
        acc = 0.0
        for k in range(3):
            acc += Sbar[k, e] * Dtx[k]
            for i in range(3):
                acc += C[i, k, e] * DtB[k, i] + DtD[i, k] * Nb[i, k, e]
        out[12 + e] += acc


@numba.njit(cache=True)
def form_gradient(Sbar, D, C, gJ, a, Na, b, Nb, scale, out):
    """out += scale ∇_q aᵀM(q)b = scale B(q, a)ᵀ b at the configuration (D, C, gJ), without the matrix."""
    nf = Sbar.shape[1]
    A, Bm = directors(a), directors(b)
    Sa, Sb = _sbar_times(Sbar, a), _sbar_times(Sbar, b)
    Ca, Cb = _c_times(C, a), _c_times(C, b)
    alpha = np.zeros((3, 3))                       # a_yᵀ N_kl b_y
    for k in range(3):
        for ell in range(3):
            acc = 0.0
            for e in range(nf):
                acc += a[12 + e] * Nb[k, ell, e]
            alpha[k, ell] = acc
    for k in range(3):
        for c in range(3):
            acc = a[c] * Sb[k] + b[c] * Sa[k]
            for i in range(3):
                acc += A[c, i] * Cb[i, k] + Bm[c, i] * Ca[i, k] + D[c, i] * (alpha[k, i] + alpha[i, k])
            out[3 + 3 * k + c] += scale * acc
    ab = np.zeros((3, 3))                          # a_i · b_j
    ad = np.zeros((3, 3))                          # a_i · d_k
    bd = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for c in range(3):
                ab[i, j] += A[c, i] * Bm[c, j]
                ad[i, j] += A[c, i] * D[c, j]
                bd[i, j] += Bm[c, i] * D[c, j]
    xb = np.zeros(3)                               # a_x · b_i + a_i · b_x
    for i in range(3):
        for c in range(3):
            xb[i] += a[c] * Bm[c, i] + A[c, i] * b[c]
    for e in range(nf):
        acc = 0.0
        for i in range(3):
            acc += Sbar[i, e] * xb[i]
            for j in range(3):
                acc += gJ[i, j, e] * ab[i, j] + ad[i, j] * Nb[i, j, e] + bd[i, j] * Na[i, j, e]
        out[12 + e] += scale * acc


@numba.njit(cache=True)
def _derivative_blocks(Sbar, D, C, gJ, w, Nw):
    """The blocks of DM(q)[w] in M's layout (:func:`_add_mass_shaped`): (S̄ w_y, Σ_e gJ w_e, its (x, y) block
    X[c, e], its (d_i, y) blocks Y[c, i, e], the weight WdᵀD + DᵀWd of its elastic block)."""
    nf = Sbar.shape[1]
    Wd = directors(w)
    Sw = _sbar_times(Sbar, w)
    gJw = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for e in range(nf):
                gJw[i, j] += gJ[i, j, e] * w[12 + e]
    X = np.zeros((3, nf))
    Y = np.zeros((3, 3, nf))
    for c in range(3):
        for e in range(nf):
            acc = 0.0
            for k in range(3):
                acc += Wd[c, k] * Sbar[k, e]
            X[c, e] = acc
            for i in range(3):
                acc = 0.0
                for k in range(3):
                    acc += Wd[c, k] * C[i, k, e] + D[c, k] * Nw[k, i, e]
                Y[c, i, e] = acc
    Wt = np.zeros((3, 3))
    for i in range(3):
        for k in range(3):
            for c in range(3):
                Wt[i, k] += Wd[c, i] * D[c, k] + D[c, i] * Wd[c, k]
    return Sw, gJw, X, Y, Wt


@numba.njit(cache=True)
def derivative_times(Sbar, D, C, gJ, w, Nw, b, Nb, scale, out):
    """out += scale DM(q)[w] b = scale B(q, b) w at the configuration (D, C, gJ), without the matrix."""
    nf = Sbar.shape[1]
    Bm = directors(b)
    Sw, gJw, X, Y, Wt = _derivative_blocks(Sbar, D, C, gJ, w, Nw)
    for c in range(3):
        acc = 0.0
        for i in range(3):
            acc += Sw[i] * Bm[c, i]
        for e in range(nf):
            acc += X[c, e] * b[12 + e]
        out[c] += scale * acc
        for i in range(3):
            acc = Sw[i] * b[c]
            for j in range(3):
                acc += gJw[i, j] * Bm[c, j]
            for e in range(nf):
                acc += Y[c, i, e] * b[12 + e]
            out[3 + 3 * i + c] += scale * acc
    for e in range(nf):
        acc = 0.0
        for c in range(3):
            acc += X[c, e] * b[c]
            for i in range(3):
                acc += Y[c, i, e] * Bm[c, i]
        for i in range(3):
            for k in range(3):
                acc += Wt[i, k] * Nb[i, k, e]
        out[12 + e] += scale * acc


@numba.njit(cache=True, inline="always")
def _add_pair(out, i, j, c, ct, val):
    """out[i, j] += c val and out[j, i] += ct val."""
    out[i, j] += c * val
    out[j, i] += ct * val


@numba.njit(cache=True, inline="always")
def _add_director_block(S, c, out):
    """out[(d_i, d_k)] += c S_ik I₃: a 3 × 3 matrix of scalars on the directors' blocks."""
    for i in range(3):
        for k in range(3):
            for cc in range(3):
                out[3 + 3 * i + cc, 3 + 3 * k + cc] += c * S[i, k]


@numba.njit(cache=True, inline="always")
def _add_director_elastic(Y, c, out):
    """out[(d_i c, y e)] and out[(y e, d_i c)] += c Y[c, i, e]: a symmetric coupling of directors and elastic
    coordinates."""
    for i in range(3):
        for e in range(Y.shape[2]):
            for cc in range(3):
                _add_pair(out, 3 + 3 * i + cc, 12 + e, c, c, Y[cc, i, e])


@numba.njit(cache=True, inline="always")
def _add_gram(A, B, c, ct, W):
    """W += c AᵀB + ct (AᵀB)ᵀ for two 3 × 3 matrices (an elastic block's weight, module docstring)."""
    for i in range(3):
        for k in range(3):
            t = A[0, i] * B[0, k] + A[1, i] * B[1, k] + A[2, i] * B[2, k]
            W[i, k] += c * t
            W[k, i] += ct * t


@numba.njit(cache=True)
def _add_mass_shaped(mass, s, J, X, Y, Wyy, c, out, W):
    """c times a matrix laid out as M(q) (module docstring), from its blocks: mass I on (x, x), s_i I on
    (x, d_i), J_ij I on (d_i, d_j), X on (x, y), Y[:, i] on (d_i, y), each with its transpose, and the weight
    Wyy of its elastic block (into W)."""
    nf = X.shape[1]
    _add_director_block(J, c, out)
    for cc in range(3):
        out[cc, cc] += c * mass
        for i in range(3):
            _add_pair(out, cc, 3 + 3 * i + cc, c, c, s[i])
        for e in range(nf):
            _add_pair(out, cc, 12 + e, c, c, X[cc, e])
    _add_director_elastic(Y, c, out)
    for i in range(3):
        for k in range(3):
            W[i, k] += c * Wyy[i, k]


@numba.njit(cache=True)
def add_mass(mass, Sbar, D, s, J, C, c, out, W):
    """c M(q) at the configuration (D, s, J, C)."""
    nf = Sbar.shape[1]
    X = np.zeros((3, nf))
    Y = np.zeros((3, 3, nf))
    DtD = np.zeros((3, 3))
    for cc in range(3):
        for e in range(nf):
            for k in range(3):
                X[cc, e] += D[cc, k] * Sbar[k, e]
                for i in range(3):
                    Y[cc, i, e] += D[cc, k] * C[i, k, e]
        for i in range(3):
            for k in range(3):
                DtD[i, k] += D[cc, i] * D[cc, k]
    _add_mass_shaped(mass[0], s, J, X, Y, DtD, c, out, W)


@numba.njit(cache=True)
def add_jacobian(Sbar, D, C, gJ, a, Na, cb, ct, out, W):
    """cb B(q, a) + ct B(q, a)ᵀ at the configuration (D, C, gJ), B(q, a) = ∂(M(q)a)/∂q; ``Na`` N applied to
    a."""
    nf = Sbar.shape[1]
    A = directors(a)
    Sa = _sbar_times(Sbar, a)
    Wa = _c_times(C, a)
    for cc in range(3):
        for k in range(3):
            _add_pair(out, cc, 3 + 3 * k + cc, cb, ct, Sa[k])
            for i in range(3):
                _add_pair(out, 3 + 3 * i + cc, 3 + 3 * k + cc, cb, ct, Wa[i, k])
        for e in range(nf):
            acc = 0.0
            for k in range(3):
                acc += A[cc, k] * Sbar[k, e]
            _add_pair(out, cc, 12 + e, cb, ct, acc)
    for i in range(3):
        for e in range(nf):
            for cc in range(3):
                # (d_i c, y e): a_x S̄ + A ∂J_i/∂y + D N_i a_y ; (y e, d_i c): S̄ a_x + C A + (N a)(D)
                row = a[cc] * Sbar[i, e]
                col = row
                for j in range(3):
                    row += A[cc, j] * gJ[i, j, e] + D[cc, j] * Na[i, j, e]
                    col += C[j, i, e] * A[cc, j] + (Na[i, j, e] + Na[j, i, e]) * D[cc, j]
                _add_pair(out, 3 + 3 * i + cc, 12 + e, cb, ct, row)
                _add_pair(out, 12 + e, 3 + 3 * i + cc, cb, ct, col)
    _add_gram(D, A, cb, ct, W)


@numba.njit(cache=True)
def add_velocity_force_derivative(v, Nv, c, out):
    """c ∂Q_v/∂q = c (½ H(v, v) − (B(v, v) − B(0, v))) (``kinetics`` docstring). Of the two terms only a
    coupling of directors and elastic coordinates is left: their director blocks (½ S_H = α, α_ik = v_yᵀN_ik v_y,
    symmetric since N_ik = N_kiᵀ) and elastic blocks (weights VᵀV) cancel, and
    ∂Q_v/∂q [(d_k c, y e)] = ∂Q_v/∂q [(y e, d_k c)] = −2 Σ_j V_cj (N_kj v_y)_e."""
    nf = Nv.shape[2]
    V = directors(v)
    Y = np.zeros((3, 3, nf))
    for k in range(3):
        for e in range(nf):
            for cc in range(3):
                for j in range(3):
                    Y[cc, k, e] -= 2.0 * V[cc, j] * Nv[k, j, e]
    _add_director_elastic(Y, c, out)


@numba.njit(cache=True)
def add_mass_derivative(Sbar, D, C, gJ, w, Nw, c, out, W):
    """c DM(q)[w] = c Σ_k w_k ∂M/∂q_k at the configuration (D, C, gJ) (M is quadratic: exact)."""
    Sw, gJw, X, Y, Wt = _derivative_blocks(Sbar, D, C, gJ, w, Nw)
    _add_mass_shaped(0.0, Sw, gJw, X, Y, Wt, c, out, W)


@numba.njit(cache=True)
def add_hessian(a, Na, b, Nb, c, out, W):
    """c H(a, b) = c ∇²_q aᵀM(q)b (constant in q)."""
    nf = Na.shape[2]
    A, Bm = directors(a), directors(b)
    S = np.zeros((3, 3))
    for k in range(3):
        for ell in range(3):
            for e in range(nf):
                S[k, ell] += (Na[k, ell, e] + Na[ell, k, e]) * b[12 + e]
    _add_director_block(S, c, out)
    Y = np.zeros((3, 3, nf))
    for k in range(3):
        for e in range(nf):
            for cc in range(3):
                for i in range(3):
                    Y[cc, k, e] += A[cc, i] * Nb[i, k, e] + Bm[cc, i] * Na[i, k, e]
    _add_director_elastic(Y, c, out)
    _add_gram(A, Bm, c, c, W)


@numba.njit(cache=True)
def add_elastic_block(N, W, out):
    """out[y, y] += Σ_ik W_ik N_ik: the elastic blocks of every term added with ``W`` (module docstring); ``N``
    raveled, (9 n_f²,)."""
    nf = out.shape[0] - 12
    N3 = N.reshape(9, nf, nf)
    for r in range(9):
        w = W[r // 3, r % 3]
        if w != 0.0:
            for a in range(nf):
                for b in range(nf):
                    out[12 + a, 12 + b] += w * N3[r, a, b]
