"""The package's one linear solver for Newton systems: dense, banded, bordered-band or general sparse.

A sparse matrix is solved, in this order of preference: as a band (LAPACK gbsv) when its
bandwidth is at most :data:`~skfem_flex.numerics.band_plans.MAX_BANDWIDTH`; as a band with a dense
border when a few rows and columns (a floating frame's coordinates, the multipliers with their zero
diagonal) are all that keep it from being one (band LU of the interior, dense Schur complement of
the border; accepted when its normwise backward error is below 1e-12); otherwise by SuperLU. Dense
matrices go to LAPACK gesv. The plans (which entry goes where) depend only on the sparsity
pattern and are built once per pattern.

Compiled code (:mod:`skfem_flex.compiled.solvers`) solves its Newton matrix the same way, band LU of the interior
and dense Schur complement of the border, with the plans of :mod:`skfem_flex.numerics.band_plans`
(:func:`~skfem_flex.numerics.band_plans.dense_bordered_plan`, once per pattern; the border by the
same rule, :func:`~skfem_flex.numerics.band_plans.choose_border`) and the Numba kernels of
:mod:`skfem_flex.numerics.band_kernels`.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .band_plans import MAX_BANDWIDTH, MAX_BORDER, choose_border, interior_band

__all__ = ["linear_solve", "PatternCache"]


class PatternCache:
    """Small cache of work that depends only on a sparsity pattern (and index sets).

    The time loop produces matrices with the same CSR pattern at every Newton evaluation; the
    maps that restrict them to the free coordinates or lay them out for a banded solver are
    built once per pattern and then applied as plain gathers."""

    def __init__(self, size=4):
        self.size, self.entries = size, []

    def get(self, mat, extra, build):
        for e in self.entries:
            if (e[0] == mat.shape and all(x is y for x, y in zip(e[1], extra))
                    and e[2].shape == mat.indptr.shape and e[3].shape == mat.indices.shape
                    and np.array_equal(e[2], mat.indptr) and np.array_equal(e[3], mat.indices)):
                return e[4]
        val = build()
        self.entries.insert(0, (mat.shape, extra, mat.indptr.copy(), mat.indices.copy(), val))
        del self.entries[self.size:]
        return val


_SOLVE_PLANS = PatternCache()


def _banded_plan(a):
    """(l, u, flat positions in the LAPACK band storage) for the CSR matrix ``a``, or None if wide."""
    n = a.shape[0]
    if a.shape[1] != n or n == 0:
        return None
    rows = np.repeat(np.arange(n), np.diff(a.indptr))
    off = a.indices - rows                              # j − i
    lo, up = int(max(0, -off.min())), int(max(0, off.max()))
    if lo + up > MAX_BANDWIDTH:
        return None
    return lo, up, (up - off) * n + a.indices          # ab[u + i − j, j] = a[i, j]


def _bordered_band_plan(a):
    """Plan of a solve of the CSR matrix ``a`` as a band with a small dense border, or None.

    Floating-frame bodies and joints make Newton matrices that are banded except for a few
    rows and columns (a body's frame coordinates couple to all its elastic ones; a joint's
    multiplier to a few far-apart coordinates). Those coordinates, the ones with an entry
    farther than half the band limit from the diagonal, form the border B (the rule of
    :func:`~skfem_flex.numerics.band_plans.choose_border`, shared with
    :func:`~skfem_flex.numerics.band_plans.dense_bordered_plan`); the rest, the interior I,
    keep their order and must then be banded. The plan holds the gathers that lay out A_II in
    LAPACK band storage, A_IB and A_BB dense and A_BI sparse.
    """
    n = a.shape[0]
    if a.shape[1] != n or n == 0:
        return None
    rows = np.repeat(np.arange(n), np.diff(a.indptr))
    cols = a.indices
    border = choose_border(rows, cols, a.diagonal() == 0.0, MAX_BANDWIDTH // 2, MAX_BORDER)
    if border is None:
        return None
    k = int(border.sum())
    if k == 0 or k == n:
        return None
    interior, lo, up = interior_band(rows, cols, border)
    if lo + up > MAX_BANDWIDTH:
        return None
    bidx = np.flatnonzero(border)
    pos = np.empty(n, dtype=np.int64)
    pos[interior] = np.arange(interior.size)
    pos[bidx] = np.arange(k)
    r_in, c_in = ~border[rows], ~border[cols]
    ii, ib, bi, bb = r_in & c_in, r_in & ~c_in, ~r_in & c_in, ~r_in & ~c_in
    off = pos[cols[ii]] - pos[rows[ii]]
    ni = interior.size
    band = (np.flatnonzero(ii), (up - off) * ni + pos[cols[ii]])
    dense_ib = (np.flatnonzero(ib), pos[rows[ib]] * k + pos[cols[ib]])
    dense_bb = (np.flatnonzero(bb), pos[rows[bb]] * k + pos[cols[bb]])
    take_bi = np.flatnonzero(bi)                       # CSR order: rows ascending, so B rows ascending
    bi_ptr = np.concatenate([[0], np.cumsum(np.bincount(pos[rows[bi]], minlength=k))])
    return lo, up, interior, bidx, band, dense_ib, dense_bb, (take_bi, pos[cols[bi]], bi_ptr), rows


def _bordered_band_solve(a, b, plan):
    """x with a x = b by the plan of :func:`_bordered_band_plan`: band LU of A_II, dense Schur complement."""
    lo, up, interior, bidx, band, dense_ib, dense_bb, (take_bi, bi_cols, bi_ptr), _ = plan
    ni, k = interior.size, bidx.size
    data = a.data
    ab = np.zeros((lo + up + 1, ni))
    ab.flat[band[1]] = data[band[0]]
    a_ib = np.zeros(ni * k)
    a_ib[dense_ib[1]] = data[dense_ib[0]]
    a_bb = np.zeros(k * k)
    a_bb[dense_bb[1]] = data[dense_bb[0]]
    a_bi = sps.csr_matrix((data[take_bi], bi_cols, bi_ptr), shape=(k, ni))
    rhs = np.column_stack([b[interior], a_ib.reshape(ni, k)])
    sol = sla.solve_banded((lo, up), ab, rhs, overwrite_ab=True, overwrite_b=True, check_finite=False)
    y, y_b = sol[:, 0], sol[:, 1:]
    schur = a_bb.reshape(k, k) - a_bi @ y_b
    x_b = np.linalg.solve(schur, b[bidx] - a_bi @ y)
    x = np.empty(a.shape[0])
    x[interior] = y - y_b @ x_b
    x[bidx] = x_b
    return x


def _backward_stable(a, x, b, rows, tol=1e-12):
    """True if x solves a x = b to a normwise backward error ‖a x − b‖ / (‖a‖ ‖x‖ + ‖b‖) ≤ ``tol``.

    The residual relative to ‖b‖ alone is no test for the Newton matrices of fine meshes: their
    condition grows like (L/h)⁴, and an exact-arithmetic-quality solve leaves ‖r‖/‖b‖ ≈ 1e-7 at
    10⁵ coordinates (as SuperLU does on the same matrix); the backward error stays near 1e-17.
    ``rows`` is the row index of every stored entry of ``a`` (part of the solve plan)."""
    if not np.all(np.isfinite(x)):
        return False
    row_sums = np.bincount(rows, weights=np.abs(a.data), minlength=a.shape[0])
    scale = float(row_sums.max(initial=0.0)) * _inf(x) + _inf(b)
    return _inf(a @ x - b) <= tol * max(scale, 1e-300)


def _sparse_lu_solve(a_csc, b, trans="N"):
    """Solve with SuperLU (COLAMD ordering), preferring diagonal pivots.

    Partial pivoting picks the frame coordinates' dense mass rows of a floating beam and fills
    the factors quadratically (6·10⁶ entries, 0.5 GB, for 6 000 coordinates instead of 4·10⁴),
    which made memory grow with the square of the mesh. A diagonal pivot is therefore kept
    unless another entry of its column is 1000 times larger; should that lose accuracy (residual
    above 10⁻⁸ of the right-hand side), the system is solved again with partial pivoting.
    """
    b = np.asarray(b, dtype=float)
    x = None
    for threshold in (1e-3, 1.0):
        try:
            x = spla.splu(a_csc, permc_spec="COLAMD", diag_pivot_thresh=threshold).solve(b, trans=trans)
        except RuntimeError as exc:                    # "Factor is exactly singular"
            if threshold == 1.0:
                raise np.linalg.LinAlgError(str(exc)) from None
            continue
        res = (a_csc.T @ x if trans == "T" else a_csc @ x) - b
        if np.all(np.isfinite(x)) and np.max(np.abs(res), initial=0.0) <= 1e-8 * max(np.max(np.abs(b), initial=0.0),
                                                                                     1e-300):
            break
    return x


def _solve_plan(a):
    """("band", plan), ("bordered", plan) or ("general", None): how the CSR matrix ``a`` is solved."""
    plan = _banded_plan(a)
    if plan is not None:
        return "band", plan
    plan = _bordered_band_plan(a)
    return ("bordered", plan) if plan is not None else ("general", None)


def _solve(a, b):
    if sps.issparse(a):
        if a.format != "csr":
            a = a.tocsr()
        if not a.has_canonical_format:
            a = a.copy()
            a.sum_duplicates()
        kind, plan = _SOLVE_PLANS.get(a, (), lambda: _solve_plan(a))
        x = None
        if kind == "band":                             # banded (free coordinates of a beam): LAPACK gbsv
            lo, up, pos = plan
            ab = np.zeros((lo + up + 1, a.shape[0]))
            ab.flat[pos] = a.data
            x = sla.solve_banded((lo, up), ab, b, overwrite_ab=True, check_finite=False)
        elif kind == "bordered":                       # a band with a dense border (frames, joints)
            try:
                x = _bordered_band_solve(a, np.asarray(b, dtype=float), plan)
            except np.linalg.LinAlgError:              # A_II singular on its own: general LU below
                x = None
            if x is not None and not _backward_stable(a, x, b, plan[-1]):
                x = None
        if x is None:                                  # Aᵀ of a CSR matrix is CSC without a copy
            x = _sparse_lu_solve(a.T, b, trans="T")
        if not np.all(np.isfinite(x)):
            raise np.linalg.LinAlgError("singular sparse matrix")
        return x
    return np.linalg.solve(a, b)


def linear_solve(a, b):
    """x with a x = b for a dense, banded-sparse or general sparse ``a`` (the core's one linear solver).

    Raises ``numpy.linalg.LinAlgError`` when ``a`` is singular.
    """
    return _solve(a, b)


def _inf(x):
    return float(np.abs(x).max()) if np.size(x) else 0.0
