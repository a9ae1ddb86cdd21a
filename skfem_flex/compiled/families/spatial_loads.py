r"""Loads on spatial bodies and beam nodes that turn with them, as functions of time
(:mod:`skfem_flex.elements.forces.spatial`; a force fixed in space is a "generalized force" of
:mod:`.point_loads`).

* "spatial following force" (``SpatialPointForce(..., following=True)``): Q = Gᵀ Σ_i F_i(t) d_i, with G the
  point's constant position gradient and d_i the directors of its triad; ∂Q/∂d_i = F_i Gᵀ.
* "spatial moment" (``SpatialMoment``): on the triad's directors f_i = W × d_i with S W = M,
  S = Σ_i (‖d_i‖² I − d_i d_iᵀ), M = M(t) (space axes) or Σ_j M_j(t) d_j (following); ∂W/∂(d_j)_c =
  S⁻¹ (M_j e_c [following] − 2 (d_j)_c W + e_c (d_j·W) + d_j W_c), ∂f_i/∂(d_j)_c = −d_i × ∂W/∂(d_j)_c
  + δ_ij W × e_c. The same equations as the elements' ``generalized_force``, held to them by
  ``tests/test_spatial_beam.py``.

The functions of time are columns of the chunk's time table at the scheme's load points (``ctx.trow``).
TASK_EVAL_LOADS adds Q(q_e, t) into ``ext`` and w_ext dqe ∂Q/∂q into the Newton matrix; TASK_LOADS adds Q.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import TASK_EVAL_LOADS, TASK_LOADS
from . import FamilyPack

NAME = "spatial loads"
FORMS = ("spatial following force", "spatial moment")


class Data(NamedTuple):
    elements: np.ndarray    # (k, 8): kind (0 force, 1 moment), following, column, d₁, d₂, d₃ (global), first,
    #                         end of the force's G entries
    gi: np.ndarray          # G entries: global coordinate, component, coefficient
    gc: np.ndarray
    gv: np.ndarray


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), i1(fam, 1), i1(fam, 2), f1(fam, 3))


def pack(items, packer):
    """("spatial following force", G, triad, F) and ("spatial moment", triad, following, M), with the triad's
    local director offsets; each element couples its triad and (forces) its point's support."""
    elements, gi, gc, gv, couplings = [], [], [], [], []
    for form, element, where in items:
        where = np.asarray(where, dtype=np.int64)
        if form[0] == "spatial following force":
            _, G, triad, fun = form
            following = 1
        else:
            _, triad, following, fun = form
            G = np.zeros((3, where.size))
        col = packer.column(fun, 0, "force")
        packer.column(fun, 1, "force")
        packer.column(fun, 2, "force")
        dirs = [int(where[o]) for o in triad]
        first = len(gi)
        for c in range(3):
            nz = np.flatnonzero(G[c])
            gi.extend(where[nz])
            gc.extend([c] * nz.size)
            gv.extend(G[c][nz])
        kind = 0 if form[0] == "spatial following force" else 1
        elements.append((kind, int(bool(following)), col, dirs[0], dirs[1], dirs[2], first, len(gi)))
        support = np.concatenate([np.arange(d, d + 3) for d in dirs] + [np.asarray(gi[first:], dtype=np.int64)])
        couplings.append(np.unique(support))
    data = Data(np.asarray(elements, dtype=np.int64).reshape(-1, 8), np.asarray(gi, dtype=np.int64),
                np.asarray(gc, dtype=np.int64), np.asarray(gv, dtype=float))
    return FamilyPack(data=data, count=len(items), couplings=couplings)


