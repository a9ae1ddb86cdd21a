r"""Spatial rigid bodies turned by quaternions (:class:`~skfem_flex.bodies.quaternion.QuaternionRigidBody`):
their inertia and the gravity acting on them.

The arithmetic is :mod:`skfem_flex.bodies.quaternion_kernel`; this family adds its results where the task
wants them (:mod:`skfem_flex.compiled.tasks`):

* TASK_EVAL, energy–momentum: the rotation's rows in Hamiltonian form, p ← π₁ (solved from
  Δe = Δt D_{T,π}) and g_k ← −D_{T,e} with their derivatives with respect to Δe; the velocity kept is
  ė₁ = A(e₁)π₁, written over the scheme's 2Δe/Δt − ė₀ (the body's own rows only: nothing else reads
  them). The centre of mass has the constant mass m (p ← m v₁);
* TASK_EVAL, Newmark and statics: p ← M(q₁)a₁, g_k ← Q_v(q₁, v₁) with their derivatives;
* gravity: V = −m g·(x + R(e)c), quadratic in q, so g_p ← ∇V(q_m) is its exact discrete gradient;
* TASK_MOMENTUM: p = M(q₁)v₁, the linear momentum and the angular momentum about the origin
  ½Ḡ(e)π + r × (linear momentum);
* TASK_ENERGY: gravity's potential at q₁.
"""
from __future__ import annotations

import numba
import numpy as np

from ...bodies.quaternion import QuaternionKernelData
from ...bodies.quaternion_kernel import em_terms, gravity_quadratic, mass, moment_rate, newmark_terms, rotation_momentum
from ..abi import context_of, f1, f2, f3, family_of, fvec, i1
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import SCHEME_EM, TASK_ENERGY, TASK_EVAL, TASK_MOMENTUM
from . import bodies_and_gravity, body_family_pack

__all__ = ["NAME", "FORMS", "pack", "kernel"]

NAME = "quaternion rigid bodies"
FORMS = ("quaternion rigid body", "quaternion rigid body gravity")

_NKD = len(QuaternionKernelData._fields)


def pack(items, packer):
    """The family's data: the offsets of the bodies' blocks, then each body's :class:`QuaternionKernelData`
    (fields ``b<k>_<name>``) with the gravity fields that act on it summed into its ``g``.

    Parameters
    ----------
    items : list
        ``(QuaternionKernelData, body, offset)`` per body and ``(("gravity", g), body, offset)`` per gravity
        field on one of them.
    packer : Packer

    Returns
    -------
    FamilyPack
        One dense coupling block per body.
    """
    bodies, gravity = bodies_and_gravity(items, QuaternionKernelData)
    packed = []
    for kd, body, off in bodies:
        if id(body) in gravity:
            g = kd.g + gravity[id(body)]
            kd = kd._replace(g=g, W=gravity_quadratic(kd.Qc, g))
        packed.append(((kd,), off, int(kd.n[0])))
    return body_family_pack("QuaternionBodiesData", packed)


@numba.njit(cache=True, inline="always")
def _body(fam, k):
    """Body data from the pools, field by field (QuaternionKernelData's order)."""
    return QuaternionKernelData(i1(fam, k), f1(fam, k + 1), f2(fam, k + 2), f2(fam, k + 3), f1(fam, k + 4),
                                f2(fam, k + 5), f1(fam, k + 6), f3(fam, k + 7), f1(fam, k + 8), f1(fam, k + 9),
                                f2(fam, k + 10))


@numba.njit(cache=True)
def _bodies(ctx, fam):
    """Every body's part of the context's task (module docstring)."""
    n, task = ctx.n, ctx.task
    offs = i1(fam, 0)
    out = fvec(ctx.out, 7)
    q1all, v1all = fvec(ctx.q1, n), fvec(ctx.v1, n)
    for b in range(offs.size):
        kd = _body(fam, 1 + _NKD * b)
        o, nb = offs[b], kd.n[0]
        r = nb - 4                                    # 3 centre-of-mass rows, or none about a pivot
        m = kd.mass[0]
        e1, ev1 = np.empty(4), np.empty(4)
        for i in range(4):
            e1[i], ev1[i] = q1all[o + r + i], v1all[o + r + i]
        if task == TASK_ENERGY:
            V = 0.0
            for a in range(4):
                for c in range(4):
                    V += e1[a] * kd.W[a, c] * e1[c]
            for i in range(3):
                V -= m * kd.g[i] * (q1all[o + i] if r else kd.anchor[i])
            out[0] += V
            continue
        if task == TASK_MOMENTUM:
            M = mass(kd.J4, e1)
            rp = fvec(ctx.p, n)
            for i in range(4):
                for j in range(4):
                    rp[o + r + i] += M[i, j] * ev1[j]
            if r:
                lin, ref = np.zeros(3), np.zeros(3)
                for i in range(3):
                    rp[o + i] += m * v1all[o + i]
                    lin[i] = m * v1all[o + i]
                    ref[i] = q1all[o + i]
            else:
                lin, ref = moment_rate(kd.Qc, e1, ev1), kd.anchor
            L = rotation_momentum(kd.J4, e1, ev1)
            L[0] += ref[1] * lin[2] - ref[2] * lin[1]
            L[1] += ref[2] * lin[0] - ref[0] * lin[2]
            L[2] += ref[0] * lin[1] - ref[1] * lin[0]
            for i in range(3):
                out[1 + i] += lin[i]
                out[4 + i] += L[i]
            continue
        _step(ctx, kd, o, r, m, e1, ev1)


