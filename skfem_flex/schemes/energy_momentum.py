r"""The energy-momentum step: the one implementation of its equations (a compiled kernel).

Unknowns x = (Δq on the free coordinates, μ = Δt λ̄). With z = Δq, except z = 2 tan(Δψ/2) on the
Cayley coordinates of exact beams (their mean rate is z/Δt),

.. math::

    q_1 = q_0 + Δq,\quad v_1 = \tfrac{2}{Δt} z - v_0,\quad q_m = q_0 + \tfrac12 Δq,\quad v_m = z/Δt,

    r = p(q_1, v_1) - p(q_0, v_0) + S\,\bigl(Δt\,D_V(q_0, q_1) - Δt\,D_G + D_Φ^\mathsf{T} μ\bigr)
        - Δt\,Q(q_m, v_m, t_m) = 0,\qquad Φ(q_1, t_1) = 0,

with S = diag(Δψ/z) on the Cayley coordinates (identity elsewhere): every discrete gradient is
conjugate to Δq, and S makes it conjugate to z with the same work. Then, exactly,
E₁ − E₀ = z·Q + (work of the prescribed coordinates) − λ̄·ΔΦ + v̄·r with v̄ = z/Δt: the energy balance
holds to the Newton tolerance for nonlinear constrained systems (docs/energy_scheme.md).

The kernel has three phases (``ctx.phase``): PREDICT (the Newton start: the quadratic through the last
step, :func:`~skfem_flex.numerics.newton.predicted_increment`, and μ = Δt λ), EVALUATE (the residual,
Newton matrix and scaled error at ``ctx.x``: the families add their parts, :mod:`skfem_flex.compiled.tasks`)
and ACCEPT (the new state, the work done, the prescribed coordinates' reactions).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from .base import Scheme, State

from ..compiled.acceptance import momentum, refused_state
from ..compiled.abi import Fields, call_families, context_of, f1, family_of, fvec, i1, ivec
from ..compiled.registry import compiled_kernel
from ..compiled.storage import add_pos, add_qq, clear, scale_row, storage_of
from ..compiled.tasks import (PHASE_ACCEPT, PHASE_EVALUATE, PHASE_PREDICT, ROWS_POSITION, SCHEME_EM, STATUS_MISSED,
                              STATUS_OK, STATUS_REFUSED, REFUSAL_TURN, TASK_EVAL, TASK_EVAL_LOADS)
from ..numerics.newton import all_finite, max_abs, predicted_increment, roundoff_floor
from ..numerics.rotations import MAX_INCREMENT, cayley_terms

__all__ = ["EnergyMomentum", "EnergyMomentumData"]

_TINY = 1e-300


class EnergyMomentumData(NamedTuple):
    """The energy-momentum step's state (carried from step to step) and work vectors (n coordinates)."""
    q: np.ndarray           # (n,) coordinates at the start of the step
    v: np.ndarray           # (n,) velocities
    acc: np.ndarray         # (n,) mean acceleration of the last step (the Newton start)
    p0: np.ndarray          # (n,) momentum at the start
    lam: np.ndarray         # (m,) λ̄ of the last step
    reaction: np.ndarray    # (npres,) generalized forces of the prescribed coordinates' laws
    work: np.ndarray        # (2,) work done by loads, laws and drivers; [1] = 1 when p0 holds p(q, v)
    pres_col: np.ndarray    # (npres,) column of each prescribed coordinate's law (value, rate, acceleration)
    cayley: np.ndarray      # (ncay,) Cayley coordinates
    dq: np.ndarray          # work vectors (n,)
    z: np.ndarray
    ratio: np.ndarray
    dratio: np.ndarray
    dz: np.ndarray
    qm: np.ndarray
    vm: np.ndarray
    r: np.ndarray
    angles: np.ndarray      # (nang,) free angle coordinates: an increment ≥ MAX_INCREMENT per step is refused


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return EnergyMomentumData(f1(fam, 0), f1(fam, 1), f1(fam, 2), f1(fam, 3), f1(fam, 4), f1(fam, 5), f1(fam, 6),
                              i1(fam, 7), i1(fam, 8), f1(fam, 9), f1(fam, 10), f1(fam, 11), f1(fam, 12), f1(fam, 13),
                              f1(fam, 14), f1(fam, 15), f1(fam, 16), i1(fam, 17))


@numba.njit(cache=True, _nrt=False)
def _momentum_at_start(ctx, s):
    """p(q, v) into s.p0 (the families' MOMENTUM task at the state, with the constant masses)."""
    n = ctx.n
    q1, v1 = ctx.q1, ctx.v1
    ctx.q1, ctx.v1 = s.q.ctypes.data, s.v.ctypes.data
    momentum(ctx)
    p = fvec(ctx.p, n)
    for i in range(n):
        s.p0[i] = p[i]
    ctx.q1, ctx.v1 = q1, v1
    s.work[1] = 1.0


