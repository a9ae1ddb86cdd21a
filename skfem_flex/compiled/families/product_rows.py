r"""Constraint rows with products of two quadratic invariants: Φ = φ₀(q) + Σ_m a_m(q) s_m(q) − s(t) (joints with
axes at a floating-frame body's material points against moving bodies,
:mod:`skfem_flex.elements.constraints.product_rows`).

Every factor is a quadratic form, evaluated by the quadratic-row family's :func:`~.quadratic_rows.add_form`
(its value at q₁, gradient at q₁ and at the mid-point of (q_a, q_b), and H v₁). Per product term, with
q_b = q₁ in every scheme (:mod:`..tasks`) and a(q_a) = a(q_b) − ∇a(q_m)·(q_b − q_a) (exact for a quadratic):

* Φ_q = a ∇s + s ∇a at q₁; D = ā ∇s(q_m) + s̄ ∇a(q_m), ā = ½(a(q_a) + a(q_b));
* ∂(Φ_q v₁)/∂q = a H_s v₁ + s H_a v₁ + ∇a (∇s·v₁) + ∇s (∇a·v₁);
* ∂(Dᵀμ)/∂q_b = μ [½ ā H_s + ½ s̄ H_a + ½ ∇s(q_m) ∇a(q_b)ᵀ + ½ ∇a(q_m) ∇s(q_b)ᵀ]: the Hessians at the pair
  terms' places, the outer products over the row's block of columns (its places ``bpos``, found once).

The Newmark schemes set q_a = q_b = q₁ and c_dg = 2, so the same code gives their Φ_q and ∇²Φ.
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
from .quadratic_rows import TermLists, add_form, form_terms, with_positions

NAME = "product constraint rows"
FORMS = ("product",)


def row_count(term):
    """The equations of one constraint's form."""
    return int(np.shape(term[2])[0])


class Data(NamedTuple):
    rows: np.ndarray        # (k, 10): row, base pair terms [p0, p1), base linear terms [l0, l1), product
    #                         terms [t0, t1), first column, law column, first place in bpos
    const: np.ndarray       # (k,) the base form's c
    pi: np.ndarray          # pair and linear terms of every form (quadratic_rows.Data's fields 2–12)
    pj: np.ndarray
    psi: np.ndarray
    psj: np.ndarray
    ph: np.ndarray
    li: np.ndarray
    lsl: np.ndarray
    lb: np.ndarray
    cols: np.ndarray
    ppos: np.ndarray
    cpos: np.ndarray
    prods: np.ndarray       # (P, 12): the factor a's pair terms [p0, p1), linear terms [l0, l1); then s's;
    #                         then the slots a touches [sup0, sup1) in ``sup``, and those s touches
    pconst: np.ndarray      # (2P,) c of a and of s, term after term
    bpos: np.ndarray        # per row its nc × nc block of places in the Newton matrix's values
    sup: np.ndarray         # the slots of each factor's coordinates (its support), factor after factor


@numba.njit(cache=True, _nrt=False)
def view_of(fam):
    """The family record's arrays as :class:`Data`."""
    return Data(i2(fam, 0), f1(fam, 1), i1(fam, 2), i1(fam, 3), i1(fam, 4), i1(fam, 5), f1(fam, 6), i1(fam, 7),
                i1(fam, 8), f1(fam, 9), i1(fam, 10), i1(fam, 11), i1(fam, 12), i2(fam, 13), f1(fam, 14),
                i1(fam, 15), i1(fam, 16))


def pack(items, packer):
    """The rows of every item (``("product", H, b, c, laws, columns, products)``) in one :class:`Data`: per row its
    base form and its product terms' two forms as pair and linear terms over the row's touched coordinates
    (``cols``), each factor's support, and a law's columns."""
    rows, const, prods, pconst, sup = [], [], [], [], []
    terms = TermLists()
    row_support, couplings = [], []
    nblock = 0
    for ((term, _), constraint, (idx, first)) in items:
        _, H, b, c, laws, columns, products = term
        idx = np.asarray(idx, dtype=np.int64)[columns]
        for k in range(H.shape[0]):
            base = form_terms(H[k], b[k])
            factors = [(form_terms(p.a.H, p.a.b), p.a.b, p.a.c, form_terms(p.s.H, p.s.b), p.s.b, p.s.c)
                       for p in products.terms if p.row == k]
            forms = [base] + [f for fa, _, _, fs, _, _ in factors for f in (fa, fs)]
            touched = np.unique(np.concatenate([np.concatenate([f[0], f[1], f[3]]) for f in forms])).astype(np.int64)
            slot = {int(t): s for s, t in enumerate(touched)}
            col = -1
            law = laws[k]
            if law is not None:
                col = packer.law_columns(law)
            p0, l0 = len(terms.pi), len(terms.li)
            terms.add(idx, slot, base, b[k])
            t0 = len(prods)
            for fa, ba, ca, fs, bs, cs in factors:
                entry = [len(terms.pi), len(terms.pi) + fa[0].size, len(terms.li), len(terms.li) + fa[3].size]
                terms.add(idx, slot, fa, ba)
                entry += [len(terms.pi), len(terms.pi) + fs[0].size, len(terms.li), len(terms.li) + fs[3].size]
                terms.add(idx, slot, fs, bs)
                for f in (fa, fs):
                    entry += [len(sup), len(sup) + np.unique(np.concatenate([f[0], f[1], f[3]])).size]
                    sup += [slot[int(t)] for t in np.unique(np.concatenate([f[0], f[1], f[3]]))]
                prods.append(entry)
                pconst += [float(ca), float(cs)]
            rows.append((first + k, p0, p0 + base[0].size, l0, l0 + base[3].size, t0, len(prods), len(terms.cols),
                         col, nblock))
            terms.cols.extend(idx[touched])
            nblock += touched.size ** 2
            const.append(float(c[k]))
            row_support.append((first + k, idx[touched]))
            couplings.append(idx[touched])
    base_data = terms.data(rows, 10, const)
    data = Data(*base_data, np.asarray(prods, dtype=np.int64).reshape(-1, 12), np.asarray(pconst, dtype=float),
                -np.ones(nblock, dtype=np.int64), np.asarray(sup, dtype=np.int64))
    return FamilyPack(data=data, count=len(rows), couplings=couplings, rows=row_support,
                      finish=lambda layout: _with_blocks(data, layout))


