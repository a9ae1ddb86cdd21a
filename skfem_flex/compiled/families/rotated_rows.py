r"""Lines on moving bodies: Φ = n(ϑ) · e = 0, one row (sliders and prismatic joints guided by a body).

n = A(ϑ) n_loc is the line's normal, turning with the angle ϑ = g · q + c of the guiding body's point, and
e = Σ s_i r_i(q) − c_e a difference of body points (position maps, :mod:`..points`): the compiled form
``("rotated projected", g, c, n_loc, ("points", [(point, s), ...], c_e))`` of a
:class:`~skfem_flex.elements.point_terms.Dot` of a :class:`~skfem_flex.elements.point_terms.Rotated` normal
and a point difference. With Δϑ = ϑ_b − ϑ_a, ϑ_m = (ϑ_a + ϑ_b)/2, σ = sinc(Δϑ/2), ē, n̄ the means of the
end values and E the quarter turn:

* Φ(q₁) = n₁ · e₁; Φ_q = (e₁ · E n₁) g + n₁ · J_e(q₁);
* the exact discrete gradient (product rule on the mean end values and A(ϑ_b) − A(ϑ_a) =
  σ Δϑ A(ϑ_m) E): D = σ (ē · E A(ϑ_m) n_loc) g + n̄ · D_e, D (q_b − q_a) = Φ(q_b) − Φ(q_a);
* its derivative for a fixed multiplier, added with the weight w = w_mu c_dg dq1 (at q_a = q_b,
  c_dg = 2: the Hessian): μ (dσ/dΔϑ ē · E a_m − ½ σ ē · a_m) g ⊗ g + ∂(μ n̄ · D_e)/∂q_b
  + ½ μ (D_nᵀ J_e + D_eᵀ J_n), a_m = A(ϑ_m) n_loc, D_n = σ E a_m ⊗ g, J_n = E n₁ ⊗ g;
* velocity and acceleration rows: ∂(Φ_q v₁)/∂q = n₁ · ∂(J_e v₁)/∂q + (g · v₁) (E n₁)ᵀ J_e
  + ((J_e v₁) · E n₁ − (g · v₁)(e₁ · n₁)) g.

The equations are those of the numpy terms (:mod:`skfem_flex.elements.point_terms`), in the same order of
summation; :func:`~skfem_flex.compiled.rows.finish_row` writes what the task and the row level need.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ...numerics.rotations import sinc_half
from ..abi import context_of, f1, f2, family_at, family_of, fmat, fvec, i1, i2
from ..points import KIND, LINEAR, NB, OFF, dgrad_into, dgrad_jacobian_parts, jacobian_into, maps_view, position_into, \
    velocity_jacobian_into
from ..registry import compiled_kernel
from ..rows import finish_row, needs_rate_jacobian
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL, TASK_ROWS
from . import FamilyPack

__all__ = ["NAME", "FORMS", "row_count", "pack", "kernel"]

NAME = "lines on moving bodies"
FORMS = ("rotated projected",)


def row_count(term):
    """Rows of a block: one."""
    return 1


class Data(NamedTuple):
    blocks: np.ndarray      # (k, 7): row, first and end angle coefficient, first and end term, first and end col
    vals: np.ndarray        # (k, 5): c (rad), n_loc (2), c_e (2, m)
    lin_idx: np.ndarray     # scene coordinates of the angle's coefficients
    lin_coef: np.ndarray    # g (rad per unit of the coordinate)
    lin_slot: np.ndarray    # position of each in its block's ``cols``
    term_map: np.ndarray    # map of each point term
    term_sign: np.ndarray   # its sign
    term_slot: np.ndarray   # first entry of its slots in ``slots``
    slots: np.ndarray       # for each coordinate of a term's body block, its position in the block's ``cols``
    cols: np.ndarray        # the coordinates each block touches (its maps' blocks and the angle's coordinates)


@numba.njit(cache=True)
def _view(fam):
    return Data(i2(fam, 0), f2(fam, 1), i1(fam, 2), f1(fam, 3), i1(fam, 4), i1(fam, 5), f1(fam, 6), i1(fam, 7),
                i1(fam, 8), i1(fam, 9))


def pack(items, packer):
    """The family's data from the items ((("rotated projected", g, c, n_loc, points), law), constraint,
    (coordinates, row)): g over the constraint's coordinates (rad per m or per rad), c (rad), n_loc the unit
    normal at ϑ = 0, ``points`` = ("points", [(point, sign), ...], c_e (m)).

    Returns
    -------
    FamilyPack
        ``rows``: each block's row and the coordinates Φ_q may touch (its maps' supports and the angle's
        coordinates); ``couplings``: the same sets (∂(Dᵀμ)/∂q couples them).

    Raises
    ------
    ValueError
        If a block has a motion law or a point has no compiled map.
    """
    blocks, vals, lin_idx, lin_coef, lin_slot = [], [], [], [], []
    tmap, tsign, tslot, slots, cols = [], [], [], [], []
    rows, couplings = [], []
    for ((term, law), constraint, (cidx, row)) in items:
        if law is not None:
            raise ValueError(f"constraint {constraint.name!r}: a motion law on a {term[0]!r} block is not supported")
        _, grad, c, nloc, (_, terms, ce) = term
        grad = np.asarray(grad, dtype=float)
        nz = np.flatnonzero(grad)
        gidx = np.asarray(cidx, dtype=np.int64)[nz]
        maps = []
        for point, sign in terms:
            k = packer.point_map(point)
            if k is None:
                raise ValueError(f"constraint {constraint.name!r}: a point has no compiled map")
            maps.append((k, float(sign), packer.block(point.body)))
        union = np.unique(np.concatenate([np.arange(o, o + nb) for _, _, (o, nb) in maps] + [gidx]))
        l0, t0 = len(lin_idx), len(tmap)
        lin_idx.extend(gidx)
        lin_coef.extend(grad[nz])
        lin_slot.extend(np.searchsorted(union, gidx))
        for k, sign, (o, nb) in maps:
            tmap.append(k)
            tsign.append(sign)
            tslot.append(len(slots))
            slots.extend(np.searchsorted(union, np.arange(o, o + nb)))
        blocks.append((row, l0, len(lin_idx), t0, len(tmap), len(cols), len(cols) + union.size))
        cols.extend(union)
        vals.append((float(c), *np.asarray(nloc, dtype=float).reshape(2), *np.asarray(ce, dtype=float).reshape(2)))
        support = np.unique(np.concatenate([packer.maps_support(k) for k, _, _ in maps] + [gidx]))
        rows.append((row, support))
        couplings.append(support)
    k = len(blocks)
    i64 = lambda a: np.asarray(a, dtype=np.int64)           # noqa: E731 (a one-line converter)
    data = Data(i64(blocks).reshape(k, 7), np.asarray(vals, dtype=float).reshape(k, 5), i64(lin_idx),
                np.asarray(lin_coef, dtype=float), i64(lin_slot), i64(tmap), np.asarray(tsign, dtype=float),
                i64(tslot), i64(slots), i64(cols))
    return FamilyPack(data=data, count=k, couplings=couplings, rows=rows)


@numba.njit(cache=True)
def _evaluate(ctx, d):
    """Every block's row for TASK_EVAL or TASK_ROWS (module docstring; ``d``: the family's Data)."""
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q1, qa, v1 = fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.v1, n)
    mu = fvec(ctx.mu, ctx.m)
    st = storage_of(ctx)
    evaluate = ctx.task == TASK_EVAL
    rate = needs_rate_jacobian(ctx)
    w = ctx.w_mu * ctx.c_dg * ctx.dq1
    scratch = fvec(ctx.scratch, ctx.nscratch)
    r = scratch[ctx.nscratch - 2:]              # a point's position (the blocks' work space stays below 11 n)
    for b in range(d.blocks.shape[0]):
        row, l0, l1, t0, t1, c0, c1 = d.blocks[b]
        nc = c1 - c0
        # Φ_q, D and ∂(Φ_q v₁)/∂q over the block's coordinates
        buf = scratch[:3 * nc]
        for i in range(3 * nc):
            buf[i] = 0.0
        cq, dd, cv = buf[:nc], buf[nc:2 * nc], buf[2 * nc:]
        nbmax = 0
        for t in range(t0, t1):
            nbmax = max(nbmax, maps.ints[d.term_map[t], NB])
        work = scratch[3 * nc:3 * nc + 8 * nbmax]
        # the angle ϑ at both ends and its rate g · v₁
        th1 = d.vals[b, 0]
        th0, gv = th1, 0.0
        for t in range(l0, l1):
            th1 += d.lin_coef[t] * q1[d.lin_idx[t]]
            th0 += d.lin_coef[t] * qa[d.lin_idx[t]]
            gv += d.lin_coef[t] * v1[d.lin_idx[t]]
        if not evaluate:
            th0 = th1
        # e = Σ s r − c_e at both ends
        e0x, e0y, e1x, e1y = -d.vals[b, 3], -d.vals[b, 4], -d.vals[b, 3], -d.vals[b, 4]
        for t in range(t0, t1):
            k, s = d.term_map[t], d.term_sign[t]
            o, nb = maps.ints[k, OFF], maps.ints[k, NB]
            if evaluate:
                position_into(maps, k, qa[o:o + nb], r)
                e0x += s * r[0]
                e0y += s * r[1]
            position_into(maps, k, q1[o:o + nb], r)
            e1x += s * r[0]
            e1y += s * r[1]
        lx, ly = d.vals[b, 1], d.vals[b, 2]
        n0x, n0y = np.cos(th0) * lx - np.sin(th0) * ly, np.sin(th0) * lx + np.cos(th0) * ly
        n1x, n1y = np.cos(th1) * lx - np.sin(th1) * ly, np.sin(th1) * lx + np.cos(th1) * ly
        tm = 0.5 * (th0 + th1)
        amx, amy = np.cos(tm) * lx - np.sin(tm) * ly, np.sin(tm) * lx + np.cos(tm) * ly    # A(ϑ_m) n_loc
        sig, dsig = sinc_half(th1 - th0)
        ebx, eby = 0.5 * (e0x + e1x), 0.5 * (e0y + e1y)
        nbx, nby = 0.5 * (n0x + n1x), 0.5 * (n0y + n1y)
        mus = w * mu[row]
        ang_cq = -e1x * n1y + e1y * n1x                     # e₁ · E n₁
        ang_d = sig * (-ebx * amy + eby * amx)              # σ ē · E a_m
        # the rotation's own term of ∂(μ Dᵀ)/∂q_b: μ (dσ/dΔϑ ē · E a_m − ½ σ ē · a_m) g ⊗ g
        cgg = mus * (dsig * (-ebx * amy + eby * amx) - 0.5 * sig * (ebx * amx + eby * amy))
        for a in range(l0, l1):
            sa = d.lin_slot[a]
            cq[sa] += ang_cq * d.lin_coef[a]
            if evaluate:
                dd[sa] += ang_d * d.lin_coef[a]
                for bb in range(l0, l1):
                    add_qq(ctx, st, d.lin_idx[a], d.lin_idx[bb], cgg * d.lin_coef[a] * d.lin_coef[bb])
        jevx, jevy = 0.0, 0.0
        for t in range(t0, t1):
            k, s = d.term_map[t], d.term_sign[t]
            o, nb = maps.ints[k, OFF], maps.ints[k, NB]
            slot = d.slots[d.term_slot[t]:d.term_slot[t] + nb]
            J = fmat(work.ctypes.data + 8 * (0), 2, nb)
            D = fmat(work.ctypes.data + 8 * (2 * nbmax), 2, nb)
            V = fmat(work.ctypes.data + 8 * (4 * nbmax), 2, nb)
            jacobian_into(maps, k, q1[o:o + nb], J)
            if evaluate:
                dgrad_into(maps, k, qa[o:o + nb], q1[o:o + nb], D)
            if rate:
                velocity_jacobian_into(maps, k, q1[o:o + nb], v1[o:o + nb], V)
            for j in range(nb):
                sj = slot[j]
                cq[sj] += s * (n1x * J[0, j] + n1y * J[1, j])
                if evaluate:
                    dd[sj] += s * (nbx * D[0, j] + nby * D[1, j])
                if rate:
                    cv[sj] += s * (n1x * V[0, j] + n1y * V[1, j]) + gv * s * (-n1y * J[0, j] + n1x * J[1, j])
                    jevx += s * J[0, j] * v1[o + j]
                    jevy += s * J[1, j] * v1[o + j]
            if not evaluate:
                continue
            if maps.ints[k, KIND] != LINEAR:                      # μ n̄ · ∂D_e/∂q_b
                _add_map_dgrad_jacobian(ctx, st, maps, k, qa[o:o + nb], q1[o:o + nb], s * mus * nbx,
                                        s * mus * nby, work[6 * nbmax:])
            # ½ μ (D_nᵀ J_e + D_eᵀ J_n), J_n = E n₁ ⊗ g
            for j in range(nb):
                dn_je = 0.5 * mus * sig * s * (-amy * J[0, j] + amx * J[1, j])
                de_jn = 0.5 * mus * s * (-n1y * D[0, j] + n1x * D[1, j])
                for a in range(l0, l1):
                    add_qq(ctx, st, d.lin_idx[a], o + j, dn_je * d.lin_coef[a])
                    add_qq(ctx, st, o + j, d.lin_idx[a], de_jn * d.lin_coef[a])
        if rate:                                            # (J_e v)·E n₁ g − (g·v)(e₁·n₁) g
            c_g = -jevx * n1y + jevy * n1x - gv * (e1x * n1x + e1y * n1y)
            for a in range(l0, l1):
                cv[d.lin_slot[a]] += c_g * d.lin_coef[a]
        finish_row(ctx, st, row, n1x * e1x + n1y * e1y, 0.0, 0.0, d.cols[c0:c1], cq, dd, cv, nc)


@numba.njit(cache=True)
def _add_map_dgrad_jacobian(ctx, st, maps, k, qa, qb, f0, f1, work):
    """Newton matrix += ∂(D_kᵀ f)/∂q_b of a FRAME map k (body block qa, qb; ``work`` ≥ 2 n_b)."""
    o, nb = maps.ints[k, OFF], maps.ints[k, NB]
    f = work[:2]
    f[0], f[1] = f0, f1
    row, col = work[2:nb - 1], work[nb - 1:2 * nb - 4]
    h22 = dgrad_jacobian_parts(maps, k, qa, qb, f, row, col)
    add_qq(ctx, st, o + 2, o + 2, h22)
    for j in range(nb - 3):
        add_qq(ctx, st, o + 2, o + 3 + j, row[j])
        add_qq(ctx, st, o + 3 + j, o + 2, col[j])


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL and TASK_ROWS."""
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, _view(family_of(fam_p)))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the family of lines on moving bodies")