@numba.njit(cache=True, _nrt=False)
def _predict(ctx, s):
    n, nf, m, h = ctx.n, ctx.nf, ctx.m, ctx.h
    free = ivec(ctx.free, nf)
    pres = ivec(ctx.pres, ctx.npres)
    trow = fvec(ctx.trow, ctx.ncol)
    if s.work[1] == 0.0:
        _momentum_at_start(ctx, s)
    for i in range(n):
        s.dq[i] = 0.0
    for j in range(pres.size):
        s.dq[pres[j]] = trow[s.pres_col[j]] - s.q[pres[j]]
    x = fvec(ctx.x, ctx.nx)
    predicted_increment(s.v, s.acc, h, free, x)
    xs = 0.0
    for i in range(nf):
        xs = max(xs, abs(s.q[free[i]]))
    ctx.x_scale = xs
    fpos = ivec(ctx.fpos, n)
    for c in s.cayley:                  # the Cayley rate of the last step, continued: Δψ = 2 atan(Δt ω0/2)
        if fpos[c] >= 0:
            x[fpos[c]] = 2.0 * np.arctan(0.5 * x[fpos[c]])
    for i in range(m):
        x[nf + i] = h * s.lam[i]
    # the step's fixed settings for the families (.tasks): discrete gradients from q0 to q1, loads at
    # the mid-point, constraint rows at position level
    ctx.scheme = SCHEME_EM
    ctx.rows = ROWS_POSITION
    ctx.w_p, ctx.w_gk, ctx.w_gp, ctx.w_ext, ctx.w_mu = 1.0, -h, h, -h, 1.0
    ctx.c_dg, ctx.dq1, ctx.da1, ctx.dqe = 1.0, 1.0, 0.0, 0.5
    ctx.q0, ctx.v0 = s.q.ctypes.data, s.v.ctypes.data
    ctx.qa, ctx.qb = ctx.q0, ctx.q1
    ctx.qe, ctx.ve = s.qm.ctypes.data, s.vm.ctypes.data
    ctx.te, ctx.t1 = ctx.t + 0.5 * h, ctx.t + h


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, s):
    n, nf, m, h = ctx.n, ctx.nf, ctx.m, ctx.h
    x = fvec(ctx.x, ctx.nx)
    free = ivec(ctx.free, nf)
    q0, v0 = s.q, s.v
    q1, v1 = fvec(ctx.q1, n), fvec(ctx.v1, n)
    dv1, dve = fvec(ctx.dv1, n), fvec(ctx.dve, n)
    p, gk, gp, ext = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.ext, n)
    dtmu, floor = fvec(ctx.dtmu, n), fvec(ctx.floor, n)
    phi, mu = fvec(ctx.phi, m), fvec(ctx.mu, m)
    rscale, rmax = fvec(ctx.rscale, m), fvec(ctx.rmax, m)
    dq, z, ratio, dratio, dz, r = s.dq, s.z, s.ratio, s.dratio, s.dz, s.r
    for i in range(nf):
        dq[free[i]] = x[i]
    for i in range(m):
        mu[i] = x[nf + i]
    for i in range(n):
        q1[i] = q0[i] + dq[i]
        z[i] = dq[i]
    for c in s.cayley:
        if not abs(dq[c]) < MAX_INCREMENT:  # 2 tan(Δψ/2) needs |Δψ| < π: the step is refused
            ctx.status, ctx.refusal = STATUS_REFUSED, REFUSAL_TURN
            return
        z[c], ratio[c], dratio[c], dz[c] = cayley_terms(dq[c])
    for i in range(n):
        v1[i] = (2.0 / h) * z[i] - v0[i]
        s.qm[i] = q0[i] + 0.5 * dq[i]
        s.vm[i] = z[i] / h
        dv1[i] = (2.0 / h) * dz[i]
        dve[i] = dz[i] / h
        p[i] = gk[i] = gp[i] = ext[i] = dtmu[i] = floor[i] = 0.0
    for i in range(m):
        phi[i] = rscale[i] = rmax[i] = 0.0
    st = storage_of(ctx)
    clear(st)
    ctx.missed = 0
    call_families(ctx, TASK_EVAL)
    if ctx.status != STATUS_OK:
        return
    for i in range(n):                  # the discrete-gradient and constraint forces
        r[i] = h * gp[i] - h * gk[i] + dtmu[i]
    fpos = st[1]
    for c in s.cayley:                  # conjugate to Δq → conjugate to the Cayley rate z
        ic = fpos[c]
        if ic >= 0:
            scale_row(st, ic, ratio[c])
            add_qq(ctx, st, c, c, r[c] * dratio[c])
        r[c] *= ratio[c]
        floor[c] *= ratio[c]
    # the constant masses: p1 += M v1, Newton matrix += M ∂v1/∂x
    ptr = ivec(ctx.mass_ptr, n + 1)
    nnz = ptr[n]
    idx, dat, pos = ivec(ctx.mass_idx, nnz), fvec(ctx.mass_dat, nnz), ivec(ctx.mass_pos, nnz)
    for i in range(n):
        acc = 0.0
        for t in range(ptr[i], ptr[i + 1]):
            j = idx[t]
            acc += dat[t] * v1[j]
            add_pos(st, pos[t], dat[t] * dv1[j])
        p[i] += acc
    call_families(ctx, TASK_EVAL_LOADS)
    if ctx.status != STATUS_OK:
        return
    scale = max(max_abs(p), max_abs(s.p0), h * max_abs(gk), h * max_abs(gp), max_abs(dtmu), h * max_abs(ext))
    for i in range(n):
        r[i] += p[i] - s.p0[i] - h * ext[i]
    res = fvec(ctx.res, ctx.nx)
    err_c = 0.0
    if m:
        cs, cmax = 0.0, 0.0
        for i in range(m):
            cs = max(cs, rscale[i])
            cmax = max(cmax, rmax[i])
            res[nf + i] = phi[i]
        err_c = max_abs(phi) / (ctx.ctol * max(cs, cmax * ctx.length_scale, _TINY))
    vr, fl_inf, vfl = 0.0, 0.0, 0.0
    for i in range(nf):
        a = free[i]
        res[i] = r[a]
        vb = z[a] / h
        vr += vb * r[a]
        fl_inf = max(fl_inf, abs(floor[a]))
        vfl += abs(vb) * floor[a]
    vr = abs(vr)
    r_inf = max_abs(res[:nf])
    zg, kin = 0.0, 0.0
    for i in range(n):
        zg += z[i] * ratio[i] * gp[i]
        kin += v1[i] * p[i]
    e_scale = max(abs(0.5 * _dot(v0, s.p0)), abs(0.5 * kin), abs(zg), _TINY)
    err = max(r_inf / (ctx.rtol * max(scale, _TINY)), err_c, vr / (ctx.etol * e_scale))
    err = roundoff_floor(err, err_c, r_inf, fl_inf, vr, vfl)
    if ctx.missed:
        ctx.status = STATUS_MISSED
    ctx.err = err if all_finite(res) else np.nan


