r"""Compiled arithmetic of a spatial floating-frame body: M(q), B(q, a), H(a, b), the strain energy and gravity.

These are the compiled twins of ``kinetics.py``, the strain objects (``strain.py``, ``solid.py``) and
:meth:`FloatingFrame3D.gravity_potential <skfem_flex.bodies.floating_spatial.frame.FloatingFrame3D.gravity_potential>`,
held to them at round-off by ``tests/test_family_spatial_floating_frame.py``: the same equations written as
loops, for the compiled core (:mod:`skfem_flex.compiled.families.spatial_floating_frame`), which calls them
once per Newton evaluation. The coordinates are q = (x, d₁, d₂, d₃, y); D[c, k] = q[3 + 3k + c].

The strain energy is V = ½ yᵀK y + ½ Σ_q w_q ε_q² with the Green–Lagrange axis ε = u₃' + ½|u'|²,
u'_k = A_k y (a beam with ``green``), or V = ½ yᵀK y + ½ K3_ijk y_i y_j y_k + ⅛ K4_ijkl y_i y_j y_k y_l (a
meshed solid's Green–Lagrange energy, with ``quartic``: the tensors of ``SolidGreenLagrange.quartic``, folded
by :func:`~skfem_flex.bodies.modal.kernel.pack_quartic` and evaluated by that module's kernels, which the
planar reduced body uses too), or V = ½ yᵀK y (linear strain: a beam's or a meshed solid's). Its
discrete gradient is the stress at the mean strain (exact), gravity's the mid-point gradient (exact:
V_g = −g·(m x + D(S₀ + S̄ y)) is quadratic).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..modal.kernel import quartic_discrete_gradient, quartic_energy

__all__ = ["SpatialFrameKernelData", "QuarticTerms", "SpatialBodyData",
           "kernel_data", "mass_matrix", "momentum_jacobian", "kinetic_hessian",
           "strain_terms", "gravity_terms", "body_terms", "STATE", "EM", "NEWMARK", "MOMENTUM", "ENERGY"]

#: what :func:`body_terms` evaluates: the state's momentum and potential energy, the energy–momentum step's
#: terms, the Newmark family's
STATE, EM, NEWMARK = 0, 1, 2
#: :data:`STATE`'s two halves, for the recording tasks that need one: p = M(q₁)v₁ alone, V alone
MOMENTUM, ENERGY = 3, 4


class SpatialFrameKernelData(NamedTuple):
    """The arrays of one body, in the order the compiled family packs them.

    Attributes
    ----------
    mass : ndarray (1,)
        m, kg.
    S0 : ndarray (3,)
        First moment of mass in the frame's axes, kg m.
    Sbar : ndarray (3, n_f)
        Its change per elastic coordinate.
    I0 : ndarray (3, 3)
        ∫ρ X₀X₀ᵀ (the second moment, not the inertia tensor), kg m².
    P : ndarray (3, 3, n_f)
        ∫ρ X₀,i S_k (bilinear invariants).
    N : ndarray (9 n_f²,)
        ∫ρ S_iᵀ S_k, (3, 3, n_f, n_f) raveled; the kernel needs it exactly symmetric, N_ikab = N_kiba
        (:func:`kernel_data` makes it so).
    K : ndarray (n_f, n_f)
        The strain energy's constant quadratic part, N/m (or per unit of y).
    green : ndarray (1,) of int
        1: add the Green–Lagrange axis ½ Σ w ε²; 0: V = ½ yᵀK y.
    A : ndarray (3, n_points, n_f)
        u'_k = A_k y at the Gauss points (empty without ``green``).
    w : ndarray (n_points,)
        EA times the quadrature weight, N m.
    g : ndarray (3,)
        The gravity field acting on the body, m/s² (zero: none).
    """

    mass: np.ndarray
    S0: np.ndarray
    Sbar: np.ndarray
    I0: np.ndarray
    P: np.ndarray
    N: np.ndarray
    K: np.ndarray
    green: np.ndarray
    A: np.ndarray
    w: np.ndarray
    g: np.ndarray


class QuarticTerms(NamedTuple):
    """The cubic and quartic terms of a body's strain energy (a Green–Lagrange solid), apart from
    :class:`SpatialFrameKernelData`, which the kinetic functions take: only :func:`strain_terms` reads them.

    Attributes
    ----------
    quartic : ndarray (1,) of int
        1: add the cubic and quartic terms of the arrays below; 0: they are empty.
    k3p, k3q, k3a, k3b, k4a, k4s, k4w : ndarray (2-D)
        The cubic and quartic tensors as :func:`~skfem_flex.bodies.modal.kernel.pack_quartic` folds them,
        N/m² and N/m³ (y in m).
    """

    quartic: np.ndarray
    k3p: np.ndarray
    k3q: np.ndarray
    k3a: np.ndarray
    k3b: np.ndarray
    k4a: np.ndarray
    k4s: np.ndarray
    k4w: np.ndarray


class SpatialBodyData(NamedTuple):
    """All the compiled core needs of one body: its frame data and its strain energy's quartic terms."""

    frame: SpatialFrameKernelData
    quartic: QuarticTerms


