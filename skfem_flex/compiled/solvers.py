r"""Kernels that solve the Newton system J y = r of the loop (``ctx.res`` → ``ctx.y``, ``ctx.regular``).

Which one a scene gets is fixed once with its storage (:func:`skfem_flex.compiled.pack.plan_solver`):

* ``dense``: the matrix stored dense: LU with partial pivoting written out for small systems (a call
  to LAPACK costs more than the factorization below about 24 unknowns), LAPACK getrf/getrs above (called
  by address: :func:`lapack_address`, nothing of numba's linear algebra to compile);
* ``bordered band``: stored dense, solved as a band with a dense border when the scene's pattern has
  such a plan (beams: frame coordinates and multipliers in the border), LAPACK if that solve is not
  backward stable (:func:`skfem_flex.numerics.band_kernels.bordered_band_solve`);
* ``bordered band (CSR)``: stored as the values of its pattern, the same elimination; a solve that is
  not backward stable is reported singular, and the step goes back to Python;
* ``sparse LU (static pivots)``: chosen by :meth:`~skfem_flex.schemes.stepper.Stepper.plan_sparse_lu` from an
  evaluated matrix when it models faster than the above (closed loops of rigid bodies): the refactorization
  of :func:`skfem_flex.numerics.sparse_lu.static_lu_solve`, its solution's backward error checked; a
  failed one is solved by the kernel the scene had before (after :data:`STATIC_LU_FAILURES` failures
  always).
"""
from __future__ import annotations

import ctypes
from typing import NamedTuple

import numba
import numpy as np
from scipy.linalg import cython_lapack

from ..numerics.band_kernels import (bordered_band_solve, bordered_band_solve_csr, csr_backward_stable,
                                     dense_backward_stable)
from ..numerics.sparse_lu import StaticLUPlan, static_lu_solve
from .abi import call_pointers, context_of, f1, family_of, fmat, fvec, i1, i32vec, ivec
from .registry import compiled_kernel

__all__ = ["SolverPlan", "StaticLUFields", "lapack_solve", "small_lu_solve", "dense_solver", "bordered_band_solver", "csr_bordered_band_solver",
           "static_lu_solver", "static_lu_fields", "SMALL_DENSE", "STATIC_LU_FAILURES"]

#: below this many unknowns the written-out LU is faster than LAPACK's
SMALL_DENSE = 24


class SolverPlan(NamedTuple):
    """A band-with-border plan (:func:`~skfem_flex.numerics.band_plans.dense_bordered_plan`): interior
    coordinates in band order, border coordinates, (lower, upper) bandwidth; and the addresses of LAPACK's
    dgetrf and dgetrs and of an int32 work array of nx + 8 entries (:func:`lapack_work`)."""
    interior: np.ndarray
    border: np.ndarray
    bands: np.ndarray
    lapack: np.ndarray


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return SolverPlan(i1(fam, 0), i1(fam, 1), i1(fam, 2), i1(fam, 3))


#: after this many failed solves the static-pivot LU is no longer tried in the run (its pivots no longer fit)
STATIC_LU_FAILURES = 8


#: the static-pivot LU solver's data: the fields of the scene's earlier solver (a :class:`SolverPlan`, the
#: fallback), the :class:`~skfem_flex.numerics.sparse_lu.StaticLUPlan`, the work arrays of
#: :func:`~skfem_flex.numerics.sparse_lu.static_lu_solve` and ``state`` = (the earlier solver: 0 dense,
#: 1 bordered band, 2 bordered band on CSR storage; failures so far in the run)
StaticLUFields = NamedTuple("StaticLUFields", [(name, np.ndarray) for name in
                                               SolverPlan._fields + StaticLUPlan._fields + ("lu", "w", "mark", "z",
                                                                                            "state")])


def static_lu_fields(fallback, plan, fallback_kind):
    """The :data:`StaticLUFields` for the LU ``plan`` with the earlier solver's :class:`SolverPlan` ``fallback``
    (kind 0, 1 or 2 as ``state`` says)."""
    n = plan.prow.size
    return StaticLUFields(*fallback, *plan, np.zeros(plan.idx.size), np.zeros(n), np.full(n, -1, dtype=np.int64),
                          np.zeros(n), np.array([fallback_kind, 0], dtype=np.int64))


@numba.njit(cache=True, _nrt=False)
def _static_view(fam):
    return StaticLUFields(i1(fam, 0), i1(fam, 1), i1(fam, 2), i1(fam, 3), i1(fam, 4), i1(fam, 5), i1(fam, 6),
                          i1(fam, 7), i1(fam, 8), i1(fam, 9), f1(fam, 10), f1(fam, 11), i1(fam, 12), f1(fam, 13),
                          i1(fam, 14))


def lapack_address(name):
    """The address of LAPACK's routine ``name`` (scipy's, as its Cython interface exports it)."""
    cap = cython_lapack.__pyx_capi__[name]
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    return api.PyCapsule_GetPointer(cap, api.PyCapsule_GetName(cap))


def lapack_work(nx):
    """(int32 work array, the ``lapack`` field of a SolverPlan) for a system of nx unknowns."""
    work = np.zeros(nx + 8, dtype=np.int32)
    return work, np.array([lapack_address("dgetrf"), lapack_address("dgetrs"), work.ctypes.data], dtype=np.int64)


