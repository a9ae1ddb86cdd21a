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

The scalar functions and the turns exp(±ψ̂/2) x are those of :mod:`.rotation_turn`.

Nothing here allocates in the compiled evaluation: results and temporaries live in a :class:`RotationWork`
made once per beam (:func:`rotation_work`, packed with its data by the family), the ``*_into`` functions write
into it, and everything is compiled without numba's reference counting (``_nrt=False``). Why: under reference
counting each array handed to a call or sliced pays an atomic increment and decrement, a third of the
evaluation's time here (as in :mod:`skfem_flex.bodies.floating_spatial.kinetic_kernel`, whose rule applies:
a function compiled with ``_nrt=False`` returns scalars or nothing, never an array). The allocating public
functions (the Python path, tests) are thin wrappers that make a new work and copy its results out.
"""
from __future__ import annotations

from collections import namedtuple
from typing import NamedTuple

import numba
import numpy as np

from .director_kernel import scatter_element
from .rotation_turn import atan_ratio, turn

__all__ = ["RotationKernelData", "RotationWork", "rotation_work", "pack", "element_strains", "first_turned",
           "potential_energy", "potential_energy_into", "discrete_gradient_terms", "discrete_gradient_terms_into"]

RotationKernelData = namedtuple("RotationKernelData", ["n", "ed", "h", "C", "e_ref", "pat_ptr", "pat_idx",
                                                       "map_el"])

#: element coordinates: φ_a, d^a_1, d^a_2, d^a_3, φ_b, d^b_1, d^b_2, d^b_3
NLOC = 24
#: the invariants z = (a, c, u, v) of an element
NZ = 10


def _gradient_blocks():
    """The first columns of the nonzero 3-column blocks of each row of ∇z (:func:`_invariants`; ascending, at
    most 6): a_k in d^a_i, d^a_j, d^b_i, d^b_j ({i, j, k} = {0, 1, 2}), c in every director, u_i in φ_a, d^a_i,
    φ_b, v_i in φ_a, φ_b, d^b_i. The products with ∇z run over these only (∇z is 55 % zeros); the sums keep
    their order."""
    starts, count = np.zeros((NZ, 6), dtype=np.int64), np.zeros(NZ, dtype=np.int64)
    rows = [sorted([3 + 3 * ((k + 2) % 3), 3 + 3 * ((k + 1) % 3), 15 + 3 * ((k + 2) % 3), 15 + 3 * ((k + 1) % 3)])
            for k in range(3)]
    rows += [[3, 6, 9, 15, 18, 21]] + [[0, 3 + 3 * i, 12] for i in range(3)] + [[0, 12, 15 + 3 * i] for i in range(3)]
    for k, r in enumerate(rows):
        starts[k, :len(r)], count[k] = r, len(r)
    return starts, count


def _gradient_rows(starts, count):
    """The same pattern by columns: the rows k (ascending, at most 6) where column b of ∇z can be nonzero."""
    rows, n = np.zeros((NLOC, 6), dtype=np.int64), np.zeros(NLOC, dtype=np.int64)
    for k in range(NZ):
        for b0 in starts[k, :count[k]]:
            for b in range(b0, b0 + 3):
                rows[b, n[b]] = k
                n[b] += 1
    return rows, n


_G_BLOCKS, _G_NBLOCKS = _gradient_blocks()
_G_ROWS, _G_COUNT = _gradient_rows(_G_BLOCKS, _G_NBLOCKS)


class RotationWork(NamedTuple):
    """The arrays of one beam's evaluation (its results and temporaries), made once by :func:`rotation_work`
    and packed with the beam's data, so that the ``*_into`` functions allocate nothing (module docstring).
    Every array is written before it is read; what an evaluation does not form keeps stale values.

    Attributes
    ----------
    g, floor : ndarray (n,)
        Results: the discrete gradient and its round-off floor.
    data : ndarray (nnz,)
        Result: ∂g/∂q_b on the beam's CSR pattern.
    qe : ndarray (3, 24)
        An element's coordinates at q_a, q_b and their mean.
    z : ndarray (3, 10)
        z(q_a), z(q_b) and z̄ = (z(q_a) + z(q_b))/2.
    zm, dz : ndarray (10,)
        z(q_m) and Δz = z(q_b) − z(q_a).
    G : ndarray (2, 10, 24)
        ∇z at q_b and at q_m.
    eps, J : ndarray (3, 6), (3, 6, 10)
        ε and ∂ε/∂z at the rows of ``z``.
    H : ndarray (6, 10, 10)
        ∂²ε/∂z² at z̄.
    B : ndarray (10, 10)
        The module docstring's B.
    vec : ndarray (3, 10)
        r, ∂c_j/∂z₁ (c_j Gonzalez's correction of ε_j) and Σ_j s_j ∂c_j/∂z₁.
    hD : ndarray (6, 10)
        ½ h C_j D_j.
    sj : ndarray (6,)
        ½ s_j.
    T : ndarray (10, 24)
        B ∇z(q_b).
    ke : ndarray (24, 24)
        An element's block of ∂g/∂q_b.
    strain : ndarray (6,)
        One element's strains (:func:`element_strains`).
    psi, dpsi, ddpsi, w, y, yw, yx, yww1, yww2, ywx1, ywx2, W, X, cr : ndarray
        Those of :func:`_jets`: ψ (3,) and its derivatives (3, 4), (3, 4, 4) in (a, c); ±ψ/2; the turned u
        and v (2, 3) and their first (2, 3, 3) and second (3, 3, 3) derivatives (:func:`.rotation_turn.turn`);
        its work arrays.
    """

    g: np.ndarray
    floor: np.ndarray
    data: np.ndarray
    qe: np.ndarray
    z: np.ndarray
    zm: np.ndarray
    dz: np.ndarray
    G: np.ndarray
    eps: np.ndarray
    J: np.ndarray
    H: np.ndarray
    B: np.ndarray
    vec: np.ndarray
    hD: np.ndarray
    sj: np.ndarray
    T: np.ndarray
    ke: np.ndarray
    strain: np.ndarray
    psi: np.ndarray
    dpsi: np.ndarray
    ddpsi: np.ndarray
    w: np.ndarray
    y: np.ndarray
    yw: np.ndarray
    yx: np.ndarray
    yww1: np.ndarray
    yww2: np.ndarray
    ywx1: np.ndarray
    ywx2: np.ndarray
    W: np.ndarray
    X: np.ndarray
    cr: np.ndarray


def rotation_work(kd):
    """A zeroed :class:`RotationWork` for the beam of ``kd`` (:class:`RotationKernelData`)."""
    n, nnz = int(np.asarray(kd.n).ravel()[0]), int(np.asarray(kd.pat_idx).size)
    z = np.zeros
    return RotationWork(z(n), z(n), z(nnz), z((3, NLOC)), z((3, NZ)), z(NZ), z(NZ), z((2, NZ, NLOC)), z((3, 6)),
                        z((3, 6, NZ)), z((6, NZ, NZ)), z((NZ, NZ)), z((3, NZ)), z((6, NZ)), z(6), z((NZ, NLOC)), z((NLOC, NLOC)), z(6), z(3), z((3, 4)),
                        z((3, 4, 4)), z(3), z((2, 3)), z((2, 3, 3)), z((2, 3, 3)), z((3, 3, 3)), z((3, 3, 3)),
                        z((3, 3, 3)), z((3, 3, 3)), z((3, 3)), z((3, 3)), z(3))


def _jets_py(z, h, level, eps, J, H, wk):
    """The strains ε(z) (without reference values) and, by ``level`` (0, 1, 2), J = ∂ε/∂z (6, 10) and
    H = ∂²ε/∂z² (6, 10, 10), into the given arrays (temporaries from ``wk``, a :class:`RotationWork`); False
    (and nothing written) where 1 + c ≤ 1e-12 or z is not finite."""
    psi, dpsi, ddpsi, w = wk.psi, wk.dpsi, wk.ddpsi, wk.w
    y1, y2, yw1, yw2, yx1, yx2 = wk.y[0], wk.y[1], wk.yw[0], wk.yw[1], wk.yx[0], wk.yx[1]
    yww1, yww2, ywx1, ywx2, W, X, cr = wk.yww1, wk.yww2, wk.ywx1, wk.ywx2, wk.W, wk.X, wk.cr
    a = z[0:3]
    c = z[3]
    for k in range(NZ):
        if not np.isfinite(z[k]):
            return False
    if not 1.0 + c > 1e-12:
        return False
    sig = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    p = 1.0 / (1.0 + c)
    A, dA, ddA = atan_ratio(sig * p * p)
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
    turn(w, z[4:7], level, y1, yw1, yx1, yww1, ywx1, W, X, cr)
    for k in range(3):
        w[k] = 0.5 * psi[k]
    turn(w, z[7:10], level, y2, yw2, yx2, yww2, ywx2, W, X, cr)
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


#: :func:`_jets_py` compiled into its one call site in :func:`discrete_gradient_terms_into` (a call per element
#: with its work arrays costs as much as the arithmetic), and as a called function for the strains alone
_jets = numba.njit(cache=True, _nrt=False, inline="always")(_jets_py)
_jets_called = numba.njit(cache=True, _nrt=False)(_jets_py)


@numba.njit(cache=True, _nrt=False)
def _invariants(qe, h, z, G, gradient):
    """z = (a, c, u, v) (10,) and, with ``gradient``, ∇z (10, 24) of the element coordinates ``qe`` (module
    docstring): a = axial ½(Q − Qᵀ), c = ½(tr Q − 1) with Q_ij = d^a_i · d^b_j, u_i = d^a_i · Δφ/h,
    v_i = d^b_i · Δφ/h."""
    # Δφ, as three numbers (an array difference would allocate)
    dp0, dp1, dp2 = qe[12] - qe[0], qe[13] - qe[1], qe[14] - qe[2]
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
        z[4 + i] = (dai[0] * dp0 + dai[1] * dp1 + dai[2] * dp2) / h
        z[7 + i] = (dbi[0] * dp0 + dbi[1] * dp1 + dbi[2] * dp2) / h
    if not gradient:
        return
    # only the entries of the pattern _G_ROWS are written (and read): the others stay as they are (zero)
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
            dpc = qe[12 + c] - qe[c]
            G[4 + i, 3 + 3 * i + c] = dpc / h
            G[4 + i, 12 + c] = dai / h
            G[4 + i, c] = -dai / h
            G[7 + i, 15 + 3 * i + c] = dpc / h
            G[7 + i, 12 + c] = dbi / h
            G[7 + i, c] = -dbi / h


@numba.njit(cache=True, _nrt=False)
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


@numba.njit(cache=True, _nrt=False)
def _element_strain(kd, wk, q, e):
    """wk.strain ← e = ε(z(q)) − ε_ref of element ``e``; False (nothing written) where it has turned half a
    turn."""
    qe, z = wk.qe[0], wk.z[0]
    for a in range(NLOC):
        qe[a] = q[kd.ed[e, a]]
    _invariants(qe, kd.h[e], z, wk.G[0], False)
    if not _jets_called(z, kd.h[e], 0, wk.strain, wk.J[0], wk.H, wk):
        return False
    for j in range(6):
        wk.strain[j] -= kd.e_ref[6 * e + j]
    return True


@numba.njit(cache=True, _nrt=False)
def _strains_into(kd, wk, q, out):
    """out (n_el, 6) ← the strains of every element (:func:`element_strains`)."""
    for e in range(kd.ed.shape[0]):
        ok = _element_strain(kd, wk, q, e)
        for j in range(6):
            out[e, j] = wk.strain[j] if ok else np.nan


def element_strains(kd, q):
    """e = ε(z(q)) − ε_ref of every element, (n_el, 6); NaN in the rows of elements turned half a turn."""
    out = np.empty((kd.ed.shape[0], 6))
    _strains_into(kd, rotation_work(kd), np.ascontiguousarray(q, dtype=float), out)
    return out


def first_turned(kd, q):
    """The first element whose relative rotation has reached half a turn at q (or is not finite), or −1."""
    bad = np.flatnonzero(~np.isfinite(element_strains(kd, q)[:, 0]))
    return int(bad[0]) if bad.size else -1


@numba.njit(cache=True, _nrt=False)
def potential_energy_into(kd, wk, q):
    """V(q) = ½ Σ_e h_e Σ_j C_j e_j², J (NaN where an element has turned half a turn); temporaries in ``wk``."""
    v = 0.0
    for e in range(kd.ed.shape[0]):
        if not _element_strain(kd, wk, q, e):
            return np.nan
        for j in range(6):
            v += 0.5 * kd.h[e] * kd.C[j] * wk.strain[j] * wk.strain[j]
    return v


def potential_energy(kd, q):
    """V(q) (:func:`potential_energy_into` on a new work)."""
    return potential_energy_into(kd, rotation_work(kd), np.ascontiguousarray(q, dtype=float))


@numba.njit(cache=True, _nrt=False)
def discrete_gradient_terms_into(kd, wk, qa, qb, residual):
    """The module docstring's discrete gradient and its derivative into ``wk`` (:class:`RotationWork`):
    g, the CSR data of ∂g/∂q_b and the floor Σ_b abs(∂g_a/∂q_b) (abs(q_a,b) + abs(q_b,b)), the round-off size
    of g. At q_a = q_b: the gradient and half the Hessian. Returns False if an element of q_a, q_b or their
    mean has turned half a turn (:func:`first_turned` names it). ``residual``: g alone (the same numbers), the
    floor zero and the data left stale: the strains' second derivatives and the element matrices, most of the
    work, are skipped."""
    ne = kd.ed.shape[0]
    g, data, floor = wk.g, wk.data, wk.floor
    g[:] = 0.0
    floor[:] = 0.0
    if not residual:
        data[:] = 0.0
    q0, q1, qm = wk.qe[0], wk.qe[1], wk.qe[2]
    zs, dz, zm = wk.z, wk.dz, wk.zm              # z at q_a, q_b, and their mean; z(q_m)
    z0, z1, zb = zs[0], zs[1], zs[2]
    G1, Gm = wk.G[0], wk.G[1]
    epss, Js, Hb = wk.eps, wk.J, wk.H
    eps0, eps1 = epss[0], epss[1]
    J1, Jb = Js[1], Js[2]
    B, T = wk.B, wk.T
    r, dc, sdc, sh, hD = wk.vec[0], wk.vec[1], wk.vec[2], wk.sj, wk.hD
    for e in range(ne):
        h = kd.h[e]
        for a in range(NLOC):
            q0[a] = qa[kd.ed[e, a]]
            q1[a] = qb[kd.ed[e, a]]
            qm[a] = 0.5 * (q0[a] + q1[a])
        _invariants(q0, h, z0, G1, False)
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
            if not _jets(zs[s], h, level, epss[s], Js[s], Hb, wk):
                return False
        for k in range(NZ):
            r[k] = 0.0
            sdc[k] = 0.0
        scj = 0.0
        for j in range(6):
            s = h * kd.C[j] * (0.5 * (eps0[j] + eps1[j]) - kd.e_ref[6 * e + j])
            # Gonzalez's discrete derivative of ε_j in z and its derivative in z₁
            cj = 0.0
            for k in range(NZ):
                dc[k] = 0.0
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
            hc = 0.5 * h * kd.C[j]
            for k in range(NZ):
                D = Jb[j, k] + cj * dz[k]
                r[k] += s * D
                hD[j, k] = hc * D
                sdc[k] += s * dc[k]
            sh[j] = 0.5 * s
            scj += s * cj
        if not residual:
            # B = Σ_j (½ h C_j D_j ⊗ ∇ε_j(z₁) + s_j (½ ∇²ε_j(z̄) + Δz ⊗ ∂c_j/∂z₁ + c_j I)), s_j = h C_j ε̄_j
            # over the nonzeros only: the curvatures (j ≥ 3) depend on (a, c) alone (z_0..3), and no strain
            # has a second derivative in (u, v) twice
            for k in range(NZ):
                for l in range(NZ):
                    t = dz[k] * sdc[l]
                    for j in range(3 if l >= 4 else 6):
                        t += hD[j, k] * J1[j, l]
                    for j in range(0 if k >= 4 and l >= 4 else (3 if k >= 4 or l >= 4 else 6)):
                        t += sh[j] * Hb[j, k, l]
                    B[k, l] = t
                B[k, k] += scj
        # g = G_mᵀ r over the nonzero rows of each column of G_m
        for a in range(NLOC):
            ga = 0.0
            for t in range(_G_COUNT[a]):
                k = _G_ROWS[a, t]
                ga += Gm[k, a] * r[k]
            g[kd.ed[e, a]] += ga
        if residual:
            continue
        # T = B G₁, its rows as sums of the nonzero blocks of the rows of G₁
        for k in range(NZ):
            for b in range(NLOC):
                T[k, b] = 0.0
            for l in range(NZ):
                c = B[k, l]
                for u in range(_G_NBLOCKS[l]):
                    b = _G_BLOCKS[l, u]
                    T[k, b] += c * G1[l, b]
                    T[k, b + 1] += c * G1[l, b + 1]
                    T[k, b + 2] += c * G1[l, b + 2]
        _element_matrix(kd, wk, e, Gm, T, r, q0, q1, h)
    return True


@numba.njit(cache=True, _nrt=False, inline="always")
def _element_matrix(kd, wk, e, Gm, T, r, q0, q1, h):
    """Element e's ke = G_mᵀ T + ½ Σ_k r_k ∇²z_k into wk.data (slots ``kd.map_el``) and its round-off size
    Σ_b abs(ke_ab) (abs(q0_b) + abs(q1_b)) into wk.floor."""
    ke = wk.ke
    # row a of G_mᵀ T: the rows of T at the nonzeros of column a of G_m (innermost loop along a row: vectorized)
    for a in range(NLOC):
        for b in range(NLOC):
            ke[a, b] = 0.0
        for u in range(_G_COUNT[a]):
            k = _G_ROWS[a, u]
            c = Gm[k, a]
            for b in range(NLOC):
                ke[a, b] += c * T[k, b]
    _add_invariant_hessians(ke, r, 0.5, h)
    base = e * NLOC * NLOC
    scatter_element(ke, kd.map_el[base:base + NLOC * NLOC].reshape((NLOC, NLOC)), kd.ed[e], q0, q1, wk.data,
                    wk.floor)


def discrete_gradient_terms(kd, qa, qb, residual):
    """(ok, g (n,), data (nnz,) of ∂g/∂q_b on the CSR pattern, floor (n,)): :func:`discrete_gradient_terms_into`
    on a new work, its results copied out; ``residual``: data empty and floor zero."""
    wk = rotation_work(kd)
    ok = discrete_gradient_terms_into(kd, wk, np.ascontiguousarray(qa, dtype=float),
                                      np.ascontiguousarray(qb, dtype=float), residual)
    return bool(ok), wk.g.copy(), np.zeros(0) if residual else wk.data.copy(), wk.floor.copy()
