r"""Compiled strain energy and gravity of a spatial floating-frame body: values, exact discrete gradients and
their derivatives, allocation-free (``*_into``, their temporaries in a work vector of
:func:`strain_work_size` entries) and as allocating functions for tests.

The strain energy is V = ½ yᵀK y + ½ Σ_q w_q ε_q² with the Green–Lagrange axis ε = u₃' + ½|u'|²,
u'_k = A_k y (a beam with ``green``), or V = ½ yᵀK y + ½ K3_ijk y_i y_j y_k + ⅛ K4_ijkl y_i y_j y_k y_l (a
meshed solid's Green–Lagrange energy, with ``quartic``: the tensors of ``SolidGreenLagrange.quartic``, folded
by :func:`~skfem_flex.bodies.modal.kernel.pack_quartic` and evaluated by that module's kernels), or
V = ½ yᵀK y (linear strain). Its discrete gradient is the stress at the mean strain (exact), gravity's the
mid-point gradient (exact: V_g = −g·(m x + D(S₀ + S̄ y)) is quadratic). The body's data are the
:class:`~skfem_flex.bodies.floating_spatial.kernel.SpatialFrameKernelData` and ``QuarticTerms`` of
:mod:`.kernel`, which calls these for :func:`~skfem_flex.bodies.floating_spatial.kernel.body_terms_into`.
"""
from __future__ import annotations

import numba
import numpy as np

from ..modal.kernel import quartic_discrete_gradient_into, quartic_energy_into, quartic_work_size
from .kinetic_kernel import directors

__all__ = ["strain_work_size", "has_gravity", "axial_strain", "strain_energy_into", "strain_energy",
           "strain_terms_into", "strain_terms", "gravity_into", "gravity_terms"]


@numba.njit(cache=True, _nrt=False)
def strain_work_size(nf, npts, quartic):
    """Entries of the strain energy's temporaries: the axis' u' and ε at y₀ and y₁, two rows of n_f; the quartic
    terms' g and ∂g/∂y and their own temporaries."""
    size = 8 * npts + 2 * nf
    if quartic:
        size += nf + nf * nf + quartic_work_size(nf)
    return size


@numba.njit(cache=True, _nrt=False, inline="always")
def has_gravity(kd):
    """False when no gravity field acts on the body (its terms are zero and are skipped)."""
    return kd.g[0] != 0.0 or kd.g[1] != 0.0 or kd.g[2] != 0.0


@numba.njit(cache=True, _nrt=False)
def axial_strain(kd, y, up, eps):
    """up (3, n_points) ← u', eps (n_points,) ← ε of the Green–Lagrange axis at y."""
    npts, nf = kd.A.shape[1], kd.A.shape[2]
    for k in range(3):
        for p in range(npts):
            acc = 0.0
            for a in range(nf):
                acc += kd.A[k, p, a] * y[a]
            up[k, p] = acc
    for p in range(npts):
        eps[p] = up[2, p] + 0.5 * (up[0, p] ** 2 + up[1, p] ** 2 + up[2, p] ** 2)


@numba.njit(cache=True, _nrt=False)
def strain_energy_into(kd, qt, y, work):
    """V(y), J (:func:`strain_energy`), its temporaries in ``work``."""
    nf = kd.K.shape[0]
    energy = 0.0
    for a in range(nf):
        acc = 0.0
        for b in range(nf):
            acc += kd.K[a, b] * y[b]
        energy += 0.5 * y[a] * acc
    if qt.quartic[0] != 0:
        energy += quartic_energy_into(qt.k3p, qt.k4a, y, 0, work)
    elif kd.green[0] != 0:
        npts = kd.A.shape[1]
        e = work[3 * npts:4 * npts]
        axial_strain(kd, y, work[:3 * npts].reshape((3, npts)), e)
        for p in range(npts):
            energy += 0.5 * kd.w[p] * e[p] * e[p]
    return energy


@numba.njit(cache=True)
def strain_energy(kd, qt, y):
    """V(y), J: ½ yᵀK y plus the quartic terms (``qt``) or the Green–Lagrange axis ½ Σ w ε² (module
    docstring)."""
    nf = kd.K.shape[0]
    return strain_energy_into(kd, qt, y, np.empty(strain_work_size(nf, kd.A.shape[1], qt.quartic[0] != 0)))


