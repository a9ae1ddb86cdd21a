r"""Compiled strain energy and discrete gradient of the spatial beam with rotation-interpolated two-node
elements (:class:`~.rotation_strain.RotationStrainPoints`; the only implementation, which the Python path
calls too).

An element joins nodes a and b (reference length h) with positions φ and directors d_i. Its strains are
functions of ten rotation-invariant functions of the element's coordinates, each quadratic in them: with
Q_ij = d^a_i · d^b_j and Δφ = φ_b − φ_a,

.. math::

    z = \big(a = \operatorname{axial}\tfrac12 (Q − Q^T),\;\; c = \tfrac12 (\operatorname{tr} Q − 1),\;\;
    u_i = d^a_i · Δφ / h,\;\; v_i = d^b_i · Δφ / h\big).

For orthonormal triads Q = R_aᵀ R_b is the element's relative rotation, and its rotation vector is

.. math::

    ψ = F(σ, c)\, a, \qquad σ = a · a, \qquad F = \frac{2 \arctan\big(\sqrt σ / (1 + c)\big)}{\sqrt σ}

(for a rotation by θ about n: a = sin θ n, c = cos θ, ψ = θ n; the same formula extends it smoothly to
any Q with 1 + c > 0). The section at the element's middle turns by R_m = R_a exp(ψ̂/2) = R_b exp(−ψ̂/2),
and the strains there (one point, weight h) are

.. math::

    K = ψ / h − K^0, \qquad Γ = \tfrac12 \big(\exp(−ψ̂/2)\, u + \exp(ψ̂/2)\, v\big) − Γ^0 ,

the curvature constant along the element, as in Crisfield and Jelenić's interpolation of the rotations
themselves. A beam bent to a constant curvature is represented exactly, so a cantilever rolled up by an end
moment 2πEI/L closes into a full circle. The strains are functions of invariants only: objective and
independent of the nodes' path.

The energy–momentum step needs a discrete gradient. With W = ½ h Σ_j C_j e_j², ε̄_j = (e_j(z₀) + e_j(z₁))/2
and Gonzalez's discrete derivative of each strain in the invariants,

.. math::

    D_j = ∇_z ε_j(z̄) + \frac{Δε_j − ∇_z ε_j(z̄) · Δz}{|Δz|^2} Δz, \qquad z̄ = (z₀ + z₁)/2,

the element force is g = Σ_k r_k ∇_q z_k(q_m) with r = h Σ_j C_j ε̄_j D_j. Each z_k is quadratic, so
∇z_k(q_m) · Δq = Δz_k exactly and g · Δq = ΔW; each ∇z_k is the gradient of a rotation-invariant function
at one configuration, so g has no net force or moment and the step keeps both momenta. Its derivative with
respect to q₁ is G_mᵀ B G₁ + ½ Σ_k r_k ∇²z_k (G = ∇z; ∇²z_k constant) with
B = Σ_j (½ h C_j D_j ⊗ ∇ε_j(z₁) + h C_j ε̄_j ∂D_j/∂z₁). At q₀ = q₁ these are the gradient and half the
Hessian.

The scalar functions (arctan √y / √y, and the coefficients of exp(ŵ), sin t/t and (1 − cos t)/t²) are
summed as series near zero, where their closed forms cancel; a straight element is the common case.
"""
from __future__ import annotations

from collections import namedtuple

import numba
import numpy as np

from .director_kernel import scatter_element

__all__ = ["RotationKernelData", "pack", "element_strains", "first_turned", "potential_energy",
           "discrete_gradient_terms"]

RotationKernelData = namedtuple("RotationKernelData", ["n", "ed", "h", "C", "e_ref", "pat_ptr", "pat_idx",
                                                       "map_el"])

#: element coordinates: φ_a, d^a_1, d^a_2, d^a_3, φ_b, d^b_1, d^b_2, d^b_3
NLOC = 24
#: the invariants z = (a, c, u, v) of an element
NZ = 10
# below these arguments the scalar functions are summed as series: their closed forms cancel
_SERIES_BELOW = 0.1


