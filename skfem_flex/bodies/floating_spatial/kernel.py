r"""Compiled arithmetic of a spatial floating-frame body: :func:`body_terms` (a step's momentum, forces and
Newton block), the strain energy and gravity, and M(q), B(q, a), H(a, b) one at a time (for tests).

These are the compiled twins of ``kinetics.py`` (through :mod:`.kinetic_kernel`), the strain objects
(``strain.py``, ``solid.py``) and
:meth:`FloatingFrame3D.gravity_potential <skfem_flex.bodies.floating_spatial.frame.FloatingFrame3D.gravity_potential>`,
held to them at round-off by ``tests/test_family_spatial_floating_frame.py``: the same equations written as
loops, for the compiled core (:mod:`skfem_flex.compiled.families.spatial_floating_frame`), which calls
:func:`body_terms` once per Newton evaluation. The coordinates are q = (x, d₁, d₂, d₃, y);
D[c, k] = q[3 + 3k + c].

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
from .kinetic_kernel import (add_elastic_block, add_hessian, add_jacobian, add_mass, add_velocity_force_derivative,
                             add_mass_derivative, configuration, contract_into, derivative_times, directors,
                             form_gradient, mass_times)

__all__ = ["SpatialFrameKernelData", "QuarticTerms", "SpatialBodyData",
           "kernel_data", "mass_matrix", "momentum_jacobian", "kinetic_hessian", "quadratic_velocity_terms",
           "strain_energy", "strain_terms", "gravity_terms", "body_terms", "STATE", "EM", "NEWMARK", "MOMENTUM", "ENERGY"]

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
    Nt : ndarray (n_f, 9 n_f)
        N with its last index first, Nt[b, (i, k, a)] = N_ikab: the order of the contraction with a vector, whose
        inner loop then runs over 9 n_f contiguous entries.
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
    Nt: np.ndarray


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
    Nsym = 0.5 * (N + N.transpose(1, 0, 3, 2))
    frame = SpatialFrameKernelData(
        np.array([float(inertia.mass)]), np.ascontiguousarray(inertia.S0, dtype=float),
        np.ascontiguousarray(Sbar), np.ascontiguousarray(inertia.I0, dtype=float),
        np.ascontiguousarray(inertia.P, dtype=float).reshape(3, 3, nf),
        np.ascontiguousarray(Nsym).ravel(), np.ascontiguousarray(K),
        np.array([1 if green else 0], dtype=np.int64), A, w, np.asarray(gravity, dtype=float).reshape(3).copy(),
        np.ascontiguousarray(Nsym.reshape(9 * nf, nf).T))
    return SpatialBodyData(frame, QuarticTerms(np.array([0 if quartic is None else 1], dtype=np.int64),
                                               *quartic_arrays))


@numba.njit(cache=True)
def _contract(kd, u):
    """N applied to the elastic part of u, a new (3, 3, n_f) array (:func:`.kinetic_kernel.contract_into`)."""
    out = np.empty((3, 3, kd.Sbar.shape[1]))
    contract_into(kd.Nt, u, out)
    return out


@numba.njit(cache=True)
def _configuration(kd, q, Nq=None):
    """(D, s, J, C, gJ) at q (:func:`.kinetic_kernel.configuration`); ``Nq`` N applied to q, formed here when
    not given."""
    if Nq is None:
        Nq = _contract(kd, q)
    return configuration(kd.S0, kd.Sbar, kd.I0, kd.P, q, Nq)


@numba.njit(cache=True)
def _has_gravity(kd):
    """False when no gravity field acts on the body (its terms are zero and are skipped)."""
    return kd.g[0] != 0.0 or kd.g[1] != 0.0 or kd.g[2] != 0.0


@numba.njit(cache=True)
def _square(kd):
    """(zero (n, n) matrix, zero 3 × 3 weight of its elastic block)."""
    n = 12 + kd.Sbar.shape[1]
    return np.zeros((n, n)), np.zeros((3, 3))


@numba.njit(cache=True)
def mass_matrix(kd, q):
    """M(q), (12 + n_f) × (12 + n_f), kg (``kinetics.mass_matrix``)."""
    out, W = _square(kd)
    D, s, J, C, _ = _configuration(kd, q)
    add_mass(kd.mass, kd.Sbar, D, s, J, C, 1.0, out, W)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def momentum_jacobian(kd, q, a):
    """B(q, a) = ∂(M(q) a)/∂q (``kinetics.momentum_jacobian``)."""
    out, W = _square(kd)
    D, _, _, C, gJ = _configuration(kd, q)
    add_jacobian(kd.Sbar, D, C, gJ, a, _contract(kd, a), 1.0, 0.0, out, W)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def kinetic_hessian(kd, a, b):
    """H(a, b) = ∇²_q aᵀM(q)b, constant in q (``kinetics.kinetic_hessian``)."""
    out, W = _square(kd)
    add_hessian(a, _contract(kd, a), b, _contract(kd, b), 1.0, out, W)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def quadratic_velocity_terms(kd, q, v):
    """(Q_v, ∂Q_v/∂q, ∂Q_v/∂v) (``kinetics.quadratic_velocity_force``): the products and matrices
    :func:`body_terms` forms for the Newmark family, one at a time."""
    n = 12 + kd.Sbar.shape[1]
    Nv = _contract(kd, v)
    D, _, _, C, gJ = _configuration(kd, q)
    f = np.zeros(n)
    form_gradient(kd.Sbar, D, C, gJ, v, Nv, v, Nv, 0.5, f)
    derivative_times(kd.Sbar, D, C, gJ, v, Nv, v, Nv, -1.0, f)
    fq, _ = _square(kd)
    add_velocity_force_derivative(v, Nv, 1.0, fq)
    fv, Wv = _square(kd)
    add_jacobian(kd.Sbar, D, C, gJ, v, Nv, -1.0, 1.0, fv, Wv)
    add_mass_derivative(kd.Sbar, D, C, gJ, v, Nv, -1.0, fv, Wv)
    add_elastic_block(kd.N, Wv, fv)
    return f, fq, fv


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
def strain_energy(kd, qt, y):
    """V(y), J: ½ yᵀK y plus the quartic terms (``qt``) or the Green–Lagrange axis ½ Σ w ε² (module
    docstring)."""
    nf = kd.K.shape[0]
    energy = 0.0
    for a in range(nf):
        acc = 0.0
        for b in range(nf):
            acc += kd.K[a, b] * y[b]
        energy += 0.5 * y[a] * acc
    if qt.quartic[0] != 0:
        energy += quartic_energy(qt.k3p, qt.k4a, y, 0)
    elif kd.green[0] != 0:
        e = _axial(kd, y)[1]
        for p in range(e.size):
            energy += 0.5 * kd.w[p] * e[p] * e[p]
    return energy


@numba.njit(cache=True)
def strain_terms(kd, qt, y0, y1):
    """(V(y1), g, ∂g/∂y1): the strain energy at y1 and its exact discrete gradient from y0 to y1 (at y0 = y1:
    the gradient and half the Hessian), ``SpatialBeamStrain.discrete_gradient`` / ``QuadraticEnergy`` /
    ``SolidGreenLagrange.discrete_gradient``; ``qt`` the body's :class:`QuarticTerms`."""
    nf = kd.K.shape[0]
    g = np.zeros(nf)
    jac = np.empty((nf, nf))
    energy = strain_energy(kd, qt, y1)
    for a in range(nf):
        for b in range(nf):
            kab = kd.K[a, b]
            g[a] += 0.5 * kab * (y0[b] + y1[b])
            jac[a, b] = 0.5 * kab
    if qt.quartic[0] != 0:
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
    D = directors(q)
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
def body_terms(kd, qt, mode, q0, q1, v0, v1, a1, qa, qb, weights, residual):
    r"""Every part of one body's residual and its Newton block, as the compiled core's tasks ask them
    (:mod:`skfem_flex.compiled.tasks`); the one compiled entry of the body's arithmetic.

    ``kd`` and ``qt``: the body's :class:`SpatialFrameKernelData` and :class:`QuarticTerms`; ``weights``: the
    task's (w_p, w_gk, dq1, dv1, da1) (:mod:`skfem_flex.compiled.tasks`; dv1 the same for every coordinate of
    the body: it has no angle coordinate). ``mode`` :data:`EM` (energy–momentum): p = M(q₁)v₁,
    g_k = ½B(q_m, v₀)ᵀv₁ (the exact discrete gradient of ½v₀ᵀM(q)v₁), and the kinetic block

    .. math::

        K = w_p (dq_1 B(q_1, v_1) + dv_1 M(q_1)) + w_{gk} (\tfrac14 dq_1 H(v_0, v_1)
            + \tfrac12 dv_1 B(q_m, v_0)^T) .

    :data:`NEWMARK`: p = M(q₁)a₁, g_k = Q_v(q₁, v₁) = ½B(q₁, v₁)ᵀv₁ − B(q₁, v₁)v₁ and

    .. math::

        K = w_p (dq_1 B(q_1, a_1) + da_1 M(q_1)) + w_{gk} \big(dq_1 [\tfrac12 H(v, v) − (B(v, v) − B(0, v))]
            + dv_1 [B(q_1, v)^T − B(q_1, v) − DM(q_1)[v]]\big) ,

    with v = v₁ (``kinetics`` docstring). Both: g_p the discrete gradient of strain and gravity from q_a to
    q_b and ∂g_p/∂q_b. :data:`STATE`: only p = M(q₁)v₁ and V (g_k zero, no matrices); :data:`MOMENTUM`
    only p, :data:`ENERGY` only V (its vectors empty).

    ``residual``: K is not formed (it comes back (0, 0)): an evaluation whose matrix is not used
    (:mod:`skfem_flex.compiled.loop`).

    Returns
    -------
    p, gk, gp : ndarray (n,)
    M1 : ndarray (n, n)
        M(q₁) under :data:`NEWMARK` (its round-off scale needs the entries), else (0, 0).
    K, dgp_dq : ndarray (n, n)
        The kinetic block above ((0, 0) with ``residual`` and for the other modes) and ∂g_p/∂q_b.
    V : float
        Strain energy at q_b plus gravity's potential at (q_a + q_b)/2, J (the potential energy at q₁ when
        q_a = q_b = q₁).
    """
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    none = np.zeros((0, 0))
    qk = np.empty(n)
    if mode == ENERGY:                               # V alone: no mass matrix, the vectors empty
        V = strain_energy(kd, qt, qb[12:])
        if _has_gravity(kd):
            for i in range(n):
                qk[i] = 0.5 * (qa[i] + qb[i])
            V += gravity_terms(kd, qk)[0]
        empty = np.zeros(0)
        return empty, empty, empty, none, none, none, V
    p = np.zeros(n)
    gk = np.zeros(n)
    w_p, w_gk, dq1, dv1, da1 = weights[0], weights[1], weights[2], weights[3], weights[4]
    Nq1, Nv1 = _contract(kd, q1), _contract(kd, v1)
    D1, s1, J1, C1, gJ1 = _configuration(kd, q1, Nq1)
    Sbar = kd.Sbar
    K, W = none, np.zeros((3, 3))
    M1 = none
    if mode == NEWMARK:
        M1, Wm = _square(kd)
        add_mass(kd.mass, Sbar, D1, s1, J1, C1, 1.0, M1, Wm)
        add_elastic_block(kd.N, Wm, M1)
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += M1[i, j] * a1[j]
            p[i] = s
        form_gradient(Sbar, D1, C1, gJ1, v1, Nv1, v1, Nv1, 0.5, gk)
        derivative_times(Sbar, D1, C1, gJ1, v1, Nv1, v1, Nv1, -1.0, gk)
        if not residual:
            # B(q₁, ·) is linear in its vector: w_p dq1 B(q₁, a₁) − w_gk dv1 B(q₁, v₁) in one pass
            ct, cq = w_gk * dv1, w_gk * dq1
            Na1 = _contract(kd, a1)
            at = np.empty(n)
            for i in range(n):
                at[i] = w_p * dq1 * a1[i] - ct * v1[i]
            Nat = np.empty((3, 3, nf))
            for i in range(3):
                for k in range(3):
                    for e in range(nf):
                        Nat[i, k, e] = w_p * dq1 * Na1[i, k, e] - ct * Nv1[i, k, e]
            K, W = _square(kd)
            for i in range(n):
                for j in range(n):
                    K[i, j] = w_p * da1 * M1[i, j]
            add_jacobian(Sbar, D1, C1, gJ1, at, Nat, 1.0, 0.0, K, W)
            add_jacobian(Sbar, D1, C1, gJ1, v1, Nv1, 0.0, ct, K, W)
            add_mass_derivative(Sbar, D1, C1, gJ1, v1, Nv1, -ct, K, W)
            add_velocity_force_derivative(v1, Nv1, cq, K)
    else:
        mass_times(kd.mass, Sbar, D1, s1, J1, C1, v1, Nv1, p)
        if mode == EM:
            qm = np.empty(n)
            for i in range(n):
                qm[i] = 0.5 * (q0[i] + q1[i])
            Nv0 = _contract(kd, v0)
            Dm, _, _, Cm, gJm = _configuration(kd, qm)
            form_gradient(Sbar, Dm, Cm, gJm, v0, Nv0, v1, Nv1, 0.5, gk)
            if not residual:
                K, W = _square(kd)
                add_mass(kd.mass, Sbar, D1, s1, J1, C1, w_p * dv1, K, W)
                add_jacobian(Sbar, D1, C1, gJ1, v1, Nv1, w_p * dq1, 0.0, K, W)
                add_hessian(v0, Nv0, v1, Nv1, 0.25 * w_gk * dq1, K, W)
                add_jacobian(Sbar, Dm, Cm, gJm, v0, Nv0, 0.0, 0.5 * w_gk * dv1, K, W)
    if mode == MOMENTUM:                             # p alone: no strain or gravity
        return p, gk, np.zeros(n), M1, none, none, 0.0
    if K.size:
        add_elastic_block(kd.N, W, K)
    # strain and gravity: discrete gradients from q_a to q_b
    gp = np.zeros(n)
    dgp_dq = np.zeros((n, n))
    vg = 0.0
    if _has_gravity(kd):
        for i in range(n):
            qk[i] = 0.5 * (qa[i] + qb[i])
        vg, grad, Hg = gravity_terms(kd, qk)
        for i in range(n):
            gp[i] = grad[i]
            for j in range(n):
                dgp_dq[i, j] = 0.5 * Hg[i, j]
    vs, gs, js = strain_terms(kd, qt, qa[12:], qb[12:])
    for a in range(nf):
        gp[12 + a] += gs[a]
        for b in range(nf):
            dgp_dq[12 + a, 12 + b] += js[a, b]
    return p, gk, gp, M1, K, dgp_dq, vs + vg
