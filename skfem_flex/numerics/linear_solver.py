"""The package's one linear solver for Newton systems: dense, banded, bordered-band or general sparse.

A sparse matrix is solved, in this order of preference: as a band (LAPACK gbsv) when its
bandwidth is at most :data:`MAX_BANDWIDTH`; as a band with a dense border when a few rows and
columns (a floating frame's coordinates, the multipliers with their zero diagonal) are all
that keep it from being one (band LU of the interior, dense Schur complement of the border;
accepted when its normwise backward error is below 1e-12); otherwise by SuperLU. Dense
matrices go to LAPACK gesv. The plans (which entry goes where) depend only on the sparsity
pattern and are built once per pattern.

Compiled code (``compiled_scene``) solves its Newton matrix the same way, band LU of the interior
and dense Schur complement of the border, with :func:`dense_bordered_plan` (once per pattern) and
the Numba kernel :func:`bordered_band_solve` (the matrix held as a dense array) or
:func:`bordered_band_solve_csr` (held as the values of a fixed CSR pattern); both share one
elimination.
"""
from __future__ import annotations

import numba
import numpy as np
from numba import uint64
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

__all__ = ["linear_solve", "PatternCache", "MAX_BANDWIDTH", "MAX_BORDER", "dense_bordered_plan",
           "reordered_band_plan", "bordered_band_solve", "bordered_band_solve_csr"]


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
#: a sparse system is solved as a banded one (LAPACK gbsv) when its bandwidth l + u is at most this
MAX_BANDWIDTH = 64


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


#: most coordinates a bordered band solve puts in its dense border (frame coordinates, multipliers)
MAX_BORDER = 128


def _choose_border(rows, cols, no_diagonal, far, max_border):
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