def _series(coefficients):
    """The coefficients of a power series Σ c_n xⁿ and of its first and second derivatives, as a (3, N) table."""
    c = np.asarray(coefficients, dtype=float)
    n = np.arange(c.size, dtype=float)
    out = np.zeros((3, c.size))
    out[0] = c
    out[1, :-1] = (n * c)[1:]
    out[2, :-2] = (n * (n - 1) * c)[2:]
    return out


_FACTORIAL = np.cumprod(np.concatenate([[1.0], np.arange(1.0, 31.0)]))
#: arctan(√y)/√y = Σ (−y)ⁿ/(2n + 1); sin t/t and (1 − cos t)/t² in τ = t²: Σ (−τ)ⁿ/(2n + 1)!, Σ (−τ)ⁿ/(2n + 2)!
_ATAN_SERIES = _series([(-1.0) ** n / (2 * n + 1) for n in range(27)])
_SIN_SERIES = _series([(-1.0) ** n / _FACTORIAL[2 * n + 1] for n in range(15)])
_COS_SERIES = _series([(-1.0) ** n / _FACTORIAL[2 * n + 2] for n in range(15)])


@numba.njit(cache=True, inline="always")
def _terms(x, most):
    """How many terms of a series in x (0 ≤ x < 1, coefficients at most 1) reach round-off: the first n with
    xⁿ below 1e-17, at most ``most``."""
    n, p = 1, x
    while p > 1e-17 and n < most:
        p *= x
        n += 1
    return n


@numba.njit(cache=True, inline="always")
def _horner(table, row, x, n):
    """Σ_{k<n} table[row, k] x^k, by Horner's rule."""
    s = 0.0
    for k in range(n - 1, -1, -1):
        s = s * x + table[row, k]
    return s


@numba.njit(cache=True, inline="always")
def _atan_ratio(y):
    """A(y) = arctan(√y)/√y and its first two derivatives in y (y ≥ 0)."""
    if y < _SERIES_BELOW:
        # the terms past n fall below round-off; the derivatives' series, two terms shorter, need two more
        n = min(_terms(y, 25) + 2, 25)
        return (_horner(_ATAN_SERIES, 0, y, n), _horner(_ATAN_SERIES, 1, y, n),
                _horner(_ATAN_SERIES, 2, y, n))
    r = np.sqrt(y)
    a = np.arctan(r) / r
    da = (1.0 / (1.0 + y) - a) / (2.0 * y)
    dda = (-1.0 / (1.0 + y) ** 2 - 3.0 * da) / (2.0 * y)
    return a, da, dda


@numba.njit(cache=True, inline="always")
def _rodrigues(tau):
    """exp(ŵ) = γ I + α ŵ + β w wᵀ with τ = w·w: (γ, α, β) and their first and second derivatives in τ."""
    if tau < _SERIES_BELOW:
        n = min(_terms(tau, 13) + 2, 13)
        al, dal, ddal = (_horner(_SIN_SERIES, 0, tau, n), _horner(_SIN_SERIES, 1, tau, n),
                         _horner(_SIN_SERIES, 2, tau, n))
        be, dbe, ddbe = (_horner(_COS_SERIES, 0, tau, n), _horner(_COS_SERIES, 1, tau, n),
                         _horner(_COS_SERIES, 2, tau, n))
        ga = 1.0 - be * tau
        return ga, al, be, -0.5 * al, dal, dbe, -0.5 * dal, ddal, ddbe
    t = np.sqrt(tau)
    ga, al = np.cos(t), np.sin(t) / t
    be = (1.0 - ga) / tau
    dga = -0.5 * al
    dal = (ga - al) / (2.0 * tau)
    dbe = (0.5 * al - be) / tau
    ddga = -0.5 * dal
    ddal = (dga - 3.0 * dal) / (2.0 * tau)
    ddbe = (0.5 * dal - 2.0 * dbe) / tau
    return ga, al, be, dga, dal, dbe, ddga, ddal, ddbe


#: the permutation symbol ε_ijk
_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0


@numba.njit(cache=True, inline="always")
def _skew(x, out):
    """out = x̂, the matrix of x × ·."""
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -x[2], x[1]
    out[1, 0], out[1, 1], out[1, 2] = x[2], 0.0, -x[0]
    out[2, 0], out[2, 1], out[2, 2] = -x[1], x[0], 0.0


