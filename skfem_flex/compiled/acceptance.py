r"""What a scheme checks before it accepts a converged step, and the energies it checks with.

A Newton root is not always the step's solution. Every scheme refuses (the driver halves the step):

* a turn of :data:`~skfem_flex.numerics.rotations.MAX_INCREMENT` or more of a free angle coordinate in
  one step (too few steps per revolution: a joint flipped), or a state that is not finite
  (:func:`refused_state`, ``ctx.refusal = REFUSAL_TURN`` or ``REFUSAL_NOT_FINITE``);
* under the Newmark schemes, an energy jump (:func:`energy_jump`, ``REFUSAL_ENERGY``): the total energy
  E = T + V rising over the step by far more than the work W of the loads (and of prescribed laws and
  rheonomic constraints) explains,

  .. math::

      E_1 - E_0 - W > J\,\bigl(T_0 + T_1 + |V_1 - V_0| + |W|\bigr)
                      + ε\,\bigl(T_0 + T_1 + |V_0| + |V_1|\bigr),\qquad J = ½,\ ε = 10^{-9},

  i.e. kinetic energy out of nowhere: the excess must exceed half of all the energy that moved in the
  step (a step that more than triples its kinetic energy with neither a drop of potential nor work to
  pay for it). A hardening spring's trapezoidal step of a fifth of its period that quadruples the
  energy scores 0.60; the same spring at half that step at most 0.23. The trapezoidal rule and
  generalized-α conserve energy only approximately: their accepted steps change it by a small fraction
  of what moved (generalized-α dissipates, so only a rise is suspect), while a spurious root or an
  unresolved nonlinear oscillation creates energy in bulk.

  The rule is relative, so it needs a run with some energy: it is skipped while the largest
  T + |V| + |W| of the run's states is zero. A run driven from rest starts there, and its first step's
  error is of the order of its energy at any step size (the spin-up's trapezoidal first step:
  T₁ = 2·10⁻¹³ J for a work of 3·10⁻¹⁵ J; the driving law is self-similar at its start), so no halving
  would help; its second step is checked (it scores 0.36).

The energy-momentum step needs no energy rule: its equations are the discrete energy balance
E₁ − E₀ = W, which every converged root satisfies to the Newton tolerance. :func:`energies` evaluates
T and V at the end of the step; the loop records them with the same function.
"""
from __future__ import annotations

import numba

from ..numerics.newton import all_finite
from ..numerics.rotations import unresolved_turn
from .abi import call_families, fvec, ivec
from .tasks import (REFUSAL_ENERGY, REFUSAL_NOT_FINITE, REFUSAL_TURN, STATUS_REFUSED, TASK_ENERGY,
                    TASK_MOMENTUM)

__all__ = ["ENERGY_JUMP", "ENERGY_ROUNDOFF", "energies", "refused_state", "energy_jump", "mass_times", "momentum"]

#: J: a rise of the energy beyond the work by more than this fraction of the energy that moved is refused
ENERGY_JUMP = 0.5
#: ε: relative round-off allowance of the energy check (a body at rest beside a large potential)
ENERGY_ROUNDOFF = 1e-9


@numba.njit(cache=True, _nrt=False)
def mass_times(ctx, v, p):
    """p = M v of the scene's constant masses (CSR ``ctx.mass_*``)."""
    n = ctx.n
    ptr = ivec(ctx.mass_ptr, n + 1)
    nnz = ptr[n]
    idx, dat = ivec(ctx.mass_idx, nnz), fvec(ctx.mass_dat, nnz)
    for i in range(n):
        s = 0.0
        for t in range(ptr[i], ptr[i + 1]):
            s += dat[t] * v[idx[t]]
        p[i] = s


@numba.njit(cache=True, _nrt=False)
def momentum(ctx):
    """p(q, v) = M(q) v at (ctx.q1, ctx.v1) into ``ctx.p`` (the constant masses, then the families' MOMENTUM
    task), and the linear and angular momentum about the origin into ``ctx.out[1:7]`` (``out`` zeroed)."""
    n = ctx.n
    out = fvec(ctx.out, 7)
    for j in range(7):
        out[j] = 0.0
    mass_times(ctx, fvec(ctx.v1, n), fvec(ctx.p, n))
    call_families(ctx, TASK_MOMENTUM)


@numba.njit(cache=True, _nrt=False)
def energies(ctx):
    """(T, V) at (ctx.q1, ctx.v1), J: T = ½ vᵀ M(q) v and the potential V(q).

    On the way :func:`momentum` fills ``ctx.p`` and ``ctx.out[1:7]``; V is ``ctx.out[0]`` (TASK_ENERGY). T goes
    to ``ctx.kin`` and ``ctx.energies_valid`` is set: the time loop clears it before a step's acceptance and
    records the step with these values when the acceptance computed them."""
    n = ctx.n
    v, p = fvec(ctx.v1, n), fvec(ctx.p, n)
    out = fvec(ctx.out, 7)
    momentum(ctx)
    kin = 0.0
    for j in range(n):
        kin += v[j] * p[j]
    call_families(ctx, TASK_ENERGY)
    ctx.kin = 0.5 * kin
    ctx.energies_valid = 1
    return 0.5 * kin, out[0]


@numba.njit(cache=True, _nrt=False)
def refused_state(ctx, dq, angles):
    """True (and ``ctx.status`` refused) when a free angle coordinate (indices ``angles`` into the step's
    increment ``dq``) turned by MAX_INCREMENT or more, or the end state (ctx.q1, ctx.v1) is not finite."""
    n = ctx.n
    if unresolved_turn(dq, angles):
        ctx.status, ctx.refusal = STATUS_REFUSED, REFUSAL_TURN
        return True
    if not (all_finite(fvec(ctx.q1, n)) and all_finite(fvec(ctx.v1, n))):
        ctx.status, ctx.refusal = STATUS_REFUSED, REFUSAL_NOT_FINITE
        return True
    return False


@numba.njit(cache=True, _nrt=False)
def energy_jump(ctx, t0, v0, t1, v1, work):
    """True (and ``ctx.status`` refused) when the energy rose by far more than the step's ``work`` explains
    (module docstring): T₀, V₀ at the start, T₁, V₁ at the end of the step (J)."""
    excess = (t1 + v1) - (t0 + v0) - work
    moved = t0 + t1 + abs(v1 - v0) + abs(work)
    floor = ENERGY_ROUNDOFF * (t0 + t1 + abs(v0) + abs(v1))
    if excess > ENERGY_JUMP * moved + floor:
        ctx.status, ctx.refusal = STATUS_REFUSED, REFUSAL_ENERGY
        return True
    return False
