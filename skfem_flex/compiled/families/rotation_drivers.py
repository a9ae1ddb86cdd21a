r"""Rotation drivers (:class:`~skfem_flex.elements.constraints.spatial_joints.RotationDriver`): one row each,

.. math::  Φ(q, t) = \cos θ(t)\, Y(q) − \sin θ(t)\, X(q),

with X = ½ qᵀH_X q + b_X·q + c_X and Y likewise (the turning direction's components along the two
directions normal to the axis) and θ(t) the driver's law, read at the step's end (columns θ, θ̇, θ̈ of the
time table), as every row's time dependence. With c = cos θ, s = sin θ:

* Φ_q = c ∇Y(q₁) − s ∇X(q₁); the exact discrete gradient at fixed t is D = c ∇Y(q_m) − s ∇X(q_m), q_m the
  mid-point of q_a and q_b, and ∂(Dᵀμ)/∂q_b = ½ μ (c H_Y − s H_X);
* Φ_t = −θ̇ (s Y + c X), which depends on q: Φ_qt = −θ̇ (s ∇Y + c ∇X);
* the rate Jacobian handed to :func:`..rows.finish_row` is ∂(Φ_q v₁ + Φ_t)/∂q = (c H_Y − s H_X) v₁ + Φ_qt, so
  that a velocity row's Newton row is exact; the acceleration row then holds Φ_q a₁ + vᵀ(c H_Y − s H_X) v +
  Φ_qt·v + (Φ_qt·v + Φ_tt), the driver's 2 Φ_qt v + Φ_tt (its ``time_terms``), with
  Φ_tt = −θ̈ (s Y + c X) − θ̇² (c Y − s X).
"""
from __future__ import annotations

import numba
import numpy as np

from ..abi import context_of, family_of
from ..registry import compiled_kernel
from ..rows import row_states, write_row
from ..storage import storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack
from .quadratic_rows import TermLists, add_form, form_terms, view_of, with_positions

NAME = "rotation drivers"
FORMS = ("rotation driver",)


def row_count(term):
    return 1


def pack(items, packer):
    """The drivers' rows in the quadratic-row family's :class:`~.quadratic_rows.Data`: per row the pair terms of
    X then of Y, their linear terms likewise, (c_X, c_Y) in ``const``; the row table (k, 9): row, pair terms
    of X [p0, p1) and of Y [p1, p2), linear terms of X [l0, l1) and of Y [l1, l2), first column, law column
    (θ, θ̇, θ̈ follow)."""
    rows, const = [], []
    terms = TermLists()
    row_support, couplings = [], []
    for ((term, _), constraint, (idx, first)) in items:
        _, Hx, bx, cx, Hy, by, cy, law = term
        idx = np.asarray(idx, dtype=np.int64)
        fx, fy = form_terms(Hx, bx), form_terms(Hy, by)
        touched = np.unique(np.concatenate([fx[0], fx[1], fx[3], fy[0], fy[1], fy[3]])).astype(np.int64)
        slot = {int(t): s for s, t in enumerate(touched)}
        col = packer.law_columns(law)
        p0, l0 = len(terms.pi), len(terms.li)
        terms.add(idx, slot, fx, bx)
        terms.add(idx, slot, fy, by)
        rows.append((first, p0, p0 + fx[0].size, len(terms.pi), l0, l0 + fx[3].size, len(terms.li), len(terms.cols),
                     col))
        terms.cols.extend(idx[touched])
        const.append((float(cx), float(cy)))
        row_support.append((first, idx[touched]))
        couplings.append(idx[touched])
    data = terms.data(rows, 9, const)
    return FamilyPack(data=data, count=len(rows), couplings=couplings, rows=row_support,
                      finish=lambda layout: with_positions(data, 7, layout))


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    q1, qa, qb, v1, mu, trow, scratch, w, evaluate = row_states(ctx)
    st = storage_of(ctx)
    n_rows = d.rows.shape[0]
    for r in range(n_rows):
        row, p0, p1, p2, l0, l1, l2, c0, col = d.rows[r]
        c1 = d.rows[r + 1, 7] if r + 1 < n_rows else d.cols.size - 1
        nc = c1 - c0
        # per form (X: 0, Y: 1) over the row's columns: ∇ at q₁, ∇ at the mid-point, H v₁
        g, dm, hv = scratch[:2 * nc], scratch[2 * nc:4 * nc], scratch[4 * nc:6 * nc]
        cq, dd, cv = scratch[6 * nc:7 * nc], scratch[7 * nc:8 * nc], scratch[8 * nc:9 * nc]
        for t in range(2 * nc):
            g[t] = 0.0
            dm[t] = 0.0
            hv[t] = 0.0
        th, om, al = trow[col], trow[col + 1], trow[col + 2]
        c, s = np.cos(th), np.sin(th)
        # the forms X and Y, each over its own half of the scratch; ∂(Dᵀμ)/∂q_b = ½ μ (c H_Y − s H_X)
        e = 0.5 * w * mu[row]
        vx = d.const[2 * r] + add_form(st, d, p0, p1, l0, l1, q1, qa, qb, v1, g[:nc], dm[:nc], hv[:nc],
                                       evaluate, -s * e)
        vy = d.const[2 * r + 1] + add_form(st, d, p1, p2, l1, l2, q1, qa, qb, v1, g[nc:], dm[nc:], hv[nc:],
                                           evaluate, c * e)
        value = c * vy - s * vx
        phi_t = -om * (s * vy + c * vx)
        qt_v = 0.0
        for t in range(nc):
            cq[t] = c * g[nc + t] - s * g[t]
            dd[t] = c * dm[nc + t] - s * dm[t]
            qt = -om * (s * g[nc + t] + c * g[t])
            cv[t] = c * hv[nc + t] - s * hv[t] + qt
            qt_v += qt * v1[d.cols[c0 + t]]
        phi_tt = qt_v - al * (s * vy + c * vx) - om * om * (c * vy - s * vx)
        write_row(ctx, st, row, value, phi_t, phi_tt, d.cols[c0:c1], cq, dd, cv, nc, d.cpos[2 * c0:2 * c1])


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, view_of(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the rotation-driver family")
