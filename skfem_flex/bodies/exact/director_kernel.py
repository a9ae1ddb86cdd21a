r"""Compiled (Numba) strain energy and discrete gradient of a :class:`~.spatial_body.SpatialExactBeam`.

The compiled copy of :class:`~.director_strain.DirectorStrainPoints`' ``energy`` and
``discrete_gradient``, held to them by ``tests/test_spatial_beam.py``: per element e and strain point p,
each strain e_j = ½ q_eᵀ H_j q_e − e⁰_j, the section force s_j = ½ C_j (e_j(q_a) + e_j(q_b)), and

.. math::

    g_e = Σ_p w_p Σ_j s_j H_j q_m, \qquad
    ∂g_e/∂q_b = ½ Σ_p w_p Σ_j (C_j (H_j q_m)(H_j q_b)ᵀ + s_j H_j),

with q_m = (q_a + q_b)/2; at q_a = q_b these are the gradient and half the Hessian. The arrays come from
:func:`pack` once (``SpatialExactBeam.compiled_strain_data()``):

* ``ed`` (n_el, 12k): the element's coordinates; the strains' constant second derivatives, each
  H_j = Σ h (e_A e_Bᵀ ⊗ I₃) over a few pairs of the element's 3-vectors A, B (a director and φ', or two
  directors): ``h_ptr`` (n_el n_p 6 + 1) into ``h_a``, ``h_b``, ``h_v``; ``W`` (n_el, n_p): the weights (m);
  ``C`` (6,): the stiffnesses;
  ``e_ref`` (raveled (n_el, n_p, 6)): the reference strains;
* the CSR pattern ``pat_ptr``, ``pat_idx`` of the body's tangent (the union of its element blocks) and
  ``map_el`` (raveled (n_el, 12k, 12k)): the position in the pattern's data of every element entry.
"""
from __future__ import annotations

from collections import namedtuple

import numba
import numpy as np

__all__ = ["DirectorKernelData", "pack", "potential_energy", "discrete_gradient_terms", "scatter_element"]

DirectorKernelData = namedtuple("DirectorKernelData", ["n", "ed", "h_ptr", "h_a", "h_b", "h_v", "W", "C", "e_ref",
                                                       "pat_ptr", "pat_idx", "map_el"])


