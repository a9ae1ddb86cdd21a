r"""The general sparse solver of the loop: a Newton matrix in CSR storage with no band plan, solved by the
package's one linear solver (:func:`skfem_flex.numerics.linear_solver.linear_solve`: SuperLU for such a
matrix) through a ``ctypes`` callback the loop calls by address, as it calls a compiled solver.

It serves the scenes above the dense storage limit whose pattern is neither a band nor a band with a
small border, even after reordering (a large unreduced plane-stress body, or many coordinates that run
through their Python methods with ``compiled=False``). The call from compiled code into Python costs a
few microseconds, small beside a SuperLU factorization of more than 150 unknowns.

Contract (as :mod:`.solvers`): J y = r with J = the CSR values ``ctx.mat`` on ``ctx.csr_ptr``/``ctx.csr_idx``,
r = ``ctx.res``, y into ``ctx.y``; ``ctx.regular`` = 0 when J is singular (or anything else fails: the
step is then handed back, as for a singular matrix).
"""
from __future__ import annotations

import ctypes

import numpy as np
import scipy.sparse as sps

from ..numerics.linear_solver import linear_solve
from .abi import record_view, vector_view

__all__ = ["sparse_solver"]


def _callback(ctx_address, fam_address):
    rec = record_view(ctx_address)
    rec["regular"] = 0
    try:
        nx = int(rec["nx"])
        ptr = vector_view(rec["csr_ptr"], nx + 1, np.int64)
        nnz = int(ptr[nx])
        # views, no copies: linear_solve reads the matrix (and copies it itself if it must change it)
        a = sps.csr_matrix((vector_view(rec["mat"], nnz), vector_view(rec["csr_idx"], nnz, np.int64), ptr),
                           shape=(nx, nx), copy=False)
        vector_view(rec["y"], nx)[:] = linear_solve(a, vector_view(rec["res"], nx))
        rec["regular"] = 1
    except BaseException:               # singular (LinAlgError) or anything else: nothing may cross the loop
        rec["regular"] = 0


_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)(_callback)


class _Kernel:
    address = ctypes.cast(_CALLBACK, ctypes.c_void_p).value


def sparse_solver():
    """The general sparse solver's kernel (an object with the ``address`` the loop calls)."""
    return _Kernel
