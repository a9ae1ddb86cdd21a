r"""Gravity: V = −g · ∫ r dm for every body it acts on, through the first moment of the body's mass.

The first moment is a position map (:mod:`..points`): linear in q for constant-mass bodies
(∫ r dm = Γ q + c: a constant gradient −Γᵀg), of the frame form for floating-frame bodies
(m R + A(θ)(S₀ + S̄ q_f)); its exact discrete gradient D gives the exact discrete gradient −Dᵀg of V.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f2, family_at, family_of, fmat, fvec, i1
from ..points import NB, OFF, add_frame_dgrad_jacobian, dgrad_into, maps_view, position_into
from ..registry import compiled_kernel
from ..storage import storage_of
from ..tasks import TASK_ENERGY, TASK_EVAL
from . import FamilyPack

NAME = "gravity"
FORMS = ("gravity",)


class Data(NamedTuple):
    maps: np.ndarray    # the first-moment map of each body
    g: np.ndarray       # (k, 2) gravitational acceleration, m/s²


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i1(fam, 0), f2(fam, 1))


def pack(items, packer):
    maps, g = [], []
    rows, cols = [], []
    for (entry, gvec), body, (off, nb) in items:
        k = packer.maps.add(entry, off, nb)
        maps.append(k)
        g.append(np.asarray(gvec, dtype=float).reshape(2))
        if entry[0] == "frame":
            # the tangent of a frame map's −Dᵀg has only the θ row and column (a first moment's support is the
            # whole body: as a dense block it would fill a large beam's Newton matrix); a linear map has none
            sup = packer.maps_support(k)
            theta = np.full(sup.size, off + 2, dtype=np.int64)
            rows += [theta, sup]
            cols += [sup, theta]
    entries = (np.concatenate(rows), np.concatenate(cols)) if rows else None
    return FamilyPack(data=Data(np.asarray(maps, dtype=np.int64), np.asarray(g).reshape(-1, 2)), count=len(items),
                      entries=entries)


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    """g_p += −Dᵀg from q_a to q_b; the frame maps' w_gp c_dg ∂(−Dᵀg)/∂q_b and round-off floor."""
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    f = scratch[ctx.nscratch - 2:ctx.nscratch]
    for i in range(d.maps.size):
        k = d.maps[i]
        o, nb = maps.ints[k, OFF], maps.ints[k, NB]
        dk = fmat(scratch.ctypes.data + 8 * (0), 2, nb)
        dgrad_into(maps, k, qa[o:o + nb], qb[o:o + nb], dk)
        f[0], f[1] = -d.g[i, 0], -d.g[i, 1]
        for j in range(nb):
            gp[o + j] += f[0] * dk[0, j] + f[1] * dk[1, j]
        add_frame_dgrad_jacobian(ctx, st, maps, k, qa, qb, f[0], f[1], ctx.w_gp * ctx.c_dg * ctx.dq1,
                                 scratch[2 * nb:4 * nb + 2], floor)


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, d):
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q, out = fvec(ctx.q1, n), fvec(ctx.out, 7)
    r = fvec(ctx.scratch, ctx.nscratch)[ctx.nscratch - 2:ctx.nscratch]
    for i in range(d.maps.size):
        k = d.maps[i]
        o = maps.ints[k, OFF]
        position_into(maps, k, q[o:o + maps.ints[k, NB]], r)
        out[0] -= d.g[i, 0] * r[0] + d.g[i, 1] * r[1]


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL:
        _evaluate(ctx, _view(family_of(fam_p)))
    elif ctx.task == TASK_ENERGY:
        _energy(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the gravity family")