def _bordered_band_plan(a):
    """Plan of a solve of the CSR matrix ``a`` as a band with a small dense border, or None.

    Floating-frame bodies and joints make Newton matrices that are banded except for a few
    rows and columns (a body's frame coordinates couple to all its elastic ones; a joint's
    multiplier to a few far-apart coordinates). Those coordinates, the ones with an entry
    farther than half the band limit from the diagonal, form the border B (the rule of
    :func:`_choose_border`, shared with :func:`dense_bordered_plan`); the rest, the interior I,
    keep their order and must then be banded. The plan holds the gathers that lay out A_II in
    LAPACK band storage, A_IB and A_BB dense and A_BI sparse.
    """
    n = a.shape[0]
    if a.shape[1] != n or n == 0:
        return None
    rows = np.repeat(np.arange(n), np.diff(a.indptr))
    cols = a.indices
    border = _choose_border(rows, cols, a.diagonal() == 0.0, MAX_BANDWIDTH // 2, MAX_BORDER)
    if border is None:
        return None
    k = int(border.sum())
    if k == 0 or k == n:
        return None
    interior, lo, up = _interior_band(rows, cols, border)
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




# ----------------------------------------------------------------------------------------------
# Bordered band solve of a dense array, for compiled (Numba) code
# ----------------------------------------------------------------------------------------------

#: :func:`dense_bordered_plan` leaves matrices smaller than this to dense LU
MIN_DENSE_BORDERED = 12
#: ... and asks the modeled work of a bordered band solve to be this many times below dense LU's.
#: The model counts multiply-adds only, which understates dense LU on small matrices (LAPACK's
#: overheads): on the flexible pendulum's Newton matrices (bands 4 + 4, 5 border coordinates)
#: the measured speed-up is 2.3× at n = 23, where the modeled ratio is 1.3, and 4× at n = 53.
DENSE_BORDERED_GAIN = 1.0


def _bordered_band_work(ni, k, lo, up):
    """Multiply-adds of :func:`bordered_band_solve` for ni interior and k border coordinates.

    Counted with the worst pivoting fill (U's bandwidth lo + up) and every border column
    coupled to the interior: band LU ni·lo·(lo + up), its forward and back solve of the k + 1
    right-hand sides, the Schur complement k·(k + 1)·ni, its LU k³/3 and x_I ni·k. The dense
    backward-error check (2n²) is not included.
    """
    return (ni * lo * (lo + up) + (k + 1) * ni * (2 * lo + up) + k * (k + 1) * ni + k ** 3 / 3.0
            + ni * k)


def _interior_band(rows, cols, border):
    """(interior, lo, up): the coordinates not in ``border`` (in order) and their band's widths."""
    interior = np.flatnonzero(~border)
    pos = np.full(border.size, -1, dtype=np.int64)
    pos[interior] = np.arange(interior.size)
    inner = ~border[rows] & ~border[cols]
    off = pos[cols[inner]] - pos[rows[inner]]
    return interior, int(max(0, -off.min(initial=0))), int(max(0, off.max(initial=0)))


#: most thresholds :func:`dense_bordered_plan` tries (each costs a pass over the pattern)
MAX_THRESHOLDS = 256


def dense_bordered_plan(pattern, far=None, max_border=None):
    """Plan of :func:`bordered_band_solve` for dense matrices with the nonzeros ``pattern``, or None.

    The border is chosen by the rule of the sparse solver (:func:`_bordered_band_plan`):
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
        border = _choose_border(rows, cols, no_diagonal, t, max_border)
        if border is None:
            continue
        k = int(border.sum())
        if k > max_border or k == n:
            continue
        interior, lo, up = _interior_band(rows, cols, border)
        work = _bordered_band_work(interior.size, k, lo, up)
        if work < best_work:
            best, best_work = (interior.astype(np.int64), np.flatnonzero(border).astype(np.int64), lo, up), work
    if best is None or DENSE_BORDERED_GAIN * (best_work + 2.0 * n * n) > n ** 3 / 3.0 + n * n:
        return None
    return best


def reordered_band_plan(pattern, max_border=MAX_BORDER):
    """Plan of :func:`bordered_band_solve` that reorders the coordinates, or None: the dense rows and
    columns (a floating frame's coordinates: more than 8 times the median number of entries, at least
    16) form the border, and the rest, Lagrange multipliers included, is ordered by reverse
    Cuthill–McKee into a band.

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

    Returns
    -------
    tuple or None
        ``(interior, border, lo, up)`` as :func:`dense_bordered_plan` returns it (the interior in the
        band's order, not ascending), or None if the border would be larger than ``max_border`` or
        the band wider than :data:`MAX_BANDWIDTH`.
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
    if lo + up > MAX_BANDWIDTH:
        return None
    return interior.astype(np.int64), np.flatnonzero(border).astype(np.int64), lo, up


@numba.njit(inline="always")
def _axpy(y, oy, x, ox, n, a):
    """y[oy:oy + n] −= a · x[ox:ox + n] on flat arrays.

    Offsets and length are unsigned (``uint64``): Numba wraps negative indices, a test on
    every access that LLVM drops only for indices it can prove nonnegative; with unsigned
    ones it is gone and the short loops of the band LU run about twice as fast."""
    for t in range(n):
        y[oy + t] -= a * x[ox + t]


@numba.njit(inline="always")
def _dot(x, ox, y, oy, n):
    """x[ox:ox + n] · y[oy:oy + n] on flat arrays, summed in order (unsigned offsets, see :func:`_axpy`)."""
    s = 0.0
    for t in range(n):
        s += x[ox + t] * y[oy + t]
    return s


@numba.njit(cache=True, fastmath={"reassoc", "nsz", "contract"})
def _dot_long(x, ox, y, oy, n):
    """:func:`_dot` for long vectors: reassociation lets LLVM vectorize the sum (no nnan/ninf flags,
    so non-finite values still propagate)."""
    s = 0.0
    for t in range(n):
        s += x[ox + t] * y[oy + t]
    return s


@numba.njit(cache=True, fastmath={"reassoc", "nsz", "contract"})
def _row_residual(mat, i, x, b):
    """(mat[i] · x − b, ‖mat[i]‖₁), vectorized as :func:`_dot_long`."""
    s = 0.0
    a = 0.0
    for j in range(x.size):
        v = mat[i, j]
        s += v * x[j]
        a += abs(v)
    return s - b, a


@numba.njit(inline="always")
def _finite_norm(x):
    """‖x‖∞, or −1 if an entry of x is not finite."""
    x_inf = 0.0
    for j in range(x.size):
        v = abs(x[j])
        if not v < np.inf:
            return -1.0
        x_inf = max(x_inf, v)
    return x_inf


@numba.njit(cache=True)
def _dense_backward_stable(mat, rhs, x, tol):
    """True if x is finite and ‖mat x − rhs‖∞ ≤ ``tol`` · (‖mat‖∞ ‖x‖∞ + ‖rhs‖∞), from every entry of mat.

    Every entry, not only the planned ones: an entry the plan did not know about (a pattern
    taken from too few evaluations) makes the residual large, and the caller solves densely.
    """
    n = x.size
    x_inf = _finite_norm(x)
    if x_inf < 0.0:
        return False
    r_inf, a_inf, b_inf = 0.0, 0.0, 0.0
    for i in range(n):
        r, a = _row_residual(mat, i, x, rhs[i])
        r = abs(r)
        if not (r < np.inf and a < np.inf):       # NaN or ∞ in mat or rhs (max() would drop a NaN)
            return False
        r_inf = max(r_inf, r)
        a_inf = max(a_inf, a)
        b_inf = max(b_inf, abs(rhs[i]))
    return r_inf <= tol * max(a_inf * x_inf + b_inf, 1e-300)


@numba.njit(cache=True, fastmath={"contract"})
def _bordered_core(ab, y, gb, sch, interior, border, lo, up, x):
    """The elimination of :func:`bordered_band_solve`, shared by its dense and CSR forms: x from the
    gathered blocks; False if a pivot is zero or not finite (x then NaN).

    ``ab``: A_II by rows, entry (r, c) at ab[r·w + c − r + lo], w = 2 lo + up + 1, the slots right of
    the band zero (the fill of row interchanges); ``y``: r_I, then A_IB's columns, each contiguous;
    ``gb``: A_BI by rows; ``sch``: [A_BB | r_B] by rows, k × (k + 1). All are overwritten."""
    ni, k = interior.size, border.size
    uu = lo + up                           # U's bandwidth after row interchanges
    w = lo + uu + 1
    # keep only the columns of A_IB that are not zero (a multiplier's column is zero on the
    # interior when it constrains frame coordinates only): act[s − 1] is the border index of
    # right-hand side s, m their number with r_I
    ints = np.empty(k + ni, dtype=np.int64)
    act, uend = ints[:k], ints[k:]
    m = 1
    for b in range(k):
        src = (b + 1) * ni
        nonzero = False
        for i in range(ni):
            if y[uint64(src + i)] != 0.0:
                nonzero = True
                break
        if nonzero:
            if m != b + 1:
                for i in range(ni):
                    y[uint64(m * ni + i)] = y[uint64(src + i)]
            act[m - 1] = b
            m += 1
    # band LU with partial pivoting (LAPACK gbtf2); the right-hand sides are eliminated along,
    # so L need not be kept. ju is the last column U reaches so far (gbtf2's JU), uend[j] that
    # of row j: with few interchanges the updates stay lo + up wide at most, usually up.
    ju = 0
    for j in range(ni):
        last = min(ni - 1, j + lo)
        dj = j * w + lo
        p = j
        big = abs(ab[uint64(dj)])
        for r in range(j + 1, last + 1):
            v = abs(ab[uint64(r * w + j - r + lo)])
            if v > big:
                big, p = v, r
        if not (big > 0.0 and big < np.inf):
            x[:] = np.nan
            return False
        ju = max(ju, min(ni - 1, p + up))
        uend[j] = ju
        ncol = ju - j
        if p != j:
            op = p * w + j - p + lo
            for t in range(ncol + 1):
                tmp = ab[uint64(dj + t)]
                ab[uint64(dj + t)] = ab[uint64(op + t)]
                ab[uint64(op + t)] = tmp
            for s in range(m):
                tmp = y[uint64(s * ni + j)]
                y[uint64(s * ni + j)] = y[uint64(s * ni + p)]
                y[uint64(s * ni + p)] = tmp
        pivot = ab[uint64(dj)]
        for r in range(j + 1, last + 1):
            o = r * w + j - r + lo
            l = ab[uint64(o)] / pivot
            if l != 0.0:
                _axpy(ab, uint64(o + 1), ab, uint64(dj + 1), uint64(ncol), l)
                for s in range(m):
                    y[uint64(s * ni + r)] -= l * y[uint64(s * ni + j)]
    # back substitution with the m right-hand sides interleaved: each alone is a chain of
    # dependent operations (latency-bound), together they overlap
    for j in range(ni - 1, -1, -1):
        o = j * w + lo
        ncol = uint64(uend[j] - j)
        d = 1.0 / ab[uint64(o)]
        for s in range(m):
            q = s * ni + j
            y[uint64(q)] = (y[uint64(q)] - _dot(ab, uint64(o + 1), y, uint64(q + 1), ncol)) * d
    # Schur complement [S | r_B − A_BI y] by rows
    kk = k + 1
    for a in range(k):
        g0 = a * ni
        nonzero = False
        for i in range(ni):
            if gb[uint64(g0 + i)] != 0.0:
                nonzero = True
                break
        if nonzero:                        # a multiplier's row is often zero on the interior
            sch[a * kk + k] -= _dot_long(gb, uint64(g0), y, uint64(0), uint64(ni))
            for s in range(1, m):
                sch[a * kk + act[s - 1]] -= _dot_long(gb, uint64(g0), y, uint64(s * ni), uint64(ni))
    # x_B: dense LU of S with partial pivoting, the right-hand side as column k
    for j in range(k):
        p = j
        big = abs(sch[j * kk + j])
        for r in range(j + 1, k):
            v = abs(sch[r * kk + j])
            if v > big:
                big, p = v, r
        if not (big > 0.0 and big < np.inf):
            x[:] = np.nan
            return False
        if p != j:
            for c in range(j, kk):
                tmp = sch[j * kk + c]
                sch[j * kk + c] = sch[p * kk + c]
                sch[p * kk + c] = tmp
        pivot = sch[j * kk + j]
        for r in range(j + 1, k):
            l = sch[r * kk + j] / pivot
            if l != 0.0:
                _axpy(sch, uint64(r * kk + j + 1), sch, uint64(j * kk + j + 1), uint64(k - j), l)
    for j in range(k - 1, -1, -1):
        t = sch[j * kk + k]
        for c in range(j + 1, k):
            t -= sch[j * kk + c] * x[border[c]]
        x[border[j]] = t / sch[j * kk + j]
    # x_I = y − Y x_B
    for i in range(ni):
        t = y[i]
        for s in range(1, m):
            t -= y[uint64(s * ni + i)] * x[border[act[s - 1]]]
        x[interior[i]] = t
    return True


@numba.njit(inline="always")
def _bordered_blocks(ni, k, lo, up):
    """The zeroed blocks :func:`_bordered_core` works on: (w, ab, y, gb, sch), w = 2 lo + up + 1."""
    w = 2 * lo + up + 1
    return w, np.zeros(ni * w), np.zeros((k + 1) * ni), np.zeros(k * ni), np.zeros(k * (k + 1))


@numba.njit(cache=True, inline="always")
def _check_plan(n, interior, border, lo, up):
    """Raise ValueError if (interior, border, lo, up) is no plan for n coordinates."""
    ni, k = interior.size, border.size
    if ni + k != n or ni == 0 or lo < 0 or up < 0:
        raise ValueError("bordered_band_solve: the plan does not fit the matrix")
    for i in range(ni):                    # unchecked unsigned indices below: a bad one would not raise
        if interior[i] < 0 or interior[i] >= n:
            raise ValueError("bordered_band_solve: interior index out of range")
    for i in range(k):
        if border[i] < 0 or border[i] >= n:
            raise ValueError("bordered_band_solve: border index out of range")


@numba.njit(cache=True, fastmath={"contract"})
def bordered_band_solve(mat, rhs, interior, border, lo, up):
    """Solve mat x = rhs as a band with a dense border (plan of :func:`dense_bordered_plan`).

    With I the interior and B the border coordinates: band LU with partial pivoting of A_II
    (row interchanges within the band, as LAPACK gbtrf, so U's upper bandwidth grows to
    lo + up), forward and back solve of A_II [y, Y] = [r_I, A_IB], the Schur complement
    S = A_BB − A_BI Y and its right-hand side r_B − A_BI y, x_B by dense LU of S with partial
    pivoting, and x_I = y − Y x_B. The entries are read from the dense ``mat``, which is not
    modified; entries of A_II outside the band are not read (the backward-error check sees
    them).

    The band LU is written out here rather than calling LAPACK's gbtrf/gbtrs: reaching LAPACK
    from Numba takes ctypes/cffi function pointers, and functions that hold those are not
    cached by Numba, so the compiled time loop calling this would compile afresh in every
    process. The k × k system is solved by hand too: ``np.linalg.solve`` costs about 0.4 µs
    even at k = 5 and raises on a singular S.

    Parameters
    ----------
    mat : ndarray, shape (n, n), C-contiguous float64
        The matrix; only read.
    rhs : ndarray, shape (n,)
        The right-hand side.
    interior, border : ndarray of int64
        A partition of range(n) (:func:`dense_bordered_plan`); interior in band order.
    lo, up : int
        Lower and upper bandwidth of A_II in that order.

    Returns
    -------
    x : ndarray, shape (n,)
        The solution; meaningless (NaN-filled if the solve stopped early) when ``ok`` is False.
    ok : bool
        False if a pivot of the band LU or of S is zero or not finite, x is not finite, or the
        normwise backward error ‖mat x − rhs‖∞ / (‖mat‖∞ ‖x‖∞ + ‖rhs‖∞), computed with all of
        ``mat``, exceeds 1e-12. The caller then solves densely: A_II can be singular or
        ill-conditioned (the Schur complement then loses accuracy) while mat is well
        conditioned, and an entry outside the planned band is not read but seen here.

    Raises
    ------
    ValueError
        If the shapes do not fit or an index is out of range (a plan for another matrix).
    """
    n = mat.shape[0]
    if mat.shape[1] != n or rhs.size != n:
        raise ValueError("bordered_band_solve: the plan does not fit the matrix")
    _check_plan(n, interior, border, lo, up)
    ni, k = interior.size, border.size
    w, ab, y, gb, sch = _bordered_blocks(ni, k, lo, up)
    for r in range(ni):
        row = interior[r]
        base = r * w + lo - r
        for c in range(max(0, r - lo), min(ni, r + up + 1)):
            ab[uint64(base + c)] = mat[row, uint64(interior[c])]
        y[r] = rhs[row]
        for b in range(k):
            y[uint64((b + 1) * ni + r)] = mat[row, uint64(border[b])]
    for a in range(k):
        row = border[a]
        for i in range(ni):
            gb[uint64(a * ni + i)] = mat[row, uint64(interior[i])]
        for b in range(k):
            sch[a * (k + 1) + b] = mat[row, uint64(border[b])]
        sch[a * (k + 1) + k] = rhs[row]
    x = np.empty(n)
    if not _bordered_core(ab, y, gb, sch, interior, border, lo, up, x):
        return x, False
    return x, _dense_backward_stable(mat, rhs, x, 1e-12)


@numba.njit(cache=True, fastmath={"contract"})
def bordered_band_solve_csr(vals, ptr, idx, rhs, interior, border, lo, up):
    """:func:`bordered_band_solve` of a matrix stored in CSR form (``vals[ptr[i]:ptr[i + 1]]`` the
    entries of row i in the columns ``idx[ptr[i]:ptr[i + 1]]``): the same elimination
    (:func:`_bordered_core`), the blocks gathered from the stored entries, the backward error
    ‖mat x − rhs‖∞ / (‖mat‖∞ ‖x‖∞ + ‖rhs‖∞) from every stored entry (O(nnz)). A stored entry of A_II
    outside the planned band is not read; that check sees it (``ok`` False).

    ``vals`` may be longer than ``ptr[-1]`` (entries past the matrix are ignored). Raises ValueError
    if the shapes do not fit or an index is out of range.
    """
    n = rhs.size
    if ptr.size != n + 1 or ptr[n] > vals.size or ptr[n] > idx.size:
        raise ValueError("bordered_band_solve_csr: the CSR structure does not fit the right-hand side")
    _check_plan(n, interior, border, lo, up)
    for t in range(ptr[n]):
        if idx[t] < 0 or idx[t] >= n:
            raise ValueError("bordered_band_solve_csr: column index out of range")
    ni, k = interior.size, border.size
    w, ab, y, gb, sch = _bordered_blocks(ni, k, lo, up)
    where = np.empty(n, dtype=np.int64)    # interior position, or −1 − border position
    for i in range(ni):
        where[interior[i]] = i
    for b in range(k):
        where[border[b]] = -1 - b
    for r in range(ni):
        row = interior[r]
        y[r] = rhs[row]
        for t in range(ptr[row], ptr[row + 1]):
            c = where[idx[t]]
            if c >= 0:
                if c - r <= up and r - c <= lo:
                    ab[uint64(r * w + c - r + lo)] = vals[t]
            else:
                y[uint64((-c) * ni + r)] = vals[t]
    for a in range(k):
        row = border[a]
        for t in range(ptr[row], ptr[row + 1]):
            c = where[idx[t]]
            if c >= 0:
                gb[uint64(a * ni + c)] = vals[t]
            else:
                sch[a * (k + 1) - 1 - c] = vals[t]
        sch[a * (k + 1) + k] = rhs[row]
    x = np.empty(n)
    if not _bordered_core(ab, y, gb, sch, interior, border, lo, up, x):
        return x, False
    x_inf = _finite_norm(x)
    if x_inf < 0.0:
        return x, False
    r_inf, a_inf, b_inf = 0.0, 0.0, 0.0
    for i in range(n):
        s, a = -rhs[i], 0.0
        for t in range(ptr[i], ptr[i + 1]):
            s += vals[t] * x[idx[t]]
            a += abs(vals[t])
        if not (abs(s) < np.inf and a < np.inf):
            return x, False
        r_inf = max(r_inf, abs(s))
        a_inf = max(a_inf, a)
        b_inf = max(b_inf, abs(rhs[i]))
    return x, r_inf <= 1e-12 * max(a_inf * x_inf + b_inf, 1e-300)
