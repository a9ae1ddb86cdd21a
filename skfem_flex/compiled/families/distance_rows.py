r"""Distance constraints of a point whose position is linear in q: Φ = ½(|r − a|² − l²) = 0.

Φ is quadratic in q, so the mid-point gradient D = (r̄ − a)ᵀ J, r̄ = (r(q_a) + r(q_b))/2, is an exact
discrete gradient; ∂(Dᵀμ)/∂q_b = ½ μ JᵀJ; ∂(Φ_q v)/∂q = (J v)ᵀ J.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_at, family_of, fmat, fvec, i1, i2
from ..points import NB, OFF, jacobian_into, maps_view, position_into
from ..registry import compiled_kernel
from ..rows import finish_row
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack

NAME = "distance constraints"
FORMS = ("distance",)


def row_count(term):
    return 1


class Data(NamedTuple):
    rows: np.ndarray        # (k, 2): row, map
    anchor: np.ndarray      # (k, 2) a, m
    length: np.ndarray      # (k,) l, m
    cols: np.ndarray        # (k·nb) the coordinates of each map's body block, in order
    cptr: np.ndarray        # (k + 1,)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f2(fam, 1), f1(fam, 2), i1(fam, 3), i1(fam, 4))


def pack(items, packer):
    rows, anchor, length, cols, cptr, support = [], [], [], [], [0], []
    for ((term, law), constraint, (idx, row)) in items:
        _, point, a, l_ = term
        entry = point.compiled_map() if hasattr(point, "compiled_map") else None
        if entry is None or entry[0] != "linear":
            raise ValueError(f"constraint {constraint.name!r}: a distance constraint needs a point linear in q")
        k = packer.point_map(point)
        o, nb = packer.block(point.body)
        rows.append((row, k))
        anchor.append(np.asarray(a, dtype=float).reshape(2))
        length.append(float(l_))
        cols.extend(range(o, o + nb))
        cptr.append(len(cols))
        support.append((row, packer.maps_support(k)))
    n = len(rows)
    data = Data(np.asarray(rows, dtype=np.int64).reshape(n, 2), np.asarray(anchor).reshape(n, 2),
                np.asarray(length, dtype=float), np.asarray(cols, dtype=np.int64), np.asarray(cptr, dtype=np.int64))
    return FamilyPack(data=data, count=n, couplings=[s for _, s in support], rows=support)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q1, qa, qb, v1 = fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.v1, n)
    mu = fvec(ctx.mu, ctx.m)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    top = ctx.nscratch
    r, ra, rb = scratch[top - 6:top - 4], scratch[top - 4:top - 2], scratch[top - 2:top]
    for i in range(d.rows.shape[0]):
        row, k = d.rows[i]
        o, nb = maps.ints[k, OFF], maps.ints[k, NB]
        J = fmat(scratch.ctypes.data + 8 * (0), 2, nb)
        cq, dd, cv = scratch[2 * nb:3 * nb], scratch[3 * nb:4 * nb], scratch[4 * nb:5 * nb]
        position_into(maps, k, q1[o:o + nb], r)
        jacobian_into(maps, k, q1[o:o + nb], J)
        dx, dy = r[0] - d.anchor[i, 0], r[1] - d.anchor[i, 1]
        position_into(maps, k, qa[o:o + nb], ra)
        position_into(maps, k, qb[o:o + nb], rb)
        mx = 0.5 * (ra[0] + rb[0]) - d.anchor[i, 0]
        my = 0.5 * (ra[1] + rb[1]) - d.anchor[i, 1]
        wx, wy = 0.0, 0.0
        for j in range(nb):
            wx += J[0, j] * v1[o + j]
            wy += J[1, j] * v1[o + j]
        for j in range(nb):
            cq[j] = dx * J[0, j] + dy * J[1, j]
            dd[j] = mx * J[0, j] + my * J[1, j]
            cv[j] = wx * J[0, j] + wy * J[1, j]
        value = 0.5 * (dx * dx + dy * dy - d.length[i] * d.length[i])
        if ctx.task == TASK_EVAL:
            w = 0.5 * ctx.w_mu * ctx.c_dg * ctx.dq1 * mu[row]
            for a in range(nb):
                for j in range(nb):
                    add_qq(ctx, st, o + a, o + j, w * (J[0, a] * J[0, j] + J[1, a] * J[1, j]))
        finish_row(ctx, st, row, value, 0.0, 0.0, d.cols[d.cptr[i]:d.cptr[i + 1]], cq, dd, cv, nb)


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the distance-constraint family")
