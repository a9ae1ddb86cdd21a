"""Plans of a solve as a band with a dense border: which coordinates form the border, which the band.

One rule chooses the border (:func:`choose_border`): coordinates without a diagonal entry (Lagrange
multipliers) and, greedily, few coordinates that cover every entry far from the diagonal (a floating
frame's coordinates); the rest, the interior, keep their order and must form a band of at most
:data:`MAX_BANDWIDTH`. The sparse solver (:mod:`skfem_flex.numerics.linear_solver`) uses it for sparse
matrices; :func:`dense_bordered_plan` and :func:`reordered_band_plan` plan the compiled kernels of
:mod:`skfem_flex.numerics.band_kernels` once per sparsity pattern of a scene's Newton matrix.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

__all__ = ["plan_work", "solve_work", "MAX_BANDWIDTH", "MAX_BORDER", "MIN_DENSE_BORDERED", "DENSE_BORDERED_GAIN", "MAX_THRESHOLDS",
           "choose_border", "interior_band", "dense_bordered_plan", "reordered_band_plan"]


#: a sparse system is solved as a banded one (LAPACK gbsv) when its bandwidth l + u is at most this
MAX_BANDWIDTH = 64


#: most coordinates a bordered band solve puts in its dense border (frame coordinates, multipliers)
MAX_BORDER = 128


def choose_border(rows, cols, no_diagonal, far, max_border):
    """The border of a bordered band solve: which coordinates are solved densely (the one rule).

    Coordinates without a diagonal entry (Lagrange multipliers) cannot be pivots of the band, so
    they start the border. To them are added few coordinates that cover every far entry, one
    (i, j) with |i − j| > ``far``: greedily, the coordinate in most uncovered far entries first.
    A frame coordinate's column is far from most elastic rows, so it is taken, not those rows.

    Parameters
    ----------
    rows, cols : ndarray of int
        Row and column of every structural nonzero.
    no_diagonal : ndarray of bool, shape (n,)
        True where the diagonal entry is missing (or zero); the start of the border. Not modified.
    far : int
        Entries with |i − j| > ``far`` must have their row or column in the border.
    max_border : int
        Give up (return None) when the border already holds this many coordinates and a far
        entry is still uncovered.

    Returns
    -------
    ndarray of bool or None
        The border mask, shape (n,), or None if covering needs more than ``max_border``.
    """
    n = no_diagonal.size
    border = np.array(no_diagonal, dtype=bool)
    outside = np.abs(rows - cols) > far
    fr, fc = rows[outside], cols[outside]
    while fr.size:
        if border.sum() >= max_border:
            return None
        worst = int(np.argmax(np.bincount(fr, minlength=n) + np.bincount(fc, minlength=n)))
        border[worst] = True
        keep = (fr != worst) & (fc != worst)
        fr, fc = fr[keep], fc[keep]
    return border


def interior_band(rows, cols, border):
    """(interior, lo, up): the coordinates not in ``border`` (in order) and their band's widths."""
    interior = np.flatnonzero(~border)
    pos = np.full(border.size, -1, dtype=np.int64)
    pos[interior] = np.arange(interior.size)
    inner = ~border[rows] & ~border[cols]
    off = pos[cols[inner]] - pos[rows[inner]]
    return interior, int(max(0, -off.min(initial=0))), int(max(0, off.max(initial=0)))


#: :func:`dense_bordered_plan` leaves matrices smaller than this to dense LU
MIN_DENSE_BORDERED = 12
#: ... and asks the modeled work of a bordered band solve to be this many times below dense LU's.
#: The model counts multiply-adds only, which understates dense LU on small matrices (LAPACK's
#: overheads): on the flexible pendulum's Newton matrices (bands 4 + 4, 5 border coordinates)
#: the measured speed-up is 2.3× at n = 23, where the modeled ratio is 1.3, and 4× at n = 53.
DENSE_BORDERED_GAIN = 1.0