@numba.njit(cache=True, _nrt=False)
def strain_terms_into(kd, qt, y0, y1, g, jac, off, jacobian, work):
    """V(y1), with g[off + a] += the exact discrete gradient from y0 to y1 and, with ``jacobian``,
    jac[off + a, off + b] += ∂g/∂y1 (:func:`strain_terms`); its temporaries in ``work``."""
    nf = kd.K.shape[0]
    npts = kd.A.shape[1]
    energy = strain_energy_into(kd, qt, y1, work)
    for a in range(nf):
        acc = 0.0
        for b in range(nf):
            acc += kd.K[a, b] * (y0[b] + y1[b])
        g[off + a] += 0.5 * acc
        if jacobian:
            for b in range(nf):
                jac[off + a, off + b] += 0.5 * kd.K[a, b]
    if qt.quartic[0] != 0:
        base = 8 * npts + 2 * nf
        g4 = work[base:base + nf]
        dg4 = work[base + nf:base + nf + nf * nf].reshape((nf, nf))
        quartic_discrete_gradient_into(qt.k3p, qt.k3q, qt.k3a, qt.k3b, qt.k4a, qt.k4s, qt.k4w, y0, y1, 0, g4, dg4,
                                       work[base + nf + nf * nf:])
        for a in range(nf):
            g[off + a] += g4[a]
            if jacobian:
                for b in range(nf):
                    jac[off + a, off + b] += dg4[a, b]
        return energy
    if kd.green[0] == 0:
        return energy
    up0, up1 = work[:3 * npts].reshape((3, npts)), work[3 * npts:6 * npts].reshape((3, npts))
    e0, e1 = work[6 * npts:7 * npts], work[7 * npts:8 * npts]
    bm, b1 = work[8 * npts:8 * npts + nf], work[8 * npts + nf:8 * npts + 2 * nf]
    axial_strain(kd, y0, up0, e0)
    axial_strain(kd, y1, up1, e1)
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
            g[off + a] += bm[a] * t
            if jacobian:
                for b in range(nf):
                    curv = 0.0
                    for k in range(3):
                        curv += kd.A[k, p, a] * kd.A[k, p, b]
                    jac[off + a, off + b] += 0.5 * w * bm[a] * b1[b] + 0.5 * t * curv
    return energy


@numba.njit(cache=True)
def strain_terms(kd, qt, y0, y1):
    """(V(y1), g, ∂g/∂y1): the strain energy at y1 and its exact discrete gradient from y0 to y1 (at y0 = y1:
    the gradient and half the Hessian), ``SpatialBeamStrain.discrete_gradient`` / ``QuadraticEnergy`` /
    ``SolidGreenLagrange.discrete_gradient``; ``qt`` the body's :class:`QuarticTerms`."""
    nf = kd.K.shape[0]
    g = np.zeros(nf)
    jac = np.zeros((nf, nf))
    work = np.empty(strain_work_size(nf, kd.A.shape[1], qt.quartic[0] != 0))
    energy = strain_terms_into(kd, qt, y0, y1, g, jac, 0, True, work)
    return energy, g, jac


@numba.njit(cache=True, _nrt=False)
def gravity_into(kd, q, D, grad, H, c, jacobian):
    """V_g(q) of V_g = −g·(m x + D(S₀ + S̄ y)), with grad ← ∇V_g(q) and, with ``jacobian``, H += c ∇²V_g
    (constant: the directors' coupling with y); ``D`` (3, 3) is written with q's directors."""
    nf = kd.Sbar.shape[1]
    g = kd.g
    directors(q, D)
    energy = 0.0
    for i in range(3):
        s = kd.S0[i]
        for a in range(nf):
            s += kd.Sbar[i, a] * q[12 + a]
        for cc in range(3):
            grad[3 + 3 * i + cc] = -s * g[cc]
            energy -= g[cc] * D[cc, i] * s
            if jacobian:
                for a in range(nf):
                    h = -c * g[cc] * kd.Sbar[i, a]
                    H[3 + 3 * i + cc, 12 + a] += h
                    H[12 + a, 3 + 3 * i + cc] += h
    for cc in range(3):
        grad[cc] = -kd.mass[0] * g[cc]
        energy -= g[cc] * kd.mass[0] * q[cc]
    for a in range(nf):
        acc = 0.0
        for i in range(3):
            acc += kd.Sbar[i, a] * (D[0, i] * g[0] + D[1, i] * g[1] + D[2, i] * g[2])
        grad[12 + a] = -acc
    return energy


@numba.njit(cache=True)
def gravity_terms(kd, q):
    """(V_g(q), ∇V_g(q), ∇²V_g) of V_g = −g·(m x + D(S₀ + S̄ y)) (``FloatingFrame3D.gravity_potential``)."""
    n = 12 + kd.Sbar.shape[1]
    grad = np.zeros(n)
    H = np.zeros((n, n))
    energy = gravity_into(kd, q, np.empty((3, 3)), grad, H, 1.0, True)
    return energy, grad, H
