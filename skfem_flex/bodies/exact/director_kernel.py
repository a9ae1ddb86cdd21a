r"""Compiled (Numba) strain energy and discrete gradient of a :class:`~.spatial_body.SpatialExactBeam`.

The compiled copy of :class:`~.director_strain.DirectorStrainPoints`' ``energy`` and
``discrete_gradient``, held to them by ``tests/test_spatial_beam.py``: per element e and strain point p,
each strain e_j = ½ q_eᵀ H_j q_e − e⁰_j, the section force s_j = ½ C_j (e_j(q_a) + e_j(q_b)), and

.. math::

    g_e = Σ_p w_p Σ_j s_j H_j q_m, \qquad
    ∂g_e/∂q_b = ½ Σ_p w_p Σ_j (C_j (H_j q_m)(H_j q_b)ᵀ + s_j H_j),

with q_m = (q_a + q_b)/2; at q_a = q_b these are the gradient and half the Hessian. The arrays come from
:func:`pack` once (``SpatialExactBeam.compiled_strain_data()``):

* ``ed`` (n_el, 12k): the element's coordinates; ``H`` (raveled (n_el, n_p, 6, 12k, 12k)): the strains'
  constant second derivatives; ``W`` (n_el, n_p): the weights (m); ``C`` (6,): the stiffnesses;
  ``e_ref`` (raveled (n_el, n_p, 6)): the reference strains;
* the CSR pattern ``pat_ptr``, ``pat_idx`` of the body's tangent (the union of its element blocks) and
  ``map_el`` (raveled (n_el, 12k, 12k)): the position in the pattern's data of every element entry.
"""
from __future__ import annotations

from collections import namedtuple

import numba
import numpy as np

__all__ = ["DirectorKernelData", "pack", "potential_energy", "discrete_gradient_terms"]

DirectorKernelData = namedtuple("DirectorKernelData", ["n", "ed", "H", "W", "C", "e_ref", "pat_ptr", "pat_idx",
                                                       "map_el"])


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
    return DirectorKernelData(
        np.array([n], dtype=np.int64), ed, np.ascontiguousarray(sp.H, dtype=float).ravel(),
        np.ascontiguousarray(sp.W, dtype=float), np.ascontiguousarray(sp.C, dtype=float),
        np.ascontiguousarray(sp.e_reference, dtype=float).ravel(), pat_ptr, pat_idx,
        np.ascontiguousarray(inv, dtype=np.int64))


@numba.njit(cache=True)
def _shape(kd):
    ne, nloc = kd.ed.shape
    npnt = kd.W.shape[1]
    return ne, npnt, nloc


@numba.njit(cache=True)
def potential_energy(kd, q):
    """V(q) = ½ Σ_p w_p Σ_j C_j e_j², J."""
    ne, npnt, nloc = _shape(kd)
    H = kd.H.reshape(ne, npnt, 6, nloc, nloc)
    eref = kd.e_ref.reshape(ne, npnt, 6)
    qe = np.empty(nloc)
    v = 0.0
    for e in range(ne):
        for a in range(nloc):
            qe[a] = q[kd.ed[e, a]]
        for p in range(npnt):
            for j in range(6):
                s = 0.0
                for a in range(nloc):
                    row = 0.0
                    for b in range(nloc):
                        row += H[e, p, j, a, b] * qe[b]
                    s += qe[a] * row
                ej = 0.5 * s - eref[e, p, j]
                v += 0.5 * kd.W[e, p] * kd.C[j] * ej * ej
    return v


@numba.njit(cache=True)
def discrete_gradient_terms(kd, qa, qb):
    """(g (n,), data (nnz,) of ∂g/∂q_b on the CSR pattern, floor (n,)): the module docstring's terms; the
    floor is Σ_b abs(∂g_a/∂q_b) (abs(q_a,b) + abs(q_b,b)), the round-off size of g."""
    n = kd.n[0]
    ne, npnt, nloc = _shape(kd)
    H = kd.H.reshape(ne, npnt, 6, nloc, nloc)
    eref = kd.e_ref.reshape(ne, npnt, 6)
    mp = kd.map_el.reshape(ne, nloc, nloc)
    g = np.zeros(n)
    data = np.zeros(kd.pat_idx.size)
    floor = np.zeros(n)
    q0, q1, qm = np.empty(nloc), np.empty(nloc), np.empty(nloc)
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
                e0 = 0.0
                e1 = 0.0
                for a in range(nloc):
                    r0 = 0.0
                    r1 = 0.0
                    rm = 0.0
                    for b in range(nloc):
                        h = H[e, p, j, a, b]
                        r0 += h * q0[b]
                        r1 += h * q1[b]
                        rm += h * qm[b]
                    e0 += q0[a] * r0
                    e1 += q1[a] * r1
                    hm[j, a] = rm
                    h1[j, a] = r1
                s[j] = 0.5 * kd.C[j] * (0.5 * e0 + 0.5 * e1 - 2.0 * eref[e, p, j])
                for a in range(nloc):
                    g[kd.ed[e, a]] += w * s[j] * hm[j, a]
            for a in range(nloc):
                for b in range(nloc):
                    t = 0.0
                    for j in range(6):
                        t += kd.C[j] * hm[j, a] * h1[j, b] + s[j] * H[e, p, j, a, b]
                    ke[a, b] += 0.5 * w * t
        for a in range(nloc):
            fa = 0.0
            for b in range(nloc):
                data[mp[e, a, b]] += ke[a, b]
                fa += abs(ke[a, b]) * (abs(q0[b]) + abs(q1[b]))
            floor[kd.ed[e, a]] += fa
    return g, data, floor
