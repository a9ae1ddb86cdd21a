r"""Springs between points of spatial bodies whose positions are affine in q
(:class:`~skfem_flex.elements.forces.SpatialSpring` on rigid bodies, point masses and exact-beam nodes):
V = ½ k (l − l₀)², l = ‖d‖, d = A q + a (the element's affine difference r_a − r_b, or r_a minus a ground point).

With s = d·d quadratic in q, the exact discrete gradient from q_a to q_b is (the element's
``potential_discrete_gradient``, the same equations in the same order)

.. math::

    g = κ\, ∇s(q_m),\quad ∇s = 2 A^\mathsf{T} d,\quad
    κ = \tfrac12 k \Bigl(1 - \frac{2 l_0}{l_a + l_b}\Bigr)\ (κ = \tfrac12 k \text{ for } l_0 = 0),

    \frac{∂g}{∂q_b} = κ\, A^\mathsf{T} A + \frac{k l_0}{2 l_b (l_a + l_b)^2}\, ∇s(q_m) ⊗ ∇s(q_b)

(at q_a = q_b the gradient and half the Hessian). TASK_EVAL adds g into ``g_p``, w_gp c_dg dq1 times its
derivative into the Newton matrix and the round-off floor into ``floor``; TASK_ENERGY adds V(q₁) (J).

Dampers along the same lines (:class:`~skfem_flex.elements.forces.SpatialDamper`, "spatial damper"): with
u = d/l and w = A v, the load at (q_e, v_e)

.. math::

    Q = −c\,(u·w)\,A^\mathsf{T} u,\quad
    ∂Q/∂q = −c\,\bigl(A^\mathsf{T} u ⊗ A^\mathsf{T} ∂u^\mathsf{T} w + (u·w)\,A^\mathsf{T} ∂u\bigr),\quad
    ∂Q/∂v = −c\,A^\mathsf{T} u ⊗ A^\mathsf{T} u,\quad ∂u = (I − u u^\mathsf{T}) A / l;

TASK_EVAL_LOADS adds Q into ``ext`` and w_ext (∂Q/∂q dqe + ∂Q/∂v dve) into the Newton matrix, TASK_LOADS Q
only. A damper whose points coincide (l = 0: no direction) refuses the step (``STATUS_REFUSED``);
:func:`refusal_error` gives the element's own error.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f2, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import STATUS_REFUSED, TASK_ENERGY, TASK_EVAL, TASK_EVAL_LOADS, TASK_LOADS
from . import FamilyPack, first_refusal

NAME = "spatial springs and dampers"
FORMS = ("spatial spring", "spatial damper")

SPRING, DAMPER = 0, 1


class Data(NamedTuple):
    span: np.ndarray    # (k, 2) first and end of each element's coordinates in ``coords`` (and of its A's columns)
    coords: np.ndarray  # the scene coordinates of each element's layout, concatenated
    A: np.ndarray       # (3, Σ n) the columns of each element's A, concatenated
    par: np.ndarray     # (k, 5) a spring's stiffness k (N/m) and rest length l₀ (m), or a damper's c (N s/m)
    #                     and 0; then a (m)
    kind: np.ndarray    # (k,) SPRING or DAMPER


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), i1(fam, 1), f2(fam, 2), f2(fam, 3), i1(fam, 4))


def pack(items, packer):
    """Spatial springs ("spatial spring", A (3, n), a (3,), k, l₀) and dampers ("spatial damper", A, a, c) on the
    scene coordinates ``where`` of their layout; each couples its coordinates as one dense block."""
    span, coords, cols, par, kind, couplings = [], [], [], [], [], []
    for form, element, where in items:
        A, a = form[1], form[2]
        where = np.asarray(where, dtype=np.int64)
        A = np.asarray(A, dtype=float).reshape(3, where.size)
        span.append((len(coords), len(coords) + where.size))
        coords.extend(where)
        cols.append(A)
        spring = form[0] == "spatial spring"
        par.append((float(form[3]), float(form[4]) if spring else 0.0, *np.asarray(a, dtype=float).reshape(3)))
        kind.append(SPRING if spring else DAMPER)
        couplings.append(np.unique(where))
    data = Data(np.asarray(span, dtype=np.int64).reshape(-1, 2), np.asarray(coords, dtype=np.int64),
                np.ascontiguousarray(np.hstack(cols) if cols else np.zeros((3, 0))),
                np.asarray(par, dtype=float).reshape(-1, 5), np.asarray(kind, dtype=np.int64))
    return FamilyPack(data=data, count=len(items), couplings=couplings)


@numba.njit(cache=True, _nrt=False)
def _difference(d, e, q, out):
    """d = A q + a of spring ``e`` at the scene coordinates q into ``out`` (3,); returns its length, m."""
    for c in range(3):
        s = d.par[e, 2 + c]
        for j in range(d.span[e, 0], d.span[e, 1]):
            s += d.A[c, j] * q[d.coords[j]]
        out[c] = s
    return np.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2])


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, fam):
    d = _view(fam)
    n = ctx.n
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    da, db = scratch[0:3], scratch[3:6]
    th = ctx.w_gp * ctx.c_dg * ctx.dq1
    for e in range(d.span.shape[0]):
        if d.kind[e] != SPRING:
            continue
        k, lr = d.par[e, 0], d.par[e, 1]
        la = _difference(d, e, qa, da)
        lb = _difference(d, e, qb, db)
        total = la + lb
        kap = 0.5 * k * (1.0 - 2.0 * lr / total) if lr > 0.0 else 0.5 * k
        c2 = k * lr / (2.0 * lb * total * total) if lr > 0.0 else 0.0
        j0, j1 = d.span[e, 0], d.span[e, 1]
        for i in range(j0, j1):
            # ∇s(q_m)_i = 2 A_i · d_m = A_i · (d_a + d_b), ∇s(q_b)_i = 2 A_i · d_b
            gm = 0.0
            for c in range(3):
                gm += d.A[c, i] * (da[c] + db[c])
            gp[d.coords[i]] += kap * gm
            fl = 0.0
            for j in range(j0, j1):
                ata, gbj = 0.0, 0.0
                for c in range(3):
                    ata += d.A[c, i] * d.A[c, j]
                    gbj += 2.0 * d.A[c, j] * db[c]
                tan = th * (kap * ata + c2 * gm * gbj)
                if tan != 0.0:
                    add_qq(ctx, st, d.coords[i], d.coords[j], tan)
                fl += abs(tan) * (abs(qa[d.coords[j]]) + abs(qb[d.coords[j]]))
            floor[d.coords[i]] += fl


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, fam):
    """out[0] += Σ ½ k (l(q₁) − l₀)², J."""
    d = _view(fam)
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    r = fvec(ctx.scratch, 3)
    pot = 0.0
    for e in range(d.span.shape[0]):
        if d.kind[e] == SPRING:
            pot += 0.5 * d.par[e, 0] * (_difference(d, e, q, r) - d.par[e, 1]) ** 2
    out[0] += pot


@numba.njit(cache=True, _nrt=False)
def _dampers(ctx, fam, tangent):
    """The dampers' loads (module docstring) and, with ``tangent``, their derivatives; STATUS_REFUSED where a
    damper's points coincide."""
    d = _view(fam)
    n = ctx.n
    q, v, ext, dve = fvec(ctx.qe, n), fvec(ctx.ve, n), fvec(ctx.ext, n), fvec(ctx.dve, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    dd, u, w = scratch[0:3], scratch[3:6], scratch[6:9]
    wq = ctx.w_ext * ctx.dqe
    for e in range(d.span.shape[0]):
        if d.kind[e] != DAMPER:
            continue
        c = d.par[e, 0]
        ln = _difference(d, e, q, dd)
        if ln == 0.0:                   # the direction is undefined: the Python path raises the damper's error
            ctx.status = STATUS_REFUSED
            return
        j0, j1 = d.span[e, 0], d.span[e, 1]
        for k in range(3):
            u[k] = dd[k] / ln
            w[k] = 0.0
            for j in range(j0, j1):
                w[k] += d.A[k, j] * v[d.coords[j]]
        rate = u[0] * w[0] + u[1] * w[1] + u[2] * w[2]
        for i in range(j0, j1):
            jtu_i = d.A[0, i] * u[0] + d.A[1, i] * u[1] + d.A[2, i] * u[2]
            ext[d.coords[i]] -= c * rate * jtu_i
            if not tangent:
                continue
            for j in range(j0, j1):
                jtu_j = d.A[0, j] * u[0] + d.A[1, j] * u[1] + d.A[2, j] * u[2]
                aij = d.A[0, i] * d.A[0, j] + d.A[1, i] * d.A[1, j] + d.A[2, i] * d.A[2, j]
                # (w − (u·w) u) · A_j / l = wᵀ ∂u/∂q_j;  A_iᵀ ∂u/∂q_j = (A_i·A_j − (u·A_i)(u·A_j)) / l
                wdu = ((w[0] - rate * u[0]) * d.A[0, j] + (w[1] - rate * u[1]) * d.A[1, j]
                       + (w[2] - rate * u[2]) * d.A[2, j]) / ln
                fq = -c * (jtu_i * wdu + rate * (aij - jtu_i * jtu_j) / ln)
                fv = -c * jtu_i * jtu_j
                add_qq(ctx, st, d.coords[i], d.coords[j], wq * fq + ctx.w_ext * fv * dve[d.coords[j]])


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL:
        _evaluate(ctx, family_of(fam_p))
    elif ctx.task == TASK_ENERGY:
        _energy(ctx, family_of(fam_p))
    elif ctx.task == TASK_EVAL_LOADS or ctx.task == TASK_LOADS:
        _dampers(ctx, family_of(fam_p), ctx.task == TASK_EVAL_LOADS)


#: the driver's :func:`refusal_error` looks at the loads' evaluation point (q_e, v_e, t_e)
REFUSAL_STATE = "loads"


def refusal_error(scene, q, v, t):
    """The ValueError of the first spatial damper whose own ``generalized_force`` raises at the loads' evaluation
    point (q, v, t) (its points coincide), or None: what the Python path raises where this family refused."""
    return first_refusal(scene.loads, ("spatial damper",), lambda f, i: f.generalized_force(q[i], v[i], t))


def kernel():
    """The family's compiled kernel (:func:`~skfem_flex.compiled.registry.compiled_kernel`), from the cache or
    compiled on first use."""
    return compiled_kernel(_kernel, "the spatial-spring and damper family")