def _bordered_band_work(ni, k, lo, up):
    """Multiply-adds of :func:`~skfem_flex.numerics.band_kernels.bordered_band_solve` for ni interior and k
    border coordinates.

    Counted with the worst pivoting fill (U's bandwidth lo + up) and every border column
    coupled to the interior: band LU ni·lo·(lo + up), its forward and back solve of the k + 1
    right-hand sides, the Schur complement k·(k + 1)·ni, its LU k³/3 and x_I ni·k. The dense
    backward-error check (2n²) is not included.
    """
    return (ni * lo * (lo + up) + (k + 1) * ni * (2 * lo + up) + k * (k + 1) * ni + k ** 3 / 3.0
            + ni * k)


def plan_work(plan):
    """Modeled multiply-adds of the bordered band solve with ``plan`` = (interior, border, lo, up) (the
    work model :func:`dense_bordered_plan` chooses by); lets a caller compare two plans of one matrix."""
    interior, border, lo, up = plan
    return _bordered_band_work(len(interior), len(border), lo, up)


def solve_work(n, plan=None, dense_storage=True):
    """Modeled multiply-adds of one solve of n unknowns: dense LU and its solve (n³/3 + n²) without a
    ``plan``, else :func:`plan_work` and, on dense storage, the dense backward-error check (2n²)."""
    if plan is None:
        return n ** 3 / 3.0 + n * n
    return plan_work(plan) + (2.0 * n * n if dense_storage else 0.0)


#: most thresholds :func:`dense_bordered_plan` tries (each costs a pass over the pattern)
MAX_THRESHOLDS = 256


def dense_bordered_plan(pattern, far=None, max_border=None):
    """Plan of :func:`~skfem_flex.numerics.band_kernels.bordered_band_solve` for dense matrices with the
    nonzeros ``pattern``, or None.

    The border is chosen by the rule of the sparse solver (``skfem_flex.numerics.linear_solver``):
    coordinates without a diagonal entry (Lagrange multipliers) and, chosen greedily, few
    coordinates that cover every entry farther than ``far`` from the diagonal (a floating
    frame's coordinates). The rest, the interior, keep their order and form a band.

    What counts as far must scale with the matrix: the sparse solver's ``MAX_BANDWIDTH // 2``
    (32) is right for large meshes, but a 30 × 30 Newton matrix has no entry that far, and
    its frame columns would stay in the interior, whose band would then be the whole matrix.
    So by default every threshold (every distance |i − j| that occurs; above
    :data:`MAX_THRESHOLDS` of them a geometric sample, dense near the diagonal) is tried and the one
    whose plan has the least modeled work (:func:`_bordered_band_work`) is kept; the largest
    such threshold on ties. For a floating beam the result is flat over a wide range of
    thresholds: any one above the elastic band's half-width and below the beam's length puts
    exactly the frame coordinates into the border.

    Parameters
    ----------
    pattern : array_like of bool or scipy sparse matrix, shape (n, n)
        The structural nonzeros: the union of ``mat != 0`` over several evaluations (states
        where an entry happens to vanish must not drop it). An entry of the interior block
        outside the band found here is not read by the solve; it shows up in the solve's
        backward-error check (``ok`` False), never as a silently wrong solution.
    far : int, optional
        Use this threshold instead of searching; ``MAX_BANDWIDTH // 2`` gives the border of
        the sparse solver.
    max_border : int, optional
        Most coordinates in the border; default n // 2 (the work model decides below that: a
        slider-crank's 40 × 40 matrix has 8 multipliers and 6 frame and joint coordinates in its
        border, 14 of 40, and solves 2× faster than by dense LU).

    Returns
    -------
    tuple or None
        ``(interior, border, lo, up)``: int64 arrays of the interior coordinates (ascending,
        the band's order) and border coordinates (ascending), and the lower and upper
        bandwidths of the interior block. None when n < :data:`MIN_DENSE_BORDERED`, when no
        border of at most ``max_border`` coordinates leaves a band, or when the modeled work
        of the bordered band solve, with its dense backward-error check (2n²), is not
        :data:`DENSE_BORDERED_GAIN` times below that of dense LU (n³/3 + n²).
    """
    if sps.issparse(pattern):
        pattern = sps.csr_matrix(pattern, dtype=bool)
    else:
        pattern = np.asarray(pattern, dtype=bool)
    if pattern.ndim != 2 or pattern.shape[0] != pattern.shape[1]:
        raise ValueError(f"pattern must be a square matrix, not of shape {pattern.shape}")
    n = pattern.shape[0]
    if n < MIN_DENSE_BORDERED:
        return None
    max_border = n // 2 if max_border is None else int(max_border)
    if sps.issparse(pattern):
        pattern.eliminate_zeros()
        rows, cols = pattern.nonzero()
        no_diagonal = ~np.asarray(pattern.diagonal(), dtype=bool)
    else:
        rows, cols = np.nonzero(pattern)
        no_diagonal = ~np.diagonal(pattern)
    if far is None:
        thresholds = np.unique(np.abs(rows - cols))[::-1]     # each gives another set of far entries
        if thresholds.size > MAX_THRESHOLDS:                   # large: a geometric sample, fine near the band
            pick = np.geomspace(1, thresholds.size, MAX_THRESHOLDS).astype(np.int64) - 1
            thresholds = thresholds[::-1][np.unique(pick)][::-1]
    else:
        thresholds = [int(far)]
    best, best_work = None, np.inf
    for t in thresholds:
        border = choose_border(rows, cols, no_diagonal, t, max_border)
        if border is None:
            continue
        k = int(border.sum())
        if k > max_border or k == n:
            continue
        interior, lo, up = interior_band(rows, cols, border)
        work = _bordered_band_work(interior.size, k, lo, up)
        if work < best_work:
            best, best_work = (interior.astype(np.int64), np.flatnonzero(border).astype(np.int64), lo, up), work
    if best is None or DENSE_BORDERED_GAIN * solve_work(n, best) > solve_work(n):
        return None
    return best