@numba.njit(cache=True, _nrt=False)
def small_lu_solve(a, b, x):
    """Solve a x = b by LU with partial pivoting (``a`` (n, n) and ``b`` are overwritten; x may be b);
    False if a pivot is zero or not finite."""
    n = b.size
    for k in range(n):
        p, big = k, abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > big:
                p, big = i, v
        if not (big > 0.0 and big < np.inf):
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            b[k], b[p] = b[p], b[k]
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] * inv
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
                b[i] -= f * b[k]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= a[i, j] * x[j]
        x[i] = s / a[i, i]
    for i in range(n):
        if not np.isfinite(x[i]):
            return False
    return True


@numba.njit(cache=True, _nrt=False)
def lapack_solve(lapack, a, y):
    """y ← a⁻¹ y by LAPACK (dgetrf, dgetrs) for the row-major ``a`` (destroyed): Fortran sees aᵀ, so the
    solve is done with its transpose ('T'); True if it succeeded."""
    n = y.size
    w = i32vec(lapack[2], n + 8)
    w[0], w[1], w[2], w[3], w[4] = n, 1, n, 0, 84           # n, nrhs, lda, info, 'T'
    d = lapack[2]
    call_pointers(lapack[0], (d, d, a.ctypes.data, d + 8, d + 32, d + 12))
    if w[3] != 0:
        return False
    call_pointers(lapack[1], (d + 16, d, d + 4, a.ctypes.data, d + 8, d + 32, y.ctypes.data, d + 8, d + 12))
    return w[3] == 0


@numba.njit(cache=True, _nrt=False)
def _dense(ctx, a, res, y, lapack):
    """The dense solve of (a, res) into y; the matrix is destroyed."""
    nx = res.size
    for i in range(nx):
        y[i] = res[i]
    if nx <= SMALL_DENSE:
        ok = small_lu_solve(a, y, y)
    else:
        ok = lapack_solve(lapack, a, y)
        for i in range(nx):
            if not np.isfinite(y[i]):
                ok = False
    ctx.regular = 1 if ok else 0


def _dense_kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    nx = ctx.nx
    _dense(ctx, fmat(ctx.mat, nx, nx), fvec(ctx.res, nx), fvec(ctx.y, nx), _view(family_of(fam_p)).lapack)


@numba.njit(cache=True)
def _bordered(ctx, plan):
    nx = ctx.nx
    a, res, y = fmat(ctx.mat, nx, nx), fvec(ctx.res, nx), fvec(ctx.y, nx)
    x, ok = bordered_band_solve(a, res, plan.interior, plan.border, plan.bands[0], plan.bands[1])
    if ok:
        for i in range(nx):
            y[i] = x[i]
        ctx.regular = 1
        return
    _dense(ctx, a, res, y, plan.lapack)


def _bordered_kernel(ctx_p, fam_p):
    _bordered(context_of(ctx_p), _view(family_of(fam_p)))


@numba.njit(cache=True)
def _bordered_csr(ctx, plan):
    nx = ctx.nx
    ptr = ivec(ctx.csr_ptr, nx + 1)
    nnz = ptr[nx]
    x, ok = bordered_band_solve_csr(fvec(ctx.mat, nnz), ptr, ivec(ctx.csr_idx, nnz), fvec(ctx.res, nx),
                                    plan.interior, plan.border, plan.bands[0], plan.bands[1])
    y = fvec(ctx.y, nx)
    for i in range(nx):
        y[i] = x[i]
    ctx.regular = 1 if ok else 0


def _csr_kernel(ctx_p, fam_p):
    _bordered_csr(context_of(ctx_p), _view(family_of(fam_p)))


@numba.njit(cache=True)
def _static_lu(ctx, f):
    nx = ctx.nx
    res, y = fvec(ctx.res, nx), fvec(ctx.y, nx)
    kind = f.state[0]
    dense = kind != 2
    if f.state[1] < STATIC_LU_FAILURES:
        if dense:
            vals = fvec(ctx.mat, nx * nx)
        else:
            vals = fvec(ctx.mat, ivec(ctx.csr_ptr, nx + 1)[nx])
        if static_lu_solve(vals, res, y, f.prow, f.qcol, f.ptr, f.idx, f.diag, f.src, f.lu, f.w, f.mark, f.z):
            # on dense storage every entry, not only the pattern's: an entry a family wrote outside its
            # declared pattern shows up here
            if dense:
                ok = dense_backward_stable(fmat(ctx.mat, nx, nx), res, y, 1e-12)
            else:
                ptr = ivec(ctx.csr_ptr, nx + 1)
                ok = csr_backward_stable(vals, ptr, ivec(ctx.csr_idx, ptr[nx]), res, y, 1e-12)
            if ok:
                ctx.regular = 1
                return
        f.state[1] += 1
    plan = SolverPlan(f.interior, f.border, f.bands, f.lapack)
    if kind == 0:
        _dense(ctx, fmat(ctx.mat, nx, nx), res, y, f.lapack)
    elif kind == 1:
        _bordered(ctx, plan)
    else:
        _bordered_csr(ctx, plan)


def _static_lu_kernel(ctx_p, fam_p):
    _static_lu(context_of(ctx_p), _static_view(family_of(fam_p)))


def static_lu_solver():
    """The static-pivot sparse LU solver's kernel."""
    return compiled_kernel(_static_lu_kernel, "the static-pivot sparse LU solver", nrt=True)


def dense_solver():
    """The dense solver's kernel."""
    return compiled_kernel(_dense_kernel, "the dense linear solver")


def bordered_band_solver():
    """The bordered band solver's kernel (dense storage)."""
    return compiled_kernel(_bordered_kernel, "the band-with-border linear solver", nrt=True)


def csr_bordered_band_solver():
    """The bordered band solver's kernel (CSR storage)."""
    return compiled_kernel(_csr_kernel, "the band-with-border linear solver (sparse storage)", nrt=True)
