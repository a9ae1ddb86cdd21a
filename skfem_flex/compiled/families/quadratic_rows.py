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

from ..abi import context_of, f1, family_of, i1, i2
from ..registry import compiled_kernel
from ..rows import row_states, write_row
from ..storage import add_pos, positions, storage_of
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
    const: np.ndarray       # (k,) c (the rotation drivers: (c_X, c_Y) a row, raveled)
    pi: np.ndarray          # pair terms h q_i q_j: i, j (global), their slots in the row's columns, h
    pj: np.ndarray
    psi: np.ndarray
    psj: np.ndarray
    ph: np.ndarray
    li: np.ndarray          # linear terms b q_i: i, slot, b
    lsl: np.ndarray
    lb: np.ndarray
    cols: np.ndarray        # the coordinates each row touches, row after row (end: the next row's first)
    ppos: np.ndarray        # per pair term the places of (i, j) and (j, i) in the Newton matrix's values
    cpos: np.ndarray        # per entry of cols the places of (column, row) and (row, column) there


@numba.njit(cache=True, _nrt=False)
def view_of(fam):
    """The family record's arrays as :class:`Data`."""
    return Data(i2(fam, 0), f1(fam, 1), i1(fam, 2), i1(fam, 3), i1(fam, 4), i1(fam, 5), f1(fam, 6), i1(fam, 7),
                i1(fam, 8), f1(fam, 9), i1(fam, 10), i1(fam, 11), i1(fam, 12))


class TermLists:
    """The pair and linear terms of quadratic forms and the coordinates of their rows, collected row after row:
    the arrays of :class:`Data` but ``rows`` and ``const`` (shared with the rotation-driver family)."""

    def __init__(self):
        self.pi, self.pj, self.psi, self.psj, self.ph, self.li, self.lsl, self.lb, self.cols = ([] for _ in range(9))

    def add(self, idx, slot, terms, b):
        """Append one form's terms (:func:`form_terms`) on the block coordinates ``idx`` (global) with their
        slots ``slot`` in the row's columns, and the linear coefficients ``b`` over the block."""
        hi, hj, hv, bi = terms
        self.pi.extend(idx[hi])
        self.pj.extend(idx[hj])
        self.psi.extend(slot[int(t)] for t in hi)
        self.psj.extend(slot[int(t)] for t in hj)
        self.ph.extend(hv)
        self.li.extend(idx[bi])
        self.lsl.extend(slot[int(t)] for t in bi)
        self.lb.extend(np.asarray(b)[bi])

    def data(self, rows, width, const):
        """The :class:`Data` of the collected terms with the row table ``rows`` (``width`` entries a row) and
        the constants ``const``."""
        i64 = lambda a: np.asarray(a, dtype=np.int64)        # noqa: E731
        return Data(i64(rows).reshape(len(rows), width), np.asarray(const, dtype=float).ravel(), i64(self.pi),
                    i64(self.pj), i64(self.psi), i64(self.psj), np.asarray(self.ph, dtype=float), i64(self.li),
                    i64(self.lsl), np.asarray(self.lb, dtype=float), i64(self.cols + [0]),
                    -np.ones(2 * len(self.pi), dtype=np.int64), -np.ones(2 * len(self.cols), dtype=np.int64))


def with_positions(data, first_column, layout):
    """``data`` with the places of its Newton-matrix entries (``ppos``, ``cpos``) in the storage of ``layout``
    (a family's ``finish``); ``first_column``: the column of the row table that holds a row's first entry of
    ``cols``."""
    fpos = layout[2]
    nf = int(np.count_nonzero(fpos >= 0))
    a, b = fpos[data.pi], fpos[data.pj]
    ppos = np.stack([positions(layout, a, b), positions(layout, b, a)], axis=1).ravel()
    starts = data.rows[:, first_column]
    ends = np.append(starts[1:], data.cols.size - 1)
    brow = nf + np.repeat(data.rows[:, 0], ends - starts)
    c = fpos[data.cols[:-1]]
    cpos = np.stack([positions(layout, c, brow), positions(layout, brow, c)], axis=1).ravel()
    return data._replace(ppos=ppos, cpos=cpos)


