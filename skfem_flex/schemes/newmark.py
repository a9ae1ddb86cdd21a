r"""The Newmark-family step (trapezoidal, generalized-α) and the consistent start: the one implementation
of their equations (a compiled kernel).

Generalized-α in the form of Arnold & Brüls (2007), unknowns x = (Δq on the free coordinates, μ = Δt λ₁):

.. math::

    a_1 = \frac{Δq - Δt v_0 - Δt^2(\tfrac12 - β) a_0}{β Δt^2},\quad
    v_1 = v_0 + Δt\,((1 - γ) a_0 + γ a_1),\quad
    \ddot q_1 = \frac{(1 - α_m) a_1 + α_m a_0 - α_f \ddot q_0}{1 - α_f}

    r = Δt\,\bigl(M(q_1)\ddot q_1 - Q_v(q_1, v_1) + ∇V(q_1) - Q(q_1, v_1, t_1)\bigr) + Φ_q(q_1)^\mathsf{T} μ = 0

with the constraint rows Φ(q₁, t₁) = 0 (position level, index 3) or (βΔt/γ)(Φ_q v₁ + Φ_t) = 0 (velocity
level, index 2: the trapezoidal rule as the established codes run it). α_m = α_f = 0, β = ¼, γ = ½ is the
trapezoidal rule. The families evaluate ∇V and Φ_q as discrete gradients at equal end points
(:mod:`skfem_flex.compiled.tasks`): one code for every scheme.

PHASE_START computes the consistent acceleration and multipliers of a state (Δq = 0, the
acceleration the unknown, constraint rows at acceleration level): M q̈ + Φ_qᵀ λ = Q + Q_v − ∇V,
Φ_q q̈ + ∂(Φ_q v)/∂q v + Φ_tt = 0, one linear solve; every scheme starts from it.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from .base import NewmarkState, Scheme

from ..compiled.acceptance import energies, energy_jump, refused_state
from ..compiled.abi import Fields, call_families, context_of, f1, family_of, fvec, i1, ivec
from ..compiled.registry import compiled_kernel
from ..compiled.storage import add_pos, clear, storage_of
from ..compiled.tasks import (PHASE_ACCEPT, PHASE_EVALUATE, PHASE_PREDICT, PHASE_START, ROWS_ACCELERATION,
                              ROWS_POSITION, ROWS_VELOCITY, SCHEME_NEWMARK, STATUS_MISSED, STATUS_OK,
                              TASK_EVAL, TASK_EVAL_LOADS, TASK_LOADS, TASK_ROWS)
from ..numerics.newton import all_finite, max_abs

__all__ = ["Newmark", "Trapezoidal", "GeneralizedAlpha", "NewmarkData", "start_kernel", "start_data"]

_TINY = 1e-300


class NewmarkData(NamedTuple):
    """The Newmark step's parameters, state and work vectors."""
    params: np.ndarray      # (6,) α_m, α_f, β, γ, velocity-level rows (1/0), rheonomic constraints (1/0)
    q: np.ndarray           # (n,) state at the start of the step
    v: np.ndarray
    acc: np.ndarray         # (n,) q̈
    pseudo: np.ndarray      # (n,) generalized-α's algorithmic acceleration a
    lam: np.ndarray         # (m,)
    reaction: np.ndarray    # (npres,)
    work: np.ndarray        # (3,) work done; [1] = 1 when ext0/phit0 hold the loads and Φ_t at the state;
    #                         [2] = 1 when ``reaction`` holds the last step's forces
    ext0: np.ndarray        # (n,) loads at the start of the step
    phit0: np.ndarray       # (m,) Φ_t at the start of the step
    pres_col: np.ndarray    # (npres,) column of each prescribed coordinate's law (value, rate, acceleration)
    dq: np.ndarray          # work vectors (n,)
    r: np.ndarray
    a_next: np.ndarray      # the algorithmic acceleration a₁ of the evaluation
    angles: np.ndarray      # (nang,) free angle coordinates: an increment ≥ MAX_INCREMENT per step is refused
    energy: np.ndarray      # (3,) kinetic and potential energy at the state (J), valid with work[1] = 1;
    #                         the largest T + |V| + |W| of the run's states (J; the check waits for > 0)


