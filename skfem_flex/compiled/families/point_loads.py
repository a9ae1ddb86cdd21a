r"""Loads given as functions of time: point forces, follower forces and generalized forces (point moments).

* "point force" (:class:`~skfem_flex.elements.forces.PointForce`): Q = J_rᵀ F(t), F in the global frame (N),
  J_r = ∂r/∂q of the point's position map (:mod:`..points`); ∂Q/∂q = ∂(J_rᵀ f)/∂q at fixed f (FRAME maps).
* "follower force" (``PointForce(..., follower=True)``): Q = J_rᵀ A(ϑ) F(t), ϑ = g·q + c the point's angle
  (linear in q); ∂Q/∂q = ∂(J_rᵀ f)/∂q|_f + J_rᵀ E f ⊗ g with f = A(ϑ) F.
* "generalized force" (:class:`~skfem_flex.elements.forces.PointMoment`): Q = Gᵀ F(t), G constant
  (k, the element's coordinates), one time-table column per row of G; no derivative.
* "quadratic point force" (a :class:`~skfem_flex.elements.forces.SpatialPointForce` fixed in space at a point
  whose position is quadratic in q, r_c = ½ qᵀH_c q + A_c·q + a_c: a floating-frame body's material point):
  Q = Σ_c F_c(t) (H_c q + A_c) = J_r(q)ᵀ F, ∂Q/∂q = Σ_c F_c(t) H_c (constant entries times the load).

The functions of time are columns of the chunk's time table, evaluated where the scheme evaluates its
loads (``packer.column(fun, component, "force")``, read from ``ctx.trow``). TASK_EVAL_LOADS adds Q(q_e, t)
into ``ext`` and w_ext ∂Q/∂q dqe into the Newton matrix; TASK_LOADS adds Q only.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_at, family_of, fmat, fvec, i1, i2
from ..points import FRAME, KIND, LINEAR, NB, OFF, hessian_parts, jacobian_into, maps_view
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL_LOADS, TASK_LOADS
from . import FamilyPack

NAME = "point loads"
FORMS = ("point force", "follower force", "generalized force", "quadratic point force")


class Data(NamedTuple):
    force: np.ndarray       # (k, 5) point and follower forces: map, first of its 2 columns, follower (1/0),
    #                         first, end of g
    angle0: np.ndarray      # (k,) c of ϑ = g·q + c (0 for a point force), rad
    gen: np.ndarray         # (l, 3) rows of generalized forces: column, first, end of their entries
    idx: np.ndarray         # global coordinates of the nonzero entries of g (followers), G's rows and A_c
    coef: np.ndarray        # the entries
    quad: np.ndarray        # (m, 5) rows c of quadratic point forces: column, first, end of H_c's entries (hij,
    #                         hcoef), first, end of A_c's (idx, coef)
    hij: np.ndarray         # (p, 2) global (row, column) of the nonzero entries of the H_c
    hcoef: np.ndarray       # the entries, m⁻¹ (per unit of q squared)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f1(fam, 1), i2(fam, 2), i1(fam, 3), f1(fam, 4), i2(fam, 5), i2(fam, 6), f1(fam, 7))


def pack(items, packer):
    """Point forces ("point force", point, F), follower forces ("follower force", point, g, c, F), generalized
    forces ("generalized force", G, F) and quadratic point forces ("quadratic point force", H, A, F): F(t) as
    time-table columns at the scheme's load points; followers couple their point's map support and g, point
    forces on frame maps their map's support, quadratic point forces the entries of their H."""
    force, angle0, gen, idx, coef, couplings = [], [], [], [], [], []
    quad, hij, hcoef = [], [], []
    for form, element, where in items:
        where = np.asarray(where, dtype=np.int64)
        name = form[0]
        if name in ("point force", "follower force"):
            k = packer.point_map(form[1])
            if k is None:
                raise ValueError(f"{name} {getattr(element, 'name', '?')!r}: its point has no compiled map")
            fun = form[-1]
            col = packer.column(fun, 0, "force")
            packer.column(fun, 1, "force")
            support = packer.maps_support(k)
            first = len(idx)
            if name == "follower force":
                grad = np.asarray(form[2], dtype=float)
                nz = np.flatnonzero(grad)
                idx.extend(where[nz])
                coef.extend(grad[nz])
                angle0.append(float(form[3]))
                couplings.append(np.unique(np.concatenate([support, where[nz]])))
            else:
                angle0.append(0.0)
                if packer.maps.rows[k][0] == FRAME:       # ∂(J_rᵀ f)/∂q couples the frame's angle and q_f
                    couplings.append(support)
            force.append((k, col, 1 if name == "follower force" else 0, first, len(idx)))
        elif name == "quadratic point force":
            _, H, A, fun = form
            for comp in range(3):
                hi, hj = np.nonzero(H[comp])
                a = np.flatnonzero(A[comp])
                quad.append((packer.column(fun, comp, "force"), len(hcoef), len(hcoef) + hi.size, len(idx),
                             len(idx) + a.size))
                hij.extend(zip(where[hi], where[hj]))
                hcoef.extend(H[comp][hi, hj])
                idx.extend(where[a])
                coef.extend(A[comp][a])
        else:
            _, gmat, fun = form
            for comp, grad in enumerate(np.atleast_2d(np.asarray(gmat, dtype=float))):
                nz = np.flatnonzero(grad)
                gen.append((packer.column(fun, comp, "force"), len(idx), len(idx) + nz.size))
                idx.extend(where[nz])
                coef.extend(grad[nz])
    data = Data(np.asarray(force, dtype=np.int64).reshape(-1, 5), np.asarray(angle0, dtype=float),
                np.asarray(gen, dtype=np.int64).reshape(-1, 3), np.asarray(idx, dtype=np.int64),
                np.asarray(coef, dtype=float), np.asarray(quad, dtype=np.int64).reshape(-1, 5),
                np.asarray(hij, dtype=np.int64).reshape(-1, 2), np.asarray(hcoef, dtype=float))
    entries = (data.hij[:, 0].copy(), data.hij[:, 1].copy()) if len(hcoef) else None
    return FamilyPack(data=data, count=len(items), couplings=couplings, entries=entries)


