r"""Point constraints in the plane: Σ s_i r_i(q) − c = 0 (two rows: pins, revolute joints, the position part of
welds) and its projection n · (Σ s_i r_i − c) = 0 on a fixed normal (one row: sliders on the ground).

The body points are position maps (:mod:`..points`). Φ is linear in the points' positions, so its exact
discrete gradient is Σ s_i D_i with the maps' exact discrete gradients D_i, and ∂(Dᵀμ)/∂q_b is the
maps' ∂(D_iᵀ f)/∂q_b with f = s_i μ (rows) or s_i μ n (projected).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_at, family_of, fmat, fvec, i1, i2
from ..points import (KIND, LINEAR, NB, OFF, dgrad_into, dgrad_jacobian_parts, jacobian_into, maps_view, position_into,
                      velocity_jacobian_into)
from ..registry import compiled_kernel
from ..rows import finish_row, needs_rate_jacobian
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack

NAME = "point constraints"
FORMS = ("points", "projected")


def row_count(term):
    """Rows of a block."""
    return 2 if term[0] == "points" else 1


class Data(NamedTuple):
    blocks: np.ndarray      # (k, 6): first row, projected (0/1), first term, end term, first col, end col
    nrm: np.ndarray         # (k, 2) normal of a projected block
    const: np.ndarray       # (k, 2) c
    term_map: np.ndarray    # map of each term
    term_sign: np.ndarray   # its sign
    term_slot: np.ndarray   # first entry of its slots in ``slots``
    slots: np.ndarray       # for each coordinate of a term's block, its position in the block's ``cols``
    cols: np.ndarray        # the coordinates each block touches (its maps' blocks, merged)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f2(fam, 1), f2(fam, 2), i1(fam, 3), f1(fam, 4), i1(fam, 5), i1(fam, 6), i1(fam, 7))


def pack(items, packer):
    blocks, nrm, const, tmap, tsign, tslot, slots, cols = [], [], [], [], [], [], [], []
    rows = []
    for ((term, law), constraint, (idx, row)) in items:
        if law is not None:
            raise ValueError(f"constraint {constraint.name!r}: a motion law on a {term[0]!r} block is not supported")
        if term[0] == "points":
            projected, normal, points_form = 0, np.zeros(2), term
        else:
            projected, normal, points_form = 1, np.asarray(term[1], dtype=float).reshape(2), term[2]
        _, terms, c = points_form
        maps = []
        for point, sign in terms:
            k = packer.point_map(point)
            if k is None:
                raise ValueError(f"constraint {constraint.name!r}: a point has no compiled map")
            maps.append((k, float(sign), packer.block(point.body)))
        union = np.unique(np.concatenate([np.arange(o, o + nb) for _, _, (o, nb) in maps]))
        t0 = len(tmap)
        for k, sign, (o, nb) in maps:
            tmap.append(k)
            tsign.append(sign)
            tslot.append(len(slots))
            slots.extend(np.searchsorted(union, np.arange(o, o + nb)))
        blocks.append((row, projected, t0, len(tmap), len(cols), len(cols) + union.size))
        cols.extend(union)
        nrm.append(normal)
        const.append(np.asarray(c, dtype=float).reshape(2))
        support = np.unique(np.concatenate([packer.maps_support(k) for k, _, _ in maps]))
        for r in range(row, row + (1 if projected else 2)):
            rows.append((r, support))
    k = len(blocks)
    data = Data(np.asarray(blocks, dtype=np.int64).reshape(k, 6), np.asarray(nrm).reshape(k, 2),
                np.asarray(const).reshape(k, 2), np.asarray(tmap, dtype=np.int64), np.asarray(tsign, dtype=float),
                np.asarray(tslot, dtype=np.int64), np.asarray(slots, dtype=np.int64),
                np.asarray(cols, dtype=np.int64))
    couplings = [np.unique(np.concatenate([packer.maps_support(tmap[t]) for t in range(b[2], b[3])]))
                 for b in blocks]
    return FamilyPack(data=data, count=k, couplings=couplings, rows=rows)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q1, qa, qb, v1 = fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.v1, n)
    mu = fvec(ctx.mu, ctx.m)
    st = storage_of(ctx)
    evaluate = ctx.task == TASK_EVAL
    rate = needs_rate_jacobian(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    r = scratch[ctx.nscratch - 2:ctx.nscratch]
    for b in range(d.blocks.shape[0]):
        row, projected, t0, t1, c0, c1 = d.blocks[b]
        nc = c1 - c0
        cols = d.cols[c0:c1]
        # per row: Φ_q, D, ∂(Φ_q v)/∂q over the block's coordinates (two rows: 6 nc)
        buf = scratch[:6 * nc]
        for i in range(6 * nc):
            buf[i] = 0.0
        cq = fmat(buf.ctypes.data + 8 * (0), 2, nc)
        dd = fmat(buf.ctypes.data + 8 * (2 * nc), 2, nc)
        cv = fmat(buf.ctypes.data + 8 * (4 * nc), 2, nc)
        acc0, acc1 = -d.const[b, 0], -d.const[b, 1]
        nbmax = 0
        for t in range(t0, t1):
            nbmax = max(nbmax, maps.ints[d.term_map[t], NB])
        work = scratch[6 * nc:6 * nc + 8 * nbmax]
        jac = work[:2 * nbmax]
        dk = work[2 * nbmax:4 * nbmax]
        vj = work[4 * nbmax:6 * nbmax]
        for t in range(t0, t1):
            k, s = d.term_map[t], d.term_sign[t]
            o, nb = maps.ints[k, OFF], maps.ints[k, NB]
            slot = d.slots[d.term_slot[t]:d.term_slot[t] + nb]
            J = fmat(jac.ctypes.data + 8 * (0), 2, nb)
            D = fmat(dk.ctypes.data + 8 * (0), 2, nb)
            position_into(maps, k, q1[o:o + nb], r)
            acc0 += s * r[0]
            acc1 += s * r[1]
            jacobian_into(maps, k, q1[o:o + nb], J)
            if evaluate:
                dgrad_into(maps, k, qa[o:o + nb], qb[o:o + nb], D)
            if rate:
                V = fmat(vj.ctypes.data + 8 * (0), 2, nb)
                velocity_jacobian_into(maps, k, q1[o:o + nb], v1[o:o + nb], V)
            for j in range(nb):
                sj = slot[j]
                for a in range(2):
                    cq[a, sj] += s * J[a, j]
                    if evaluate:
                        dd[a, sj] += s * D[a, j]
                    if rate:
                        cv[a, sj] += s * vj[a * nb + j]
            if evaluate and maps.ints[k, KIND] != LINEAR:
                # w_mu c_dg dq1 ∂(D_kᵀ f)/∂q_b with f = s μ (rows) or s μ n (projected)
                if projected:
                    f0 = s * d.nrm[b, 0] * mu[row]
                    f1 = s * d.nrm[b, 1] * mu[row]
                else:
                    f0, f1 = s * mu[row], s * mu[row + 1]
                _add_map_dgrad_jacobian(ctx, st, maps, k, qa[o:o + nb], qb[o:o + nb], f0, f1,
                                        ctx.w_mu * ctx.c_dg * ctx.dq1, work[6 * nbmax:])
        if projected:
            nx_, ny_ = d.nrm[b, 0], d.nrm[b, 1]
            for j in range(nc):
                cq[0, j] = nx_ * cq[0, j] + ny_ * cq[1, j]
                dd[0, j] = nx_ * dd[0, j] + ny_ * dd[1, j]
                cv[0, j] = nx_ * cv[0, j] + ny_ * cv[1, j]
            finish_row(ctx, st, row, nx_ * acc0 + ny_ * acc1, 0.0, 0.0, cols, cq[0], dd[0], cv[0], nc)
        else:
            finish_row(ctx, st, row, acc0, 0.0, 0.0, cols, cq[0], dd[0], cv[0], nc)
            finish_row(ctx, st, row + 1, acc1, 0.0, 0.0, cols, cq[1], dd[1], cv[1], nc)


@numba.njit(cache=True, _nrt=False)
def _add_map_dgrad_jacobian(ctx, st, maps, k, qa, qb, f0, f1, w, work):
    """Newton matrix += w ∂(D_kᵀ f)/∂q_b of a FRAME map k (body block qa, qb; ``work`` ≥ 2 n_b)."""
    o, nb = maps.ints[k, OFF], maps.ints[k, NB]
    f = work[:2]
    f[0], f[1] = f0, f1
    row, col = work[2:nb - 1], work[nb - 1:2 * nb - 4]
    h22 = dgrad_jacobian_parts(maps, k, qa, qb, f, row, col)
    add_qq(ctx, st, o + 2, o + 2, w * h22)
    for j in range(nb - 3):
        add_qq(ctx, st, o + 2, o + 3 + j, w * row[j])
        add_qq(ctx, st, o + 3 + j, o + 2, w * col[j])


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the point-constraint family")