def kernel_data(inertia, K, A=None, w=None, quartic=None, gravity=(0.0, 0.0, 0.0)):
    """The kernel's arrays of one body (:class:`SpatialBodyData`).

    Parameters
    ----------
    inertia : SpatialFrameInertia
        The invariants on the body's n_f elastic coordinates (:mod:`.inertia`).
    K : array_like (n_f, n_f)
        The strain energy's constant quadratic part (N/m or per unit of the coordinates).
    A, w : array_like (3, n_points, n_f) and (n_points,), optional
        Both or neither: the Green–Lagrange axis's rows u'_k = A_k y and its weights EA dx (N m).
    quartic : tuple of seven arrays, optional
        The cubic and quartic terms of a quartic energy on y, as
        :func:`~skfem_flex.bodies.modal.kernel.pack_quartic` returns them (not with A and w).
    gravity : array_like (3,)
        The gravity field on the body, m/s².

    Raises
    ------
    ValueError
        Arrays of the wrong shapes, only one of A and w, or the quartic terms with them.
    """
    Sbar = np.asarray(inertia.Sbar, dtype=float)
    nf = Sbar.shape[1] if Sbar.ndim == 2 and Sbar.shape[0] == 3 else -1
    K = np.asarray(K, dtype=float)
    if nf < 0 or K.shape != (nf, nf) or np.size(inertia.N) != 9 * nf * nf or np.size(inertia.P) != 9 * nf:
        raise ValueError(f"the invariants and K must be on one set of elastic coordinates: S̄ {Sbar.shape}, "
                         f"K {K.shape}, N of size {np.size(inertia.N)}, P of size {np.size(inertia.P)}")
    if (A is None) != (w is None):
        raise ValueError("the Green–Lagrange axis needs both its rows A and its weights w, or neither")
    # N_ikab = N_kiba (∫ρ S_iᵀS_k); the kernel's contractions rely on it, so it is made exact here
    N = np.asarray(inertia.N, dtype=float).reshape(3, 3, nf, nf)
    green = A is not None
    A = np.zeros((3, 0, nf)) if A is None else np.ascontiguousarray(A, dtype=float)
    w = np.zeros(0) if w is None else np.ascontiguousarray(w, dtype=float)
    if A.ndim != 3 or A.shape[0] != 3 or A.shape[2] != nf or w.shape != (A.shape[1],):
        raise ValueError(f"A must be (3, n_points, {nf}) and w (n_points,), got {A.shape} and {w.shape}")
    if quartic is None:
        quartic_arrays = (np.zeros((0, 0)),) * 7
    else:
        if green:
            raise ValueError("a body has either the Green–Lagrange axis (A, w) or the quartic terms, not both")
        ns, nw = nf * (nf + 1) // 2, nf * (nf - 1) // 2
        shapes = [(nf, ns), (nf, ns), (nf * nf, nf), (nf * nf, nf), (ns, ns), (ns, ns), (nw, nw)]
        quartic_arrays = tuple(np.ascontiguousarray(a, dtype=float) for a in quartic)
        if [a.shape for a in quartic_arrays] != shapes:
            raise ValueError(f"the quartic terms on {nf} elastic coordinates must have the shapes {shapes}, "
                             f"got {[a.shape for a in quartic_arrays]}")
    frame = SpatialFrameKernelData(
        np.array([float(inertia.mass)]), np.ascontiguousarray(inertia.S0, dtype=float),
        np.ascontiguousarray(Sbar), np.ascontiguousarray(inertia.I0, dtype=float),
        np.ascontiguousarray(inertia.P, dtype=float).reshape(3, 3, nf),
        np.ascontiguousarray(0.5 * (N + N.transpose(1, 0, 3, 2))).ravel(), np.ascontiguousarray(K),
        np.array([1 if green else 0], dtype=np.int64), A, w, np.asarray(gravity, dtype=float).reshape(3).copy())
    return SpatialBodyData(frame, QuarticTerms(np.array([0 if quartic is None else 1], dtype=np.int64),
                                               *quartic_arrays))


