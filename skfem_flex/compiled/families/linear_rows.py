r"""Linear constraint rows: Φ = g · q + c − x(t) = 0 (drivers of a coordinate or of a relative angle, the
angle part of welds and prismatic joints). Φ_q = D = g exactly; Φ_t = −ẋ(t), Φ_tt = −ẍ(t) from the row's
motion law (columns of the time table at the step's end), or 0 without one.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..rows import finish_row
from ..storage import storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack

NAME = "linear constraint rows"
FORMS = ("linear",)


def row_count(term):
    return 1


class Data(NamedTuple):
    rows: np.ndarray        # (k, 4): row, first coefficient, end coefficient, law column (−1: none)
    const: np.ndarray       # (k,) c
    idx: np.ndarray         # coordinates of the coefficients
    coef: np.ndarray        # g


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f1(fam, 1), i1(fam, 2), f1(fam, 3))


def pack(items, packer):
    rows, const, idx, coef, row_support = [], [], [], [], []
    for ((term, law), constraint, (cidx, row)) in items:
        grad = np.asarray(term[1], dtype=float)
        nz = np.flatnonzero(grad)
        col = -1
        if law is not None:
            col = packer.law_columns(law)
        rows.append((row, len(idx), len(idx) + nz.size, col))
        idx.extend(np.asarray(cidx)[nz])
        coef.extend(grad[nz])
        const.append(float(term[2]))
        row_support.append((row, np.asarray(cidx)[nz]))
    k = len(rows)
    data = Data(np.asarray(rows, dtype=np.int64).reshape(k, 4), np.asarray(const, dtype=float),
                np.asarray(idx, dtype=np.int64), np.asarray(coef, dtype=float))
    return FamilyPack(data=data, count=k, rows=row_support)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    n = ctx.n
    q1 = fvec(ctx.q1, n)
    trow = fvec(ctx.trow, ctx.ncol)
    st = storage_of(ctx)
    zero = fvec(ctx.scratch, ctx.nscratch)
    for i in range(d.rows.shape[0]):
        row, a, b, col = d.rows[i]
        val, phi_t, phi_tt = d.const[i], 0.0, 0.0
        for t in range(a, b):
            val += d.coef[t] * q1[d.idx[t]]
        if col >= 0:
            val -= trow[col]
            phi_t, phi_tt = -trow[col + 1], -trow[col + 2]
        for t in range(b - a):
            zero[t] = 0.0
        finish_row(ctx, st, row, val, phi_t, phi_tt, d.idx[a:b], d.coef[a:b], d.coef[a:b], zero[:b - a], b - a)


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the linear-constraint family")