def pack(items, packer):
    rows, const = [], []
    terms = TermLists()
    row_support, couplings = [], []
    for ((term, _), constraint, (idx, first)) in items:
        _, H, b, c, laws, columns = term
        idx = np.asarray(idx, dtype=np.int64)[columns]
        for k in range(H.shape[0]):
            hi, hj, hv, bi = form = form_terms(H[k], b[k])
            touched = np.unique(np.concatenate([hi, hj, bi])).astype(np.int64)
            slot = {int(t): s for s, t in enumerate(touched)}
            col = -1
            law = laws[k]
            if law is not None:
                col = packer.law_columns(law)
            rows.append((first + k, len(terms.pi), len(terms.pi) + hi.size, len(terms.li), len(terms.li) + bi.size,
                         len(terms.cols), col))
            terms.add(idx, slot, form, b[k])
            terms.cols.extend(idx[touched])
            const.append(float(c[k]))
            row_support.append((first + k, idx[touched]))
            if hi.size:
                couplings.append(np.unique(idx[np.concatenate([hi, hj])]))
    data = terms.data(rows, 7, const)
    return FamilyPack(data=data, count=len(rows), couplings=couplings, rows=row_support,
                      finish=lambda layout: with_positions(data, 5, layout))


@numba.njit(cache=True, _nrt=False)
def add_form(st, d, p0, p1, l0, l1, q1, qa, qb, v1, g, dm, hv, evaluate, e):
    """One quadratic form f(q) = ½ qᵀH q + bᵀq (its products d.p*[p0:p1], linear terms d.l*[l0:l1]) over a row's
    columns: g += ∇f(q₁), hv += H v₁ and, when ``evaluate``, dm += ∇f at the mid-point of (q_a, q_b) and the
    Newton matrix += e H (the constraint force's own derivative); dm takes b always. Returns f(q₁) − c."""
    val = 0.0
    for t in range(l0, l1):
        b, sl = d.lb[t], d.lsl[t]
        val += b * q1[d.li[t]]
        g[sl] += b
        dm[sl] += b
    for t in range(p0, p1):
        i, j, h = d.pi[t], d.pj[t], d.ph[t]
        si, sj = d.psi[t], d.psj[t]
        val += h * q1[i] * q1[j]
        g[si] += h * q1[j]
        g[sj] += h * q1[i]
        hv[si] += h * v1[j]
        hv[sj] += h * v1[i]
        if evaluate:
            dm[si] += 0.5 * h * (qa[j] + qb[j])
            dm[sj] += 0.5 * h * (qa[i] + qb[i])
            add_pos(st, d.ppos[2 * t], e * h)
            add_pos(st, d.ppos[2 * t + 1], e * h)
    return val


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    q1, qa, qb, v1, mu, trow, scratch, w, evaluate = row_states(ctx)
    st = storage_of(ctx)
    n_rows = d.rows.shape[0]
    for r in range(n_rows):
        row, p0, p1, l0, l1, c0, col = d.rows[r]
        c1 = d.rows[r + 1, 5] if r + 1 < n_rows else d.cols.size - 1
        nc = c1 - c0
        cq, dd, cv = scratch[:nc], scratch[nc:2 * nc], scratch[2 * nc:3 * nc]
        for t in range(nc):
            cq[t] = 0.0
            dd[t] = 0.0
            cv[t] = 0.0
        phi_t, phi_tt = 0.0, 0.0
        # ∂(Dᵀμ)/∂q_b = ½ μ H
        val = d.const[r] + add_form(st, d, p0, p1, l0, l1, q1, qa, qb, v1, cq, dd, cv, evaluate,
                                    0.5 * w * mu[row])
        if col >= 0:
            val -= trow[col]
            phi_t, phi_tt = -trow[col + 1], -trow[col + 2]
        write_row(ctx, st, row, val, phi_t, phi_tt, d.cols[c0:c1], cq, dd, cv, nc, d.cpos[2 * c0:2 * c1])


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, view_of(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the quadratic-constraint family")