@numba.njit(cache=True, _nrt=False)
def _dot(a, b):
    s = 0.0
    for i in range(a.size):
        s += a[i] * b[i]
    return s


@numba.njit(cache=True, _nrt=False)
def _accept(ctx, s):
    n, m, h = ctx.n, ctx.m, ctx.h
    pres = ivec(ctx.pres, ctx.npres)
    q1, v1, p, ext = fvec(ctx.q1, n), fvec(ctx.v1, n), fvec(ctx.p, n), fvec(ctx.ext, n)
    mu, ddphi = fvec(ctx.mu, m), fvec(ctx.ddphi, m)
    if refused_state(ctx, s.dq, s.angles):
        return
    w = _dot(s.z, ext)
    for j in range(pres.size):
        s.reaction[j] = s.r[pres[j]] / h
        w += s.z[pres[j]] * s.reaction[j]
    for i in range(m):                  # μ = Δt λ̄: the work of the constraint forces is −λ̄·ΔΦ
        w -= mu[i] * ddphi[i] / h
        s.lam[i] = mu[i] / h
    s.work[0] += w
    for i in range(n):
        s.acc[i] = (v1[i] - s.v[i]) / h
        s.q[i] = q1[i]
        s.v[i] = v1[i]
        s.p0[i] = p[i]
    s.work[1] = 1.0


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    s = _view(family_of(fam_p))
    if ctx.phase == PHASE_EVALUATE:
        _evaluate(ctx, s)
    elif ctx.phase == PHASE_PREDICT:
        _predict(ctx, s)
    elif ctx.phase == PHASE_ACCEPT:
        _accept(ctx, s)


class EnergyMomentum(Scheme):
    """Energy-conserving discrete-gradient mid-point scheme (``"energy-momentum"``).

    See the module docstring for the equations. Prescribed coordinates take q1 from their law and
    v1 = 2Δq/Δt − v0 (so that v̄ Δt = Δq holds for every coordinate, which the exact energy identity
    needs); their residual rows are the impulse the law exerts, and its work v̄_P · r_P enters the
    external work.

    Parameters
    ----------
    newton : NewtonSettings, optional
    """

    name = "energy-momentum"
    state_type = State
    mid_point_loads = True

    def kernel(self):
        return compiled_kernel(_kernel, "the energy-momentum step")

    def pack_state(self, packed, state):
        n, m = state.q.size, packed.m
        z = np.zeros
        acc = z(n) if state.acc is None or np.size(state.acc) != n else state.acc
        lam = state.lam if np.size(state.lam) == m else z(m)
        reaction = state.prescribed_force if np.size(state.prescribed_force) == packed.pres.size \
            else z(packed.pres.size)
        data = EnergyMomentumData(
            np.array(state.q, dtype=float), np.array(state.v, dtype=float), np.array(acc, dtype=float), z(n),
            np.array(lam, dtype=float), np.array(reaction, dtype=float), np.array([float(state.work), 0.0]),
            packed.pres_cols, packed.cayley, z(n), z(n), np.ones(n), z(n), np.ones(n), z(n), z(n), z(n),
            packed.angles)
        return Fields(data)

    def unpack_state(self, fields, t):
        a = fields.array
        return State(float(t), a("q").copy(), a("v").copy(), acc=a("acc").copy(), lam=a("lam").copy(),
                     prescribed_force=a("reaction").copy(), work=float(a("work")[0]))