@numba.njit(cache=True, _nrt=False)
def _view(fam):
    return NewmarkData(f1(fam, 0), f1(fam, 1), f1(fam, 2), f1(fam, 3), f1(fam, 4), f1(fam, 5), f1(fam, 6),
                       f1(fam, 7), f1(fam, 8), f1(fam, 9), i1(fam, 10), f1(fam, 11), f1(fam, 12), f1(fam, 13),
                       i1(fam, 14), f1(fam, 15))


@numba.njit(cache=True, _nrt=False)
def _coefficients(ctx, s):
    """(c_a, c_v) = (∂q̈₁/∂Δq, ∂v₁/∂Δq)."""
    am, af, beta, gamma = s.params[0], s.params[1], s.params[2], s.params[3]
    h = ctx.h
    return (1.0 - am) / ((1.0 - af) * beta * h * h), gamma / (beta * h)


@numba.njit(cache=True, _nrt=False)
def _settings(ctx, s, c_a, c_v, rows):
    """The families' settings (.tasks): everything at q1, gradients as discrete gradients at equal
    points (c_dg = 2)."""
    n, h = ctx.n, ctx.h
    ctx.scheme = SCHEME_NEWMARK
    ctx.rows = rows
    ctx.w_p, ctx.w_gk, ctx.w_gp, ctx.w_ext, ctx.w_mu = h, -h, h, -h, 1.0
    ctx.c_dg, ctx.dq1, ctx.da1, ctx.dqe, ctx.c_v = 2.0, 1.0, c_a, 1.0, c_v
    ctx.q0, ctx.v0 = s.q.ctypes.data, s.v.ctypes.data
    ctx.qa, ctx.qb, ctx.qe, ctx.ve = ctx.q1, ctx.q1, ctx.q1, ctx.v1
    ctx.te = ctx.t1 = ctx.t + h
    dv1, dve = fvec(ctx.dv1, n), fvec(ctx.dve, n)
    for i in range(n):
        dv1[i] = c_v
        dve[i] = c_v


@numba.njit(cache=True, _nrt=False)
def _loads_at_start(ctx, s):
    """Loads, Φ_t and the energies at the state (the work and the energy check of the first step use both
    ends)."""
    n, m = ctx.n, ctx.m
    q1, v1, trow, te, t1 = ctx.q1, ctx.v1, ctx.trow, ctx.te, ctx.t1
    ctx.qe, ctx.ve = s.q.ctypes.data, s.v.ctypes.data
    ctx.q1, ctx.v1 = ctx.qe, ctx.ve
    # the table row before the step's is the one at the state's time (row 0 of a chunk: its start)
    ctx.trow = trow - 8 * ctx.ncol
    ctx.te = ctx.t1 = ctx.t
    ext = fvec(ctx.ext, n)
    for i in range(n):
        ext[i] = 0.0
    call_families(ctx, TASK_LOADS)
    for i in range(n):
        s.ext0[i] = ext[i]
    s.energy[0], s.energy[1] = energies(ctx)
    ctx.energies_valid = 0              # computed at the start state, not at q1: no record may take them
    s.energy[2] = max(s.energy[2], s.energy[0] + abs(s.energy[1]) + abs(s.work[0]))
    if s.params[5] != 0.0:
        phit = fvec(ctx.phit, m)
        call_families(ctx, TASK_ROWS)
        for i in range(m):
            s.phit0[i] = phit[i]
    ctx.q1, ctx.v1, ctx.trow, ctx.te, ctx.t1 = q1, v1, trow, te, t1
    s.work[1] = 1.0


@numba.njit(cache=True, _nrt=False)
def _predict(ctx, s):
    n, nf, m, h = ctx.n, ctx.nf, ctx.m, ctx.h
    free, pres = ivec(ctx.free, nf), ivec(ctx.pres, ctx.npres)
    trow = fvec(ctx.trow, ctx.ncol)
    c_a, c_v = _coefficients(ctx, s)
    if s.work[1] == 0.0:
        # the start row of a chunk's table holds the functions of time at the state (.time_table)
        _loads_at_start(ctx, s)
    for i in range(n):
        s.dq[i] = 0.0
    for j in range(pres.size):
        s.dq[pres[j]] = trow[s.pres_col[j]] - s.q[pres[j]]
    x = fvec(ctx.x, ctx.nx)
    xs = 0.0
    for i in range(nf):
        a = free[i]
        x[i] = h * s.v[a] + 0.5 * h * h * s.acc[a]
        xs = max(xs, abs(s.q[a]))
    for i in range(m):
        x[nf + i] = h * s.lam[i]
    ctx.x_scale = xs
    _settings(ctx, s, c_a, c_v, ROWS_VELOCITY if s.params[4] != 0.0 else ROWS_POSITION)


