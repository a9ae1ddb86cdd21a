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

Nothing here allocates: every function writes into arrays it is given and takes its temporaries from ``tmp``
(a float vector of at least :func:`tmp_size` entries), and all are compiled without numba's reference
counting (``_nrt=False``). Why: a call that allocates, or that unpacks arrays from a tuple under reference
counting, pays an atomic increment and decrement per array (the body's data are a dozen arrays); measured on
the reduced rotating beam of ``examples/benchmark_peers.py``, those, not the arithmetic, were two thirds of a
Newton evaluation.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

__all__ = ["Configuration", "tmp_size", "directors", "contract_into", "configuration", "mass_times", "form_gradient",
           "derivative_times", "add_mass", "add_jacobian", "add_velocity_force_derivative", "add_mass_derivative",
           "add_hessian", "add_elastic_block"]


class Configuration(NamedTuple):
    """What the kinetic terms need of a configuration q (module docstring), written by :func:`configuration`.

    Attributes
    ----------
    D : ndarray (3, 3)
        The directors as columns.
    s : ndarray (3,)
        S₀ + S̄ y, kg m.
    J : ndarray (3, 3)
        I₀ + (P_ij + P_ji)·y + yᵀN_ij y, kg m².
    C : ndarray (3, 3, n_f)
        C_ik = P_ik + N_ikᵀ y.
    gJ : ndarray (3, 3, n_f)
        ∂J_ij/∂y_e.
    """

    D: np.ndarray
    s: np.ndarray
    J: np.ndarray
    C: np.ndarray
    gJ: np.ndarray


@numba.njit(cache=True, _nrt=False)
def tmp_size(nf):
    """Entries of the ``tmp`` vector every function here needs for n_f elastic coordinates."""
    return 12 * nf + 96


@numba.njit(cache=True, _nrt=False, inline="always")
def directors(q, D):
    """D (3, 3) ← the director parts of a coordinate (or velocity) vector as columns.

    Like every function here that writes into its arguments, it returns nothing: a function compiled without
    reference counting must not hand an array back to a caller that counts them (the caller would release
    it once too often)."""
    for k in range(3):
        for c in range(3):
            D[c, k] = q[3 + 3 * k + c]


@numba.njit(cache=True, _nrt=False)
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


@numba.njit(cache=True, _nrt=False)
def configuration(S0, Sbar, I0, P, q, Nq, cf):
    """Write the :class:`Configuration` ``cf`` at q (module docstring); ``Nq`` the contraction of N with q
    (:func:`contract_into`)."""
    nf = Sbar.shape[1]
    D, s, J, C, gJ = cf
    directors(q, D)
    for i in range(3):
        acc = S0[i]
        for e in range(nf):
            acc += Sbar[i, e] * q[12 + e]
        s[i] = acc
        for j in range(3):
            acc = I0[i, j]
            for e in range(nf):
                pij = P[i, j, e] + P[j, i, e]
                acc += (pij + Nq[i, j, e]) * q[12 + e]
                C[i, j, e] = P[i, j, e] + Nq[j, i, e]
                gJ[i, j, e] = pij + Nq[i, j, e] + Nq[j, i, e]
            J[i, j] = acc


@numba.njit(cache=True, _nrt=False, inline="always")
def _sbar_times(Sbar, u, out):
    """out (3,) ← S̄ u_y."""
    nf = Sbar.shape[1]
    for k in range(3):
        acc = 0.0
        for e in range(nf):
            acc += Sbar[k, e] * u[12 + e]
        out[k] = acc


@numba.njit(cache=True, _nrt=False, inline="always")
def _c_times(C, u, out):
    """out (3, 3) ← Σ_e C[i, k, e] u_y,e."""
    nf = C.shape[2]
    for i in range(3):
        for k in range(3):
            acc = 0.0
            for e in range(nf):
                acc += C[i, k, e] * u[12 + e]
            out[i, k] = acc


@numba.njit(cache=True, _nrt=False)
def mass_times(mass, Sbar, cf, b, Nb, out, tmp):
    """out += M(q) b at the configuration ``cf`` (:func:`configuration`), without the matrix; ``Nb`` N applied
    to b (:func:`contract_into`)."""
    nf = Sbar.shape[1]
    D, s, J, C = cf.D, cf.s, cf.J, cf.C
    Bm, Cb, DtD, DtB = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:27].reshape((3, 3)), tmp[27:36].reshape((3, 3))
    Sb, Dtx = tmp[36:39], tmp[39:42]
    directors(b, Bm)
    _c_times(C, b, Cb)
    _sbar_times(Sbar, b, Sb)
    for k in range(3):
        Dtx[k] = D[0, k] * b[0] + D[1, k] * b[1] + D[2, k] * b[2]
        for i in range(3):
            DtD[k, i] = D[0, k] * D[0, i] + D[1, k] * D[1, i] + D[2, k] * D[2, i]
            DtB[k, i] = D[0, k] * Bm[0, i] + D[1, k] * Bm[1, i] + D[2, k] * Bm[2, i]
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