@numba.njit(cache=True)
def _step(ctx, kd, o, r, m, e1, ev1):
    """TASK_EVAL of one body (module docstring)."""
    n = ctx.n
    st = storage_of(ctx)
    rp, rgk, rgp, floor = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    dv1 = fvec(ctx.dv1, n)
    w_p, w_gk, dq1 = ctx.w_p, ctx.w_gk, ctx.dq1
    em = ctx.scheme == SCHEME_EM
    if em:
        q0, v0 = fvec(ctx.q0, n), fvec(ctx.v0, n)
        e0, ev0 = np.empty(4), np.empty(4)
        for i in range(4):
            e0[i], ev0[i] = q0[o + r + i], v0[o + r + i]
        p, gk, dp, dgk, vnew = em_terms(kd.J4, kd.J4i, kd.kin, kd.U, kd.cu, e0, e1, ev0, ctx.h)
        v1 = fvec(ctx.v1, n)
        for i in range(4):
            v1[o + r + i] = vnew[i]
        for i in range(4):
            rp[o + r + i] += p[i]
            rgk[o + r + i] += gk[i]
            for j in range(4):
                val = w_p * dp[i, j] * dq1 + w_gk * dgk[i, j] * dq1
                if val != 0.0:
                    add_qq(ctx, st, o + r + i, o + r + j, val)
        for i in range(r):
            rp[o + i] += m * fvec(ctx.v1, n)[o + i]
            add_qq(ctx, st, o + i, o + i, w_p * m * dv1[o + i])
    else:
        a1 = fvec(ctx.a1, n)
        ea1 = np.empty(4)
        for i in range(4):
            ea1[i] = a1[o + r + i]
        M1, pa, dpa, f, fe, fv = newmark_terms(kd.J4, e1, ev1, ea1)
        mterms, terms = fvec(ctx.mterms, n), fvec(ctx.terms, n)
        for i in range(4):
            rp[o + r + i] += pa[i]
            rgk[o + r + i] += f[i]
            s = 0.0
            for j in range(4):
                val = w_p * (dpa[i, j] * dq1 + M1[i, j] * ctx.da1) + w_gk * (fe[i, j] * dq1 + fv[i, j] * dv1[o + r + j])
                if val != 0.0:
                    add_qq(ctx, st, o + r + i, o + r + j, val)
                s += abs(M1[i, j]) * terms[o + r + j]
            mterms[o + r + i] += s
        for i in range(r):
            rp[o + i] += m * a1[o + i]
            add_qq(ctx, st, o + i, o + i, w_p * m * ctx.da1)
            mterms[o + i] += m * terms[o + i]
    # gravity: V = eᵀWe − m g·x, its gradient at the mid-point of q_a and q_b and half its Hessian
    qa, qb = fvec(ctx.qa, n), fvec(ctx.qb, n)
    W = kd.W
    th = ctx.w_gp * ctx.c_dg * dq1
    for i in range(r):
        rgp[o + i] -= m * kd.g[i]
    for i in range(4):
        s = 0.0
        fl = 0.0
        for j in range(4):
            s += W[i, j] * (qa[o + r + j] + qb[o + r + j])
            tp = th * W[i, j]
            if tp != 0.0:
                add_qq(ctx, st, o + r + i, o + r + j, tp)
            fl += abs(tp) * (abs(qa[o + r + j]) + abs(qb[o + r + j]))
        rgp[o + r + i] += s
        floor[o + r + i] += fl


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL, TASK_MOMENTUM and TASK_ENERGY."""
    ctx = context_of(ctx_p)
    task = ctx.task
    if task == TASK_EVAL or task == TASK_MOMENTUM or task == TASK_ENERGY:
        _bodies(ctx, family_of(fam_p))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the quaternion rigid-body family", nrt=True)
