r"""Quadratic constraint rows: Φ = Σ h q_i q_j + Σ b q_i + c − s(t) (the rigidity of spatial bodies and every
spatial joint, :mod:`skfem_flex.elements.constraints.quadratic`).

Per row: Φ_q = the sum over its pair terms of h (q_j e_i + q_i e_j) plus b; the exact discrete gradient
is Φ_q at the mid-point (q_a + q_b)/2; ∂(Φ_q v)/∂q the same sums with v; and
∂(Dᵀμ)/∂q_b = ½ μ H (the pair terms' entries), written with the weight w_mu c_dg dq1 of every constraint
family (:mod:`..tasks`). Φ_t = −ṡ(t), Φ_tt = −s̈(t) from the row's motion law (columns of the time table
at the step's end), or 0 without one.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..rows import finish_row
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack

NAME = "quadratic constraint rows"
FORMS = ("quadratic",)


def row_count(term):
    return int(np.shape(term[2])[0])


def form_terms(H, b):
    """The terms of one quadratic form ½ qᵀHq + b·q over a block's coordinates: pair terms h q_i q_j (i ≤ j,
    the upper triangle of ½ H) as (hi, hj, h) and the linear terms' coordinates bi."""
    hi, hj = np.nonzero(np.triu(H))
    return hi, hj, np.where(hi == hj, 0.5, 1.0) * H[hi, hj], np.flatnonzero(b)


class Data(NamedTuple):
    rows: np.ndarray        # (k, 7): row, first/end pair term, first/end linear term, first column, law column
    const: np.ndarray       # (k,) c
    pi: np.ndarray          # pair terms h q_i q_j: i, j (global), their slots in the row's columns, h
    pj: np.ndarray
    psi: np.ndarray
    psj: np.ndarray
    ph: np.ndarray
    li: np.ndarray          # linear terms b q_i: i, slot, b
    lsl: np.ndarray
    lb: np.ndarray
    cols: np.ndarray        # the coordinates each row touches, row after row (end: the next row's first)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f1(fam, 1), i1(fam, 2), i1(fam, 3), i1(fam, 4), i1(fam, 5), f1(fam, 6), i1(fam, 7),
                i1(fam, 8), f1(fam, 9), i1(fam, 10))


def pack(items, packer):
    rows, const = [], []
    pi, pj, psi, psj, ph, li, lsl, lb, cols = ([] for _ in range(9))
    row_support, couplings = [], []
    for ((term, _), constraint, (idx, first)) in items:
        _, H, b, c, laws, columns = term
        idx = np.asarray(idx, dtype=np.int64)[columns]
        for k in range(H.shape[0]):
            hi, hj, hv, bi = form_terms(H[k], b[k])
            touched = np.unique(np.concatenate([hi, hj, bi])).astype(np.int64)
            slot = {int(t): s for s, t in enumerate(touched)}
            col = -1
            law = laws[k]
            if law is not None:
                col = packer.column(law.position, 0, "end")
                packer.column(law.velocity, 0, "end")
                packer.column(law.acceleration, 0, "end")
            rows.append((first + k, len(pi), len(pi) + hi.size, len(li), len(li) + bi.size, len(cols), col))
            pi.extend(idx[hi])
            pj.extend(idx[hj])
            psi.extend(slot[int(t)] for t in hi)
            psj.extend(slot[int(t)] for t in hj)
            ph.extend(hv)
            li.extend(idx[bi])
            lsl.extend(slot[int(t)] for t in bi)
            lb.extend(b[k][bi])
            cols.extend(idx[touched])
            const.append(float(c[k]))
            row_support.append((first + k, idx[touched]))
            if hi.size:
                couplings.append(np.unique(idx[np.concatenate([hi, hj])]))
    n_rows = len(rows)
    i64 = lambda a: np.asarray(a, dtype=np.int64)        # noqa: E731
    data = Data(i64(rows).reshape(n_rows, 7), np.asarray(const, dtype=float), i64(pi), i64(pj), i64(psi), i64(psj),
                np.asarray(ph, dtype=float), i64(li), i64(lsl), np.asarray(lb, dtype=float), i64(cols + [0]))
    return FamilyPack(data=data, count=n_rows, couplings=couplings, rows=row_support)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    n = ctx.n
    q1, qa, qb, v1 = fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.v1, n)
    mu = fvec(ctx.mu, ctx.m)
    trow = fvec(ctx.trow, ctx.ncol)
    st = storage_of(ctx)
    evaluate = ctx.task == TASK_EVAL
    scratch = fvec(ctx.scratch, ctx.nscratch)
    n_rows = d.rows.shape[0]
    w = ctx.w_mu * ctx.c_dg * ctx.dq1
    for r in range(n_rows):
        row, p0, p1, l0, l1, c0, col = d.rows[r]
        c1 = d.rows[r + 1, 5] if r + 1 < n_rows else d.cols.size - 1
        nc = c1 - c0
        cq, dd, cv = scratch[:nc], scratch[nc:2 * nc], scratch[2 * nc:3 * nc]
        for t in range(nc):
            cq[t] = 0.0
            dd[t] = 0.0
            cv[t] = 0.0
        val, phi_t, phi_tt = d.const[r], 0.0, 0.0
        for t in range(l0, l1):
            val += d.lb[t] * q1[d.li[t]]
            cq[d.lsl[t]] += d.lb[t]
            dd[d.lsl[t]] += d.lb[t]
        for t in range(p0, p1):
            i, j, h = d.pi[t], d.pj[t], d.ph[t]
            si, sj = d.psi[t], d.psj[t]
            val += h * q1[i] * q1[j]
            cq[si] += h * q1[j]
            cq[sj] += h * q1[i]
            cv[si] += h * v1[j]
            cv[sj] += h * v1[i]
            if evaluate:
                dd[si] += 0.5 * h * (qa[j] + qb[j])
                dd[sj] += 0.5 * h * (qa[i] + qb[i])
                # ∂(Dᵀμ)/∂q_b = ½ μ H: the pair's two entries
                e = 0.5 * w * h * mu[row]
                add_qq(ctx, st, i, j, e)
                add_qq(ctx, st, j, i, e)
        if col >= 0:
            val -= trow[col]
            phi_t, phi_tt = -trow[col + 1], -trow[col + 2]
        finish_row(ctx, st, row, val, phi_t, phi_tt, d.cols[c0:c1], cq, dd, cv, nc)


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the quadratic-constraint family")