@numba.njit(cache=True, _nrt=False, inline="always")
def _add_elastic_products(oy, scale, x, Sbar, W1, T1, W2, T2, W3, T3):
    """oy += scale (Σ_i x_i S̄_i + Σ_ij (W1_ij T1_ij + W2_ij T2_ij + W3_ij T3_ij)): the elastic rows of a
    product with M's derivatives, three (3, 3, n_f) tensors weighted by 3 × 3 matrices; the inner loops run
    over the contiguous elastic index (they vectorize)."""
    nf = oy.size
    for i in range(3):
        cx = scale * x[i]
        for e in range(nf):
            oy[e] += cx * Sbar[i, e]
        for j in range(3):
            c1, c2, c3 = scale * W1[i, j], scale * W2[i, j], scale * W3[i, j]
            t1, t2, t3 = T1[i, j], T2[i, j], T3[i, j]
            for e in range(nf):
                oy[e] += c1 * t1[e] + c2 * t2[e] + c3 * t3[e]


@numba.njit(cache=True, _nrt=False)
def form_gradient(Sbar, cf, a, Na, b, Nb, scale, out, tmp):
    """out += scale ∇_q aᵀM(q)b = scale B(q, a)ᵀ b at the configuration ``cf``, without the matrix."""
    nf = Sbar.shape[1]
    D, C, gJ = cf.D, cf.C, cf.gJ
    A, Bm, Ca, Cb = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:27].reshape((3, 3)), tmp[27:36].reshape((3, 3))
    alpha = tmp[36:45].reshape((3, 3))                          # a_yᵀ N_kl b_y
    ab, ad, bd = tmp[45:54].reshape((3, 3)), tmp[54:63].reshape((3, 3)), tmp[63:72].reshape((3, 3))      # a_i · b_j, a_i · d_k, b_i · d_k
    Sa, Sb, xb = tmp[72:75], tmp[75:78], tmp[78:81]
    directors(a, A)
    directors(b, Bm)
    _c_times(C, a, Ca)
    _c_times(C, b, Cb)
    _sbar_times(Sbar, a, Sa)
    _sbar_times(Sbar, b, Sb)
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
    for i in range(3):
        xb[i] = 0.0                                # a_x · b_i + a_i · b_x
        for c in range(3):
            xb[i] += a[c] * Bm[c, i] + A[c, i] * b[c]
        for j in range(3):
            ab[i, j] = A[0, i] * Bm[0, j] + A[1, i] * Bm[1, j] + A[2, i] * Bm[2, j]
            ad[i, j] = A[0, i] * D[0, j] + A[1, i] * D[1, j] + A[2, i] * D[2, j]
            bd[i, j] = Bm[0, i] * D[0, j] + Bm[1, i] * D[1, j] + Bm[2, i] * D[2, j]
    _add_elastic_products(out[12:], scale, xb, Sbar, ab, gJ, ad, Nb, bd, Na)