@numba.njit(cache=True, inline="always")
def _turn(w, x, level, y, yw, yx, yww, ywx, W, X, cr):
    """y = exp(ŵ) x = γ x + α w × x + β (w·x) w and (``level`` ≥ 1) its derivatives ∂y/∂w, ∂y/∂x and
    (``level`` 2) ∂²y/∂w², ∂²y/∂w∂x (y_i, [i, l], [i, m], [i, l, m], [i, l, m]), written into the given
    arrays (W, X, cr: work arrays)."""
    tau = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    ga, al, be, dga, dal, dbe, ddga, ddal, ddbe = _rodrigues(tau)
    wx = w[0] * x[0] + w[1] * x[1] + w[2] * x[2]
    _skew(w, W)
    _skew(x, X)
    cr[0] = w[1] * x[2] - w[2] * x[1]
    cr[1] = w[2] * x[0] - w[0] * x[2]
    cr[2] = w[0] * x[1] - w[1] * x[0]
    for i in range(3):
        y[i] = ga * x[i] + al * cr[i] + be * wx * w[i]
    if level == 0:
        return
    for i in range(3):
        for m in range(3):
            dim = 1.0 if i == m else 0.0
            yx[i, m] = ga * dim + al * W[i, m] + be * w[i] * w[m]
            # ∂(w × x)/∂w = −x̂
            yw[i, m] = (2.0 * dga * w[m] * x[i] + 2.0 * dal * w[m] * cr[i] - al * X[i, m]
                        + 2.0 * dbe * wx * w[i] * w[m] + be * w[i] * x[m] + be * wx * dim)
    if level < 2:
        return
    for i in range(3):
        for l in range(3):
            dil = 1.0 if i == l else 0.0
            for m in range(3):
                dim = 1.0 if i == m else 0.0
                dlm = 1.0 if l == m else 0.0
                yww[i, l, m] = (2.0 * dga * dlm * x[i] + 4.0 * ddga * w[l] * w[m] * x[i]
                                + 2.0 * dal * dlm * cr[i] + 4.0 * ddal * w[l] * w[m] * cr[i]
                                - 2.0 * dal * (w[l] * X[i, m] + w[m] * X[i, l])
                                + 2.0 * dbe * (x[m] * w[i] * w[l] + w[m] * w[i] * x[l])
                                + 2.0 * dbe * wx * (dim * w[l] + dil * w[m] + w[i] * dlm)
                                + 4.0 * ddbe * wx * w[i] * w[l] * w[m]
                                + be * (dim * x[l] + dil * x[m]))
                # ∂(−α x̂_il)/∂x_m = −α ε_iml = α ε_ilm, and ε_ilm = −(ê_m)_il
                ywx[i, l, m] = (2.0 * dga * w[l] * dim + 2.0 * dal * w[l] * W[i, m] + al * _EPS[i, l, m]
                                + 2.0 * dbe * w[m] * w[i] * w[l] + be * w[i] * dlm + be * w[m] * dil)


@numba.njit(cache=True)
def _workspace():
    """The work arrays of :func:`_jets` (allocated once per kernel call, not per element)."""
    return (np.empty(3), np.empty((3, 4)), np.empty((3, 4, 4)), np.empty(3), np.empty(3), np.empty(3),
            np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3, 3)),
            np.empty((3, 3, 3)), np.empty((3, 3, 3)), np.empty((3, 3, 3)), np.empty((3, 3)), np.empty((3, 3)),
            np.empty(3))


