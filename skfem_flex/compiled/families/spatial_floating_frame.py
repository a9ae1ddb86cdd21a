r"""Spatial floating-frame bodies (:class:`~skfem_flex.bodies.floating_spatial.body.FloatingBeam3D`,
:class:`~skfem_flex.bodies.floating_spatial.solid.FloatingSolid3D`, linear or Green–Lagrange): a director frame and
elastic coordinates with a mass matrix M(q) that is a polynomial of degree two in q, their strain energy and
the gravity acting on them.

The arithmetic is the bodies' compiled kernel (:mod:`skfem_flex.bodies.floating_spatial.kernel`, on each
body's ``compiled_kernel_data()``); this family adds its results where the task wants them
(:mod:`skfem_flex.compiled.tasks`):

* TASK_EVAL: p, g_k and g_p of :func:`~skfem_flex.bodies.floating_spatial.kernel.body_terms_into` into the
  residual's parts and, into the body's dense block of the Newton matrix,

  .. math::

      w_p(∂_{q_1}p\,dq_1 + M(q_1)\,d\dot{}) + w_{gk}(∂_{q_1}g_k\,dq_1 + ∂_{v_1}g_k\,dv_1)
      + w_{gp} c_{dg}\,dq_1\, ∂_{q_b} g_p ,

  with d = dv₁ (energy–momentum: p = M(q₁)v₁) or da₁ (Newmark: p = M(q₁)a₁), its kinetic part formed by
  ``body_terms_into`` with the task's weights folded in (its block K; dv₁ is the same for every coordinate of
  a body, which has no angle coordinate); the potential's round-off floor |w_gp c_dg dq₁ ∂g_p/∂q_b|
  (|q_a| + |q_b|) into ``floor`` (neither block nor floor in a residual-only evaluation) and, for the Newmark family,
  Σ_j |M_ij| terms_j into ``mterms``;
* TASK_MOMENTUM: p = M(q₁)v₁ into ``p``, the linear momentum (the x rows of p) into ``out[1:4]`` and the
  angular momentum about the origin Σ_k q_k × p_k over x and the three directors into ``out[4:7]``;
* TASK_ENERGY: the strain energy and gravity's potential at q₁ into ``out[0]``.
"""
from __future__ import annotations

import numba

from ...bodies.floating_spatial.kernel import (EM, ENERGY, MOMENTUM, NEWMARK, BodyWork, QuarticTerms,
                                               SpatialBodyData, SpatialFrameKernelData, body_terms_into, body_work)
from ..abi import context_of, f1, f2, f3, family_of, fvec, i1
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import SCHEME_EM, TASK_ENERGY, TASK_EVAL, TASK_MOMENTUM
from . import bodies_and_gravity, body_family_pack

__all__ = ["NAME", "FORMS", "pack", "kernel"]

NAME = "spatial floating-frame bodies"
FORMS = ("spatial floating frame", "spatial floating frame gravity")
#: an evaluation whose matrix is not used (ctx.fresh = 0) forms no Newton block, only products with
#: vectors (about half of the work): the loop then checks an update's residual alone (:func:`..loop.run_steps`, ``lazy``)
RESIDUAL_ONLY = True

#: fields per body: those of SpatialFrameKernelData, then those of QuarticTerms, then the body's BodyWork (its
#: results and temporaries: the kernel allocates nothing), after the family's one (the bodies' offsets)
_NFRAME = len(SpatialFrameKernelData._fields)
_NQT = _NFRAME + len(QuarticTerms._fields)
_NKD = _NQT + len(BodyWork._fields)


def pack(items, packer):
    """The family's data: the offsets of the bodies' blocks, then each body's kernel data (fields
    ``b<k>_<name>``), with the gravity fields that act on it summed into its ``g``.

    Parameters
    ----------
    items : list
        ``(SpatialBodyData, body, offset)`` per body (form "spatial floating frame") and
        ``(("gravity", g), body, offset)`` per gravity field on one of them.
    packer : Packer

    Returns
    -------
    FamilyPack
        One dense coupling block per body.
    """
    bodies, gravity = bodies_and_gravity(items, SpatialBodyData)
    packed = []
    for data, body, off in bodies:
        kd = data.frame
        if id(body) in gravity:
            kd = kd._replace(g=kd.g + gravity[id(body)])
        packed.append(((kd, data.quartic, body_work(kd, data.quartic)), off, 12 + kd.Sbar.shape[1]))
    return body_family_pack("SpatialFloatingFrameData", packed)


@numba.njit(cache=True, inline="always")
def _body(fam, k):
    """Body data from the pools, field by field (SpatialFrameKernelData's order)."""
    return SpatialFrameKernelData(f1(fam, k), f1(fam, k + 1), f2(fam, k + 2), f2(fam, k + 3), f3(fam, k + 4),
                                  f1(fam, k + 5), f2(fam, k + 6), i1(fam, k + 7), f3(fam, k + 8), f1(fam, k + 9),
                                  f1(fam, k + 10), f2(fam, k + 11))