@numba.njit(cache=True, _nrt=False)
def _assemble(ctx, s, q1, v1, acc1):
    """Zero the parts, let the families add theirs, add the constant masses' inertia; returns the force
    scale (False status: an element refused)."""
    n, m = ctx.n, ctx.m
    p, gk, gp, ext = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.ext, n)
    dtmu, mterms, terms = fvec(ctx.dtmu, n), fvec(ctx.mterms, n), fvec(ctx.terms, n)
    for i in range(n):
        p[i] = gk[i] = gp[i] = ext[i] = dtmu[i] = mterms[i] = 0.0
    phi, rscale, rmax, phit = fvec(ctx.phi, m), fvec(ctx.rscale, m), fvec(ctx.rmax, m), fvec(ctx.phit, m)
    for i in range(m):
        phi[i] = rscale[i] = rmax[i] = phit[i] = 0.0
    st = storage_of(ctx)
    clear(st)
    ctx.missed = 0
    call_families(ctx, TASK_EVAL)
    if ctx.status == STATUS_OK:
        call_families(ctx, TASK_EVAL_LOADS)
    # the constant masses: M q̈₁, |M| terms, Δt c_a M
    ptr = ivec(ctx.mass_ptr, n + 1)
    nnz = ptr[n]
    idx, dat, pos = ivec(ctx.mass_idx, nnz), fvec(ctx.mass_dat, nnz), ivec(ctx.mass_pos, nnz)
    for i in range(n):
        acc, sa = 0.0, 0.0
        for t in range(ptr[i], ptr[i + 1]):
            j = idx[t]
            acc += dat[t] * acc1[j]
            sa += abs(dat[t]) * terms[j]
            add_pos(st, pos[t], ctx.w_p * ctx.da1 * dat[t])
        p[i] += acc
        mterms[i] += sa


@numba.njit(cache=True, _nrt=False)
def _evaluate(ctx, s):
    n, nf, m, h = ctx.n, ctx.nf, ctx.m, ctx.h
    am, af, beta, gamma = s.params[0], s.params[1], s.params[2], s.params[3]
    c_a, c_v = _coefficients(ctx, s)
    x = fvec(ctx.x, ctx.nx)
    free, pres = ivec(ctx.free, nf), ivec(ctx.pres, ctx.npres)
    trow = fvec(ctx.trow, ctx.ncol)
    q0, v0, a0, acc0 = s.q, s.v, s.pseudo, s.acc
    q1, v1, a1 = fvec(ctx.q1, n), fvec(ctx.v1, n), fvec(ctx.a1, n)
    terms, mu = fvec(ctx.terms, n), fvec(ctx.mu, m)
    dq = s.dq
    acc1 = s.a_next
    for i in range(nf):
        dq[free[i]] = x[i]
    for i in range(m):
        mu[i] = x[nf + i]
    for i in range(n):
        q1[i] = q0[i] + dq[i]
        acc1[i] = (dq[i] - h * v0[i] - h * h * (0.5 - beta) * a0[i]) / (beta * h * h)
        v1[i] = v0[i] + h * ((1.0 - gamma) * a0[i] + gamma * acc1[i])
        a1[i] = ((1.0 - am) * acc1[i] + am * a0[i] - af * acc0[i]) / (1.0 - af)
        terms[i] = abs(dq[i]) + h * abs(v0[i]) + h * h * abs(0.5 - beta) * abs(a0[i])
    for j in range(pres.size):
        i = pres[j]
        v1[i], a1[i], acc1[i] = trow[s.pres_col[j] + 1], trow[s.pres_col[j] + 2], trow[s.pres_col[j] + 2]
    _assemble(ctx, s, q1, v1, a1)
    if ctx.status != STATUS_OK:
        return
    p, gk, gp, ext = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.ext, n)
    dtmu, mterms = fvec(ctx.dtmu, n), fvec(ctx.mterms, n)
    scale = max(max_abs(p), max_abs(gp), c_a * max_abs(mterms), max_abs(gk), max_abs(ext))
    scale = max(h * scale, max_abs(dtmu))
    r = s.r
    for i in range(n):
        r[i] = h * (p[i] + gp[i] - gk[i] - ext[i]) + dtmu[i]
    res = fvec(ctx.res, ctx.nx)
    err_c = _rows_error(ctx, res, nf, m, c_v)
    for i in range(nf):
        res[i] = r[free[i]]
    err = max(max_abs(res[:nf]) / (ctx.rtol * max(scale, _TINY)), err_c)
    if ctx.missed:
        ctx.status = STATUS_MISSED
    ctx.err = err if all_finite(res) else np.nan