def _jets_py(z, h, level, eps, J, H, wk):
    """The strains ε(z) (without reference values) and, by ``level`` (0, 1, 2), J = ∂ε/∂z (6, 10) and
    H = ∂²ε/∂z² (6, 10, 10), into the given arrays (``wk``: :func:`_workspace`); False (and nothing
    written) where 1 + c ≤ 1e-12 or z is not finite."""
    psi, dpsi, ddpsi, w, y1, y2, yw1, yx1, yw2, yx2, yww1, ywx1, yww2, ywx2, W, X, cr = wk
    a = z[0:3]
    c = z[3]
    for k in range(NZ):
        if not np.isfinite(z[k]):
            return False
    if not 1.0 + c > 1e-12:
        return False
    sig = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    p = 1.0 / (1.0 + c)
    A, dA, ddA = _atan_ratio(sig * p * p)
    F = 2.0 * p * A
    Fs = 2.0 * p ** 3 * dA
    Fc = -2.0 * p * p * A - 4.0 * sig * p ** 4 * dA
    # ψ(y), y = (a, c): value, first (3, 4) and second (3, 4, 4) derivatives
    for k in range(3):
        psi[k] = F * a[k]
        for l in range(3):
            dpsi[k, l] = (F if k == l else 0.0) + 2.0 * Fs * a[k] * a[l]
        dpsi[k, 3] = Fc * a[k]
    # the turned u and v: y₁ = exp(−ψ̂/2) u, y₂ = exp(ψ̂/2) v
    for k in range(3):
        w[k] = -0.5 * psi[k]
    _turn(w, z[4:7], level, y1, yw1, yx1, yww1, ywx1, W, X, cr)
    for k in range(3):
        w[k] = 0.5 * psi[k]
    _turn(w, z[7:10], level, y2, yw2, yx2, yww2, ywx2, W, X, cr)
    if level == 0:
        for i in range(3):
            eps[i] = 0.5 * (y1[i] + y2[i])
            eps[3 + i] = psi[i] / h
        return True
    J[:, :] = 0.0
    for i in range(3):
        eps[i] = 0.5 * (y1[i] + y2[i])
        eps[3 + i] = psi[i] / h
        for q in range(4):
            J[3 + i, q] = dpsi[i, q] / h
            # Γ through w = ψ/2: ∂y₁/∂w = −yw1, ∂y₂/∂w = yw2
            s = 0.0
            for l in range(3):
                s += 0.25 * (yw2[i, l] - yw1[i, l]) * dpsi[l, q]
            J[i, q] = s
        for m in range(3):
            J[i, 4 + m] = 0.5 * yx1[i, m]
            J[i, 7 + m] = 0.5 * yx2[i, m]
    if level < 2:
        return True
    Fss = 2.0 * p ** 5 * ddA
    Fsc = -6.0 * p ** 4 * dA - 4.0 * sig * p ** 6 * ddA
    Fcc = 4.0 * p ** 3 * A + 20.0 * sig * p ** 5 * dA + 8.0 * sig * sig * p ** 7 * ddA
    for k in range(3):
        for l in range(3):
            for m in range(3):
                ddpsi[k, l, m] = (2.0 * Fs * ((a[m] if k == l else 0.0) + (a[l] if k == m else 0.0)
                                              + (a[k] if l == m else 0.0)) + 4.0 * Fss * a[k] * a[l] * a[m])
            ddpsi[k, l, 3] = ddpsi[k, 3, l] = (Fc if k == l else 0.0) + 2.0 * Fsc * a[k] * a[l]
        ddpsi[k, 3, 3] = Fcc * a[k]
    H[:, :, :] = 0.0
    for i in range(3):
        for q in range(4):
            for r in range(4):
                H[3 + i, q, r] = ddpsi[i, q, r] / h
    # ∂²y₁/∂w² = yww1, ∂²y₁/∂w∂u = −ywx1
    for i in range(3):
        for q in range(4):
            for r in range(q, 4):
                s = 0.0
                for l in range(3):
                    s += 0.25 * (yw2[i, l] - yw1[i, l]) * ddpsi[l, q, r]
                    t = 0.0
                    for m in range(3):
                        t += 0.25 * (yww1[i, l, m] + yww2[i, l, m]) * dpsi[m, r]
                    s += 0.5 * dpsi[l, q] * t
                H[i, q, r] = H[i, r, q] = s
            for m in range(3):
                su, sv = 0.0, 0.0
                for l in range(3):
                    su -= 0.25 * ywx1[i, l, m] * dpsi[l, q]
                    sv += 0.25 * ywx2[i, l, m] * dpsi[l, q]
                H[i, q, 4 + m] = H[i, 4 + m, q] = su
                H[i, q, 7 + m] = H[i, 7 + m, q] = sv
    return True


#: :func:`_jets_py` compiled into its one call site in :func:`discrete_gradient_terms` (the per-element calls
#: with their work arrays cost as much as the arithmetic), and as a called function for the strains alone
_jets = numba.njit(cache=True, inline="always")(_jets_py)
_jets_called = numba.njit(cache=True)(_jets_py)