@numba.njit(cache=True)
def _gram(A, B):
    """Aᵀ B of two 3 × 3 matrices."""
    out = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = A[0, i] * B[0, j] + A[1, i] * B[1, j] + A[2, i] * B[2, j]
    return out


@numba.njit(cache=True)
def _amax(x):
    out = 0.0
    for v in x:
        out = max(out, abs(v))
    return out


@numba.njit(cache=True)
def _directors(q):
    D = np.empty((3, 3))
    for k in range(3):
        for c in range(3):
            D[c, k] = q[3 + 3 * k + c]
    return D


@numba.njit(cache=True)
def _contract_into(kd, q, out):
    """out[i, k, a] = Σ_b N_ikab y_b (y = q[12:]). As N_ikab = N_kiba, Σ_b N_ikba y_b = out[k, i, a]: one
    contraction (over the contiguous last index) serves both."""
    nf = kd.Sbar.shape[1]
    N = kd.N.reshape(9 * nf, nf)
    flat = out.reshape(9 * nf)
    for r in range(9 * nf):
        acc = 0.0
        for b in range(nf):
            acc += N[r, b] * q[12 + b]
        flat[r] = acc


@numba.njit(cache=True)
def _contract(kd, q):
    """:func:`_contract_into` into a new array (3, 3, n_f)."""
    out = np.zeros((3, 3, kd.Sbar.shape[1]))
    _contract_into(kd, q, out)
    return out