def _with_blocks(data, layout):
    """``data`` with its pair terms' and border entries' places (:func:`~.quadratic_rows.with_positions`) and
    each row's block of places (column i, column j) of its touched coordinates."""
    data = with_positions(data, 7, layout)
    fpos = layout[2]
    starts = data.rows[:, 7]
    ends = np.append(starts[1:], data.cols.size - 1)
    blocks = []
    for a, b in zip(starts, ends):
        f = fpos[data.cols[a:b]]
        blocks.append(positions(layout, np.repeat(f, f.size), np.tile(f, f.size)))
    return data._replace(bpos=np.concatenate(blocks) if blocks else data.bpos)


@numba.njit(cache=True, _nrt=False)
def _add_pairs(st, d, p0, p1, e):
    """The Newton matrix += e H over a form's pair terms."""
    for t in range(p0, p1):
        add_pos(st, d.ppos[2 * t], e * d.ph[t])
        add_pos(st, d.ppos[2 * t + 1], e * d.ph[t])


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    """Every row at the context's states (module docstring), written by :func:`..rows.write_row`."""
    q1, qa, qb, v1, mu, trow, scratch, w, evaluate = row_states(ctx)
    st = storage_of(ctx)
    n_rows = d.rows.shape[0]
    for r in range(n_rows):
        row, p0, p1, l0, l1, t0, t1, c0, col, b0 = d.rows[r]
        c1 = d.rows[r + 1, 7] if r + 1 < n_rows else d.cols.size - 1
        nc = c1 - c0
        cols = d.cols[c0:c1]
        cq, dd, cv = scratch[:nc], scratch[nc:2 * nc], scratch[2 * nc:3 * nc]
        ga, dma, hva = scratch[3 * nc:4 * nc], scratch[4 * nc:5 * nc], scratch[5 * nc:6 * nc]
        gs, dms, hvs = scratch[6 * nc:7 * nc], scratch[7 * nc:8 * nc], scratch[8 * nc:9 * nc]
        for u in range(3 * nc):
            scratch[u] = 0.0
        e = 0.5 * w * mu[row]
        val = d.const[r] + add_form(st, d, p0, p1, l0, l1, q1, qa, qb, v1, cq, dd, cv, evaluate, e)
        for t in range(t0, t1):
            for u in range(3 * nc, 9 * nc):
                scratch[u] = 0.0
            ap0, ap1, al0, al1, sp0, sp1, sl0, sl1, as0, as1, ss0, ss1 = d.prods[t]
            a1 = d.pconst[2 * t] + add_form(st, d, ap0, ap1, al0, al1, q1, qa, qb, v1, ga, dma, hva, evaluate, 0.0)
            s1 = d.pconst[2 * t + 1] + add_form(st, d, sp0, sp1, sl0, sl1, q1, qa, qb, v1, gs, dms, hvs, evaluate,
                                                0.0)
            # a(q_b) − a(q_a) = ∇a(q_m)·(q_b − q_a) exactly; a(q_b) = a(q₁) as q_b = q₁ in every scheme (..tasks)
            da, ds, gav, gsv = 0.0, 0.0, 0.0, 0.0
            for u in range(nc):
                j = cols[u]
                gav += ga[u] * v1[j]
                gsv += gs[u] * v1[j]
                if evaluate:                        # q_a, q_b are set for TASK_EVAL only
                    da += dma[u] * (qb[j] - qa[j])
                    ds += dms[u] * (qb[j] - qa[j])
            abar, sbar = a1 - 0.5 * da, s1 - 0.5 * ds
            val += a1 * s1
            for u in range(nc):
                cq[u] += a1 * gs[u] + s1 * ga[u]
                dd[u] += abar * dms[u] + sbar * dma[u]
                cv[u] += a1 * hvs[u] + s1 * hva[u] + ga[u] * gsv + gs[u] * gav
            if evaluate and e != 0.0:
                _add_pairs(st, d, sp0, sp1, e * abar)
                _add_pairs(st, d, ap0, ap1, e * sbar)
                # the outer products over the factors' supports only: ∇s(q_m) ∇a(q_b)ᵀ + ∇a(q_m) ∇s(q_b)ᵀ
                for i in range(ss0, ss1):
                    u = d.sup[i]
                    for k in range(as0, as1):
                        x = d.sup[k]
                        add_pos(st, d.bpos[b0 + u * nc + x], e * dms[u] * ga[x])
                for i in range(as0, as1):
                    u = d.sup[i]
                    for k in range(ss0, ss1):
                        x = d.sup[k]
                        add_pos(st, d.bpos[b0 + u * nc + x], e * dma[u] * gs[x])
        phi_t, phi_tt = 0.0, 0.0
        if col >= 0:
            val -= trow[col]
            phi_t, phi_tt = -trow[col + 1], -trow[col + 2]
        write_row(ctx, st, row, val, phi_t, phi_tt, cols, cq, dd, cv, nc, d.cpos[2 * c0:2 * c1])


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ROWS:
        _evaluate(ctx, view_of(family_of(fam_p)))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the product-constraint family")