@numba.njit(cache=True)
def _invariants(qe, h, z, G, gradient):
    """z = (a, c, u, v) (10,) and, with ``gradient``, ∇z (10, 24) of the element coordinates ``qe`` (module
    docstring): a = axial ½(Q − Qᵀ), c = ½(tr Q − 1) with Q_ij = d^a_i · d^b_j, u_i = d^a_i · Δφ/h,
    v_i = d^b_i · Δφ/h."""
    dphi = qe[12:15] - qe[0:3]
    # a_k = ½ (Q_ij − Q_ji) for (k, i, j) = (0, 2, 1), (1, 0, 2), (2, 1, 0)
    for k in range(3):
        i, j = (k + 2) % 3, (k + 1) % 3
        dai, daj = qe[3 + 3 * i:6 + 3 * i], qe[3 + 3 * j:6 + 3 * j]
        dbi, dbj = qe[15 + 3 * i:18 + 3 * i], qe[15 + 3 * j:18 + 3 * j]
        z[k] = 0.5 * (dai[0] * dbj[0] + dai[1] * dbj[1] + dai[2] * dbj[2]
                      - daj[0] * dbi[0] - daj[1] * dbi[1] - daj[2] * dbi[2])
    z[3] = -0.5
    for i in range(3):
        dai = qe[3 + 3 * i:6 + 3 * i]
        dbi = qe[15 + 3 * i:18 + 3 * i]
        z[3] += 0.5 * (dai[0] * dbi[0] + dai[1] * dbi[1] + dai[2] * dbi[2])
        z[4 + i] = (dai[0] * dphi[0] + dai[1] * dphi[1] + dai[2] * dphi[2]) / h
        z[7 + i] = (dbi[0] * dphi[0] + dbi[1] * dphi[1] + dbi[2] * dphi[2]) / h
    if not gradient:
        return
    G[:, :] = 0.0
    for k in range(3):
        i, j = (k + 2) % 3, (k + 1) % 3
        for c in range(3):
            G[k, 3 + 3 * i + c] = 0.5 * qe[15 + 3 * j + c]
            G[k, 15 + 3 * j + c] = 0.5 * qe[3 + 3 * i + c]
            G[k, 3 + 3 * j + c] = -0.5 * qe[15 + 3 * i + c]
            G[k, 15 + 3 * i + c] = -0.5 * qe[3 + 3 * j + c]
    for i in range(3):
        for c in range(3):
            dai, dbi = qe[3 + 3 * i + c], qe[15 + 3 * i + c]
            G[3, 3 + 3 * i + c] = 0.5 * dbi
            G[3, 15 + 3 * i + c] = 0.5 * dai
            G[4 + i, 3 + 3 * i + c] = dphi[c] / h
            G[4 + i, 12 + c] = dai / h
            G[4 + i, c] = -dai / h
            G[7 + i, 15 + 3 * i + c] = dphi[c] / h
            G[7 + i, 12 + c] = dbi / h
            G[7 + i, c] = -dbi / h


@numba.njit(cache=True)
def _add_invariant_hessians(ke, r, scale, h):
    """ke += scale Σ_k r_k ∇²z_k (each ∇²z_k a few identity blocks)."""
    for k in range(3):
        i, j = (k + 2) % 3, (k + 1) % 3
        v = 0.5 * scale * r[k]
        for c in range(3):
            ke[3 + 3 * i + c, 15 + 3 * j + c] += v
            ke[15 + 3 * j + c, 3 + 3 * i + c] += v
            ke[3 + 3 * j + c, 15 + 3 * i + c] -= v
            ke[15 + 3 * i + c, 3 + 3 * j + c] -= v
    for i in range(3):
        v = 0.5 * scale * r[3]
        for c in range(3):
            ke[3 + 3 * i + c, 15 + 3 * i + c] += v
            ke[15 + 3 * i + c, 3 + 3 * i + c] += v
        # u_i and v_i: blocks (d_i, φ_b) = I/h, (d_i, φ_a) = −I/h
        for d, v in ((3 + 3 * i, scale * r[4 + i] / h), (15 + 3 * i, scale * r[7 + i] / h)):
            for c in range(3):
                ke[d + c, 12 + c] += v
                ke[12 + c, d + c] += v
                ke[d + c, c] -= v
                ke[c, d + c] -= v