def pack(strain_points):
    """The kernel data of a :class:`~.director_strain.DirectorStrainPoints`."""
    sp = strain_points
    n, ed = sp.n_dofs, np.ascontiguousarray(sp.ed, dtype=np.int64)
    ne, nloc = ed.shape
    rows = np.broadcast_to(ed[:, :, None], (ne, nloc, nloc)).ravel()
    cols = np.broadcast_to(ed[:, None, :], (ne, nloc, nloc)).ravel()
    uniq, inv = np.unique(rows * n + cols, return_inverse=True)
    pat_idx = np.ascontiguousarray(uniq % n, dtype=np.int64)
    pat_ptr = np.ascontiguousarray(np.searchsorted(uniq // n, np.arange(n + 1)), dtype=np.int64)
    # H_j's 3 × 3 blocks are multiples of I₃: keep the block entries h of the vector pairs (A, B)
    blocks = np.asarray(sp.H)[..., 0::3, 0::3].reshape(-1, nloc // 3, nloc // 3)       # (n_el n_p 6, 4k, 4k)
    which, a, b = np.nonzero(blocks)
    h_ptr = np.searchsorted(which, np.arange(blocks.shape[0] + 1)).astype(np.int64)
    return DirectorKernelData(
        np.array([n], dtype=np.int64), ed, h_ptr, a.astype(np.int64), b.astype(np.int64),
        np.ascontiguousarray(blocks[which, a, b], dtype=float), np.ascontiguousarray(sp.W, dtype=float),
        np.ascontiguousarray(sp.C, dtype=float), np.ascontiguousarray(sp.e_reference, dtype=float).ravel(),
        pat_ptr, pat_idx, np.ascontiguousarray(inv, dtype=np.int64))


@numba.njit(cache=True)
def _shape(kd):
    ne, nloc = kd.ed.shape
    npnt = kd.W.shape[1]
    return ne, npnt, nloc


@numba.njit(cache=True)
def _apply(kd, k, x, out):
    """out = H_k x for the element vector x (H_k: the k-th strain's block entries, ``kd.h_ptr[k]``…)."""
    out[:] = 0.0
    for t in range(kd.h_ptr[k], kd.h_ptr[k + 1]):
        a, b, h = 3 * kd.h_a[t], 3 * kd.h_b[t], kd.h_v[t]
        out[a] += h * x[b]
        out[a + 1] += h * x[b + 1]
        out[a + 2] += h * x[b + 2]


@numba.njit(cache=True)
def potential_energy(kd, q):
    """V(q) = ½ Σ_p w_p Σ_j C_j e_j², J."""
    ne, npnt, nloc = _shape(kd)
    eref = kd.e_ref.reshape(ne, npnt, 6)
    qe, hq = np.empty(nloc), np.empty(nloc)
    v = 0.0
    for e in range(ne):
        for a in range(nloc):
            qe[a] = q[kd.ed[e, a]]
        for p in range(npnt):
            for j in range(6):
                _apply(kd, (e * npnt + p) * 6 + j, qe, hq)
                ej = 0.5 * np.dot(qe, hq) - eref[e, p, j]
                v += 0.5 * kd.W[e, p] * kd.C[j] * ej * ej
    return v


@numba.njit(cache=True)
def discrete_gradient_terms(kd, qa, qb, residual):
    """(g (n,), data (nnz,) of ∂g/∂q_b on the CSR pattern, floor (n,)): the module docstring's terms; the
    floor is Σ_b abs(∂g_a/∂q_b) (abs(q_a,b) + abs(q_b,b)), the round-off size of g. ``residual``: g alone
    (the same numbers), data empty and floor zero (the element matrices, most of the work, are skipped)."""
    n = kd.n[0]
    ne, npnt, nloc = _shape(kd)
    eref = kd.e_ref.reshape(ne, npnt, 6)
    mp = kd.map_el.reshape(ne, nloc, nloc)
    g = np.zeros(n)
    data = np.zeros(0 if residual else kd.pat_idx.size)
    floor = np.zeros(n)
    q0, q1, qm, h0 = np.empty(nloc), np.empty(nloc), np.empty(nloc), np.empty(nloc)
    hm, h1 = np.empty((6, nloc)), np.empty((6, nloc))
    s = np.empty(6)
    ke = np.empty((nloc, nloc))
    for e in range(ne):
        for a in range(nloc):
            q0[a] = qa[kd.ed[e, a]]
            q1[a] = qb[kd.ed[e, a]]
            qm[a] = 0.5 * (q0[a] + q1[a])
        ke[:, :] = 0.0
        for p in range(npnt):
            w = kd.W[e, p]
            for j in range(6):
                k = (e * npnt + p) * 6 + j
                _apply(kd, k, q0, h0)
                _apply(kd, k, q1, h1[j])
                _apply(kd, k, qm, hm[j])
                s[j] = 0.5 * kd.C[j] * (0.5 * np.dot(q0, h0) + 0.5 * np.dot(q1, h1[j]) - 2.0 * eref[e, p, j])
                for a in range(nloc):
                    g[kd.ed[e, a]] += w * s[j] * hm[j, a]
                if residual:
                    continue
                # ½ w s_j H_j: the block entries times I₃
                for t in range(kd.h_ptr[k], kd.h_ptr[k + 1]):
                    a3, b3, hv = 3 * kd.h_a[t], 3 * kd.h_b[t], 0.5 * w * s[j] * kd.h_v[t]
                    ke[a3, b3] += hv
                    ke[a3 + 1, b3 + 1] += hv
                    ke[a3 + 2, b3 + 2] += hv
            for a in range(nloc if not residual else 0):
                for b in range(nloc):
                    t = 0.0
                    for j in range(6):
                        t += kd.C[j] * hm[j, a] * h1[j, b]
                    ke[a, b] += 0.5 * w * t
        if not residual:
            scatter_element(ke, mp[e], kd.ed[e], q0, q1, data, floor)
    return g, data, floor


@numba.njit(cache=True, _nrt=False)
def scatter_element(ke, positions, coords, q0, q1, data, floor):
    """Add an element's tangent ``ke`` into the body's CSR ``data`` (``positions[a, b]``: each entry's slot) and
    its round-off size Σ_b abs(ke_ab) (abs(q0_b) + abs(q1_b)) into ``floor`` at the element's ``coords``. Both
    exact-beam kernels use it; compiled without reference counting (it returns nothing), so the rotation
    kernel's allocation-free evaluation calls it too."""
    nloc = ke.shape[0]
    for a in range(nloc):
        fa = 0.0
        for b in range(nloc):
            data[positions[a, b]] += ke[a, b]
            fa += abs(ke[a, b]) * (abs(q0[b]) + abs(q1[b]))
        floor[coords[a]] += fa
