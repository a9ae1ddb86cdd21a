r"""Two-point springs (:class:`~skfem_flex.elements.forces.LinearSpring`): V = ½ k (l − l₀)², l = ‖d‖,
d = r_a − r_b between two body points (position maps, :mod:`..points`) or a body point and a ground point.

With s = d·d, V(s) = ½ k (√s − l₀)² has the divided difference (free of cancellation)

.. math::

    κ = \frac{V(s_b) - V(s_a)}{s_b - s_a} = \tfrac12 k \Bigl(1 - \frac{2 l_0}{l_a + l_b}\Bigr)
    \quad(κ = \tfrac12 k \text{ for } l_0 = 0),

and s has the exact discrete gradient (d_a + d_b)ᵀ D (D the exact discrete gradient of d: the maps'
D of point a minus point b's), so the element's exact discrete gradient is κ (d_a + d_b)ᵀ D. Its
derivative with respect to q_b is

.. math::

    κ\,\bigl(D^\mathsf{T} J_b + 2\,∂(D^\mathsf{T} \bar f)/∂q_b\bigr)
    + \frac{k l_0}{2 l_b (l_a + l_b)^2}\,(D^\mathsf{T}(d_a + d_b)) ⊗ 2 J_b^\mathsf{T} d_b,
    \qquad \bar f = (d_a + d_b)/2,

(J_b = ∂d/∂q at q_b; the second term of the first bracket is the maps' ∂(Dᵀf)/∂q_b with f = ±κ (d_a + d_b),
nonzero for FRAME maps only). TASK_EVAL adds the gradient into ``g_p``, w_gp c_dg dq1 times its
derivative into the Newton matrix and the round-off floor into ``floor``; TASK_ENERGY adds V(q₁) (J).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f2, family_at, family_of, fmat, fvec, i2
from ..points import (NB, OFF, add_frame_dgrad_jacobian, dgrad_into, jacobian_into,
                      maps_view, position_into)
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import TASK_ENERGY, TASK_EVAL
from . import FamilyPack

NAME = "two-point springs"
FORMS = ("two-point spring",)


class Data(NamedTuple):
    maps: np.ndarray    # (k, 2) map of point a, map of point b or −1 (the ground)
    par: np.ndarray     # (k, 4) stiffness k (N/m), rest length l₀ (m), ground point (m)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f2(fam, 1))


def pack_pairs(items, packer, what):
    """(maps (k, 2), anchors (k, 2), couplings) of two-point elements ("…", a, b, anchor, …): point b None
    means the ground point ``anchor``. Shared with the two-point dampers."""
    maps, anchors, couplings = [], [], []
    for form, element, where in items:
        ka = packer.point_map(form[1])
        kb = -1 if form[2] is None else packer.point_map(form[2])
        if ka is None or kb is None:
            raise ValueError(f"{what} {getattr(element, 'name', '?')!r}: a point has no compiled map")
        maps.append((ka, kb))
        anchors.append(np.zeros(2) if form[3] is None else np.asarray(form[3], dtype=float).reshape(2))
        couplings.append(np.unique(np.concatenate([packer.maps_support(k) for k in (ka, kb) if k >= 0])))
    k = len(maps)
    return np.asarray(maps, dtype=np.int64).reshape(k, 2), np.asarray(anchors, dtype=float).reshape(k, 2), couplings


def pack(items, packer):
    """Two-point springs ("two-point spring", a, b, anchor, k, l₀): maps, k, l₀ and the ground point."""
    maps, anchors, couplings = pack_pairs(items, packer, "two-point spring")
    par = np.column_stack([[float(f[4]) for f, _, _ in items], [float(f[5]) for f, _, _ in items], anchors])
    return FamilyPack(data=Data(maps, par.reshape(-1, 4)), count=len(items), couplings=couplings)


@numba.njit(cache=True, _nrt=False)
def pair_distance(maps, ka, kb, ax, ay, q, r):
    """d = r_a − r_b at the global coordinates q (b: map kb or, if −1, the ground point (ax, ay)), m;
    ``r``: 2 floats to work in."""
    o = maps.ints[ka, OFF]
    position_into(maps, ka, q[o:o + maps.ints[ka, NB]], r)
    dx, dy = r[0], r[1]
    if kb < 0:
        return dx - ax, dy - ay
    o = maps.ints[kb, OFF]
    position_into(maps, kb, q[o:o + maps.ints[kb, NB]], r)
    return dx - r[0], dy - r[1]


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, fam):
    d = _view(fam)
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    th = ctx.w_gp * ctx.c_dg * ctx.dq1
    for e in range(d.maps.shape[0]):
        ka, kb = d.maps[e, 0], d.maps[e, 1]
        k, lr, ax, ay = d.par[e, 0], d.par[e, 1], d.par[e, 2], d.par[e, 3]
        d0x, d0y = pair_distance(maps, ka, kb, ax, ay, qa, scratch)
        d1x, d1y = pair_distance(maps, ka, kb, ax, ay, qb, scratch)
        l0, l1 = np.hypot(d0x, d0y), np.hypot(d1x, d1y)
        kap = 0.5 * k * (1.0 - 2.0 * lr / (l0 + l1)) if lr > 0.0 else 0.5 * k
        c2 = k * lr / (2.0 * l1 * (l0 + l1) ** 2) if lr > 0.0 else 0.0
        sx, sy = d0x + d1x, d0y + d1y
        nsides = 1 if kb < 0 else 2
        # side pairs (A, B): the discrete gradient D_A of ±r_A from q_a to q_b and the Jacobian J_B of ±r_B at
        # q_b, one pair at a time (scratch: 2 n_A + 2 n_B floats)
        for sa in range(nsides):
            kA = ka if sa == 0 else kb
            sgA = 1.0 if sa == 0 else -1.0
            oA, nA = maps.ints[kA, OFF], maps.ints[kA, NB]
            DA = fmat(scratch.ctypes.data + 8 * (0), 2, nA)
            dgrad_into(maps, kA, qa[oA:oA + nA], qb[oA:oA + nA], DA)
            for a in range(nA):
                dd0, dd1 = sgA * DA[0, a], sgA * DA[1, a]
                gp[oA + a] += kap * (sx * dd0 + sy * dd1)
            for sb in range(nsides):
                kB = ka if sb == 0 else kb
                sgB = 1.0 if sb == 0 else -1.0
                oB, nB = maps.ints[kB, OFF], maps.ints[kB, NB]
                JB = fmat(scratch.ctypes.data + 8 * (2 * nA), 2, nB)
                jacobian_into(maps, kB, qb[oB:oB + nB], JB)
                for a in range(nA):
                    ia = oA + a
                    dd0, dd1 = sgA * DA[0, a], sgA * DA[1, a]
                    dsa = sx * dd0 + sy * dd1
                    for b in range(nB):
                        jb = oB + b
                        jd0, jd1 = sgB * JB[0, b], sgB * JB[1, b]
                        tan = th * (kap * (dd0 * jd0 + dd1 * jd1) + c2 * dsa * 2.0 * (d1x * jd0 + d1y * jd1))
                        floor[ia] += abs(tan) * (abs(qa[jb]) + abs(qb[jb]))
                        add_qq(ctx, st, ia, jb, tan)
        # κ ∂(Dᵀ(d_a + d_b))/∂q_b of the FRAME maps, f = ±κ (d_a + d_b)
        for side in range(nsides):
            kk = ka if side == 0 else kb
            sign = 1.0 if side == 0 else -1.0
            add_frame_dgrad_jacobian(ctx, st, maps, kk, qa, qb, sign * kap * sx, sign * kap * sy, th, scratch,
                                     floor)


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, fam):
    """out[0] += Σ ½ k (l(q₁) − l₀)², J."""
    d = _view(fam)
    maps = maps_view(family_at(ctx.maps))
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    r = fvec(ctx.scratch, 2)
    pot = 0.0
    for e in range(d.maps.shape[0]):
        dx, dy = pair_distance(maps, d.maps[e, 0], d.maps[e, 1], d.par[e, 2], d.par[e, 3], q, r)
        pot += 0.5 * d.par[e, 0] * (np.hypot(dx, dy) - d.par[e, 1]) ** 2
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
    return compiled_kernel(_kernel, "the two-point-spring family")