def pack(ed, h, stiffness, q_reference, n_dofs):
    """The kernel data: element coordinates ``ed`` (n_el, 24), lengths h (m), stiffnesses C, the reference
    strains (the strains of ``q_reference``) and the CSR pattern of the element blocks."""
    ed = np.ascontiguousarray(ed, dtype=np.int64)
    ne, nloc = ed.shape
    n = int(n_dofs)
    rows = np.broadcast_to(ed[:, :, None], (ne, nloc, nloc)).ravel()
    cols = np.broadcast_to(ed[:, None, :], (ne, nloc, nloc)).ravel()
    uniq, inv = np.unique(rows * n + cols, return_inverse=True)
    pat_idx = np.ascontiguousarray(uniq % n, dtype=np.int64)
    pat_ptr = np.ascontiguousarray(np.searchsorted(uniq // n, np.arange(n + 1)), dtype=np.int64)
    kd = RotationKernelData(np.array([n], dtype=np.int64), ed, np.ascontiguousarray(h, dtype=float),
                            np.ascontiguousarray(stiffness, dtype=float), np.zeros(6 * ne), pat_ptr, pat_idx,
                            np.ascontiguousarray(inv, dtype=np.int64))
    eref = element_strains(kd, np.ascontiguousarray(q_reference, dtype=float))
    return kd._replace(e_ref=np.ascontiguousarray(eref.ravel()))


@numba.njit(cache=True)
def element_strains(kd, q):
    """e = ε(z(q)) − ε_ref of every element, (n_el, 6); NaN in the rows of elements turned half a turn."""
    ne = kd.ed.shape[0]
    out = np.empty((ne, 6))
    qe, z, G = np.empty(NLOC), np.empty(NZ), np.empty((NZ, NLOC))
    eps, J, H = np.empty(6), np.empty((6, NZ)), np.empty((1, 1, 1))
    wk = _workspace()
    for e in range(ne):
        for a in range(NLOC):
            qe[a] = q[kd.ed[e, a]]
        _invariants(qe, kd.h[e], z, G, False)
        ok = _jets_called(z, kd.h[e], 0, eps, J, H, wk)
        for j in range(6):
            out[e, j] = eps[j] - kd.e_ref[6 * e + j] if ok else np.nan
    return out


@numba.njit(cache=True)
def first_turned(kd, q):
    """The first element whose relative rotation has reached half a turn at q (or is not finite), or −1."""
    e = element_strains(kd, q)
    for k in range(e.shape[0]):
        if not np.isfinite(e[k, 0]):
            return k
    return -1


@numba.njit(cache=True)
def potential_energy(kd, q):
    """V(q) = ½ Σ_e h_e Σ_j C_j e_j², J (NaN where an element has turned half a turn)."""
    e = element_strains(kd, q)
    v = 0.0
    for k in range(e.shape[0]):
        for j in range(6):
            v += 0.5 * kd.h[k] * kd.C[j] * e[k, j] * e[k, j]
    return v


@numba.njit(cache=True)
def discrete_gradient_terms(kd, qa, qb, residual):
    """(ok, g (n,), data (nnz,) of ∂g/∂q_b on the CSR pattern, floor (n,)): the module docstring's discrete
    gradient and its derivative; the floor is Σ_b abs(∂g_a/∂q_b) (abs(q_a,b) + abs(q_b,b)), the round-off
    size of g. At q_a = q_b: the gradient and half the Hessian. ``ok`` is False if an element of q_a, q_b
    or their mean has turned half a turn (:func:`first_turned` names it). ``residual``: g alone (the same
    numbers), data empty and floor zero: the strains' second derivatives and the element matrices, most of
    the work, are skipped."""
    n = kd.n[0]
    ne = kd.ed.shape[0]
    mp = kd.map_el.reshape(ne, NLOC, NLOC)
    g = np.zeros(n)
    data = np.zeros(0 if residual else kd.pat_idx.size)
    floor = np.zeros(n)
    q0, q1, qm = np.empty(NLOC), np.empty(NLOC), np.empty(NLOC)
    zs, dz, zm = np.empty((3, NZ)), np.empty(NZ), np.empty(NZ)   # z at q_a, q_b, and their mean
    z0, z1, zb = zs[0], zs[1], zs[2]
    G0, G1, Gm = np.empty((NZ, NLOC)), np.empty((NZ, NLOC)), np.empty((NZ, NLOC))
    epss, Js = np.empty((3, 6)), np.empty((3, 6, NZ))
    eps0, eps1 = epss[0], epss[1]
    J1, Jb = Js[1], Js[2]
    Hb, none = np.empty((6, NZ, NZ)), np.empty((1, 1, 1))
    B, r, D, dc = np.empty((NZ, NZ)), np.empty(NZ), np.empty(NZ), np.empty(NZ)
    T, ke = np.empty((NZ, NLOC)), np.empty((NLOC, NLOC))
    wk = _workspace()
    for e in range(ne):
        h = kd.h[e]
        for a in range(NLOC):
            q0[a] = qa[kd.ed[e, a]]
            q1[a] = qb[kd.ed[e, a]]
            qm[a] = 0.5 * (q0[a] + q1[a])
        _invariants(q0, h, z0, G0, False)
        _invariants(q1, h, z1, G1, not residual)
        _invariants(qm, h, zm, Gm, True)                  # ∇z is linear in q: Gm is its mid-point value
        nd, nb = 0.0, 0.0
        for k in range(NZ):
            zb[k] = 0.5 * (z0[k] + z1[k])
            dz[k] = z1[k] - z0[k]
            nd += dz[k] * dz[k]
            nb += zb[k] * zb[k]
        for s in range(3):          # values at q_a; with J at q_b and J, H at the mean (less for the residual)
            level = s - 1 if residual and s > 0 else (0 if s == 0 else s)
            if not _jets(zs[s], h, level, epss[s], Js[s], Hb if s == 2 else none, wk):
                return False, g, data, floor
        B[:, :] = 0.0
        r[:] = 0.0
        for j in range(6):
            s = h * kd.C[j] * (0.5 * (eps0[j] + eps1[j]) - kd.e_ref[6 * e + j])
            # Gonzalez's discrete derivative of ε_j in z and its derivative in z₁
            cj = 0.0
            dc[:] = 0.0
            # below |Δz| = 1e-5 |z̄| the correction is round-off divided by |Δz|² (and its energy O(|Δz|³)):
            # left out there
            if nd > 1e-10 * max(1.0, nb):
                jd = 0.0
                for k in range(NZ):
                    jd += Jb[j, k] * dz[k]
                cj = (eps1[j] - eps0[j] - jd) / nd
                for l in range(NZ if not residual else 0):
                    hd = 0.0
                    for k in range(NZ):
                        hd += Hb[j, l, k] * dz[k]
                    dc[l] = (J1[j, l] - Jb[j, l] - 0.5 * hd - 2.0 * cj * dz[l]) / nd
            for k in range(NZ):
                D[k] = Jb[j, k] + cj * dz[k]
                r[k] += s * D[k]
            if residual:
                continue
            hc = 0.5 * h * kd.C[j]
            for k in range(NZ):
                for l in range(NZ):
                    B[k, l] += hc * D[k] * J1[j, l] + s * (0.5 * Hb[j, k, l] + dz[k] * dc[l])
                B[k, k] += s * cj
        if residual:
            for a in range(NLOC):
                ga = 0.0
                for k in range(NZ):
                    ga += Gm[k, a] * r[k]
                g[kd.ed[e, a]] += ga
            continue
        # ke = G_mᵀ B G₁ + ½ Σ_k r_k ∇²z_k, g = G_mᵀ r
        for k in range(NZ):
            for b in range(NLOC):
                t = 0.0
                for l in range(NZ):
                    t += B[k, l] * G1[l, b]
                T[k, b] = t
        for a in range(NLOC):
            ga = 0.0
            for k in range(NZ):
                ga += Gm[k, a] * r[k]
            g[kd.ed[e, a]] += ga
            for b in range(NLOC):
                t = 0.0
                for k in range(NZ):
                    t += Gm[k, a] * T[k, b]
                ke[a, b] = t
        _add_invariant_hessians(ke, r, 0.5, h)
        scatter_element(ke, mp[e], kd.ed[e], q0, q1, data, floor)
    return True, g, data, floor
