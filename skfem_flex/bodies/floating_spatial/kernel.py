r"""Compiled arithmetic of a spatial floating-frame body: :func:`body_terms_into` (a step's momentum, forces and
Newton block, into the body's :class:`BodyWork`), and M(q), B(q, a), H(a, b) one at a time (for tests).

These are the compiled twins of ``kinetics.py`` (through :mod:`.kinetic_kernel`), the strain objects
(``strain.py``, ``solid.py``) and
:meth:`FloatingFrame3D.gravity_potential <skfem_flex.bodies.floating_spatial.frame.FloatingFrame3D.gravity_potential>`
(through :mod:`.potential_kernel`), held to them at round-off by ``tests/test_family_spatial_floating_frame.py``:
the same equations written as loops, for the compiled core (:mod:`skfem_flex.compiled.families.spatial_floating_frame`),
which calls :func:`body_terms_into` once per Newton evaluation. The coordinates are q = (x, d₁, d₂, d₃, y);
D[c, k] = q[3 + 3k + c].

:func:`body_terms_into` allocates nothing and is compiled without reference counting: its results and
temporaries live in a :class:`BodyWork` made once per body (:func:`body_work`) and packed with the body's data
(:mod:`.kinetic_kernel` says why). :func:`body_terms` is the same with a new work, its results returned.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from .kinetic_kernel import (Configuration, add_elastic_block, add_hessian, add_jacobian, add_mass,
                             add_mass_derivative, add_velocity_force_derivative, configuration, contract_into,
                             derivative_times, form_gradient, mass_times, tmp_size)
from .potential_kernel import (gravity_into, gravity_terms, has_gravity, strain_energy, strain_energy_into,
                               strain_terms, strain_terms_into, strain_work_size)

__all__ = ["SpatialFrameKernelData", "QuarticTerms", "SpatialBodyData", "BodyWork", "kernel_data", "body_work",
           "mass_matrix", "momentum_jacobian", "kinetic_hessian", "quadratic_velocity_terms", "strain_energy",
           "strain_terms", "gravity_terms", "body_terms", "body_terms_into", "STATE", "EM", "NEWMARK", "MOMENTUM",
           "ENERGY"]

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


class BodyWork(NamedTuple):
    """The arrays one body's evaluation writes (its results and temporaries), made once by :func:`body_work` and
    packed with the body's data, so that :func:`body_terms_into` allocates nothing (:mod:`.kinetic_kernel`
    says why).

    Attributes
    ----------
    p, gk, gp : ndarray (n,)
        Results: momentum (or M(q₁)a₁), kinetic and potential discrete gradients.
    M1, block, dgp : ndarray (n, n)
        Results: M(q₁) (Newmark), the weighted kinetic block K, ∂g_p/∂q_b.
    Nu : ndarray (4, 9, n_f)
        N applied to up to four vectors of a step.
    D, s, J, C, gJ : ndarray (2, ...)
        Two :class:`~.kinetic_kernel.Configuration` s (at q₁ and at the mid-point).
    vec : ndarray (2, n)
        Two coordinate vectors (the mid-point, the combined vector of B).
    W : ndarray (2, 3, 3)
        Weights of elastic blocks.
    weights : ndarray (5,)
        The task's weights (w_p, w_gk, dq₁, dv₁, da₁), written by the caller.
    tmp : ndarray
        The kinetic functions' temporaries (:func:`~.kinetic_kernel.tmp_size`).
    strain : ndarray
        The strain energy's temporaries (:func:`strain_work_size`).
    """

    p: np.ndarray
    gk: np.ndarray
    gp: np.ndarray
    M1: np.ndarray
    block: np.ndarray
    dgp: np.ndarray
    Nu: np.ndarray
    D: np.ndarray
    s: np.ndarray
    J: np.ndarray
    C: np.ndarray
    gJ: np.ndarray
    vec: np.ndarray
    W: np.ndarray
    weights: np.ndarray
    tmp: np.ndarray
    strain: np.ndarray


def body_work(kd, qt):
    """Zeroed :class:`BodyWork` for the body of ``kd`` (:class:`SpatialFrameKernelData`) and ``qt``
    (:class:`QuarticTerms`)."""
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    z = np.zeros
    return BodyWork(z(n), z(n), z(n), z((n, n)), z((n, n)), z((n, n)), z((4, 9, nf)), z((2, 3, 3)), z((2, 3)),
                    z((2, 3, 3)), z((2, 9, nf)), z((2, 9, nf)), z((2, n)), z((2, 3, 3)), z(5), z(tmp_size(nf)),
                    z(max(1, strain_work_size(nf, kd.A.shape[1], qt.quartic[0] != 0))))


@numba.njit(cache=True, _nrt=False, inline="always")
def _nu(wk, k):
    """The k-th (3, 3, n_f) contraction array of the work."""
    nf = wk.Nu.shape[2]
    return wk.Nu[k].reshape((3, 3, nf))


@numba.njit(cache=True, _nrt=False, inline="always")
def _config(wk, k):
    """The k-th Configuration of the work (views)."""
    nf = wk.C.shape[2]
    return Configuration(wk.D[k], wk.s[k], wk.J[k], wk.C[k].reshape((3, 3, nf)), wk.gJ[k].reshape((3, 3, nf)))


@numba.njit(cache=True, _nrt=False, inline="always")
def _at(kd, q, Nq, cf):
    """The Configuration ``cf`` at q, with ``Nq`` (written here) N applied to q."""
    contract_into(kd.Nt, q, Nq)
    configuration(kd.S0, kd.Sbar, kd.I0, kd.P, q, Nq, cf)


@numba.njit(cache=True, _nrt=False, inline="always")
def _fill(a, value):
    """Every entry of the C-contiguous array ``a`` ← value."""
    flat = a.reshape(a.size)
    for i in range(flat.size):
        flat[i] = value


# ------------------------------------------------------------------ one term at a time (tests), allocating
@numba.njit(cache=True)
def _case(kd):
    """(zero (n, n) matrix, zero 3 × 3 weight, a Configuration, N-contraction arrays (3, 9, n_f), tmp) for the
    one-term functions below."""
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    cf = Configuration(np.empty((3, 3)), np.empty(3), np.empty((3, 3)), np.empty((3, 3, nf)), np.empty((3, 3, nf)))
    return np.zeros((n, n)), np.zeros((3, 3)), cf, np.empty((3, 3, 3, nf)), np.empty(tmp_size(nf))


@numba.njit(cache=True)
def mass_matrix(kd, q):
    """M(q), (12 + n_f) × (12 + n_f), kg (``kinetics.mass_matrix``)."""
    out, W, cf, Nu, tmp = _case(kd)
    _at(kd, q, Nu[0], cf)
    add_mass(kd.mass, kd.Sbar, cf, 1.0, out, W, tmp)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def momentum_jacobian(kd, q, a):
    """B(q, a) = ∂(M(q) a)/∂q (``kinetics.momentum_jacobian``)."""
    out, W, cf, Nu, tmp = _case(kd)
    _at(kd, q, Nu[0], cf)
    contract_into(kd.Nt, a, Nu[1])
    add_jacobian(kd.Sbar, cf, a, Nu[1], 1.0, 0.0, out, W, tmp)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def kinetic_hessian(kd, a, b):
    """H(a, b) = ∇²_q aᵀM(q)b, constant in q (``kinetics.kinetic_hessian``)."""
    out, W, cf, Nu, tmp = _case(kd)
    contract_into(kd.Nt, a, Nu[0])
    contract_into(kd.Nt, b, Nu[1])
    add_hessian(a, Nu[0], b, Nu[1], 1.0, out, W, tmp)
    add_elastic_block(kd.N, W, out)
    return out


@numba.njit(cache=True)
def quadratic_velocity_terms(kd, q, v):
    """(Q_v, ∂Q_v/∂q, ∂Q_v/∂v) (``kinetics.quadratic_velocity_force``): the products and matrices
    :func:`body_terms_into` forms for the Newmark family, one at a time."""
    fq, _, cf, Nu, tmp = _case(kd)
    fv, Wv = np.zeros_like(fq), np.zeros((3, 3))
    _at(kd, q, Nu[0], cf)
    Nv = Nu[1]
    contract_into(kd.Nt, v, Nv)
    f = np.zeros(fq.shape[0])
    form_gradient(kd.Sbar, cf, v, Nv, v, Nv, 0.5, f, tmp)
    derivative_times(kd.Sbar, cf, v, Nv, v, Nv, -1.0, f, tmp)
    add_velocity_force_derivative(v, Nv, 1.0, fq, tmp)
    add_jacobian(kd.Sbar, cf, v, Nv, -1.0, 1.0, fv, Wv, tmp)
    add_mass_derivative(kd.Sbar, cf, v, Nv, -1.0, fv, Wv, tmp)
    add_elastic_block(kd.N, Wv, fv)
    return f, fq, fv


@numba.njit(cache=True, _nrt=False, inline="always")
def _potential(kd, qt, wk, qa, qb, gradient, jacobian):
    """Strain energy at q_b plus gravity's potential at (q_a + q_b)/2, J; with ``gradient`` gp ← their discrete
    gradient from q_a to q_b and, with ``jacobian``, dgp ← ∂gp/∂q_b."""
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    gp, dgp = wk.gp, wk.dgp
    if jacobian:
        _fill(dgp, 0.0)
    vg = 0.0
    if has_gravity(kd):
        qk = wk.vec[1]
        for i in range(n):
            qk[i] = 0.5 * (qa[i] + qb[i])
        # gp doubles as the gradient's target: gravity's comes first, the strain's is added to it
        vg = gravity_into(kd, qk, wk.D[1], gp, dgp, 0.5, jacobian)
        if not gradient:
            return vg + strain_energy_into(kd, qt, qb[12:], wk.strain)
    elif gradient:
        _fill(gp, 0.0)
    else:
        return strain_energy_into(kd, qt, qb[12:], wk.strain)
    return vg + strain_terms_into(kd, qt, qa[12:], qb[12:], gp, dgp, 12, jacobian, wk.strain)


@numba.njit(cache=True, _nrt=False)
def body_terms_into(kd, qt, wk, mode, q0, q1, v0, v1, a1, qa, qb, weights, residual):
    r"""Every part of one body's residual and its Newton block, as the compiled core's tasks ask them
    (:mod:`skfem_flex.compiled.tasks`), into the body's :class:`BodyWork` ``wk``; returns the potential energy V.
    The one compiled entry of the body's arithmetic; it allocates nothing.

    ``kd`` and ``qt``: the body's :class:`SpatialFrameKernelData` and :class:`QuarticTerms`; ``weights``: the
    task's (w_p, w_gk, dq1, dv1, da1) (:mod:`skfem_flex.compiled.tasks`; dv1 the same for every coordinate of
    the body: it has no angle coordinate). ``mode`` :data:`EM` (energy–momentum): p = M(q₁)v₁,
    g_k = ½B(q_m, v₀)ᵀv₁ (the exact discrete gradient of ½v₀ᵀM(q)v₁), and the kinetic block

    .. math::

        K = w_p (dq_1 B(q_1, v_1) + dv_1 M(q_1)) + w_{gk} (\tfrac14 dq_1 H(v_0, v_1)
            + \tfrac12 dv_1 B(q_m, v_0)^T) .

    :data:`NEWMARK`: M1 = M(q₁), p = M(q₁)a₁, g_k = Q_v(q₁, v₁) = ½B(q₁, v₁)ᵀv₁ − B(q₁, v₁)v₁ and

    .. math::

        K = w_p (dq_1 B(q_1, a_1) + da_1 M(q_1)) + w_{gk} \big(dq_1 [\tfrac12 H(v, v) − (B(v, v) − B(0, v))]
            + dv_1 [B(q_1, v)^T − B(q_1, v) − DM(q_1)[v]]\big) ,

    with v = v₁ (``kinetics`` docstring). Both: g_p the discrete gradient of strain and gravity from q_a to
    q_b and dgp = ∂g_p/∂q_b. :data:`STATE`: only p = M(q₁)v₁ and V; :data:`MOMENTUM` only p, :data:`ENERGY`
    only V.

    ``residual``: neither K nor dgp is formed: an evaluation whose matrix is not used, which needs no
    round-off floor either (:mod:`skfem_flex.compiled.loop`). What is not formed keeps stale values.

    Returns
    -------
    V : float
        Strain energy at q_b plus gravity's potential at (q_a + q_b)/2, J (the potential energy at q₁ when
        q_a = q_b = q₁); 0 for :data:`MOMENTUM`.
    """
    if mode == ENERGY:                               # V alone: no mass matrix
        return _potential(kd, qt, wk, qa, qb, False, False)
    nf = kd.Sbar.shape[1]
    n = 12 + nf
    Sbar, tmp = kd.Sbar, wk.tmp
    p, gk = wk.p, wk.gk
    _fill(p, 0.0)
    _fill(gk, 0.0)
    w_p, w_gk, dq1, dv1, da1 = weights[0], weights[1], weights[2], weights[3], weights[4]
    Nv1 = _nu(wk, 1)
    cf1 = _config(wk, 0)
    _at(kd, q1, _nu(wk, 0), cf1)
    contract_into(kd.Nt, v1, Nv1)
    full = not residual and (mode == EM or mode == NEWMARK)
    K, W = wk.block, wk.W[0]
    if full:
        _fill(K, 0.0)
        _fill(W, 0.0)
    if mode == NEWMARK:
        M1, Wm = wk.M1, wk.W[1]
        _fill(M1, 0.0)
        _fill(Wm, 0.0)
        add_mass(kd.mass, Sbar, cf1, 1.0, M1, Wm, tmp)
        add_elastic_block(kd.N, Wm, M1)
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += M1[i, j] * a1[j]
            p[i] = s
        form_gradient(Sbar, cf1, v1, Nv1, v1, Nv1, 0.5, gk, tmp)
        derivative_times(Sbar, cf1, v1, Nv1, v1, Nv1, -1.0, gk, tmp)
        if full:
            # B(q₁, ·) is linear in its vector: w_p dq1 B(q₁, a₁) − w_gk dv1 B(q₁, v₁) in one pass
            ct, cq = w_gk * dv1, w_gk * dq1
            Na1, Nat = _nu(wk, 2), _nu(wk, 3)
            contract_into(kd.Nt, a1, Na1)
            at = wk.vec[0]
            for i in range(n):
                at[i] = w_p * dq1 * a1[i] - ct * v1[i]
            for i in range(3):
                for k in range(3):
                    for e in range(nf):
                        Nat[i, k, e] = w_p * dq1 * Na1[i, k, e] - ct * Nv1[i, k, e]
            for i in range(n):
                for j in range(n):
                    K[i, j] = w_p * da1 * M1[i, j]
            add_jacobian(Sbar, cf1, at, Nat, 1.0, 0.0, K, W, tmp)
            add_jacobian(Sbar, cf1, v1, Nv1, 0.0, ct, K, W, tmp)
            add_mass_derivative(Sbar, cf1, v1, Nv1, -ct, K, W, tmp)
            add_velocity_force_derivative(v1, Nv1, cq, K, tmp)
    else:
        mass_times(kd.mass, Sbar, cf1, v1, Nv1, p, tmp)
        if mode == EM:
            qm = wk.vec[0]
            for i in range(n):
                qm[i] = 0.5 * (q0[i] + q1[i])
            Nv0 = _nu(wk, 2)
            contract_into(kd.Nt, v0, Nv0)
            cfm = _config(wk, 1)
            _at(kd, qm, _nu(wk, 3), cfm)
            form_gradient(Sbar, cfm, v0, Nv0, v1, Nv1, 0.5, gk, tmp)
            if full:
                add_mass(kd.mass, Sbar, cf1, w_p * dv1, K, W, tmp)
                add_jacobian(Sbar, cf1, v1, Nv1, w_p * dq1, 0.0, K, W, tmp)
                add_hessian(v0, Nv0, v1, Nv1, 0.25 * w_gk * dq1, K, W, tmp)
                add_jacobian(Sbar, cfm, v0, Nv0, 0.0, 0.5 * w_gk * dv1, K, W, tmp)
    if mode == MOMENTUM:                             # p alone: no strain or gravity
        return 0.0
    if full:
        add_elastic_block(kd.N, W, K)
    # strain and gravity: discrete gradients from q_a to q_b
    return _potential(kd, qt, wk, qa, qb, True, not residual)


def body_terms(kd, qt, mode, q0, q1, v0, v1, a1, qa, qb, weights, residual):
    """:func:`body_terms_into` on a new :class:`BodyWork`, its results returned (tests): (p, g_k, g_p, M1, K,
    dgp, V), each matrix (0, 0) where the mode or ``residual`` does not form it, and the vectors empty for
    :data:`ENERGY`."""
    wk = body_work(kd, qt)
    V = body_terms_into(kd, qt, wk, mode, q0, q1, v0, v1, a1, qa, qb, np.asarray(weights, dtype=float), residual)
    none, empty = np.zeros((0, 0)), np.zeros(0)
    if mode == ENERGY:
        return empty, empty, empty, none, none, none, V
    full = not residual and mode in (EM, NEWMARK)
    return (wk.p.copy(), wk.gk.copy(), np.zeros_like(wk.p) if mode == MOMENTUM else wk.gp.copy(),
            wk.M1.copy() if mode == NEWMARK else none, wk.block.copy() if full else none,
            wk.dgp.copy() if mode in (EM, NEWMARK) and not residual else none, V)
