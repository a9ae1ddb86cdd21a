r"""Bodies with a constant mass matrix (point masses, rigid bodies, exact beams): their momenta.

Their inertia is the scheme's own (the scene's constant mass matrix, :mod:`skfem_flex.schemes`); this
family adds, for the MOMENTUM task, each body's linear and angular momentum about the origin from
p = M v (already in ``ctx.p``), by the body's momentum layout: p_x = Σ p[l_x], p_y = Σ p[l_y],
L = Σ (X + q[i_x]) p[i_y] − (Y + q[i_y]) p[i_x] + Σ p[i_angle].
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_of, fvec, i1
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


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i1(fam, 0), i1(fam, 1), i1(fam, 2), i1(fam, 3), f1(fam, 4), f1(fam, 5), i1(fam, 6))


def pack(items, packer):
    parts = [[] for _ in range(7)]
    for (layout, body, off) in items:
        for k, a in enumerate(layout):
            a = np.asarray(a)
            parts[k].append(a + off if k not in (4, 5) else a.astype(float))
    data = Data(*(np.concatenate(p).astype(np.int64 if k not in (4, 5) else float) for k, p in enumerate(parts)))
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


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_MOMENTUM:
        _momenta(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the constant-mass bodies' family")