@numba.njit(cache=True, _nrt=False, inline="always")
def _derivative_blocks(Sbar, cf, w, Nw, tmp):
    """The blocks of DM(q)[w] in M's layout (:func:`_add_mass_shaped`): (S̄ w_y, Σ_e gJ w_e, its (x, y) block
    X[c, e], its (d_i, y) blocks Y[c, i, e], the weight WdᵀD + DᵀWd of its elastic block), views of ``tmp``
    (its first 12 n_f + 30 entries)."""
    nf = Sbar.shape[1]
    D, C, gJ = cf.D, cf.C, cf.gJ
    Wd, gJw, Wt = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:27].reshape((3, 3))
    Sw = tmp[27:30]
    directors(w, Wd)
    _sbar_times(Sbar, w, Sw)
    X = tmp[30:30 + 3 * nf].reshape((3, nf))
    Y = tmp[30 + 3 * nf:30 + 12 * nf].reshape((3, 3, nf))
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for e in range(nf):
                acc += gJ[i, j, e] * w[12 + e]
            gJw[i, j] = acc
    for c in range(3):
        for e in range(nf):
            X[c, e] = Wd[c, 0] * Sbar[0, e] + Wd[c, 1] * Sbar[1, e] + Wd[c, 2] * Sbar[2, e]
            for i in range(3):
                acc = 0.0
                for k in range(3):
                    acc += Wd[c, k] * C[i, k, e] + D[c, k] * Nw[k, i, e]
                Y[c, i, e] = acc
    for i in range(3):
        for k in range(3):
            acc = 0.0
            for c in range(3):
                acc += Wd[c, i] * D[c, k] + D[c, i] * Wd[c, k]
            Wt[i, k] = acc
    return Sw, gJw, X, Y, Wt


@numba.njit(cache=True, _nrt=False)
def derivative_times(Sbar, cf, w, Nw, b, Nb, scale, out, tmp):
    """out += scale DM(q)[w] b = scale B(q, b) w at the configuration ``cf``, without the matrix.

    The blocks of DM(q)[w] (:func:`_derivative_blocks`: X = W_d S̄, Y_i = W_d C_iᵀ + D N_iᵀw_y, ...) are never
    formed: their products with b are contracted in the order that needs the fewest operations (S̄b, C b and
    N w_y b first), a third of the work of forming them."""
    nf = Sbar.shape[1]
    D, C, gJ = cf.D, cf.C, cf.gJ
    Wd, Bm, gJw, Wt = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:27].reshape((3, 3)), tmp[27:36].reshape((3, 3))
    Cb, Nwb, WB, DB = tmp[36:45].reshape((3, 3)), tmp[45:54].reshape((3, 3)), tmp[54:63].reshape((3, 3)), tmp[63:72].reshape((3, 3))
    Sw, Sb, Wx = tmp[72:75], tmp[75:78], tmp[78:81]
    directors(w, Wd)
    directors(b, Bm)
    _sbar_times(Sbar, w, Sw)
    _sbar_times(Sbar, b, Sb)
    _c_times(C, b, Cb)
    for i in range(3):
        for j in range(3):
            acc, accn = 0.0, 0.0
            for e in range(nf):
                acc += gJ[i, j, e] * w[12 + e]
                accn += Nw[i, j, e] * b[12 + e]
            gJw[i, j] = acc
            Nwb[i, j] = accn
    for i in range(3):
        Wx[i] = Wd[0, i] * b[0] + Wd[1, i] * b[1] + Wd[2, i] * b[2]
        for k in range(3):
            Wt[i, k] = (Wd[0, i] * D[0, k] + Wd[1, i] * D[1, k] + Wd[2, i] * D[2, k]
                        + D[0, i] * Wd[0, k] + D[1, i] * Wd[1, k] + D[2, i] * Wd[2, k])
            WB[i, k] = Wd[0, k] * Bm[0, i] + Wd[1, k] * Bm[1, i] + Wd[2, k] * Bm[2, i]
            DB[k, i] = D[0, k] * Bm[0, i] + D[1, k] * Bm[1, i] + D[2, k] * Bm[2, i]
    for c in range(3):
        acc = 0.0
        for i in range(3):
            acc += Sw[i] * Bm[c, i] + Wd[c, i] * Sb[i]
        out[c] += scale * acc
        for i in range(3):
            acc = Sw[i] * b[c]
            for j in range(3):
                acc += gJw[i, j] * Bm[c, j] + Wd[c, j] * Cb[i, j] + D[c, j] * Nwb[j, i]
            out[3 + 3 * i + c] += scale * acc
    _add_elastic_products(out[12:], scale, Wx, Sbar, WB, C, DB, Nw, Wt, Nb)


