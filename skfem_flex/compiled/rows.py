r"""Constraint rows: the one place where a row's value, derivatives and force enter the step.

A constraint family computes, for each of its rows at the context's states, the value Φ(q₁, t₁), Φ_t
and Φ_tt, and over the coordinates the row touches (``cols``) the Jacobian Φ_q(q₁), the exact discrete
gradient D(q_a, q_b) and, when the rows are at velocity or acceleration level, ∂(Φ_q v₁)/∂q; it then
calls :func:`finish_row`, which writes what the task and the row level need (:mod:`.tasks`):

* TASK_EVAL: the constraint force w_mu Dᵀμ (``dtmu``) and the border column w_mu D; the row value
  and the border row — position: Φ, Φ_q dq1; velocity: (Φ_q v₁ + Φ_t)/c_v,
  (∂(Φ_q v₁)/∂q dq1 + Φ_q dv1)/c_v; acceleration: Φ_q a₁ + ∂(Φ_q v₁)/∂q v₁ + Φ_tt, Φ_q da1; the row's
  scale Σ|Φ_q||q₁| (velocity rows also Σ|Φ_q||v₁|/c_v and |Φ_t|/c_v) and max|Φ_q|; D·(q_b − q_a) and Φ_t;
* TASK_ROWS: Φ into ``phi``, Φ_t into ``phit`` and Φ_q v₁ + Φ_t into ``ddphi``.

The second-derivative term w_mu c_dg dq1 ∂(Dᵀμ)/∂q_b is the family's own (it knows its structure).
"""
from __future__ import annotations

import numba

from .abi import fvec
from .storage import add_mq, add_pos, add_qm
from .tasks import ROWS_ACCELERATION, ROWS_POSITION, ROWS_VELOCITY, TASK_EVAL, TASK_ROWS

__all__ = ["finish_row", "write_row", "needs_rate_jacobian", "row_states"]


@numba.njit(cache=True, _nrt=False)
def row_states(ctx):
    """What a row family reads from the context: (q₁, q_a, q_b, v₁, μ, the time row, the scratch vector, the
    weight w_mu c_dg dq1 of ∂(Dᵀμ)/∂q_b, and whether the task is TASK_EVAL)."""
    n = ctx.n
    return (fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.qb, n), fvec(ctx.v1, n), fvec(ctx.mu, ctx.m),
            fvec(ctx.trow, ctx.ncol), fvec(ctx.scratch, ctx.nscratch), ctx.w_mu * ctx.c_dg * ctx.dq1,
            ctx.task == TASK_EVAL)


@numba.njit(cache=True, _nrt=False)
def needs_rate_jacobian(ctx):
    """True when the rows need ∂(Φ_q v₁)/∂q (velocity or acceleration level)."""
    return ctx.task == TASK_EVAL and ctx.rows != ROWS_POSITION


@numba.njit(cache=True, _nrt=False)
def finish_row(ctx, st, row, value, phi_t, phi_tt, cols, cq, d, cv, k):
    """Write constraint row ``row`` (module docstring); ``cols[:k]`` the coordinates it touches, ``cq``,
    ``d``, ``cv`` its Φ_q, D and ∂(Φ_q v₁)/∂q there (``cv`` read only when :func:`needs_rate_jacobian`)."""
    write_row(ctx, st, row, value, phi_t, phi_tt, cols, cq, d, cv, k, cols[:0])


@numba.njit(cache=True, _nrt=False)
def _border(ctx, st, pos, t, j, row, val, column):
    """Add ``val`` to the border column (∂r_j/∂μ_row, ``column``) or row (∂c_row/∂Δq_j): at the place
    ``pos[2t]`` or ``pos[2t + 1]`` when the family found them (:func:`~.storage.positions`), else by search."""
    if pos.size:
        add_pos(st, pos[2 * t + (0 if column else 1)], val)
    elif column:
        add_qm(ctx, st, j, row, val)
    else:
        add_mq(ctx, st, row, j, val)


@numba.njit(cache=True, _nrt=False)
def write_row(ctx, st, row, value, phi_t, phi_tt, cols, cq, d, cv, k, pos):
    """:func:`finish_row` with the places of the row's border entries: ``pos[2t]`` of (cols[t], row) and
    ``pos[2t + 1]`` of (row, cols[t]) in the Newton matrix's values, or ``pos`` empty (found by search)."""
    n, m = ctx.n, ctx.m
    v1 = fvec(ctx.v1, n)
    phi, phit = fvec(ctx.phi, m), fvec(ctx.phit, m)
    if ctx.task == TASK_ROWS:
        s = phi_t
        for t in range(k):
            s += cq[t] * v1[cols[t]]
        phi[row] = value
        phit[row] = phi_t
        fvec(ctx.ddphi, m)[row] = s
        return
    if ctx.task != TASK_EVAL:
        return
    q1, qa, qb = fvec(ctx.q1, n), fvec(ctx.qa, n), fvec(ctx.qb, n)
    dtmu, dv1 = fvec(ctx.dtmu, n), fvec(ctx.dv1, n)
    mu = fvec(ctx.mu, m)[row]
    w_mu = ctx.w_mu
    dd, rs, rmax = 0.0, 0.0, 0.0
    for t in range(k):
        j = cols[t]
        dtmu[j] += w_mu * d[t] * mu
        _border(ctx, st, pos, t, j, row, w_mu * d[t], True)
        dd += d[t] * (qb[j] - qa[j])
        a = abs(cq[t])
        rs += a * abs(q1[j])
        rmax = max(rmax, a)
    fvec(ctx.ddphi, m)[row] = dd
    phit[row] = phi_t
    level = ctx.rows
    if level == ROWS_POSITION:
        phi[row] = value
        for t in range(k):
            _border(ctx, st, pos, t, cols[t], row, cq[t] * ctx.dq1, False)
    elif level == ROWS_VELOCITY:
        c_v = ctx.c_v
        s, sv = phi_t, 0.0
        for t in range(k):
            j = cols[t]
            s += cq[t] * v1[j]
            sv += abs(cq[t]) * abs(v1[j])
            _border(ctx, st, pos, t, j, row, (cv[t] * ctx.dq1 + cq[t] * dv1[j]) / c_v, False)
        phi[row] = s / c_v
        rs = max(rs, sv / c_v, abs(phi_t) / c_v)
    elif level == ROWS_ACCELERATION:
        a1 = fvec(ctx.a1, n)
        s = phi_tt
        for t in range(k):
            j = cols[t]
            s += cq[t] * a1[j] + cv[t] * v1[j]
            _border(ctx, st, pos, t, j, row, cq[t] * ctx.da1, False)
        phi[row] = s
    fvec(ctx.rscale, m)[row] = rs
    fvec(ctx.rmax, m)[row] = rmax