@numba.njit(cache=True, _nrt=False)
def _rows_error(ctx, res, nf, m, c_v):
    """Constraint rows into the residual; their scaled error."""
    if m == 0:
        return 0.0
    phi, rscale, rmax = fvec(ctx.phi, m), fvec(ctx.rscale, m), fvec(ctx.rmax, m)
    cs, cmax = 0.0, 0.0
    for i in range(m):
        cs = max(cs, rscale[i])
        cmax = max(cmax, rmax[i])
        res[nf + i] = phi[i]
    return max_abs(phi) / (ctx.ctol * max(cs, cmax * ctx.length_scale, _TINY))


@numba.njit(cache=True, _nrt=False)
def _accept(ctx, s):
    n, m, h = ctx.n, ctx.m, ctx.h
    pres = ivec(ctx.pres, ctx.npres)
    q1, v1, a1 = fvec(ctx.q1, n), fvec(ctx.v1, n), fvec(ctx.a1, n)
    acc1 = s.a_next
    ext, mu, phit = fvec(ctx.ext, n), fvec(ctx.mu, m), fvec(ctx.phit, m)
    if refused_state(ctx, s.dq, s.angles):
        return
    # work of the loads (trapezoidal in time), of the prescribed laws and of rheonomic constraints
    w = 0.0
    for i in range(n):
        w += s.dq[i] * 0.5 * (s.ext0[i] + ext[i])
    for j in range(pres.size):
        react = s.r[pres[j]] / h
        prev = s.reaction[j] if s.work[2] != 0.0 else react
        w += s.dq[pres[j]] * 0.5 * (prev + react)
    if s.params[5] != 0.0:
        s0, s1 = 0.0, 0.0
        for i in range(m):
            s0 += s.lam[i] * s.phit0[i]
            s1 += mu[i] / h * phit[i]
        w += 0.5 * h * (s0 + s1)
    kin, pot = energies(ctx)
    if s.energy[2] > 0.0 and energy_jump(ctx, s.energy[0], s.energy[1], kin, pot, w):
        return
    s.energy[0], s.energy[1] = kin, pot
    s.energy[2] = max(s.energy[2], kin + abs(pot) + abs(s.work[0] + w))
    for j in range(pres.size):
        s.reaction[j] = s.r[pres[j]] / h
    s.work[2] = 1.0
    s.work[0] += w
    for i in range(n):
        s.q[i] = q1[i]
        s.v[i] = v1[i]
        s.acc[i] = a1[i]
        s.pseudo[i] = acc1[i]
        s.ext0[i] = ext[i]
    for i in range(m):
        s.lam[i] = mu[i] / h
        s.phit0[i] = phit[i]


