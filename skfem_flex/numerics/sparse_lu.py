r"""Sparse LU with pivots fixed in advance, for the compiled time loop: the plan and the kernel.

A Newton matrix keeps its sparsity pattern for a whole run, and its values change smoothly from one
iteration to the next. So the costly choices of a sparse factorization — a fill-reducing column order
and the pivot rows — are made once, by SuperLU on one evaluated matrix (:func:`static_lu_plan`); every
solve of the loop then refactorizes numerically on the fixed structure (:func:`static_lu_solve`),
without searching for pivots. It pays on the closed loops of rigid bodies (a spatial slider–crank: 71
unknowns, 622 entries; the band of :mod:`.band_plans` needs a border of all 35 multipliers there and
does 30 times the multiply-adds).

With the rows and columns permuted, B = P A Q = L U is factorized row by row (Doolittle, each row's
pattern the closure of its entries under the rows above: the symbolic factorization of the plan):

.. math::

    l_{ik} = \Bigl(b_{ik} - \sum_{j<k} l_{ij} u_{jk}\Bigr) / u_{kk}\ (k < i),\qquad
    u_{ik} = b_{ik} - \sum_{j<i} l_{ij} u_{jk}\ (k \ge i),

then L z = P r, U w = z and x = Q w. Pivots fixed in advance can fail on a later matrix: a zero or
non-finite pivot makes the kernel answer False, and its caller solves another way (the loop's solver
kernel, :mod:`skfem_flex.compiled.solvers`, also checks the backward error of every solution).
"""
from __future__ import annotations

import heapq
from typing import NamedTuple

import numba
import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

__all__ = ["StaticLUPlan", "static_lu_plan", "static_lu_solve", "modeled_seconds", "MAX_UNKNOWNS", "ORDERINGS"]

#: the plan's symbolic factorization runs in Python: above this many unknowns it is not tried (the
#: band plans serve long chains and meshes better anyway)
MAX_UNKNOWNS = 2000
#: SuperLU's column orderings tried; the plan with the least modeled time is kept
ORDERINGS = ("MMD_ATA", "COLAMD", "MMD_AT_PLUS_A")
#: modeled cost of the kernel: per multiply-add of the elimination, per entry of L + U, and per call, s; a fit
#: to the Newton matrices of seven scenes (33 to 460 unknowns), within 15 % of each, measured by
#: ``python examples/calibrate_dense_solve.py`` (the earlier 1.5e-9, 6e-9, 1e-6 overestimated every one of them
#: 1.7 to 2.4 times)
SECONDS_PER_UPDATE, SECONDS_PER_ENTRY, SECONDS_PER_CALL = 1.0e-9, 2.5e-9, 3e-7


class StaticLUPlan(NamedTuple):
    """The structure of B = P A Q = L U (int64 arrays; n unknowns, nnz entries of L + U).

    ``prow[i]``: the row of A that is row i of B; ``qcol[j]``: the column of A that is column j of B;
    ``ptr``, ``idx``: L (strictly lower) and U (upper, diagonal included) of B as one CSR structure,
    columns ascending in each row; ``diag[i]``: the position of u_ii; ``src[p]``: where entry p of B is
    stored in the matrix's values (dense: row-major index; CSR: position in the pattern), −1 for fill.
    """

    prow: np.ndarray
    qcol: np.ndarray
    ptr: np.ndarray
    idx: np.ndarray
    diag: np.ndarray
    src: np.ndarray


def _symbolic(b):
    """(ptr, idx) of L + U for the sorted CSR pattern ``b`` eliminated in order without pivoting: row i holds
    its own entries, the diagonal and, for each k < i it holds (in ascending order, including those it
    gains on the way), the entries of U's row k."""
    n = b.shape[0]
    upper = []
    ptr, idx = [0], []
    for i in range(n):
        cols = set(b.indices[b.indptr[i]:b.indptr[i + 1]].tolist())
        cols.add(i)
        heap = [c for c in cols if c < i]
        heapq.heapify(heap)
        done = set()
        while heap:
            k = heapq.heappop(heap)
            if k in done:
                continue
            done.add(k)
            for c in upper[k]:
                if c not in cols:
                    cols.add(c)
                    if c < i:
                        heapq.heappush(heap, c)
        row = sorted(cols)
        upper.append([c for c in row if c > i])
        idx.extend(row)
        ptr.append(len(idx))
    return np.asarray(ptr, dtype=np.int64), np.asarray(idx, dtype=np.int64)


def modeled_seconds(plan):
    """Modeled time of one :func:`static_lu_solve` with ``plan`` (s): updates, entries and the call."""
    upper = plan.ptr[1:] - plan.diag - 1            # entries of U right of the diagonal, per row
    updates = 0
    for i in range(plan.diag.size):
        updates += int(upper[plan.idx[plan.ptr[i]:plan.diag[i]]].sum())
    return SECONDS_PER_UPDATE * updates + SECONDS_PER_ENTRY * plan.idx.size + SECONDS_PER_CALL