@numba.njit(cache=True)
def _add_weighted(kd, W, out, scale, transpose):
    """out[12 + a, 12 + b] += scale Σ_ik W_ik N_ikab (N_ikba with ``transpose``); loops, no slices: numba's
    slice assignment costs seconds of compile."""
    nf = kd.Sbar.shape[1]
    N = kd.N.reshape(9, nf, nf)
    for r in range(9):
        w = scale * W[r // 3, r % 3]
        if w != 0.0:
            for a in range(nf):
                for b in range(nf):
                    out[12 + a, 12 + b] += w * (N[r, b, a] if transpose else N[r, a, b])


@numba.njit(cache=True)
def _configuration(kd, q, Ny):
    """s (3,), J (3, 3), C (3, 3, n_f) at the elastic coordinates of q (``kinetics._configuration``); Ny the
    contraction of N with them (:func:`_contract`)."""
    nf = kd.Sbar.shape[1]
    y = q[12:]
    s = kd.S0.copy()
    J = kd.I0.copy()
    C = kd.P.copy()
    for i in range(3):
        for a in range(nf):
            s[i] += kd.Sbar[i, a] * y[a]
        for j in range(3):
            acc = 0.0
            for a in range(nf):
                acc += (kd.P[i, j, a] + kd.P[j, i, a] + Ny[i, j, a]) * y[a]
                C[i, j, a] += Ny[j, i, a]
            J[i, j] += acc
    return s, J, C


@numba.njit(cache=True)
def _mass(kd, q, Ny):
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    D = _directors(q)
    s, J, C = _configuration(kd, q, Ny)
    M = np.zeros((n, n))
    for c in range(3):
        M[c, c] = kd.mass[0]
        for i in range(3):
            M[c, 3 + 3 * i + c] = s[i]
            M[3 + 3 * i + c, c] = s[i]
            for j in range(3):
                M[3 + 3 * i + c, 3 + 3 * j + c] = J[i, j]
        for ell in range(nf):
            acc = 0.0
            for k in range(3):
                acc += D[c, k] * kd.Sbar[k, ell]
            M[c, 12 + ell] = acc
            M[12 + ell, c] = acc
            for i in range(3):
                acc = 0.0
                for k in range(3):
                    acc += D[c, k] * C[i, k, ell]
                M[3 + 3 * i + c, 12 + ell] = acc
                M[12 + ell, 3 + 3 * i + c] = acc
    _add_weighted(kd, _gram(D, D), M, 1.0, False)
    return M


@numba.njit(cache=True)
def mass_matrix(kd, q):
    """M(q), (12 + n_f) × (12 + n_f), kg (``kinetics.mass_matrix``)."""
    return _mass(kd, q, _contract(kd, q))


@numba.njit(cache=True)
def _jacobian(kd, q, a, Ny, Na):
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    D = _directors(q)
    A = _directors(a)
    _, _, C = _configuration(kd, q, Ny)
    ay = a[12:]
    Wa = np.zeros((3, 3))
    Sa = np.zeros(3)
    for i in range(3):
        for ell in range(nf):
            Sa[i] += kd.Sbar[i, ell] * ay[ell]
        for k in range(3):
            for ell in range(nf):
                Wa[i, k] += C[i, k, ell] * ay[ell]
    B = np.zeros((n, n))
    for c in range(3):
        for ell in range(nf):
            acc = 0.0
            for k in range(3):
                acc += A[c, k] * kd.Sbar[k, ell]
            B[c, 12 + ell] = acc
        for i in range(3):
            B[c, 3 + 3 * i + c] = Sa[i]
            for k in range(3):
                B[3 + 3 * i + c, 3 + 3 * k + c] = Wa[i, k]
    for i in range(3):
        for c in range(3):
            for ell in range(nf):
                acc = a[c] * kd.Sbar[i, ell]
                for j in range(3):
                    # ∂J_ij/∂y_l = P_ijl + P_jil + Σ_b (N_ijlb + N_ijbl) y_b
                    gj = kd.P[i, j, ell] + kd.P[j, i, ell] + Ny[i, j, ell] + Ny[j, i, ell]
                    acc += A[c, j] * gj + D[c, j] * Na[i, j, ell]
                B[3 + 3 * i + c, 12 + ell] = acc
    for k in range(3):
        for c in range(3):
            for ell in range(nf):
                acc = kd.Sbar[k, ell] * a[c]
                for i in range(3):
                    acc += C[i, k, ell] * A[c, i] + (Na[k, i, ell] + Na[i, k, ell]) * D[c, i]
                B[12 + ell, 3 + 3 * k + c] = acc
    _add_weighted(kd, _gram(A, D), B, 1.0, True)
    return B


@numba.njit(cache=True)
def momentum_jacobian(kd, q, a):
    """B(q, a) = ∂(M(q) a)/∂q (``kinetics.momentum_jacobian``)."""
    return _jacobian(kd, q, a, _contract(kd, q), _contract(kd, a))


@numba.njit(cache=True)
def _hessian(kd, a, b, Na, Nb):
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    A = _directors(a)
    Bv = _directors(b)
    by = b[12:]
    alpha = np.zeros((3, 3))
    for i in range(3):
        for k in range(3):
            for e in range(nf):
                alpha[i, k] += Na[i, k, e] * by[e]
    H = np.zeros((n, n))
    for k in range(3):
        for ell in range(3):
            val = alpha[k, ell] + alpha[ell, k]
            for c in range(3):
                H[3 + 3 * k + c, 3 + 3 * ell + c] = val
        for c in range(3):
            for e in range(nf):
                acc = 0.0
                for i in range(3):
                    acc += A[c, i] * Nb[i, k, e] + Bv[c, i] * Na[i, k, e]
                H[3 + 3 * k + c, 12 + e] = acc
                H[12 + e, 3 + 3 * k + c] = acc
    T = _gram(A, Bv)
    _add_weighted(kd, T, H, 1.0, False)
    _add_weighted(kd, T, H, 1.0, True)
    return H


@numba.njit(cache=True)
def kinetic_hessian(kd, a, b):
    """H(a, b) = ∇²_q aᵀM(q)b, constant in q (``kinetics.kinetic_hessian``)."""
    return _hessian(kd, a, b, _contract(kd, a), _contract(kd, b))


@numba.njit(cache=True)
def _axial(kd, y):
    """(u' (3, n_points), ε (n_points,)) of the Green–Lagrange axis."""
    npts, nf = kd.A.shape[1], kd.A.shape[2]
    up = np.zeros((3, npts))
    eps = np.zeros(npts)
    for k in range(3):
        for p in range(npts):
            acc = 0.0
            for a in range(nf):
                acc += kd.A[k, p, a] * y[a]
            up[k, p] = acc
    for p in range(npts):
        eps[p] = up[2, p] + 0.5 * (up[0, p] ** 2 + up[1, p] ** 2 + up[2, p] ** 2)
    return up, eps


@numba.njit(cache=True)
def strain_terms(kd, qt, y0, y1):
    """(V(y1), g, ∂g/∂y1): the strain energy at y1 and its exact discrete gradient from y0 to y1 (at y0 = y1:
    the gradient and half the Hessian), ``SpatialBeamStrain.discrete_gradient`` / ``QuadraticEnergy`` /
    ``SolidGreenLagrange.discrete_gradient``; ``qt`` the body's :class:`QuarticTerms`."""
    nf = kd.K.shape[0]
    g = np.zeros(nf)
    jac = np.empty((nf, nf))
    energy = 0.0
    for a in range(nf):
        for b in range(nf):
            kab = kd.K[a, b]
            g[a] += 0.5 * kab * (y0[b] + y1[b])
            jac[a, b] = 0.5 * kab
            energy += 0.5 * y1[a] * kab * y1[b]
    if qt.quartic[0] != 0:
        energy += quartic_energy(qt.k3p, qt.k4a, y1, 0)
        g4, dg4 = quartic_discrete_gradient(qt.k3p, qt.k3q, qt.k3a, qt.k3b, qt.k4a, qt.k4s, qt.k4w, y0, y1, 0)
        for a in range(nf):
            g[a] += g4[a]
            for b in range(nf):
                jac[a, b] += dg4[a, b]
        return energy, g, jac
    if kd.green[0] == 0:
        return energy, g, jac
    npts = kd.A.shape[1]
    up0, e0 = _axial(kd, y0)
    up1, e1 = _axial(kd, y1)
    bm = np.empty(nf)
    b1 = np.empty(nf)
    for p in range(npts):
        w = kd.w[p]
        energy += 0.5 * w * e1[p] * e1[p]
        t = w * 0.5 * (e0[p] + e1[p])
        for a in range(nf):
            bm[a] = kd.A[2, p, a]
            b1[a] = kd.A[2, p, a]
            for k in range(3):
                bm[a] += 0.5 * (up0[k, p] + up1[k, p]) * kd.A[k, p, a]
                b1[a] += up1[k, p] * kd.A[k, p, a]
        for a in range(nf):
            g[a] += bm[a] * t
            for b in range(nf):
                curv = 0.0
                for k in range(3):
                    curv += kd.A[k, p, a] * kd.A[k, p, b]
                jac[a, b] += 0.5 * w * bm[a] * b1[b] + 0.5 * t * curv
    return energy, g, jac


@numba.njit(cache=True)
def gravity_terms(kd, q):
    """(V_g(q), ∇V_g(q), ∇²V_g) of V_g = −g·(m x + D(S₀ + S̄ y)) (``FloatingFrame3D.gravity_potential``)."""
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    g = kd.g
    D = _directors(q)
    s = kd.S0.copy()
    for i in range(3):
        for a in range(nf):
            s[i] += kd.Sbar[i, a] * q[12 + a]
    grad = np.zeros(n)
    H = np.zeros((n, n))
    energy = 0.0
    for c in range(3):
        grad[c] = -kd.mass[0] * g[c]
        energy -= g[c] * (kd.mass[0] * q[c] + D[c, 0] * s[0] + D[c, 1] * s[1] + D[c, 2] * s[2])
        for i in range(3):
            grad[3 + 3 * i + c] = -s[i] * g[c]
            for a in range(nf):
                H[3 + 3 * i + c, 12 + a] = -g[c] * kd.Sbar[i, a]
                H[12 + a, 3 + 3 * i + c] = -g[c] * kd.Sbar[i, a]
    for a in range(nf):
        acc = 0.0
        for i in range(3):
            acc += kd.Sbar[i, a] * (D[0, i] * g[0] + D[1, i] * g[1] + D[2, i] * g[2])
        grad[12 + a] = -acc
    return energy, grad, H


@numba.njit(cache=True)
def body_terms(kd, qt, mode, q0, q1, v0, v1, a1, qa, qb, residual=False):
    r"""Every part of one body's residual and its derivatives, as the compiled core's tasks ask them
    (:mod:`skfem_flex.compiled.tasks`); the one compiled entry of the body's arithmetic.

    ``kd`` and ``qt``: the body's :class:`SpatialFrameKernelData` and :class:`QuarticTerms`. ``mode`` :data:`EM`
    (energy–momentum): p = M(q₁)v₁ with ∂p/∂q₁ = B(q₁, v₁), ∂p/∂v₁ = M(q₁);
    g_k = ½B(q_m, v₀)ᵀv₁ (the exact discrete gradient of ½v₀ᵀM(q)v₁) with ∂/∂q₁ = ¼H(v₀, v₁),
    ∂/∂v₁ = ½B(q_m, v₀)ᵀ. :data:`NEWMARK`: p = M(q₁)a₁ with ∂p/∂q₁ = B(q₁, a₁), ∂p/∂a₁ = M(q₁);
    g_k = Q_v(q₁, v₁) = ½Bᵀv − Bv with ∂/∂q₁ = ½H(v, v) − (B(v, v) − B(0, v)), ∂/∂v₁ = Bᵀ − B − DM(q₁)[v₁]
    (DM exact as the central difference of the quadratic M). Both: g_p the discrete gradient of strain and
    gravity from q_a to q_b and ∂g_p/∂q_b. :data:`STATE`: only p = M(q₁)v₁ and V (the rest zero);
    :data:`MOMENTUM` only p, :data:`ENERGY` only V.

    ``residual``: only p, g_k, g_p, M(q₁) and ∂g_p/∂q_b (which the round-off floor reads) are formed; the
    kinetic derivatives come back zero (an evaluation whose matrix is not used, :mod:`skfem_flex.compiled.loop`).

    Returns
    -------
    p, gk, gp : ndarray (n,)
    M1, dp_dq, dgk_dq, dgk_dv, dgp_dq : ndarray (n, n)
        M(q₁) (the derivative of p with respect to v₁ or a₁) and the other derivatives.
    V : float
        Strain energy at q_b plus gravity's potential at (q_a + q_b)/2, J (the potential energy at q₁ when
        q_a = q_b = q₁).
    """
    em = mode == EM
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    if mode == ENERGY:                               # V alone: no mass matrix
        none = np.zeros((n, n))
        qk = np.empty(n)
        for i in range(n):
            qk[i] = 0.5 * (qa[i] + qb[i])
        return (np.zeros(n), np.zeros(n), np.zeros(n), none, none, none, none, none,
                strain_terms(kd, qt, qa[12:], qb[12:])[0] + gravity_terms(kd, qk)[0])
    # plain loops throughout: numba's array expressions and slice assignments cost seconds of compile each
    T = np.zeros((3, n, n))                          # ∂p/∂q₁, ∂g_k/∂v₁, ∂g_k/∂q₁
    p = np.zeros(n)
    gk = np.zeros(n)
    # the vectors the terms need (rows of X) and their contractions with N (linear: combined, not recomputed)
    X = np.zeros((5, n))
    Ns = np.zeros((5, 3, 3, nf))
    if mode == NEWMARK:                              # q₁, v₁, a₁, 0
        nx = 3
        for i in range(n):
            X[0, i], X[1, i], X[2, i] = q1[i], v1[i], a1[i]
    else:                                            # q₁, v₁, q_m, v₀
        nx = 4 if mode == EM else 1
        for i in range(n):
            X[0, i], X[1, i], X[2, i], X[3, i] = q1[i], v1[i], 0.5 * (q0[i] + q1[i]), v0[i]
    for k in range(nx):
        _contract_into(kd, X[k], Ns[k])
    # the B(q, a) the scheme needs: rows of X, and (target, coefficient of B, of Bᵀ, of Bᵀv₁, of B v₁ in g_k)
    nj = 0 if mode == STATE or mode == MOMENTUM else (2 if em else 4)
    for k in range(nj):
        if em:
            iq, ia, target, cb, cbt, gt, gb = (0, 1, 0, 1.0, 0.0, 0.0, 0.0) if k == 0 else (2, 3, 1, 0.0, 0.5, 0.5, 0.0)
        elif k == 0:
            iq, ia, target, cb, cbt, gt, gb = 0, 2, 0, 1.0, 0.0, 0.0, 0.0
        elif k == 1:
            iq, ia, target, cb, cbt, gt, gb = 0, 1, 1, -1.0, 1.0, 0.5, -1.0
        else:
            iq, ia, target, cb, cbt, gt, gb = (1 if k == 2 else 4), 1, 2, (-1.0 if k == 2 else 1.0), 0.0, 0.0, 0.0
        if residual and gt == 0.0 and gb == 0.0:
            continue                                 # a derivative only
        B = _jacobian(kd, X[iq], X[ia], Ns[iq], Ns[ia])
        for i in range(n):
            for j in range(n):
                T[target, i, j] += cb * B[i, j] + cbt * B[j, i]
        if gt != 0.0 or gb != 0.0:
            for i in range(n):
                for j in range(n):
                    gk[j] += gt * B[i, j] * v1[i]
                    gk[i] += gb * B[i, j] * v1[j]
    # M(q₁) and, for DM(q₁)[v₁] (exact: M is quadratic), M(q₁ ± h v₁)
    wn = _amax(v1) if mode == NEWMARK and not residual else 0.0
    h = max(_amax(q1), 1.0) / wn if wn > 0.0 else 0.0
    M1 = _mass(kd, q1, Ns[0])
    qk = np.empty(n)
    if wn > 0.0:
        Nk = np.empty((3, 3, nf))
        for sign in (1.0, -1.0):
            for i in range(n):
                qk[i] = q1[i] + sign * h * v1[i]
            for i in range(3):
                for j in range(3):
                    for a in range(nf):
                        Nk[i, j, a] = Ns[0, i, j, a] + sign * h * Ns[1, i, j, a]
            Mk = _mass(kd, qk, Nk)
            c = -sign / (2.0 * h)
            for i in range(n):
                for j in range(n):
                    T[1, i, j] += c * Mk[i, j]
    acc = a1 if mode == NEWMARK else v1
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += M1[i, j] * acc[j]
        p[i] = s
    if mode == MOMENTUM:                             # p alone: no strain or gravity
        none = np.zeros((n, n))
        return p, gk, np.zeros(n), M1, none, none, none, none, 0.0
    if mode != STATE and not residual:
        ia = 3 if em else 1                          # H(v₀, v₁) or H(v₁, v₁)
        H = _hessian(kd, X[ia], X[1], Ns[ia], Ns[1])
        ch = 0.25 if em else 0.5
        for i in range(n):
            for j in range(n):
                T[2, i, j] += ch * H[i, j]
    # strain and gravity: discrete gradients from q_a to q_b
    for i in range(n):
        qk[i] = 0.5 * (qa[i] + qb[i])
    vg, gp, Hg = gravity_terms(kd, qk)
    dgp_dq = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            dgp_dq[i, j] = 0.5 * Hg[i, j]
    vs, gs, js = strain_terms(kd, qt, qa[12:], qb[12:])
    for a in range(nf):
        gp[12 + a] += gs[a]
        for b in range(nf):
            dgp_dq[12 + a, 12 + b] += js[a, b]
    return p, gk, gp, M1, T[0], T[2], T[1], dgp_dq, vs + vg
