r"""The Newton matrix as kernels write it: free coordinates first, then the multipliers (nx rows).

Two storages, fixed once per scene (:func:`skfem_flex.compiled.pack.pack`): dense (entry (i, j) at
``mat[i·nx + j]``) up to :data:`DENSE_STORAGE_LIMIT` rows, and above that the values of the matrix's
fixed sparsity pattern (CSR; entry (i, j) found by a binary search of row i). A value written outside
the pattern is counted in ``ctx.missed`` and the step is handed back, never silently dropped.

Kernels address the matrix by *coordinate* (global index among all n coordinates; prescribed ones
have no column and are skipped) and by constraint *row* (0 … m − 1):

* :func:`add_qq` — ∂(coordinate row i)/∂(coordinate j),
* :func:`add_qm` — ∂(coordinate row i)/∂μ_row (the border column, Dᵀ),
* :func:`add_mq` — ∂(constraint row)/∂(coordinate j) (the border row).

A family that writes many entries on a large CSR matrix finds their places once, when the scene is packed
(:func:`positions`, from a family's ``finish``), and adds by place (:func:`add_pos`) instead of searching.
"""
from __future__ import annotations

import numba
import numpy as np

from .abi import fvec, ivec

__all__ = ["DENSE", "CSR", "storage_of", "add_qq", "add_qm", "add_mq", "add_at", "add_pos", "positions", "slot",
           "scale_row", "clear"]

DENSE, CSR = 0, 1


@numba.njit(cache=True, _nrt=False)
def storage_of(ctx):
    """The context's Newton matrix as a tuple (mat: values, fpos: free position of each coordinate, −1
    for a prescribed one, kind: DENSE or CSR, nx, nf, ptr and idx: the CSR pattern, unused when dense)."""
    nx = ctx.nx
    if ctx.storage == DENSE:
        mat = fvec(ctx.mat, nx * nx)
        ptr = ivec(ctx.fpos, 1)
        idx = ivec(ctx.fpos, 1)
    else:
        ptr = ivec(ctx.csr_ptr, nx + 1)
        idx = ivec(ctx.csr_idx, ptr[nx])
        mat = fvec(ctx.mat, ptr[nx])
    return mat, ivec(ctx.fpos, ctx.n), ctx.storage, nx, ctx.nf, ptr, idx


@numba.njit(cache=True, _nrt=False)
def slot(s, i, j):
    """Position of entry (i, j) (bordered indices) in the values, or −1 outside a CSR pattern."""
    mat, fpos, kind, nx, nf, ptr, idx = s
    if kind == DENSE:
        return i * nx + j
    lo, hi = ptr[i], ptr[i + 1]
    while lo < hi:
        mid = (lo + hi) >> 1
        c = idx[mid]
        if c < j:
            lo = mid + 1
        elif c > j:
            hi = mid
        else:
            return mid
    return -1


@numba.njit(cache=True, _nrt=False)
def add_at(ctx, s, i, j, val):
    """Add ``val`` at bordered indices (i, j); a nonzero value outside the pattern is counted."""
    k = slot(s, i, j)
    if k >= 0:
        s[0][k] += val
    elif val != 0.0:
        ctx.missed += 1


@numba.njit(cache=True, _nrt=False)
def add_pos(s, k, val):
    """Add ``val`` at place ``k`` of the values (from :func:`positions`; −1: a prescribed row or column,
    skipped)."""
    if k >= 0:
        s[0][k] += val


def positions(layout, i, j):
    """The places in the Newton matrix's values of the entries at bordered indices (i[t], j[t]) (free
    positions, then nf + constraint row): i·nx + j (dense) or the entry's slot in the pattern (CSR); −1 where
    i or j is negative (a prescribed coordinate).

    Parameters
    ----------
    layout : tuple
        (storage kind, scipy CSR pattern of the bordered Newton matrix, fpos, nx) (:mod:`.pack`).
    i, j : array_like of int

    Raises
    ------
    AssertionError
        If an entry lies outside the pattern (the family declared a coupling it does not write).
    """
    kind, pattern, _, nx = layout
    i, j = np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64)
    ok = (i >= 0) & (j >= 0)
    pos = -np.ones(i.size, dtype=np.int64)
    want = i[ok] * np.int64(nx) + j[ok]
    if kind == DENSE:
        pos[ok] = want
        return pos
    # the pattern's entries as sorted keys row·nx + column (rows in order, sorted columns in each)
    keys = np.repeat(np.arange(nx, dtype=np.int64), np.diff(pattern.indptr)) * np.int64(nx) + pattern.indices
    where = np.searchsorted(keys, want)
    if want.size and (where.max() >= keys.size or np.any(keys[where] != want)):
        raise AssertionError("an entry a family writes lies outside the scene's Newton pattern")
    pos[ok] = where
    return pos


@numba.njit(cache=True, _nrt=False)
def add_qq(ctx, s, i, j, val):
    """Add ``val`` to ∂r_i/∂Δq_j (coordinates i, j; skipped where either is prescribed)."""
    fpos = s[1]
    a, b = fpos[i], fpos[j]
    if a >= 0 and b >= 0:
        add_at(ctx, s, a, b, val)


@numba.njit(cache=True, _nrt=False)
def add_qm(ctx, s, i, row, val):
    """Add ``val`` to ∂r_i/∂μ_row (coordinate i, constraint row)."""
    a = s[1][i]
    if a >= 0:
        add_at(ctx, s, a, s[4] + row, val)


@numba.njit(cache=True, _nrt=False)
def add_mq(ctx, s, row, j, val):
    """Add ``val`` to ∂c_row/∂Δq_j (constraint row, coordinate j)."""
    b = s[1][j]
    if b >= 0:
        add_at(ctx, s, s[4] + row, b, val)


@numba.njit(cache=True, _nrt=False)
def scale_row(s, i, factor):
    """Multiply bordered row i of the matrix by ``factor``."""
    mat, fpos, kind, nx, nf, ptr, idx = s
    if kind == DENSE:
        for j in range(nx):
            mat[i * nx + j] *= factor
    else:
        for t in range(ptr[i], ptr[i + 1]):
            mat[t] *= factor


@numba.njit(cache=True, _nrt=False)
def clear(s):
    """Zero every stored value."""
    mat = s[0]
    for k in range(mat.size):
        mat[k] = 0.0