def static_lu_plan(pattern, sample, dense_storage, budget=np.inf):
    """The plan of :func:`static_lu_solve` for matrices with the structural nonzeros ``pattern``, its pivots
    chosen by SuperLU (partial pivoting) on the values ``sample``; the ordering with the least
    :func:`modeled_seconds` of :data:`ORDERINGS`. None above :data:`MAX_UNKNOWNS` unknowns, if SuperLU finds
    the sample singular in every ordering, or if no plan models below ``budget``.

    Parameters
    ----------
    pattern : scipy.sparse matrix, shape (n, n)
        The structural nonzeros (sorted CSR when the matrices are stored as its values).
    sample : ndarray or scipy.sparse matrix, shape (n, n)
        One matrix of the kind to be solved (its entries outside ``pattern`` are ignored).
    dense_storage : bool
        The matrices are stored dense, row-major (``src`` indexes n·row + column), else as the values of
        ``pattern``'s CSR structure.
    budget : float
        Modeled time (s) a plan must stay below; an ordering whose L + U alone (SuperLU's count, before the
        symbolic factorization that costs as many Python steps as the elimination has updates) would cost
        more is not planned.

    Returns
    -------
    StaticLUPlan or None
    """
    pat = sps.csr_matrix(pattern, dtype=bool)
    pat.sort_indices()
    n = pat.shape[0]
    if pat.shape != (n, n):
        raise ValueError(f"pattern must be square, not of shape {pat.shape}")
    if n == 0 or n > MAX_UNKNOWNS:
        return None
    ones = sps.csr_matrix((np.ones(pat.nnz), pat.indices, pat.indptr), shape=(n, n))
    values = sps.csr_matrix(sample).multiply(ones).tocsr()
    scale = float(abs(values).max()) if values.nnz else 0.0
    if not (np.isfinite(scale) and scale > 0.0):
        return None
    # every structural entry takes part in the ordering (an entry zero in this sample need not be in the next),
    # the tiny ones never chosen as pivots
    a = (values + ones * (1e-30 * scale)).tocsc()
    # where each entry of A is stored: dense row-major, or its position in the pattern (+ 1: 0 is "none")
    where = sps.csr_matrix(((np.arange(pat.nnz) + 1).astype(float), pat.indices, pat.indptr), shape=(n, n))
    best, best_time = None, budget
    for order in ORDERINGS:
        try:
            lu = spla.splu(a, permc_spec=order, diag_pivot_thresh=1.0)
        except RuntimeError:                      # singular in this ordering
            continue
        if SECONDS_PER_ENTRY * (lu.L.nnz + lu.U.nnz - n) + SECONDS_PER_CALL >= best_time:
            continue
        prow = np.argsort(lu.perm_r).astype(np.int64)         # Pr A Pc = L U: B row perm_r[i] is A row i
        qcol = np.argsort(lu.perm_c).astype(np.int64)
        b = pat[prow][:, qcol].tocsr()
        b.sort_indices()
        ptr, idx = _symbolic(b)
        diag = np.array([ptr[i] + np.searchsorted(idx[ptr[i]:ptr[i + 1]], i) for i in range(n)], dtype=np.int64)
        ar, ac = prow[np.repeat(np.arange(n), np.diff(ptr))], qcol[idx]
        pos = np.asarray(where[ar, ac]).ravel().astype(np.int64) - 1
        src = np.where(pos >= 0, ar * n + ac, -1) if dense_storage else pos
        plan = StaticLUPlan(prow, qcol, ptr, idx, diag, src.astype(np.int64))
        t = modeled_seconds(plan)
        if t < best_time:
            best, best_time = plan, t
    return best


@numba.njit(cache=True, _nrt=False, fastmath={"contract"})
def static_lu_solve(vals, rhs, x, prow, qcol, ptr, idx, diag, src, lu, w, mark, z):
    """x ← A⁻¹ rhs with the plan's fixed pivots; False if a pivot is zero or not finite, or an update falls
    outside the planned structure (nothing else is checked: the caller checks the solution).

    ``vals``: the matrix's stored values (dense row-major or the pattern's CSR values, as the plan's
    ``src``); ``lu`` (nnz), ``w``, ``mark`` (int64), ``z`` (n): work arrays, ``mark`` all negative before the
    first call. Allocates nothing."""
    n = rhs.size
    for i in range(n):
        a, b = ptr[i], ptr[i + 1]
        for p in range(a, b):
            c = idx[p]
            s = src[p]
            w[c] = vals[s] if s >= 0 else 0.0
            mark[c] = i
        for p in range(a, diag[i]):
            k = idx[p]
            lik = w[k] / lu[diag[k]]
            w[k] = lik
            if lik != 0.0:
                for q in range(diag[k] + 1, ptr[k + 1]):
                    c = idx[q]
                    if mark[c] != i:
                        return False
                    w[c] -= lik * lu[q]
        for p in range(a, b):
            lu[p] = w[idx[p]]
        d = abs(lu[diag[i]])
        if not (d > 0.0 and d < np.inf):
            return False
    for i in range(n):
        s = rhs[prow[i]]
        for p in range(ptr[i], diag[i]):
            s -= lu[p] * z[idx[p]]
        z[i] = s
    for i in range(n - 1, -1, -1):
        s = z[i]
        for p in range(diag[i] + 1, ptr[i + 1]):
            s -= lu[p] * z[idx[p]]
        z[i] = s / lu[diag[i]]
    for j in range(n):
        x[qcol[j]] = z[j]
    return True