def reordered_band_plan(pattern, max_border=MAX_BORDER, max_bandwidth=MAX_BANDWIDTH):
    """Plan of :func:`~skfem_flex.numerics.band_kernels.bordered_band_solve` that reorders the coordinates,
    or None: the dense rows and columns (a floating frame's coordinates: more than 8 times the median
    number of entries, at least 16) form the border, and the rest, Lagrange multipliers included, is
    ordered by reverse Cuthill–McKee into a band.

    For matrices whose natural order is no band with a small border: a chain of many bodies, whose
    multipliers (no diagonal entry) would all go to the border of :func:`dense_bordered_plan` and make
    its Schur complement as large as the chain. Beside its coordinates a multiplier has a zero
    diagonal; the band LU's partial pivoting takes a coordinate's row as its pivot instead, and the
    backward-error check of the solve reports a failure.

    Parameters
    ----------
    pattern : array_like of bool or scipy sparse matrix, shape (n, n)
        The structural nonzeros.
    max_border : int
        Most coordinates in the border.
    max_bandwidth : int
        Widest band lo + up accepted.

    Returns
    -------
    tuple or None
        ``(interior, border, lo, up)`` as :func:`dense_bordered_plan` returns it (the interior in the
        band's order, not ascending), or None if the border would be larger than ``max_border`` or
        the band wider than ``max_bandwidth``.
    """
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    p = sps.csr_matrix(pattern, dtype=bool)
    n = p.shape[0]
    if p.shape != (n, n) or n == 0:
        raise ValueError(f"pattern must be a non-empty square matrix, not of shape {p.shape}")
    sym = (p + p.T).tocsr()
    degree = np.diff(sym.indptr)
    border = degree > max(8.0 * np.median(degree), 16.0)
    if border.sum() > max_border or border.all():
        return None
    rest = np.flatnonzero(~border)
    interior = rest[reverse_cuthill_mckee(sym[rest][:, rest].tocsr(), symmetric_mode=True)]
    pos = np.full(n, -1, dtype=np.int64)
    pos[interior] = np.arange(interior.size)
    rows, cols = p.nonzero()
    inner = ~border[rows] & ~border[cols]
    off = pos[cols[inner]] - pos[rows[inner]]
    lo, up = int(max(0, -off.min(initial=0))), int(max(0, off.max(initial=0)))
    if lo + up > max_bandwidth:
        return None
    return interior.astype(np.int64), np.flatnonzero(border).astype(np.int64), lo, up