@numba.njit(cache=True, _nrt=False, inline="always")
def _add_pair(out, i, j, c, ct, val):
    """out[i, j] += c val and out[j, i] += ct val."""
    out[i, j] += c * val
    out[j, i] += ct * val


@numba.njit(cache=True, _nrt=False, inline="always")
def _add_director_block(S, c, out):
    """out[(d_i, d_k)] += c S_ik I₃: a 3 × 3 matrix of scalars on the directors' blocks."""
    for i in range(3):
        for k in range(3):
            for cc in range(3):
                out[3 + 3 * i + cc, 3 + 3 * k + cc] += c * S[i, k]


@numba.njit(cache=True, _nrt=False, inline="always")
def _add_director_elastic(Y, c, out):
    """out[(d_i c, y e)] and out[(y e, d_i c)] += c Y[c, i, e]: a symmetric coupling of directors and elastic
    coordinates."""
    for i in range(3):
        for e in range(Y.shape[2]):
            for cc in range(3):
                _add_pair(out, 3 + 3 * i + cc, 12 + e, c, c, Y[cc, i, e])


@numba.njit(cache=True, _nrt=False, inline="always")
def _add_gram(A, B, c, ct, W):
    """W += c AᵀB + ct (AᵀB)ᵀ for two 3 × 3 matrices (an elastic block's weight, module docstring)."""
    for i in range(3):
        for k in range(3):
            t = A[0, i] * B[0, k] + A[1, i] * B[1, k] + A[2, i] * B[2, k]
            W[i, k] += c * t
            W[k, i] += ct * t


@numba.njit(cache=True, _nrt=False)
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


@numba.njit(cache=True, _nrt=False)
def add_mass(mass, Sbar, cf, c, out, W, tmp):
    """c M(q) at the configuration ``cf``."""
    nf = Sbar.shape[1]
    D, C = cf.D, cf.C
    DtD = tmp[0:9].reshape((3, 3))
    X = tmp[9:9 + 3 * nf].reshape((3, nf))
    Y = tmp[9 + 3 * nf:9 + 12 * nf].reshape((3, 3, nf))
    for cc in range(3):
        for e in range(nf):
            X[cc, e] = D[cc, 0] * Sbar[0, e] + D[cc, 1] * Sbar[1, e] + D[cc, 2] * Sbar[2, e]
            for i in range(3):
                Y[cc, i, e] = D[cc, 0] * C[i, 0, e] + D[cc, 1] * C[i, 1, e] + D[cc, 2] * C[i, 2, e]
    for i in range(3):
        for k in range(3):
            DtD[i, k] = D[0, i] * D[0, k] + D[1, i] * D[1, k] + D[2, i] * D[2, k]
    _add_mass_shaped(mass[0], cf.s, cf.J, X, Y, DtD, c, out, W)


