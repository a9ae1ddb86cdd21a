r"""Springs between points of spatial bodies whose positions are affine in q
(:class:`~skfem_flex.elements.forces.SpatialSpring` on rigid bodies, point masses and exact-beam nodes):
V = ½ k (l − l₀)², l = ‖d‖, d = A q + a (the element's affine difference r_a − r_b, or r_a minus a ground point).

With s = d·d quadratic in q, the exact discrete gradient from q_a to q_b is (the element's
``potential_discrete_gradient``, the same equations in the same order)

.. math::

    g = κ\, ∇s(q_m),\quad ∇s = 2 A^\mathsf{T} d,\quad
    κ = \tfrac12 k \Bigl(1 - \frac{2 l_0}{l_a + l_b}\Bigr)\ (κ = \tfrac12 k \text{ for } l_0 = 0),

    \frac{∂g}{∂q_b} = κ\, A^\mathsf{T} A + \frac{k l_0}{2 l_b (l_a + l_b)^2}\, ∇s(q_m) ⊗ ∇s(q_b)

(at q_a = q_b the gradient and half the Hessian). TASK_EVAL adds g into ``g_p``, w_gp c_dg dq1 times its
derivative into the Newton matrix and the round-off floor into ``floor``; TASK_ENERGY adds V(q₁) (J).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f2, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import TASK_ENERGY, TASK_EVAL
from . import FamilyPack

NAME = "spatial springs"
FORMS = ("spatial spring",)


class Data(NamedTuple):
    span: np.ndarray    # (k, 2) first and end of each spring's coordinates in ``coords`` (and of its A's columns)
    coords: np.ndarray  # the scene coordinates of each spring's layout, concatenated
    A: np.ndarray       # (3, Σ n) the columns of each spring's A, concatenated
    par: np.ndarray     # (k, 5) stiffness k (N/m), rest length l₀ (m), a (m)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), i1(fam, 1), f2(fam, 2), f2(fam, 3))


def pack(items, packer):
    """Spatial springs ("spatial spring", A (3, n), a (3,), k, l₀) on the scene coordinates ``where`` of their
    layout; each couples its coordinates as one dense block."""
    span, coords, cols, par, couplings = [], [], [], [], []
    for (_, A, a, k, rest), element, where in items:
        where = np.asarray(where, dtype=np.int64)
        A = np.asarray(A, dtype=float).reshape(3, where.size)
        span.append((len(coords), len(coords) + where.size))
        coords.extend(where)
        cols.append(A)
        par.append((float(k), float(rest), *np.asarray(a, dtype=float).reshape(3)))
        couplings.append(np.unique(where))
    data = Data(np.asarray(span, dtype=np.int64).reshape(-1, 2), np.asarray(coords, dtype=np.int64),
                np.ascontiguousarray(np.hstack(cols) if cols else np.zeros((3, 0))),
                np.asarray(par, dtype=float).reshape(-1, 5))
    return FamilyPack(data=data, count=len(items), couplings=couplings)


@numba.njit(cache=True, _nrt=False)
def _difference(d, e, q, out):
    """d = A q + a of spring ``e`` at the scene coordinates q into ``out`` (3,); returns its length, m."""
    for c in range(3):
        s = d.par[e, 2 + c]
        for j in range(d.span[e, 0], d.span[e, 1]):
            s += d.A[c, j] * q[d.coords[j]]
        out[c] = s
    return np.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2])


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, fam):
    d = _view(fam)
    n = ctx.n
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    da, db = scratch[0:3], scratch[3:6]
    th = ctx.w_gp * ctx.c_dg * ctx.dq1
    for e in range(d.span.shape[0]):
        k, lr = d.par[e, 0], d.par[e, 1]
        la = _difference(d, e, qa, da)
        lb = _difference(d, e, qb, db)
        total = la + lb
        kap = 0.5 * k * (1.0 - 2.0 * lr / total) if lr > 0.0 else 0.5 * k
        c2 = k * lr / (2.0 * lb * total * total) if lr > 0.0 else 0.0
        j0, j1 = d.span[e, 0], d.span[e, 1]
        for i in range(j0, j1):
            # ∇s(q_m)_i = 2 A_i · d_m = A_i · (d_a + d_b), ∇s(q_b)_i = 2 A_i · d_b
            gm = 0.0
            for c in range(3):
                gm += d.A[c, i] * (da[c] + db[c])
            gp[d.coords[i]] += kap * gm
            fl = 0.0
            for j in range(j0, j1):
                ata, gbj = 0.0, 0.0
                for c in range(3):
                    ata += d.A[c, i] * d.A[c, j]
                    gbj += 2.0 * d.A[c, j] * db[c]
                tan = th * (kap * ata + c2 * gm * gbj)
                if tan != 0.0:
                    add_qq(ctx, st, d.coords[i], d.coords[j], tan)
                fl += abs(tan) * (abs(qa[d.coords[j]]) + abs(qb[d.coords[j]]))
            floor[d.coords[i]] += fl


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, fam):
    """out[0] += Σ ½ k (l(q₁) − l₀)², J."""
    d = _view(fam)
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    r = fvec(ctx.scratch, 3)
    pot = 0.0
    for e in range(d.span.shape[0]):
        pot += 0.5 * d.par[e, 0] * (_difference(d, e, q, r) - d.par[e, 1]) ** 2
    out[0] += pot


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL:
        _evaluate(ctx, family_of(fam_p))
    elif ctx.task == TASK_ENERGY:
        _energy(ctx, family_of(fam_p))


def kernel():
    """The family's compiled kernel (:func:`~skfem_flex.compiled.registry.compiled_kernel`), from the cache or
    compiled on first use."""
    return compiled_kernel(_kernel, "the spatial-spring family")
