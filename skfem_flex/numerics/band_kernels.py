"""Bordered band solve of a dense (or CSR-held) matrix, for compiled (Numba) code.

:func:`bordered_band_solve` (the matrix held as a dense array) and :func:`bordered_band_solve_csr`
(held as the values of a fixed CSR pattern) share one elimination (:func:`_bordered_core`): band LU of
the interior, dense Schur complement of the border, with the plans of
:mod:`skfem_flex.numerics.band_plans`.
"""
from __future__ import annotations

import numba
import numpy as np
from numba import uint64

__all__ = ["bordered_band_solve", "bordered_band_solve_csr", "dense_backward_stable", "csr_backward_stable"]


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
def dense_backward_stable(mat, rhs, x, tol):
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
    """Solve mat x = rhs as a band with a dense border (plan of
    :func:`~skfem_flex.numerics.band_plans.dense_bordered_plan`).

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
        A partition of range(n) (:func:`~skfem_flex.numerics.band_plans.dense_bordered_plan`); interior in band order.
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
    return x, dense_backward_stable(mat, rhs, x, 1e-12)


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
    return x, csr_backward_stable(vals, ptr, idx, rhs, x, 1e-12)


@numba.njit(cache=True, _nrt=False)
def csr_backward_stable(vals, ptr, idx, rhs, x, tol):
    """True if x is finite and ‖A x − rhs‖∞ ≤ ``tol`` · (‖A‖∞ ‖x‖∞ + ‖rhs‖∞) for the CSR-held A (every
    stored entry; O(nnz))."""
    n = rhs.size
    x_inf = _finite_norm(x)
    if x_inf < 0.0:
        return False
    r_inf, a_inf, b_inf = 0.0, 0.0, 0.0
    for i in range(n):
        s, a = -rhs[i], 0.0
        for t in range(ptr[i], ptr[i + 1]):
            s += vals[t] * x[idx[t]]
            a += abs(vals[t])
        if not (abs(s) < np.inf and a < np.inf):
            return False
        r_inf = max(r_inf, abs(s))
        a_inf = max(a_inf, a)
        b_inf = max(b_inf, abs(rhs[i]))
    return r_inf <= tol * max(a_inf * x_inf + b_inf, 1e-300)
