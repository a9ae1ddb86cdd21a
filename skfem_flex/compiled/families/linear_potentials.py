r"""Potentials linear in q: V = f·q + e (gravity on spatial bodies: V = −g·(Γ q + c), f = −Γᵀg, e = −g·c).

The gradient f is constant, so it is its own exact discrete gradient and adds nothing to the Newton
matrix; TASK_ENERGY adds V(q₁).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, family_of, fvec, i1
from ..registry import compiled_kernel
from ..tasks import TASK_ENERGY, TASK_EVAL
from . import FamilyPack

NAME = "linear potentials"
FORMS = ("linear potential",)


class Data(NamedTuple):
    idx: np.ndarray     # coordinates of the gradient's entries
    f: np.ndarray       # the entries, N (or N m)
    e: np.ndarray       # (1,) the constant part of all the potentials, J


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i1(fam, 0), f1(fam, 1), f1(fam, 2))


def pack(items, packer):
    """items: ``((f, e), element, indices)`` with the local gradient f and the constant e."""
    idx, f, e = [], [], 0.0
    for (grad, const), _, where in items:
        grad = np.asarray(grad, dtype=float)
        nz = np.flatnonzero(grad)
        idx.extend(np.asarray(where, dtype=np.int64)[nz])
        f.extend(grad[nz])
        e += float(const)
    data = Data(np.asarray(idx, dtype=np.int64), np.asarray(f, dtype=float), np.array([e]))
    return FamilyPack(data=data, count=len(items))


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, d):
    gp = fvec(ctx.gp, ctx.n)
    for t in range(d.idx.size):
        gp[d.idx[t]] += d.f[t]


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, d):
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    v = d.e[0]
    for t in range(d.idx.size):
        v += d.f[t] * q[d.idx[t]]
    out[0] += v


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL:
        _evaluate(ctx, _view(family_of(fam_p)))
    elif ctx.task == TASK_ENERGY:
        _energy(ctx, _view(family_of(fam_p)))


def kernel():
    return compiled_kernel(_kernel, "the linear-potential family")
