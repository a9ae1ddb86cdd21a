r"""Where the terms of a :class:`~skfem_flex.bodies.FloatingBeam`'s matrices go, and its compiled-kernel data.

Every n × n matrix of the body (M, B, the kinetic and potential tangents, load Jacobians) is
made of the same pieces: the reference rows ``top`` (3, n), the block ``left`` (n_f, 3) below
them, multiples of the constant elastic blocks M_A, H, M_ff, K, and (Green–Lagrange strain)
element matrices of the axial kernel (``floating_strain.py``) on each element's (u, w) DOFs.

* Sparse bodies (:class:`SparsePattern`) fill one fixed CSR pattern, the union of all pieces,
  through index maps computed once, so a matrix costs one ``np.zeros`` and a few scatters (no
  COO conversion or sorting per call, which dominated the time of large bodies).
* Dense bodies compose with ``FloatingFrame.compose_matrix`` and scatter the element matrices into the
  elastic block through :class:`DenseScatter` (O(n) work, not the O(n³) of dense dεᵀ dε).
* :func:`kernel_data` packs the arrays the compiled kernels (``floating_kernel.py``) work on: the
  tangent is written as the data of the body's one CSR pattern (dense bodies use it too, and
  scatter it into their dense matrix), so every term gets its positions in that pattern here.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps

from . import kernel as _kernel

__all__ = ["SparsePattern", "sparse_pattern", "compose_sparse", "DenseScatter", "dense_scatter",
           "scatter_elements", "kernel_data"]

#: keys of the constant elastic blocks, in the order the pattern and the kernel data take them
BLOCK_KEYS = ("MA", "H", "Mff", "K")


def _element_pairs(loc):
    """Row and column elastic indices (n_el, 2 n_l, 2 n_l) of the element matrices, and the mask of the
    entries kept (both DOFs elastic; −1 = eliminated by the reference condition)."""
    lr = np.broadcast_to(loc[:, :, None], (loc.shape[0],) + (loc.shape[1],) * 2)
    lc = np.broadcast_to(loc[:, None, :], lr.shape)
    return lr, lc, (lr >= 0) & (lc >= 0)


@dataclass(frozen=True, eq=False)
class SparsePattern:
    """The one CSR pattern of every matrix of a sparse body, and the position of each term in its data.

    Attributes
    ----------
    n : int
        Body coordinates.
    indptr, indices : ndarray of int32
        The CSR pattern.
    nnz : int
        Stored entries.
    map_top, map_left : ndarray of int
        Positions of ``top.ravel()`` (3 n) and ``left.ravel()`` (n_f × 3).
    map_ff, ff_data : dict
        For each block key (``BLOCK_KEYS``): positions and values of its canonical CSR entries.
    loc_mask : ndarray of bool (n_el, 2 n_l, 2 n_l)
        Entries of the axial element matrices that land in q_f.
    map_loc : ndarray of int
        Position of each kept element-matrix entry (duplicates summed with ``bincount``).
    """

    n: int
    indptr: np.ndarray
    indices: np.ndarray
    nnz: int
    map_top: np.ndarray
    map_left: np.ndarray
    map_ff: dict
    ff_data: dict
    loc_mask: np.ndarray
    map_loc: np.ndarray


def sparse_pattern(n, nf, blocks, loc):
    """The :class:`SparsePattern` of a body with ``n`` coordinates, ``nf`` elastic.

    Parameters
    ----------
    blocks : dict
        The constant elastic blocks by key (``BLOCK_KEYS``), sparse or dense (n_f, n_f).
    loc : ndarray of int (n_el, 2 n_l)
        ``AxialQuadrature.loc``.
    """
    rows, cols = [], []
    r, c = np.divmod(np.arange(3 * n), n)
    rows.append(r), cols.append(c)
    r, c = np.divmod(np.arange(nf * 3), 3)
    rows.append(r + 3), cols.append(c)
    ff_data = {}
    ff_keys = {}
    for key in BLOCK_KEYS:
        X = sps.csr_matrix(blocks[key], copy=True)
        X.sum_duplicates()
        X.sort_indices()
        xc = X.tocoo()
        ff_data[key] = X.data.copy()
        # flat keys row·n + col exceed int32 (scipy's index type) beyond 46 340 coordinates
        xr, xcol = xc.row.astype(np.int64), xc.col.astype(np.int64)
        ff_keys[key] = (xr + 3) * n + xcol + 3
        rows.append(xr + 3), cols.append(xcol + 3)
    lr, lc, loc_mask = _element_pairs(loc)
    loc_keys = (lr[loc_mask].astype(np.int64) + 3) * n + lc[loc_mask] + 3
    keys = np.unique(np.concatenate([np.asarray(r) * n + np.asarray(c) for r, c in zip(rows, cols)]
                                    + [loc_keys]))
    prow, pcol = np.divmod(keys, n)
    r, c = np.divmod(np.arange(nf * 3), 3)
    return SparsePattern(n=n, indptr=np.searchsorted(prow, np.arange(n + 1)).astype(np.int32),
                         indices=pcol.astype(np.int32), nnz=keys.size,
                         map_top=np.searchsorted(keys, np.arange(3 * n)),
                         map_left=np.searchsorted(keys, (r + 3) * n + c),
                         map_ff={k: np.searchsorted(keys, v) for k, v in ff_keys.items()}, ff_data=ff_data,
                         loc_mask=loc_mask, map_loc=np.searchsorted(keys, loc_keys))


def compose_sparse(pat, top, left, terms=(), loc=None):
    """n × n CSR matrix in the pattern ``pat`` from its pieces (module docstring).

    Parameters
    ----------
    top : ndarray (3, n) or None
        Reference rows (None: zero).
    left : ndarray (n_f, 3) or None
        Block below them.
    terms : sequence of (coef, key)
        Elastic block Σ coef · X[key], key in ``BLOCK_KEYS``.
    loc : ndarray (n_el, 2 n_l, 2 n_l), optional
        Axial element matrices, added into the elastic block.
    """
    data = np.zeros(pat.nnz)
    if top is not None:
        data[pat.map_top] = top.ravel()
    if left is not None:
        data[pat.map_left] = left.ravel()
    for coef, key in terms:
        data[pat.map_ff[key]] += coef * pat.ff_data[key]
    if loc is not None:
        data += np.bincount(pat.map_loc, weights=loc[pat.loc_mask], minlength=pat.nnz)
    return sps.csr_matrix((data, pat.indices, pat.indptr), shape=(pat.n, pat.n))


@dataclass(frozen=True, eq=False)
class DenseScatter:
    """Flat positions (row · n_f + col) in the dense elastic block of the kept entries of the axial
    element matrices (``loc_mask``)."""

    nf: int
    loc_mask: np.ndarray
    loc_flat: np.ndarray


def dense_scatter(loc, nf):
    """The :class:`DenseScatter` of the element DOF map ``loc`` (``AxialQuadrature.loc``)."""
    lr, lc, mask = _element_pairs(loc)
    return DenseScatter(nf=nf, loc_mask=mask, loc_flat=lr[mask] * nf + lc[mask])


def scatter_elements(sc, mats):
    """Sum of the element matrices ``mats`` (n_el, 2 n_l, 2 n_l) as a dense (n_f, n_f) elastic block."""
    nf = sc.nf
    return np.bincount(sc.loc_flat, weights=mats[sc.loc_mask], minlength=nf * nf).reshape(nf, nf)


def kernel_data(n, nf, green, inertia, blocks, pattern, dNt, loc, wq):
    """Pack the arrays of the compiled kernels (:func:`.floating_kernel.pack`) of a FloatingBeam.

    Parameters
    ----------
    n, nf : int
        Body and elastic coordinates.
    green : bool
        Green–Lagrange axial strain (the kernel then evaluates the axial terms).
    inertia : BeamInertia
        The invariants (``floating_inertia.py``).
    blocks : dict
        The constant elastic blocks M_A, H, M_ff, K by key (as the body holds them).
    pattern : SparsePattern
        The body's pattern (:func:`sparse_pattern`, for dense bodies too: their elastic block is a band).
    dNt, loc, wq : ndarray
        ``AxialQuadrature.dNt``, ``.loc``, ``.wq``.

    Raises
    ------
    RuntimeError
        If a term falls outside the pattern (a bug in :func:`sparse_pattern`, not bad input).
    """
    ptr, idx = pattern.indptr, pattern.indices
    keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(ptr)) * n + idx   # row-major keys of the pattern

    def at(flat):
        pos = np.searchsorted(keys, flat)
        if flat.size and not np.array_equal(keys[np.minimum(pos, keys.size - 1)], flat):
            raise RuntimeError("FloatingBeam: a kernel term lies outside the matrix pattern")
        return pos
    maps = {"top": at(np.arange(3 * n))}
    r, c = np.divmod(np.arange(nf * 3), 3)
    maps["left"] = at((r + 3) * n + c)
    for key, mat in blocks.items():
        ptr_b, idx_b, _ = _kernel.csr_parts(mat)
        rows_b = np.repeat(np.arange(nf, dtype=np.int64), np.diff(ptr_b))
        maps[key] = at((rows_b + 3) * n + idx_b + 3)
    lr, lc, keep = _element_pairs(loc)
    map_loc = -np.ones(lr.shape, dtype=np.int64)
    map_loc[keep] = at((lr[keep].astype(np.int64) + 3) * n + lc[keep] + 3)
    return _kernel.pack(n, nf, green, inertia.mass, inertia.S0, inertia.I0, inertia.Sbar, inertia.c,
                        inertia.k0n, blocks, (ptr, idx), maps, dNt, loc, wq, map_loc)