@numba.njit(cache=True, inline="always")
def _quartic(fam, k):
    """The body's QuarticTerms from the pools (their order)."""
    return QuarticTerms(i1(fam, k), f2(fam, k + 1), f2(fam, k + 2), f2(fam, k + 3), f2(fam, k + 4), f2(fam, k + 5),
                        f2(fam, k + 6), f2(fam, k + 7))


@numba.njit(cache=True, inline="always")
def _work(fam, k):
    """The body's BodyWork from the pools (its order)."""
    return BodyWork(f1(fam, k), f1(fam, k + 1), f1(fam, k + 2), f2(fam, k + 3), f2(fam, k + 4), f2(fam, k + 5),
                    f3(fam, k + 6), f3(fam, k + 7), f2(fam, k + 8), f3(fam, k + 9), f3(fam, k + 10), f3(fam, k + 11),
                    f2(fam, k + 12), f3(fam, k + 13), f1(fam, k + 14), f1(fam, k + 15), f1(fam, k + 16))


@numba.njit(cache=True, inline="always")
def _bodies(ctx, fam):
    """Every body's part of the context's task (module docstring)."""
    n, task = ctx.n, ctx.task
    mode = (EM if ctx.scheme == SCHEME_EM else NEWMARK) if task == TASK_EVAL else (
        ENERGY if task == TASK_ENERGY else MOMENTUM)
    offs = i1(fam, 0)
    out = fvec(ctx.out, 7)
    rp, rgk, rgp, floor = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    for b in range(offs.size):
        k0 = 1 + _NKD * b
        kd, qt, wk = _body(fam, k0), _quartic(fam, k0 + _NFRAME), _work(fam, k0 + _NQT)
        o, nb = offs[b], 12 + kd.Sbar.shape[1]
        q1, v1 = fvec(ctx.q1 + 8 * o, nb), fvec(ctx.v1 + 8 * o, nb)
        if mode == ENERGY or mode == MOMENTUM:  # only q₁ and v₁ are set for these tasks
            q0, v0, a1, qa, qb = q1, v1, v1, q1, q1
        else:
            q0, v0, a1 = fvec(ctx.q0 + 8 * o, nb), fvec(ctx.v0 + 8 * o, nb), fvec(ctx.a1 + 8 * o, nb)
            qa, qb = fvec(ctx.qa + 8 * o, nb), fvec(ctx.qb + 8 * o, nb)
        residual = ctx.fresh == 0                 # an update's check: its matrix is not used
        weights = wk.weights
        weights[0], weights[1], weights[2], weights[3], weights[4] = (ctx.w_p, ctx.w_gk, ctx.dq1,
                                                                      fvec(ctx.dv1, n)[o], ctx.da1)
        V = body_terms_into(kd, qt, wk, mode, q0, q1, v0, v1, a1, qa, qb, weights, residual)
        p = wk.p
        if task == TASK_ENERGY:
            out[0] += V
            continue
        if task == TASK_MOMENTUM:
            for i in range(nb):
                rp[o + i] += p[i]
            for c in range(3):
                out[1 + c] += p[c]
            for k in range(4):
                x0, x1, x2 = q1[3 * k], q1[3 * k + 1], q1[3 * k + 2]
                out[4] += x1 * p[3 * k + 2] - x2 * p[3 * k + 1]
                out[5] += x2 * p[3 * k] - x0 * p[3 * k + 2]
                out[6] += x0 * p[3 * k + 1] - x1 * p[3 * k]
            continue
        gk, gp = wk.gk, wk.gp
        for i in range(nb):
            rp[o + i] += p[i]
            rgk[o + i] += gk[i]
            rgp[o + i] += gp[i]
        if not residual:
            # the Newton block and the potential's round-off floor (neither wanted by a residual-only check)
            K, dgp = wk.block, wk.dgp
            st = storage_of(ctx)
            th = ctx.w_gp * ctx.c_dg * ctx.dq1
            for i in range(nb):
                fl = 0.0
                for j in range(nb):
                    tp = th * dgp[i, j]
                    val = K[i, j] + tp
                    if val != 0.0:
                        add_qq(ctx, st, o + i, o + j, val)
                    fl += abs(tp) * (abs(qa[j]) + abs(qb[j]))
                floor[o + i] += fl
        if mode == NEWMARK:
            M1 = wk.M1
            mterms, terms = fvec(ctx.mterms, n), fvec(ctx.terms, n)
            for i in range(nb):
                s = 0.0
                for j in range(nb):
                    s += abs(M1[i, j]) * terms[o + j]
                mterms[o + i] += s


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL, TASK_MOMENTUM and TASK_ENERGY."""
    ctx = context_of(ctx_p)
    task = ctx.task
    if task == TASK_EVAL or task == TASK_MOMENTUM or task == TASK_ENERGY:
        _bodies(ctx, family_of(fam_p))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the spatial floating-frame family")
