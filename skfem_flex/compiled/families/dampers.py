r"""Dampers: forces linear in the velocities.

* "linear damper" (:class:`~skfem_flex.elements.forces.RotationalDamper`): Q = −c (g·v) g, g constant (the
  relative angle's gradient), c in N m s/rad; ∂Q/∂v = −c g gᵀ, ∂Q/∂q = 0.
* "two-point damper" (:class:`~skfem_flex.elements.forces.LinearDamper`): the force −c (u·ẇ) u along
  u = d/l, d = r_a − r_b (l = ‖d‖, the other end a body point or a ground point), c in N s/m:

  .. math::

      Q = -c\,(u·w)\,J_d^\mathsf{T} u,\quad w = J_d v,

      ∂Q/∂q = -c\,\bigl(J_d^\mathsf{T} u ⊗ ∂(u·w)/∂q + (u·w)\,(∂(J_d^\mathsf{T} u)/∂q|_u
              + J_d^\mathsf{T} ∂u/∂q)\bigr),\quad ∂Q/∂v = -c\,J_d^\mathsf{T} u ⊗ J_d^\mathsf{T} u,

  with ∂u/∂q = (I − u uᵀ) J_d / l and ∂(u·w)/∂q = wᵀ ∂u/∂q + uᵀ ∂(J_d v)/∂q (J_d = J_a − J_b from the
  points' position maps, :mod:`..points`).

TASK_EVAL_LOADS adds Q(q_e, v_e) into ``ext`` and w_ext (∂Q/∂q dqe + ∂Q/∂v dve) into the Newton matrix;
TASK_LOADS adds Q only. A two-point damper whose points coincide (l = 0: no direction) sets
``ctx.status = STATUS_REFUSED``: the step is handed back, and the element's own
``generalized_force`` raises its ValueError ("… its two points coincide …") on the Python path;
:func:`refusal_error` gives that error for the driver.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_at, family_of, fmat, fvec, i1, i2
from ..points import KIND, LINEAR, NB, OFF, hessian_parts, jacobian_into, maps_view, velocity_jacobian_into
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import STATUS_REFUSED, TASK_EVAL_LOADS, TASK_LOADS
from . import FamilyPack, first_refusal
from .two_point_springs import pack_pairs, pair_distance

NAME = "dampers"
FORMS = ("linear damper", "two-point damper")


class Data(NamedTuple):
    lin: np.ndarray         # (k, 2) linear dampers: first, end of their entries in idx / coef
    lin_c: np.ndarray       # (k,) their damping c
    idx: np.ndarray         # global coordinates of the nonzero entries of g
    coef: np.ndarray        # the entries of g
    pair: np.ndarray        # (l, 2) two-point dampers: map of point a, map of point b or −1 (the ground)
    pair_par: np.ndarray    # (l, 3) their damping c (N s/m) and ground point (m)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), f1(fam, 1), i1(fam, 2), f1(fam, 3), i2(fam, 4), f2(fam, 5))


def pack(items, packer):
    """Linear dampers ("linear damper", g, c) and two-point dampers ("two-point damper", a, b, anchor, c), g over
    the element's own coordinates; each couples its coordinates (g's, or its points' maps' supports)."""
    lin, lin_c, idx, coef, couplings, pairs = [], [], [], [], [], []
    for item in items:
        form, element, where = item
        if form[0] == "linear damper":
            _, grad, c = form
            grad = np.asarray(grad, dtype=float)
            nz = np.flatnonzero(grad)
            where = np.asarray(where, dtype=np.int64)
            lin.append((len(idx), len(idx) + nz.size))
            lin_c.append(float(c))
            idx.extend(where[nz])
            coef.extend(grad[nz])
            couplings.append(where[nz])
        else:
            pairs.append(item)
    maps, anchors, pair_couplings = pack_pairs(pairs, packer, "two-point damper")
    par = np.column_stack([[float(f[4]) for f, _, _ in pairs], anchors]).reshape(-1, 3)
    data = Data(np.asarray(lin, dtype=np.int64).reshape(-1, 2), np.asarray(lin_c, dtype=float),
                np.asarray(idx, dtype=np.int64), np.asarray(coef, dtype=float), maps, par)
    return FamilyPack(data=data, count=len(items), couplings=couplings + pair_couplings)


@numba.njit(cache=True, _nrt=False)
def _linear(ctx, fam, tangent):
    """Q = −c (g·v) g; w_ext ∂Q/∂v dve."""
    d = _view(fam)
    st = storage_of(ctx)
    n = ctx.n
    v, ext, dve = fvec(ctx.ve, n), fvec(ctx.ext, n), fvec(ctx.dve, n)
    for e in range(d.lin.shape[0]):
        i0, i1_ = d.lin[e, 0], d.lin[e, 1]
        c, rate = d.lin_c[e], 0.0
        for t in range(i0, i1_):
            rate += d.coef[t] * v[d.idx[t]]
        for a in range(i0, i1_):
            ia, ga = d.idx[a], d.coef[a]
            ext[ia] -= c * rate * ga
            if tangent:
                for b in range(i0, i1_):
                    jb = d.idx[b]
                    add_qq(ctx, st, ia, jb, ctx.w_ext * (-c * ga * d.coef[b]) * dve[jb])


@numba.njit(cache=True, _nrt=False)
def _two_point(ctx, fam, tangent):
    """The two-point dampers (module docstring); STATUS_REFUSED where the points coincide."""
    d = _view(fam)
    st = storage_of(ctx)
    n = ctx.n
    maps = maps_view(family_at(ctx.maps))
    q, v, ext, dve = fvec(ctx.qe, n), fvec(ctx.ve, n), fvec(ctx.ext, n), fvec(ctx.dve, n)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    wq = ctx.w_ext * ctx.dqe
    for e in range(d.pair.shape[0]):
        ka, kb = d.pair[e, 0], d.pair[e, 1]
        c = d.pair_par[e, 0]
        dx, dy = pair_distance(maps, ka, kb, d.pair_par[e, 1], d.pair_par[e, 2], q, scratch)
        ln = np.hypot(dx, dy)
        if ln == 0.0:                   # the direction is undefined: the Python path raises the damper's error
            ctx.status = STATUS_REFUSED
            return
        ux, uy = dx / ln, dy / ln
        nsides = 1 if kb < 0 else 2
        # w = J_d v = Σ ±J_s v_s
        wx, wy = 0.0, 0.0
        for s in range(nsides):
            k = ka if s == 0 else kb
            sg = 1.0 if s == 0 else -1.0
            o, nb = maps.ints[k, OFF], maps.ints[k, NB]
            J = fmat(scratch.ctypes.data + 8 * (0), 2, nb)
            jacobian_into(maps, k, q[o:o + nb], J)
            for j in range(nb):
                wx += sg * J[0, j] * v[o + j]
                wy += sg * J[1, j] * v[o + j]
        rate = ux * wx + uy * wy
        # side pairs (A, B): J_A, then J_B and ∂(J_B v)/∂q (scratch: 2 n_A + 4 n_B floats)
        for sa in range(nsides):
            kA = ka if sa == 0 else kb
            sgA = 1.0 if sa == 0 else -1.0
            oA, nA = maps.ints[kA, OFF], maps.ints[kA, NB]
            JA = fmat(scratch.ctypes.data + 8 * (0), 2, nA)
            jacobian_into(maps, kA, q[oA:oA + nA], JA)
            for a in range(nA):
                ext[oA + a] -= c * rate * (sgA * JA[0, a] * ux + sgA * JA[1, a] * uy)
            if not tangent:
                continue
            for sb in range(nsides):
                kB = ka if sb == 0 else kb
                sgB = 1.0 if sb == 0 else -1.0
                oB, nB = maps.ints[kB, OFF], maps.ints[kB, NB]
                JB = fmat(scratch.ctypes.data + 8 * (2 * nA), 2, nB)
                VB = fmat(scratch.ctypes.data + 8 * (2 * nA + 2 * nB), 2, nB)
                jacobian_into(maps, kB, q[oB:oB + nB], JB)
                velocity_jacobian_into(maps, kB, q[oB:oB + nB], v[oB:oB + nB], VB)
                for a in range(nA):
                    ja0, ja1 = sgA * JA[0, a], sgA * JA[1, a]
                    jtua = ja0 * ux + ja1 * uy
                    for b in range(nB):
                        jb0, jb1 = sgB * JB[0, b], sgB * JB[1, b]
                        jtub = jb0 * ux + jb1 * uy
                        # wᵀ (I − u uᵀ) J_d / l = (w − (u·w) u)ᵀ J_d / l, plus uᵀ ∂(J_d v)/∂q
                        drate = ((wx - rate * ux) * jb0 + (wy - rate * uy) * jb1) / ln \
                            + ux * sgB * VB[0, b] + uy * sgB * VB[1, b]
                        # J_dᵀ ∂u/∂q = J_dᵀ (I − u uᵀ) J_d / l
                        jdu = (ja0 * jb0 + ja1 * jb1 - jtua * jtub) / ln
                        fq = -c * (jtua * drate + rate * jdu)
                        fv = -c * jtua * jtub
                        add_qq(ctx, st, oA + a, oB + b, wq * fq + ctx.w_ext * fv * dve[oB + b])
        if tangent:
            # −c (u·w) ∂(J_dᵀ u)/∂q at fixed u (FRAME maps)
            for s in range(nsides):
                k = ka if s == 0 else kb
                if maps.ints[k, KIND] == LINEAR:
                    continue
                sg = 1.0 if s == 0 else -1.0
                o, nb = maps.ints[k, OFF], maps.ints[k, NB]
                f = scratch[:2]
                f[0], f[1] = sg * ux, sg * uy
                row = scratch[2:nb - 1]
                h22 = hessian_parts(maps, k, q[o:o + nb], f, row)
                w = wq * (-c * rate)
                add_qq(ctx, st, o + 2, o + 2, w * h22)
                for j in range(nb - 3):
                    add_qq(ctx, st, o + 2, o + 3 + j, w * row[j])
                    add_qq(ctx, st, o + 3 + j, o + 2, w * row[j])


#: the driver's :func:`refusal_error` looks at the loads' evaluation point (q_e, v_e, t_e)
REFUSAL_STATE = "loads"


def refusal_error(scene, q, v, t):
    """The error the Python path raises where this family refused a state (``ctx.status = STATUS_REFUSED``,
    ``ctx.bad_family`` this family): the ValueError of the first two-point damper whose own
    ``generalized_force`` raises at the loads' evaluation point, or None.

    Parameters
    ----------
    scene : Scene
    q, v : ndarray
        Coordinates and velocities where the loads were evaluated (the context's q_e, v_e), m, rad and
        m/s, rad/s.
    t : float
        Its time (the context's t_e), s.
    """
    return first_refusal(scene.loads, ("two-point damper",), lambda f, i: f.generalized_force(q[i], v[i], t))


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL_LOADS or ctx.task == TASK_LOADS:
        tangent = ctx.task == TASK_EVAL_LOADS
        _linear(ctx, family_of(fam_p), tangent)
        _two_point(ctx, family_of(fam_p), tangent)


def kernel():
    """The family's compiled kernel (:func:`~skfem_flex.compiled.registry.compiled_kernel`), from the cache or
    compiled on first use."""
    return compiled_kernel(_kernel, "the damper family")