@numba.njit(cache=True, _nrt=False)
def _loads(ctx, fam, tangent):
    """Q(q_e, t) into ``ext``; with ``tangent`` also w_ext dqe ∂Q/∂q into the Newton matrix."""
    d = _view(fam)
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q, ext = fvec(ctx.qe, n), fvec(ctx.ext, n)
    trow = fvec(ctx.trow, ctx.ncol)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    st = storage_of(ctx)
    w = ctx.w_ext * ctx.dqe
    for e in range(d.force.shape[0]):
        # Q = Jᵀ f, f = F(t) or A(ϑ) F(t), ϑ = g·q + c
        k, col, follower, g0, g1 = d.force[e, 0], d.force[e, 1], d.force[e, 2], d.force[e, 3], d.force[e, 4]
        o, nb = maps.ints[k, OFF], maps.ints[k, NB]
        qb = q[o:o + nb]
        jac = fmat(scratch.ctypes.data + 8 * (0), 2, nb)
        jacobian_into(maps, k, qb, jac)
        fx, fy = trow[col], trow[col + 1]
        if follower:
            ang = d.angle0[e]
            for t in range(g0, g1):
                ang += d.coef[t] * q[d.idx[t]]
            C, S = np.cos(ang), np.sin(ang)
            fx, fy = C * trow[col] - S * trow[col + 1], S * trow[col] + C * trow[col + 1]
            if tangent:
                for a in range(nb):                 # ∂(Jᵀ A F)/∂ϑ ⊗ g = Jᵀ E f ⊗ g
                    jef = -jac[0, a] * fy + jac[1, a] * fx
                    for t in range(g0, g1):
                        add_qq(ctx, st, o + a, d.idx[t], w * jef * d.coef[t])
        for a in range(nb):
            ext[o + a] += jac[0, a] * fx + jac[1, a] * fy
        if tangent and maps.ints[k, KIND] != LINEAR:      # ∂(Jᵀ f)/∂q at fixed f
            f = scratch[2 * nb:2 * nb + 2]
            f[0], f[1] = fx, fy
            row = scratch[2 * nb + 2:3 * nb - 1]
            h22 = hessian_parts(maps, k, qb, f, row)
            add_qq(ctx, st, o + 2, o + 2, w * h22)
            for j in range(nb - 3):
                add_qq(ctx, st, o + 2, o + 3 + j, w * row[j])
                add_qq(ctx, st, o + 3 + j, o + 2, w * row[j])
    for e in range(d.gen.shape[0]):
        # Q = g F_c(t)
        val = trow[d.gen[e, 0]]
        for t in range(d.gen[e, 1], d.gen[e, 2]):
            ext[d.idx[t]] += d.coef[t] * val
    for e in range(d.quad.shape[0]):
        # Q = F_c(t) (H_c q + A_c), ∂Q/∂q = F_c(t) H_c
        val = trow[d.quad[e, 0]]
        for t in range(d.quad[e, 1], d.quad[e, 2]):
            i, j = d.hij[t, 0], d.hij[t, 1]
            ext[i] += d.hcoef[t] * val * q[j]
            if tangent:
                add_qq(ctx, st, i, j, w * d.hcoef[t] * val)
        for t in range(d.quad[e, 3], d.quad[e, 4]):
            ext[d.idx[t]] += d.coef[t] * val


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL_LOADS:
        _loads(ctx, family_of(fam_p), True)
    elif ctx.task == TASK_LOADS:
        _loads(ctx, family_of(fam_p), False)


def kernel():
    """The family's compiled kernel (:func:`~skfem_flex.compiled.registry.compiled_kernel`), from the cache or
    compiled on first use."""
    return compiled_kernel(_kernel, "the point-load family")