@numba.njit(cache=True, _nrt=False)
def add_jacobian(Sbar, cf, a, Na, cb, ct, out, W, tmp):
    """cb B(q, a) + ct B(q, a)ᵀ at the configuration ``cf``, B(q, a) = ∂(M(q)a)/∂q; ``Na`` N applied to a."""
    nf = Sbar.shape[1]
    D, C, gJ = cf.D, cf.C, cf.gJ
    A, Wa, Sa = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:21]
    directors(a, A)
    _c_times(C, a, Wa)
    _sbar_times(Sbar, a, Sa)
    for cc in range(3):
        for k in range(3):
            _add_pair(out, cc, 3 + 3 * k + cc, cb, ct, Sa[k])
            for i in range(3):
                _add_pair(out, 3 + 3 * i + cc, 3 + 3 * k + cc, cb, ct, Wa[i, k])
        for e in range(nf):
            acc = A[cc, 0] * Sbar[0, e] + A[cc, 1] * Sbar[1, e] + A[cc, 2] * Sbar[2, e]
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


@numba.njit(cache=True, _nrt=False)
def add_velocity_force_derivative(v, Nv, c, out, tmp):
    """c ∂Q_v/∂q = c (½ H(v, v) − (B(v, v) − B(0, v))) (``kinetics`` docstring). Of the two terms only a
    coupling of directors and elastic coordinates is left: their director blocks (½ S_H = α, α_ik = v_yᵀN_ik v_y,
    symmetric since N_ik = N_kiᵀ) and elastic blocks (weights VᵀV) cancel, and
    ∂Q_v/∂q [(d_k c, y e)] = ∂Q_v/∂q [(y e, d_k c)] = −2 Σ_j V_cj (N_kj v_y)_e."""
    nf = Nv.shape[2]
    V = tmp[0:9].reshape((3, 3))
    directors(v, V)
    Y = tmp[9:9 + 9 * nf].reshape((3, 3, nf))
    for k in range(3):
        for e in range(nf):
            for cc in range(3):
                Y[cc, k, e] = -2.0 * (V[cc, 0] * Nv[k, 0, e] + V[cc, 1] * Nv[k, 1, e] + V[cc, 2] * Nv[k, 2, e])
    _add_director_elastic(Y, c, out)


@numba.njit(cache=True, _nrt=False)
def add_mass_derivative(Sbar, cf, w, Nw, c, out, W, tmp):
    """c DM(q)[w] = c Σ_k w_k ∂M/∂q_k at the configuration ``cf`` (M is quadratic: exact)."""
    Sw, gJw, X, Y, Wt = _derivative_blocks(Sbar, cf, w, Nw, tmp)
    _add_mass_shaped(0.0, Sw, gJw, X, Y, Wt, c, out, W)


@numba.njit(cache=True, _nrt=False)
def add_hessian(a, Na, b, Nb, c, out, W, tmp):
    """c H(a, b) = c ∇²_q aᵀM(q)b (constant in q)."""
    nf = Na.shape[2]
    A, Bm, S = tmp[0:9].reshape((3, 3)), tmp[9:18].reshape((3, 3)), tmp[18:27].reshape((3, 3))
    directors(a, A)
    directors(b, Bm)
    for k in range(3):
        for ell in range(3):
            acc = 0.0
            for e in range(nf):
                acc += (Na[k, ell, e] + Na[ell, k, e]) * b[12 + e]
            S[k, ell] = acc
    _add_director_block(S, c, out)
    Y = tmp[27:27 + 9 * nf].reshape((3, 3, nf))
    for k in range(3):
        for e in range(nf):
            for cc in range(3):
                acc = 0.0
                for i in range(3):
                    acc += A[cc, i] * Nb[i, k, e] + Bm[cc, i] * Na[i, k, e]
                Y[cc, k, e] = acc
    _add_director_elastic(Y, c, out)
    _add_gram(A, Bm, c, c, W)


@numba.njit(cache=True, _nrt=False)
def add_elastic_block(N, W, out):
    """out[y, y] += Σ_ik W_ik N_ik: the elastic blocks of every term added with ``W`` (module docstring); ``N``
    raveled, (9 n_f²,)."""
    nf = out.shape[0] - 12
    N3 = N.reshape((9, nf, nf))
    for r in range(9):
        w = W[r // 3, r % 3]
        if w != 0.0:
            for a in range(nf):
                for b in range(nf):
                    out[12 + a, 12 + b] += w * N3[r, a, b]