@numba.njit(cache=True, _nrt=False)
def _start(ctx, s):
    """The consistent acceleration and multipliers at the state, into ``ctx.x`` as (q̈_free, λ), by the
    Newton matrix of the residual linear in them; the loop's driver solves once (Δq = 0)."""
    n, nf, m = ctx.n, ctx.nf, ctx.m
    free, pres = ivec(ctx.free, nf), ivec(ctx.pres, ctx.npres)
    trow = fvec(ctx.trow, ctx.ncol)
    x = fvec(ctx.x, ctx.nx)
    q1, v1, a1 = fvec(ctx.q1, n), fvec(ctx.v1, n), fvec(ctx.a1, n)
    mu, terms = fvec(ctx.mu, m), fvec(ctx.terms, n)
    for i in range(n):
        q1[i] = s.q[i]
        v1[i] = s.v[i]
        a1[i] = 0.0
        terms[i] = 0.0
    for i in range(nf):
        a1[free[i]] = x[i]
    for j in range(pres.size):
        a1[pres[j]] = trow[s.pres_col[j] + 2]
    for i in range(m):
        mu[i] = x[nf + i]
    ctx.h = 1.0
    _settings(ctx, s, 1.0, 0.0, ROWS_ACCELERATION)
    ctx.dq1, ctx.da1, ctx.dqe = 0.0, 1.0, 0.0
    ctx.te = ctx.t1 = ctx.t
    _assemble(ctx, s, q1, v1, a1)
    if ctx.status != STATUS_OK:
        return
    p, gk, gp, ext, dtmu = fvec(ctx.p, n), fvec(ctx.gk, n), fvec(ctx.gp, n), fvec(ctx.ext, n), fvec(ctx.dtmu, n)
    res = fvec(ctx.res, ctx.nx)
    r = s.r
    for i in range(n):
        r[i] = p[i] + gp[i] - gk[i] - ext[i] + dtmu[i]
    for i in range(nf):
        res[i] = r[free[i]]
    phi = fvec(ctx.phi, m)
    for i in range(m):
        res[nf + i] = phi[i]
    if ctx.missed:
        ctx.status = STATUS_MISSED
    ctx.err = 0.0 if all_finite(res) else np.nan


def _kernel(ctx_p, fam_p):
    ctx = context_of(ctx_p)
    s = _view(family_of(fam_p))
    if ctx.phase == PHASE_EVALUATE:
        _evaluate(ctx, s)
    elif ctx.phase == PHASE_PREDICT:
        _predict(ctx, s)
    elif ctx.phase == PHASE_ACCEPT:
        _accept(ctx, s)
    elif ctx.phase == PHASE_START:
        _start(ctx, s)


def _data(packed, params, q, v, acc, pseudo, lam, reaction, work):
    n, m = q.size, packed.m
    z = np.zeros
    return Fields(NewmarkData(np.asarray(params, dtype=float), np.array(q, dtype=float), np.array(v, dtype=float),
                              np.array(acc, dtype=float), np.array(pseudo, dtype=float), np.array(lam, dtype=float),
                              np.array(reaction, dtype=float), np.asarray(work, dtype=float), z(n), z(m),
                              packed.pres_cols, z(n), z(n), z(n), packed.angles, z(3)))


def _start_kernel(ctx_p, fam_p):
    # the consistent start alone: a run under another scheme compiles this, not the whole Newmark step
    ctx = context_of(ctx_p)
    if ctx.phase == PHASE_START:
        _start(ctx, _view(family_of(fam_p)))


def start_kernel():
    """The kernel that computes consistent starts (PHASE_START of the Newmark step's equations)."""
    return compiled_kernel(_start_kernel, "the consistent start")


def start_data(packed, q, v):
    """A data record for :func:`start_kernel` at the state (q, v)."""
    n = q.size
    return _data(packed, (0.0, 0.0, 0.25, 0.5, 0.0, 0.0), q, v, np.zeros(n), np.zeros(n), np.zeros(packed.m),
                 np.zeros(packed.pres.size), (0.0, 0.0, 0.0))