@numba.njit(cache=True)
def _solve3(S, b):
    """S⁻¹ b for a symmetric 3 × 3 S (cofactors)."""
    c00 = S[1, 1] * S[2, 2] - S[1, 2] * S[2, 1]
    c01 = S[1, 2] * S[2, 0] - S[1, 0] * S[2, 2]
    c02 = S[1, 0] * S[2, 1] - S[1, 1] * S[2, 0]
    det = S[0, 0] * c00 + S[0, 1] * c01 + S[0, 2] * c02
    inv = np.empty((3, 3))
    inv[0, 0], inv[1, 0], inv[2, 0] = c00 / det, c01 / det, c02 / det
    inv[0, 1] = (S[0, 2] * S[2, 1] - S[0, 1] * S[2, 2]) / det
    inv[1, 1] = (S[0, 0] * S[2, 2] - S[0, 2] * S[2, 0]) / det
    inv[2, 1] = (S[0, 1] * S[2, 0] - S[0, 0] * S[2, 1]) / det
    inv[0, 2] = (S[0, 1] * S[1, 2] - S[0, 2] * S[1, 1]) / det
    inv[1, 2] = (S[0, 2] * S[1, 0] - S[0, 0] * S[1, 2]) / det
    inv[2, 2] = (S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]) / det
    out = np.zeros(3)
    for i in range(3):
        for j in range(3):
            out[i] += inv[i, j] * b[j]
    return out


@numba.njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@numba.njit(cache=True)
def _loads(ctx, d, tangent):
    n = ctx.n
    q, ext = fvec(ctx.qe, n), fvec(ctx.ext, n)
    trow = fvec(ctx.trow, ctx.ncol)
    st = storage_of(ctx)
    w = ctx.w_ext * ctx.dqe
    dv = np.empty((3, 3))
    for e in range(d.elements.shape[0]):
        kind, following, col = d.elements[e, 0], d.elements[e, 1], d.elements[e, 2]
        F = np.array([trow[col], trow[col + 1], trow[col + 2]])
        for i in range(3):
            for c in range(3):
                dv[i, c] = q[d.elements[e, 3 + i] + c]
        if kind == 0:
            # Q = Gᵀ Σ_i F_i d_i
            f = F[0] * dv[0] + F[1] * dv[1] + F[2] * dv[2]
            for t in range(d.elements[e, 6], d.elements[e, 7]):
                ext[d.gi[t]] += d.gv[t] * f[d.gc[t]]
                if tangent:
                    for i in range(3):
                        add_qq(ctx, st, d.gi[t], d.elements[e, 3 + i] + d.gc[t], w * d.gv[t] * F[i])
            continue
        S = np.zeros((3, 3))
        for i in range(3):
            nn = dv[i, 0] ** 2 + dv[i, 1] ** 2 + dv[i, 2] ** 2
            for a in range(3):
                S[a, a] += nn
                for b in range(3):
                    S[a, b] -= dv[i, a] * dv[i, b]
        Mw = F.copy()
        if following:
            Mw = F[0] * dv[0] + F[1] * dv[1] + F[2] * dv[2]
        W = _solve3(S, Mw)
        for i in range(3):
            fi = _cross(W, dv[i])
            for c in range(3):
                ext[d.elements[e, 3 + i] + c] += fi[c]
        if not tangent:
            continue
        # W × e_c is column c of skew(W)
        skw = np.array([[0.0, -W[2], W[1]], [W[2], 0.0, -W[0]], [-W[1], W[0], 0.0]])
        rhs = np.empty(3)
        for j in range(3):
            dj = dv[j]
            d_j_w = dj[0] * W[0] + dj[1] * W[1] + dj[2] * W[2]
            for c in range(3):
                for a in range(3):
                    rhs[a] = -2.0 * W[a] * dj[c] + dj[a] * W[c]
                rhs[c] += d_j_w + (F[j] if following else 0.0)
                dW = _solve3(S, rhs)
                col_j = d.elements[e, 3 + j] + c
                for i in range(3):
                    dfi = _cross(dv[i], dW)
                    for a in range(3):
                        val = -dfi[a] + (skw[a, c] if i == j else 0.0)
                        add_qq(ctx, st, d.elements[e, 3 + i] + a, col_j, w * val)


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL_LOADS:
        _loads(ctx, _view(family_of(fam_p)), True)
    elif ctx.task == TASK_LOADS:
        _loads(ctx, _view(family_of(fam_p)), False)


def kernel():
    """The family's compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the spatial-load family", nrt=True)
