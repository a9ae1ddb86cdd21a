r"""Bodies with a constant mass matrix (point masses, rigid bodies, exact beams, spatial bodies): momenta.

Their inertia is the scheme's own (the scene's constant mass matrix, :mod:`skfem_flex.schemes`); this
family adds, for the MOMENTUM task, each body's linear and angular momentum about the origin from
p = M v (already in ``ctx.p``), by the body's momentum layout: p_x = Σ p[l_x], p_y = Σ p[l_y],
planar L_z = Σ (X + q[i_x]) p[i_y] − (Y + q[i_y]) p[i_x] + Σ p[i_angle] into ``out[6]``. A spatial
body (``spatial_momentum_layout()``) gives its linear momentum as Γ v (the first moment of its mass,
∫ r dm = Γ q + c) into ``out[1:4]`` and its angular momentum about the origin
L = Σ q[t] × p[t] + a × Γ v over index triples t (a position or a director) and an anchor a (a pivot)
into ``out[4:7]``.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..tasks import TASK_MOMENTUM
from . import FamilyPack

NAME = "constant-mass bodies"
FORMS = ("constant mass",)


class Data(NamedTuple):
    lx: np.ndarray      # global indices summed into p_x
    ly: np.ndarray      # … into p_y
    ix: np.ndarray      # x coordinates of the points of L
    iy: np.ndarray      # y coordinates
    X: np.ndarray       # offsets added to q[ix]
    Y: np.ndarray       # offsets added to q[iy]
    ia: np.ndarray      # angle coordinates (p[ia] adds to L)
    tri: np.ndarray     # (k, 3) index triples whose q × p add to the spatial L
    gidx: np.ndarray    # spatial linear momentum Γ v: the v index of each entry of Γ
    gcomp: np.ndarray   # … its component (0, 1, 2)
    gcoef: np.ndarray   # … its value, kg
    gw: np.ndarray      # (k, 3) … its share of a × Γ v: Γ_entry (a × e_comp)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i1(fam, 0), i1(fam, 1), i1(fam, 2), i1(fam, 3), f1(fam, 4), f1(fam, 5), i1(fam, 6), i2(fam, 7),
                i1(fam, 8), i1(fam, 9), f1(fam, 10), f2(fam, 11))


def pack(items, packer):
    parts = [[] for _ in range(7)]
    tri, gidx, gcomp, gcoef, gw = [np.zeros((0, 3), dtype=np.int64)], [], [], [], []
    for (layout, body, off) in items:
        if isinstance(layout[0], str):                # ("spatial", triples, anchor, Γ)
            _, triples, anchor, gam = layout
            tri.append(np.asarray(triples, dtype=np.int64).reshape(-1, 3) + off)
            comp, col = np.nonzero(gam)
            gidx.append(col + off)
            gcomp.append(comp)
            gcoef.append(gam[comp, col])
            gw.append(gam[comp, col][:, None] * np.cross(anchor, np.eye(3)[comp]))
            continue
        for k, a in enumerate(layout):
            a = np.asarray(a)
            parts[k].append(a + off if k not in (4, 5) else a.astype(float))
    cat = [np.concatenate(p) if p else np.zeros(0) for p in parts]
    data = Data(*(c.astype(np.int64 if k not in (4, 5) else float) for k, c in enumerate(cat)),
                np.concatenate(tri), np.concatenate(gidx).astype(np.int64) if gidx else np.zeros(0, np.int64),
                np.concatenate(gcomp).astype(np.int64) if gcomp else np.zeros(0, np.int64),
                np.concatenate(gcoef).astype(float) if gcoef else np.zeros(0),
                np.concatenate(gw).reshape(-1, 3) if gw else np.zeros((0, 3)))
    return FamilyPack(data=data, count=len(items))


@numba.njit(cache=True, _nrt=False)
def _momenta(ctx, d):
    n = ctx.n
    q, p, out = fvec(ctx.q1, n), fvec(ctx.p, n), fvec(ctx.out, 7)
    for i in d.lx:
        out[1] += p[i]
    for i in d.ly:
        out[2] += p[i]
    ang = 0.0
    for j in range(d.ix.size):
        ang += (d.X[j] + q[d.ix[j]]) * p[d.iy[j]] - (d.Y[j] + q[d.iy[j]]) * p[d.ix[j]]
    for i in d.ia:
        ang += p[i]
    out[6] += ang
    v = fvec(ctx.v1, n)
    for j in range(d.gidx.size):
        vi = v[d.gidx[j]]
        out[1 + d.gcomp[j]] += d.gcoef[j] * vi
        for c in range(3):
            out[4 + c] += d.gw[j, c] * vi
    for j in range(d.tri.shape[0]):
        a, b, c = d.tri[j, 0], d.tri[j, 1], d.tri[j, 2]
        out[4] += q[b] * p[c] - q[c] * p[b]
        out[5] += q[c] * p[a] - q[a] * p[c]
        out[6] += q[a] * p[b] - q[b] * p[a]


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_MOMENTUM:
        _momenta(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the constant-mass bodies' family")