class Newmark(Scheme):
    """Newmark family in generalized-α form (Chung & Hulbert 1993; Arnold & Brüls 2007).

    Parameters
    ----------
    alpha_m, alpha_f, beta, gamma : float
        Algorithmic parameters.
    constraint_level : {"position", "velocity"}
        Enforce Φ(q_{n+1}, t_{n+1}) = 0 (index 3) or Φ_q v_{n+1} + Φ_t = 0 (index 2). The velocity-level
        row is multiplied by βΔt/γ, so that its Jacobian is Φ_q + (βΔt/γ) ∂(Φ_q v)/∂q, the same size as
        the position-level one.
    newton : NewtonSettings, optional
    """

    name = "newmark"
    state_type = NewmarkState

    def __init__(self, alpha_m=0.0, alpha_f=0.0, beta=0.25, gamma=0.5, newton=None, constraint_level="position"):
        super().__init__(newton)
        self.alpha_m, self.alpha_f, self.beta, self.gamma = map(float, (alpha_m, alpha_f, beta, gamma))
        for name in ("alpha_m", "alpha_f", "beta", "gamma"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if not (self.beta > 0 and self.alpha_f < 1):
            raise ValueError(f"Newmark needs beta > 0 and alpha_f < 1, got beta={beta!r}, alpha_f={alpha_f!r}")
        if constraint_level not in ("position", "velocity"):
            raise ValueError(f"constraint_level must be 'position' or 'velocity', got {constraint_level!r}")
        self.constraint_level = constraint_level

    def kernel(self):
        return compiled_kernel(_kernel, "the Newmark step")

    def pack_state(self, packed, state):
        n, m = state.q.size, packed.m
        acc = np.zeros(n) if state.acc is None or np.size(state.acc) != n else state.acc
        pseudo = getattr(state, "pseudo", None)
        pseudo = acc if pseudo is None or np.size(pseudo) != n else pseudo
        lam = state.lam if np.size(state.lam) == m else np.zeros(m)
        npres = packed.pres.size
        have = np.size(state.prescribed_force) == npres and npres > 0
        reaction = state.prescribed_force if have else np.zeros(npres)
        params = (self.alpha_m, self.alpha_f, self.beta, self.gamma,
                  1.0 if self.constraint_level == "velocity" else 0.0, 1.0 if packed.rheonomic else 0.0)
        return _data(packed, params, state.q, state.v, acc, pseudo, lam, reaction,
                     (float(state.work), 0.0, 1.0 if have else 0.0))

    def unpack_state(self, fields, t):
        a = fields.array
        return NewmarkState(float(t), a("q").copy(), a("v").copy(), acc=a("acc").copy(), lam=a("lam").copy(),
                            prescribed_force=a("reaction").copy(), work=float(a("work")[0]),
                            pseudo=a("pseudo").copy())


class Trapezoidal(Newmark):
    """Average-acceleration Newmark (β = ¼, γ = ½) with velocity-level constraints, ``"trapezoidal"``.

    Index 2, as the established multibody codes run the trapezoidal rule:
    Φ_q(q_{n+1}) v_{n+1} + Φ_t(t_{n+1}) = 0. The position-level (index-3) form is
    ``Newmark(constraint_level="position")``; it drives the multipliers into a growing zigzag on a
    swinging pendulum.
    """

    name = "trapezoidal"

    def __init__(self, newton=None):
        super().__init__(0.0, 0.0, 0.25, 0.5, newton, constraint_level="velocity")


class GeneralizedAlpha(Newmark):
    """Chung–Hulbert generalized-α with spectral radius ρ∞ at infinite frequency.

    α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), γ = ½ − α_m + α_f, β = ¼ (γ + ½)².

    Parameters
    ----------
    rho_inf : float
        ρ∞ in [0, 1]; 1 keeps every frequency, 0 annihilates the highest.
    newton : NewtonSettings, optional
    constraint_level : {"position", "velocity"}
        Φ(q₁) = 0 (index 3, the default) or Φ_q v₁ + Φ_t = 0 (index 2, as the trapezoidal rule). A fast
        spinning spatial body in director coordinates needs the velocity level: at position level the
        velocities normal to the rigidity constraints oscillate (the Simo–Wong top at Δt = 0.009 s with
        ρ∞ = 0.9: the kinetic energy alternates between 0.7 and 2.1 times its start, docs/spatial.md).
    """

    name = "generalized-alpha"

    def __init__(self, rho_inf=0.9, newton=None, constraint_level="position"):
        rho = float(rho_inf)
        if not (np.isfinite(rho) and 0.0 <= rho <= 1.0):
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf!r}")
        am = (2.0 * rho - 1.0) / (rho + 1.0)
        af = rho / (rho + 1.0)
        gamma = 0.5 - am + af
        super().__init__(am, af, 0.25 * (gamma + 0.5) ** 2, gamma, newton, constraint_level=constraint_level)
        self.rho_inf = rho

    def __repr__(self):
        level = "" if self.constraint_level == "position" else f", constraint_level={self.constraint_level!r}"
        return f"GeneralizedAlpha(rho_inf={self.rho_inf!r}{level})"
