r"""Torsional springs and dampers about a hinge axis (:class:`~skfem_flex.elements.forces.SpatialTorsionalSpring`,
:class:`~skfem_flex.elements.forces.SpatialTorsionalDamper`): their angle θ = σ atan2(y, x) is read from the
two invariants x = u·n₁ and y = u·n₂, each a quadratic form ½ qᵀH q + b·q + c over the element's coordinates
(σ = ±1: −1 against the ground). With r² = x² + y²,

.. math::

    ∇θ = σ (x ∇y − y ∇x) / r², \qquad
    ∇²θ = σ \bigl((∇y ∇xᵀ − ∇x ∇yᵀ) + x H_y − y H_x\bigr) / r² − 2 σ (x ∇y − y ∇x)(x ∇x + y ∇y)ᵀ / r⁴ .

* "torsional spring", V = ½ k (θ − θ₀)²: the discrete gradient is Gonzalez's in the plane of z = (x, y),
  G = ∇_z V(z̄) + (ΔV − ∇_z V(z̄)·Δz)/|Δz|² Δz with z̄ = (z₀ + z₁)/2, times ∇x(q_m), ∇y(q_m) (the element's
  ``potential_discrete_gradient``: exact, and without a net moment, since x and y do not change when the
  whole system turns). Its derivative in q₁ is Σ_c ∂G_c/∂z₁ ∇z(q₁) ⊗ ∇z_c(q_m) + ½ G_c H_c, with
  ∂G/∂z₁ = ½ ∇²V(z̄) + Δz ⊗ ∂c/∂z₁ + c I, c the correction's coefficient. TASK_EVAL adds them (weight
  w_gp c_dg dq1) with the round-off floor; TASK_ENERGY V(q₁).
* "torsional damper", Q = −c θ̇ ∇θ, θ̇ = ∇θ·v, at (q_e, v_e): ∂Q/∂q = −c (∇θ ⊗ ∇²θ v + θ̇ ∇²θ),
  ∂Q/∂v = −c ∇θ ∇θᵀ (TASK_EVAL_LOADS, TASK_LOADS).

Where r = 0 (the turning direction along the axis) the angle is undefined: the step is refused
(``STATUS_REFUSED``) and :func:`refusal_error` gives the element's own error.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..abi import context_of, f1, f2, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import add_qq, storage_of
from ..tasks import STATUS_REFUSED, TASK_ENERGY, TASK_EVAL, TASK_EVAL_LOADS, TASK_LOADS
from . import FamilyPack, first_refusal

NAME = "spatial torsional springs and dampers"
FORMS = ("torsional spring", "torsional damper")

SPRING, DAMPER = 0, 1


class Data(NamedTuple):
    span: np.ndarray    # (k, 2) first and end of each element's coordinates in ``coords``
    coords: np.ndarray  # the scene coordinates of each element, concatenated
    hoff: np.ndarray    # (k,) first entry of each element's H_x (then H_y) in ``H``
    H: np.ndarray       # the dense H_x and H_y of every element, raveled one after another
    b: np.ndarray       # (2, Σ n) b_x, b_y, concatenated like ``coords``
    par: np.ndarray     # (k, 5) c_x, c_y, σ, k (N m/rad) or c (N m s/rad), θ₀ (rad)
    kind: np.ndarray    # (k,) SPRING or DAMPER


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return Data(i2(fam, 0), i1(fam, 1), i1(fam, 2), f1(fam, 3), f2(fam, 4), f2(fam, 5), i1(fam, 6))


def pack(items, packer):
    """Torsional springs ("torsional spring", H_x, b_x, c_x, H_y, b_y, c_y, σ, k, θ₀) and dampers
    ("torsional damper", …, σ, c, 0) on the scene coordinates ``where`` of their layout; each couples its
    coordinates as one dense block."""
    span, coords, hoff, H, bx, by, par, kind, couplings = [], [], [], [], [], [], [], [], []
    for form, element, where in items:
        _, Hx, b_x, cx, Hy, b_y, cy, sign, value, rest = form
        where = np.asarray(where, dtype=np.int64)
        span.append((len(coords), len(coords) + where.size))
        coords.extend(where)
        hoff.append(len(H))
        H.extend(np.asarray(Hx, dtype=float).ravel())
        H.extend(np.asarray(Hy, dtype=float).ravel())
        bx.extend(np.asarray(b_x, dtype=float))
        by.extend(np.asarray(b_y, dtype=float))
        par.append((float(cx), float(cy), float(sign), float(value), float(rest)))
        kind.append(SPRING if form[0] == "torsional spring" else DAMPER)
        couplings.append(np.unique(where))
    data = Data(np.asarray(span, dtype=np.int64).reshape(-1, 2), np.asarray(coords, dtype=np.int64),
                np.asarray(hoff, dtype=np.int64), np.asarray(H, dtype=float),
                np.ascontiguousarray(np.vstack([bx, by]).reshape(2, -1)), np.asarray(par, dtype=float).reshape(-1, 5),
                np.asarray(kind, dtype=np.int64))
    return FamilyPack(data=data, count=len(items), couplings=couplings)


@numba.njit(cache=True, _nrt=False)
def _invariants(d, e, q, g):
    """(x, y) of element ``e`` at the scene coordinates q, and ∇x, ∇y into g[0], g[1] (over its coordinates)."""
    j0, j1 = d.span[e, 0], d.span[e, 1]
    ne = j1 - j0
    hx, hy = d.hoff[e], d.hoff[e] + ne * ne
    x, y = d.par[e, 0], d.par[e, 1]
    for a in range(ne):
        sx, sy = d.b[0, j0 + a], d.b[1, j0 + a]
        for c in range(ne):
            qc = q[d.coords[j0 + c]]
            sx += d.H[hx + a * ne + c] * qc
            sy += d.H[hy + a * ne + c] * qc
        g[0, a], g[1, a] = sx, sy
        qa = q[d.coords[j0 + a]]
        x += 0.5 * (sx + d.b[0, j0 + a]) * qa
        y += 0.5 * (sy + d.b[1, j0 + a]) * qa
    return x, y


@numba.njit(cache=True, _nrt=False)
def _angle_jets(x, y, sign, k, rest):
    """V(z) = ½ k (σ atan2(y, x) − θ₀)² of z = (x, y), its gradient and Hessian: (V, V_x, V_y, V_xx, V_xy, V_yy)."""
    r2 = x * x + y * y
    th = sign * np.arctan2(y, x)
    tx, ty = -sign * y / r2, sign * x / r2                      # ∇θ
    # ∇²(atan2) = [[2xy, y² − x²], [y² − x², −2xy]] / r⁴
    r4 = r2 * r2
    f = k * (th - rest)
    return (0.5 * k * (th - rest) ** 2, f * tx, f * ty, k * tx * tx + f * sign * 2.0 * x * y / r4,
            k * tx * ty + f * sign * (y * y - x * x) / r4, k * ty * ty - f * sign * 2.0 * x * y / r4)


@numba.njit(cache=True, _nrt=False)
def _springs(ctx, d):
    n = ctx.n
    qa, qb, gp, floor = fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.gp, n), fvec(ctx.floor, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    qm = scratch[:n]
    for i in range(n):
        qm[i] = 0.5 * (qa[i] + qb[i])
    w = ctx.w_gp * ctx.c_dg * ctx.dq1
    for e in range(d.span.shape[0]):
        if d.kind[e] != SPRING:
            continue
        j0, j1 = d.span[e, 0], d.span[e, 1]
        ne = j1 - j0
        g0 = scratch[n:n + 2 * ne].reshape(2, ne)
        g1 = scratch[n + 2 * ne:n + 4 * ne].reshape(2, ne)
        gm = scratch[n + 4 * ne:n + 6 * ne].reshape(2, ne)
        hx, hy = d.hoff[e], d.hoff[e] + ne * ne
        sign, k, rest = d.par[e, 2], d.par[e, 3], d.par[e, 4]
        x0, y0 = _invariants(d, e, qa, g0)
        x1, y1 = _invariants(d, e, qb, g1)
        _invariants(d, e, qm, gm)
        xb, yb = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        if x0 * x0 + y0 * y0 == 0.0 or x1 * x1 + y1 * y1 == 0.0 or xb * xb + yb * yb == 0.0:
            ctx.status = STATUS_REFUSED
            return
        v0 = _angle_jets(x0, y0, sign, k, rest)[0]
        v1, g1x, g1y = _angle_jets(x1, y1, sign, k, rest)[:3]
        _, gbx, gby, hbxx, hbxy, hbyy = _angle_jets(xb, yb, sign, k, rest)
        dzx, dzy = x1 - x0, y1 - y0
        nd = dzx * dzx + dzy * dzy
        c, dcx, dcy = 0.0, 0.0, 0.0
        # below |Δz| = 1e-5 |z̄| the correction is round-off divided by |Δz|²: left out there
        if nd > 1e-10 * max(1.0, xb * xb + yb * yb):
            c = (v1 - v0 - gbx * dzx - gby * dzy) / nd
            dcx = (g1x - gbx - 0.5 * (hbxx * dzx + hbxy * dzy) - 2.0 * c * dzx) / nd
            dcy = (g1y - gby - 0.5 * (hbxy * dzx + hbyy * dzy) - 2.0 * c * dzy) / nd
        Gx, Gy = gbx + c * dzx, gby + c * dzy
        # ∂G/∂z₁ = ½ ∇²V(z̄) + Δz ⊗ ∂c/∂z₁ + c I
        dxx, dxy = 0.5 * hbxx + dzx * dcx + c, 0.5 * hbxy + dzx * dcy
        dyx, dyy = 0.5 * hbxy + dzy * dcx, 0.5 * hbyy + dzy * dcy + c
        for a in range(ne):
            ia = d.coords[j0 + a]
            gp[ia] += Gx * gm[0, a] + Gy * gm[1, a]
            fl = 0.0
            for b in range(ne):
                ib = d.coords[j0 + b]
                t = (0.5 * (Gx * d.H[hx + a * ne + b] + Gy * d.H[hy + a * ne + b])
                     + gm[0, a] * (dxx * g1[0, b] + dxy * g1[1, b]) + gm[1, a] * (dyx * g1[0, b] + dyy * g1[1, b]))
                if t != 0.0 and w != 0.0:
                    add_qq(ctx, st, ia, ib, w * t)
                fl += abs(w * t) * (abs(qa[ib]) + abs(qb[ib]))
            floor[ia] += fl


@numba.njit(cache=True, _nrt=False)
def _energy(ctx, d):
    q, out = fvec(ctx.q1, ctx.n), fvec(ctx.out, 7)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    pot = 0.0
    for e in range(d.span.shape[0]):
        if d.kind[e] == SPRING:
            ne = d.span[e, 1] - d.span[e, 0]
            x, y = _invariants(d, e, q, scratch[:2 * ne].reshape(2, ne))
            pot += _angle_jets(x, y, d.par[e, 2], d.par[e, 3], d.par[e, 4])[0]
    out[0] += pot


@numba.njit(cache=True, _nrt=False)
def _dampers(ctx, d, tangent):
    n = ctx.n
    q, v, ext, dve = fvec(ctx.qe, n), fvec(ctx.ve, n), fvec(ctx.ext, n), fvec(ctx.dve, n)
    st = storage_of(ctx)
    scratch = fvec(ctx.scratch, ctx.nscratch)
    wq = ctx.w_ext * ctx.dqe
    for e in range(d.span.shape[0]):
        if d.kind[e] != DAMPER:
            continue
        j0, j1 = d.span[e, 0], d.span[e, 1]
        ne = j1 - j0
        g = scratch[:2 * ne].reshape(2, ne)
        gt, hv = scratch[2 * ne:3 * ne], scratch[3 * ne:4 * ne]
        hx, hy = d.hoff[e], d.hoff[e] + ne * ne
        sign, c = d.par[e, 2], d.par[e, 3]
        x, y = _invariants(d, e, q, g)
        r2 = x * x + y * y
        if r2 == 0.0:
            ctx.status = STATUS_REFUSED
            return
        rate = 0.0
        for a in range(ne):
            gt[a] = sign * (x * g[1, a] - y * g[0, a]) / r2
            rate += gt[a] * v[d.coords[j0 + a]]
        for a in range(ne):
            ext[d.coords[j0 + a]] -= c * rate * gt[a]
        if not tangent:
            continue
        # −c (∇θ ⊗ ∇²θ v + θ̇ ∇²θ) dqe − c ∇θ ∇θᵀ dve, with ∇²θ built once
        hth = scratch[4 * ne:4 * ne + ne * ne].reshape(ne, ne)
        for a in range(ne):
            s = 0.0
            for b in range(ne):
                hth[a, b] = _theta_hessian(d, ne, hx, hy, sign, x, y, r2, g, a, b)
                s += hth[a, b] * v[d.coords[j0 + b]]
            hv[a] = s
        for a in range(ne):
            ia = d.coords[j0 + a]
            for b in range(ne):
                ib = d.coords[j0 + b]
                fq = -c * (gt[a] * hv[b] + rate * hth[a, b])
                fv = -c * gt[a] * gt[b]
                add_qq(ctx, st, ia, ib, wq * fq + ctx.w_ext * fv * dve[ib])


@numba.njit(cache=True, _nrt=False)
def _theta_hessian(d, ne, hx, hy, sign, x, y, r2, g, a, b):
    """(∇²θ)_ab (module docstring)."""
    w = x * g[1, a] - y * g[0, a]
    return sign * ((g[1, a] * g[0, b] - g[0, a] * g[1, b] + x * d.H[hy + a * ne + b] - y * d.H[hx + a * ne + b]) / r2
                   - 2.0 * w * (x * g[0, b] + y * g[1, b]) / (r2 * r2))


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL:
        _springs(ctx, _view(family_of(fam_p)))
    elif ctx.task == TASK_ENERGY:
        _energy(ctx, _view(family_of(fam_p)))
    elif ctx.task == TASK_EVAL_LOADS or ctx.task == TASK_LOADS:
        _dampers(ctx, _view(family_of(fam_p)), ctx.task == TASK_EVAL_LOADS)


#: the driver's :func:`refusal_error` looks at the loads' evaluation point (q_e, v_e, t_e); a spring refuses
#: at a state its own methods refuse too (they are asked at the step's end)
REFUSAL_STATE = "loads"


def refusal_error(scene, q, v, t):
    """The ValueError of the first torsional element whose own methods raise at (q, v, t) (its turning direction
    along the axis), or None: what the Python path raises where this family refused."""
    return first_refusal(list(scene.loads) + list(scene.conservative_forces), FORMS,
                         lambda f, i: f.angle_gradient(q[i]))


def kernel():
    """The family's compiled kernel (:func:`~skfem_flex.compiled.registry.compiled_kernel`), from the cache or
    compiled on first use."""
    return compiled_kernel(_kernel, "the spatial torsional family")
