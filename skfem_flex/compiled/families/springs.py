r"""Conservative force elements on coordinates: coordinate springs and quadratic springs.

* "coordinate spring" (:class:`~skfem_flex.elements.forces.NonlinearSpring`): V = ½ k u^p on one
  coordinate u (p a positive integer). Its exact discrete gradient is the divided difference

  .. math::

      \frac{V(u_b) - V(u_a)}{u_b - u_a} = \tfrac12 k \sum_{j=0}^{p-1} u_b^j\, u_a^{p-1-j}

  (free of cancellation) and its derivative with respect to u_b is
  ½ k Σ_{j≥1} j u_b^{j−1} u_a^{p−1−j}; at u_a = u_b these are ∇V and half the Hessian.
* "quadratic spring" (:class:`~skfem_flex.elements.forces.RotationalSpring`): V = ½ k (g·q + c)². V is
  quadratic, so the mid-point gradient k (g·q̄ + c) g, q̄ = (q_a + q_b)/2, is an exact discrete gradient;
  its derivative with respect to q_b is ½ k g gᵀ.

TASK_EVAL adds the discrete gradients into ``g_p``, w_gp c_dg dq1 ∂/∂q_b into the Newton matrix and the
round-off floor |w_gp c_dg dq1 ∂g/∂q_b| (|q_a| + |q_b|) into ``floor``; TASK_ENERGY adds V(q₁) (J) into
``out[0]``. Stiffness k in N/m^(p−1) (coordinate springs) or in N m/rad, N/m (quadratic springs, after
the units of g·q).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import TASK_ENERGY, TASK_EVAL
from . import FamilyPack

NAME = "springs"
FORMS = ("coordinate spring", "quadratic spring")


class Data(NamedTuple):
    coord: np.ndarray       # (k, 2) coordinate spring: global coordinate i, power p
    coord_k: np.ndarray     # (k,) its stiffness k
    quad: np.ndarray        # (l, 2) quadratic spring: first, end of its entries in idx / coef
    quad_kc: np.ndarray     # (l, 2) its stiffness k and constant c
    idx: np.ndarray         # global coordinates of the nonzero entries of g
    coef: np.ndarray        # the entries of g


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f1(fam, 1), i2(fam, 2), f2(fam, 3), i1(fam, 4), f1(fam, 5))


def pack(items, packer):
    """Coordinate springs ("coordinate spring", i, k, p) and quadratic springs ("quadratic spring", g, c, k),
    i and g over the element's own coordinates ``idx``."""
    coord, coord_k, quad, quad_kc, idx, coef, couplings = [], [], [], [], [], [], []
    for form, element, where in items:
        where = np.asarray(where, dtype=np.int64)
        if form[0] == "coordinate spring":
            _, i, k, power = form
            coord.append((int(where[i]), int(power)))
            coord_k.append(float(k))
            couplings.append(where[i:i + 1])
        else:
            _, grad, c, k = form
            grad = np.asarray(grad, dtype=float)
            nz = np.flatnonzero(grad)
            quad.append((len(idx), len(idx) + nz.size))
            quad_kc.append((float(k), float(c)))
            idx.extend(where[nz])
            coef.extend(grad[nz])
            couplings.append(where[nz])
    data = Data(np.asarray(coord, dtype=np.int64).reshape(-1, 2), np.asarray(coord_k, dtype=float),
                np.asarray(quad, dtype=np.int64).reshape(-1, 2), np.asarray(quad_kc, dtype=float).reshape(-1, 2),
                np.asarray(idx, dtype=np.int64), np.asarray(coef, dtype=float))
    return FamilyPack(data=data, count=len(items), couplings=couplings)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, fam):
    """g_p += the discrete gradients from q_a to q_b; w_gp c_dg dq1 ∂/∂q_b into the Newton matrix; floor."""
    d = _view(fam)
    n = ctx.n
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    th = ctx.w_gp * ctx.c_dg * ctx.dq1
    for e in range(d.coord.shape[0]):
        # V = ½ k u^p: its exact divided difference (no cancellation)
        i, p, k = d.coord[e, 0], d.coord[e, 1], d.coord_k[e]
        u0, u1 = qa[i], qb[i]
        g, tan = 0.0, 0.0
        for a in range(p):
            g += u1 ** a * u0 ** (p - 1 - a)
            if a >= 1:
                tan += a * u1 ** (a - 1) * u0 ** (p - 1 - a)
        gp[i] += 0.5 * k * g
        tan *= 0.5 * k * th
        add_qq(ctx, st, i, i, tan)
        floor[i] += abs(tan) * (abs(u0) + abs(u1))
    for e in range(d.quad.shape[0]):
        # V = ½ k (g·q + c)²: the mid-point gradient is exact
        i0, i1_ = d.quad[e, 0], d.quad[e, 1]
        k, s = d.quad_kc[e, 0], d.quad_kc[e, 1]
        for t in range(i0, i1_):
            s += d.coef[t] * 0.5 * (qa[d.idx[t]] + qb[d.idx[t]])
        for a in range(i0, i1_):
            ia, ga = d.idx[a], d.coef[a]
            gp[ia] += k * s * ga
            for b in range(i0, i1_):
                jb = d.idx[b]
                tan = 0.5 * th * k * ga * d.coef[b]
                floor[ia] += abs(tan) * (abs(qa[jb]) + abs(qb[jb]))
                add_qq(ctx, st, ia, jb, tan)


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, fam):
    """out[0] += V(q₁), J."""
    d = _view(fam)
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    pot = 0.0
    for e in range(d.coord.shape[0]):
        pot += 0.5 * d.coord_k[e] * q[d.coord[e, 0]] ** d.coord[e, 1]
    for e in range(d.quad.shape[0]):
        s = d.quad_kc[e, 1]
        for t in range(d.quad[e, 0], d.quad[e, 1]):
            s += d.coef[t] * q[d.idx[t]]
        pot += 0.5 * d.quad_kc[e, 0] * s * s
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
    return compiled_kernel(_kernel, "the springs family")
