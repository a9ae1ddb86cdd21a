r"""Compiled (Numba) arithmetic of the quartic strain energy of a :class:`~skfem_flex.bodies.ModalBody`.

The Green–Lagrange strain energy on a reduced basis is the quartic polynomial of
:class:`~skfem_flex.bodies.modal.stiffening.QuarticEnergy`

.. math::

    V(η) = ½ ηᵀ K η + ½ K^{(3)}_{ijk} η_i η_j η_k + ⅛ K^{(4)}_{ijkl} η_i η_j η_k η_l .

The floating-frame kernels (:mod:`.floating_kernel`) already hold the quadratic part ½ ηᵀKη
(the constant block K, as for every floating-frame body); the functions here add the cubic and
quartic parts: the energy, and the "stress at the mean strain" discrete gradient with its
derivative, the terms of :meth:`QuarticEnergy.discrete_gradient` (η̄ = (η₀ + η₁)/2,
P = (η₀η₀ᵀ + η₁η₁ᵀ)/2, A_mk = K4_mkjl P_jl)::

    g_m    = ½ K3_mjk P_jk + K3_jmk η̄_j η̄_k + ½ A_mk η̄_k
    ∂g/∂η1 = ½ K3_mnk η1_k + ½ (K3_nmk + K3_kmn) η̄_k + ¼ A_mn + ½ B_mn,
    B_mn   = K4_mknl η̄_k η1_l.

The contractions with K4 (m⁴ multiply–adds each) are the cost, so :func:`pack_quartic` folds the
symmetries QuarticEnergy guarantees (K3 in (j, k); K4 in (i, j), in (k, l) and under (ij) ↔ (kl))
into the tensors once: sums over index pairs run over j ≤ l only, A and the symmetric part of B
(contracted with S = (η̄η1ᵀ + η1η̄ᵀ)/2) are computed on m ≤ k, the antisymmetric part of B (with
W = (η̄η1ᵀ − η1η̄ᵀ)/2) on m < n; about 2.5 times fewer operations than the plain sums. The loops
may reorder their sums (``fastmath`` limited to reassociation and fused multiply–add, so that
they vectorize; no assumption about NaN or ∞). :meth:`QuarticEnergy.energy` and
:meth:`QuarticEnergy.discrete_gradient` (numpy) are the reference; the two agree to round-off
(tests/test_modal_kernel.py).
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["pack_quartic", "quartic_work_size", "quartic_energy", "quartic_energy_into", "quartic_discrete_gradient",
           "quartic_discrete_gradient_into"]

_FAST = {"reassoc", "contract"}


def pack_quartic(K3, K4):
    """The arrays of the kernels below from the tensors of a :class:`QuarticEnergy` (numpy, once).

    Index pairs (j, l) with j ≤ l are numbered row-major (``np.triu_indices(m)``: j outer), n_s =
    m(m+1)/2 of them; pairs j < l likewise (``np.triu_indices(m, 1)``), n_w = m(m−1)/2.

    Returns
    -------
    k3p : (m, n_s)    K3_mjl + K3_mlj (j < l), K3_mjj: Σ_jl K3_mjl X_jl for a symmetric X
    k3q : (m, n_s)    K3_jml + K3_lmj (j < l), K3_jmj: Σ_jl K3_jml X_jl for a symmetric X
    k3a : (m², m)     K3_ink at row i m + n
    k3b : (m², m)     K3_nik + K3_kin at row i m + n
    k4a : (n_s, n_s)  K4_mkjl (+ K4_mklj for j < l), rows m ≤ k: A
    k4s : (n_s, n_s)  K4_mknl (+ K4_mlnk for k < l), rows m ≤ n: the symmetric part of B
    k4w : (n_w, n_w)  K4_mknl − K4_mlnk, rows m < n, columns k < l: the antisymmetric part of B
    """
    K3, K4 = np.asarray(K3, dtype=float), np.asarray(K4, dtype=float)
    m = K3.shape[0]
    j, l = np.triu_indices(m)
    off = (j < l).astype(float)
    js, ls = np.triu_indices(m, 1)
    k3p = K3[:, j, l] + off * K3[:, l, j]
    k3q = (K3[j, :, l] + off[:, None] * K3[l, :, j]).T
    k3a = K3.reshape(m * m, m)
    k3b = (K3.transpose(1, 0, 2) + K3.transpose(1, 2, 0)).reshape(m * m, m)
    X = K4[j, l]                                     # (n_s, m, m): K4_mk.. for m ≤ k
    k4a = X[:, j, l] + off * X[:, l, j]
    M2 = K4.transpose(0, 2, 1, 3)                    # M2[m, n, k, l] = K4_mknl
    Y = M2[j, l]
    k4s = Y[:, j, l] + off * Y[:, l, j]
    Z = M2[js, ls]
    k4w = Z[:, js, ls] - Z[:, ls, js]
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (k3p, k3q, k3a, k3b, k4a, k4s, k4w))


@numba.njit(cache=True, _nrt=False)
def quartic_work_size(m):
    """Entries of the ``work`` vector :func:`quartic_energy_into` and :func:`quartic_discrete_gradient_into`
    need for m coordinates."""
    ns, nw = m * (m + 1) // 2, m * (m - 1) // 2
    return 2 * m + 3 * ns + nw + m * m


@numba.njit(cache=True, fastmath=_FAST, _nrt=False)
def quartic_energy_into(k3p, k4a, q, off, work):
    """½ K3_ijk η_i η_j η_k + ⅛ K4_ijkl η_i η_j η_k η_l for η = q[off:], J (the quadratic part is not included);
    its temporaries in ``work`` (:func:`quartic_work_size` entries), nothing allocated."""
    m = k3p.shape[0]
    ns = k4a.shape[0]
    E = work[:ns]                                    # η_j η_l, j ≤ l
    wr = work[ns:2 * ns]                             # 2 off the diagonal: the pairs (j, l) and (l, j)
    p = 0
    for j in range(m):
        for l in range(j, m):
            E[p] = q[off + j] * q[off + l]
            wr[p] = 1.0 if l == j else 2.0
            p += 1
    e3 = 0.0
    for i in range(m):
        s = 0.0
        for p in range(ns):
            s += k3p[i, p] * E[p]
        e3 += q[off + i] * s
    e4 = 0.0
    for r in range(ns):
        s = 0.0
        for p in range(ns):
            s += k4a[r, p] * E[p]
        e4 += wr[r] * E[r] * s
    return 0.5 * e3 + 0.125 * e4


@numba.njit(cache=True, fastmath=_FAST)
def quartic_energy(k3p, k4a, q, off):
    """:func:`quartic_energy_into` with its temporaries allocated here."""
    return quartic_energy_into(k3p, k4a, q, off, np.empty(quartic_work_size(k3p.shape[0])))


@numba.njit(cache=True, fastmath=_FAST, _nrt=False)
def quartic_discrete_gradient_into(k3p, k3q, k3a, k3b, k4a, k4s, k4w, q0, q1, off, g, dg, work):
    """g (m,) and dg = ∂g/∂η1 (m, m) ← the discrete gradient of the cubic and quartic parts (module docstring)
    for η_i = q_i[off:]; its temporaries in ``work`` (:func:`quartic_work_size` entries), nothing allocated.

    The arrays are those of :func:`pack_quartic`."""
    m = k3p.shape[0]
    ns, nw = k4a.shape[0], k4w.shape[0]
    e1 = work[:m]
    em = work[m:2 * m]
    P = work[2 * m:2 * m + ns]          # (η0η0ᵀ + η1η1ᵀ)/2, η̄η̄ᵀ, S on the pairs j ≤ l; W on j < l
    E = work[2 * m + ns:2 * m + 2 * ns]
    S = work[2 * m + 2 * ns:2 * m + 3 * ns]
    W = work[2 * m + 3 * ns:2 * m + 3 * ns + nw]
    A = work[2 * m + 3 * ns + nw:2 * m + 3 * ns + nw + m * m].reshape((m, m))
    for i in range(m):
        e1[i] = q1[off + i]
        em[i] = 0.5 * (q0[off + i] + e1[i])
    p, w = 0, 0
    for j in range(m):
        for l in range(j, m):
            P[p] = 0.5 * (q0[off + j] * q0[off + l] + e1[j] * e1[l])
            E[p] = em[j] * em[l]
            S[p] = 0.5 * (em[j] * e1[l] + e1[j] * em[l])
            if l > j:
                W[w] = 0.5 * (em[j] * e1[l] - e1[j] * em[l])
                w += 1
            p += 1
    r = 0
    for i in range(m):                               # A and ½ B_S, symmetric: rows i ≤ k
        for k in range(i, m):
            sa, sb = 0.0, 0.0
            for p in range(ns):
                sa += k4a[r, p] * P[p]
                sb += k4s[r, p] * S[p]
            A[i, k] = sa
            A[k, i] = sa
            dg[i, k] = 0.5 * sb
            dg[k, i] = 0.5 * sb
            r += 1
    r = 0
    for i in range(m):                               # ½ B_W, antisymmetric: rows i < n
        for n in range(i + 1, m):
            s = 0.0
            for p in range(nw):
                s += k4w[r, p] * W[p]
            dg[i, n] += 0.5 * s
            dg[n, i] -= 0.5 * s
            r += 1
    for i in range(m):
        s3p, s3q, sa = 0.0, 0.0, 0.0
        for p in range(ns):
            s3p += k3p[i, p] * P[p]
            s3q += k3q[i, p] * E[p]
        for k in range(m):
            sa += A[i, k] * em[k]
        g[i] = 0.5 * s3p + s3q + 0.5 * sa
        for n in range(m):
            r = i * m + n
            t = 0.0
            for k in range(m):
                t += k3a[r, k] * e1[k] + k3b[r, k] * em[k]
            dg[i, n] += 0.5 * t + 0.25 * A[i, n]


@numba.njit(cache=True, fastmath=_FAST)
def quartic_discrete_gradient(k3p, k3q, k3a, k3b, k4a, k4s, k4w, q0, q1, off):
    """(g, ∂g/∂η1) of the cubic and quartic parts (module docstring) for η_i = q_i[off:]; (m,), (m, m)
    (:func:`quartic_discrete_gradient_into` with its arrays allocated here).

    The arrays are those of :func:`pack_quartic`."""
    m = k3p.shape[0]
    g = np.empty(m)
    dg = np.empty((m, m))
    quartic_discrete_gradient_into(k3p, k3q, k3a, k3b, k4a, k4s, k4w, q0, q1, off, g, dg,
                                   np.empty(quartic_work_size(m)))
    return g, dg
