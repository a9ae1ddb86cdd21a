r"""The compiled time loop: many steps per call, one Newton core, every scheme and every scene.

The loop knows neither schemes nor elements. For each step it asks the scheme's kernel (called by
address, :mod:`.abi`) to PREDICT the Newton start, drives the Newton core
(:mod:`skfem_flex.numerics.newton`: EVALUATE → the scheme's kernel, SOLVE → the solver's kernel) until
the core answers, asks the scheme to ACCEPT the step and records the steps asked for. It returns at the
first step it cannot finish, with the state before that step (a scheme changes its state only when it
accepts), so that Python can halve the step or raise. It is compiled once per machine for all scenes.
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import numba
import numpy as np

from ..numerics.newton import (CONVERGED, CONVERGED_BELOW, EVALUATE, newton_evaluated, newton_reset,
                              newton_solved)
from .abi import CONTEXT, FAMILY, call, call_families, fvec
from .points import NB, OFF, maps_view, position_into
from .abi import family_at
from .acceptance import energies
from .tasks import PHASE_ACCEPT, PHASE_EVALUATE, PHASE_PREDICT, PHASE_START, REFUSAL_NONE, STATUS_OK, TASK_ROWS

__all__ = ["Records", "NewtonArrays", "entry_types", "run_steps", "start_state", "evaluate_once", "record_at", "REFUSED", "DERIVED"]

#: status of :func:`run_steps` when an element refused a state, a Python element raised or a kernel wrote
#: outside the Newton pattern (``ctx.status`` says which)
REFUSED = 10
#: the derived values recorded per step, in the columns of ``Records.derived``
DERIVED = ("kinetic", "potential", "px", "py", "pz", "lx", "ly", "lz", "constraint_residual",
           "velocity_constraint_residual")


class Records(NamedTuple):
    """The arrays a chunk records into, one row per recorded step."""
    t: np.ndarray            # (nr,) s
    q: np.ndarray            # (nr, n)
    v: np.ndarray            # (nr, n)
    lam: np.ndarray          # (nr, m)
    work: np.ndarray         # (nr,) J
    iterations: np.ndarray   # (nr,) Newton iterations of the step
    reaction: np.ndarray     # (nr, npres)
    derived: np.ndarray      # (nr, len(DERIVED))
    probes: np.ndarray       # (nr, number of probe maps, 2)
    probe_maps: np.ndarray   # (number of probe maps,) map indices

    @classmethod
    def empty(cls, nr, n, m, npres, probe_maps):
        """Zeroed records of ``nr`` rows for n coordinates, m multipliers, npres prescribed coordinates."""
        z = np.zeros
        return cls(z(nr), z((nr, n)), z((nr, n)), z((nr, m)), z(nr), z(nr, dtype=np.int64), z((nr, npres)),
                   z((nr, len(DERIVED))), z((nr, probe_maps.size, 3)), np.ascontiguousarray(probe_maps, np.int64))


class NewtonArrays(NamedTuple):
    """The Newton core's state (:func:`~skfem_flex.numerics.newton.newton_start`), allocated once per chunk."""
    x: np.ndarray
    dx: np.ndarray
    x_try: np.ndarray
    fl: np.ndarray
    ints: np.ndarray

    @classmethod
    def empty(cls, nx):
        """Zeroed arrays for nx Newton unknowns."""
        return cls(np.zeros(nx), np.zeros(nx), np.zeros(nx), np.zeros(4), np.zeros(5, dtype=np.int64))


@numba.njit(cache=True, _nrt=False)
def record_step(ctx, records, i, t):
    """Record row i at time t from the state (ctx.q1, ctx.v1, the scheme's λ, work and reactions)."""
    n, m = ctx.n, ctx.m
    q, v = fvec(ctx.q1, n), fvec(ctx.v1, n)
    out = fvec(ctx.out, 7)
    lam, reaction = fvec(ctx.lam, m), fvec(ctx.reaction, ctx.npres)
    records.t[i] = t
    for j in range(n):
        records.q[i, j] = q[j]
        records.v[i, j] = v[j]
    for j in range(m):
        records.lam[i, j] = lam[j]
    for j in range(reaction.size):
        records.reaction[i, j] = reaction[j]
    records.work[i] = fvec(ctx.work, 1)[0]
    records.iterations[i] = ctx.its
    # the acceptance of the step may have computed the energies and momenta at this state already
    kin = ctx.kin if ctx.energies_valid else energies(ctx)[0]
    d = records.derived[i]
    d[0] = kin
    for j in range(7):
        d[1 + j] = out[j]
    phi_max, rate_max = 0.0, 0.0
    if m:
        call_families(ctx, TASK_ROWS)
        phi, rate = fvec(ctx.phi, m), fvec(ctx.ddphi, m)
        for j in range(m):
            phi_max = max(phi_max, abs(phi[j]))
            rate_max = max(rate_max, abs(rate[j]))
    d[8] = phi_max
    d[9] = rate_max
    if records.probe_maps.size:
        maps = maps_view(family_at(ctx.maps))
        for j in range(records.probe_maps.size):
            k = records.probe_maps[j]
            o = maps.ints[k, OFF]
            position_into(maps, k, q[o:o + maps.ints[k, NB]], records.probes[i, j])


@numba.njit(cache=True, _nrt=False)
def _evaluate(c, kernel, sch, fresh):
    """The scheme's evaluation (its ``kernel``) at the Newton point; ``fresh`` False: only its residual is used,
    so its matrix entries go to the spare storage and families may skip their derivatives."""
    real = c.mat
    if not fresh:
        c.mat = c.mat_spare
    c.fresh = 1 if fresh else 0
    c.phase = PHASE_EVALUATE
    call(kernel, c.self, sch)
    c.mat = real
    c.fresh = 1


@numba.njit(cache=True, _nrt=False)
def run_steps(ctx, scheme, solver, hs, times, recorded, records, newton, max_iterations, line_search, table, lazy):
    """Advance ``hs.size`` steps; returns (status, steps done, records written, Newton iterations).

    ``ctx``: the context array (one record, :mod:`.abi`); ``scheme``, ``solver``: one FAMILY record each;
    ``hs[k]``: the size of step k, from ``times[k]`` to ``times[k + 1]`` (the caller's exact times, so that
    how a run is cut into chunks changes nothing); ``table``: the chunk's functions of time, row 0 at
    times[0] and row k + 1 for step k; ``recorded[k]``: record step k. On a status other than CONVERGED the
    state is the one before the failing step.

    ``lazy``: while the steps converge in a steady number of iterations k (the last two steps took k), the
    evaluation after the k-th update of a step asks only for the residual (the converged step never uses
    that matrix); unless its scaled error shows convergence, the same point is evaluated again with its
    matrix before the core decides. It pays when a family forms its derivatives at a cost well above its
    residual's (a family with ``RESIDUAL_ONLY``), and changes no iterate: a residual-only evaluation gives the
    residual and the error scales of the full one, and may leave out only the round-off floor of the
    error, which matters (:func:`~skfem_flex.numerics.newton.roundoff_floor`) only above convergence."""
    c = ctx[0]
    n_rec = 0
    its_total = 0
    sch, sol = scheme.ctypes.data, solver.ctypes.data
    c.x = newton.x_try.ctypes.data
    last_its, steady = 0, False         # the iterations of the last step; the same as the step's before
    for k in range(hs.size):
        c.t = times[k]
        c.h = hs[k]
        c.trow = table.ctypes.data + 8 * (k + 1) * c.ncol
        c.status, c.bad_family, c.refusal = STATUS_OK, -1, REFUSAL_NONE
        c.phase = PHASE_PREDICT
        call(scheme[0].kernel, c.self, sch)
        newton_reset(newton, c.x_scale, max_iterations, line_search)
        status = EVALUATE
        fresh = True
        solves = 0
        while status < 0:               # do what the Newton core asks; its rules are all in the core
            if status == EVALUATE:
                _evaluate(c, scheme[0].kernel, sch, fresh)
                if c.status != STATUS_OK:
                    return REFUSED, k, n_rec, its_total
                if not fresh and not c.err <= CONVERGED_BELOW:
                    # not converged: the same point again, with its matrix and every family's round-off
                    # floor (which may cap the error above 1 and is not formed by a residual-only evaluation)
                    _evaluate(c, scheme[0].kernel, sch, True)
                    if c.status != STATUS_OK:
                        return REFUSED, k, n_rec, its_total
                status = newton_evaluated(newton, c.err)
            else:
                call(solver[0].kernel, c.self, sol)
                solves += 1
                fresh = not (lazy and steady and solves >= last_its)
                status = newton_solved(newton, fvec(c.y, c.nx), c.regular != 0)
        if status != CONVERGED:
            return status, k, n_rec, its_total
        c.its = newton.ints[0]
        its_total += c.its
        steady = c.its == last_its
        last_its = c.its
        c.phase = PHASE_ACCEPT
        c.energies_valid = 0
        call(scheme[0].kernel, c.self, sch)
        if c.status != STATUS_OK:
            return REFUSED, k, n_rec, its_total
        if recorded[k]:
            record_step(c, records, n_rec, times[k + 1])
            n_rec += 1
    return CONVERGED, hs.size, n_rec, its_total


@numba.njit(cache=True, _nrt=False)
def record_at(ctx, records, t, table):
    """Record row 0 of ``records`` from the state in (ctx.q1, ctx.v1) at time t (``table``: one row at t)."""
    c = ctx[0]
    c.trow = table.ctypes.data
    c.t = t
    c.h = 0.0
    c.te = c.t1 = t
    c.status = STATUS_OK
    c.energies_valid = 0
    record_step(c, records, 0, t)


@numba.njit(cache=True, _nrt=False)
def evaluate_once(ctx, scheme, phase):
    """One call of the scheme's kernel in ``phase`` (tests, linearization, statics)."""
    c = ctx[0]
    c.phase = phase
    call(scheme[0].kernel, c.self, scheme.ctypes.data)


@numba.njit(cache=True, _nrt=False)
def start_state(ctx, scheme, solver, table, t):
    """The consistent acceleration and multipliers of the scheme's state (PHASE_START of the scheme's
    kernel: a residual linear in them, solved once); returns True when the solve succeeded, with the
    solution in ``ctx.x`` and the residual at it (the prescribed coordinates' forces) in the scheme."""
    c = ctx[0]
    sch, sol = scheme.ctypes.data, solver.ctypes.data
    c.trow = table.ctypes.data
    c.t = t
    c.status = STATUS_OK
    x = fvec(c.x, c.nx)
    for i in range(c.nx):
        x[i] = 0.0
    c.phase = PHASE_START
    call(scheme[0].kernel, c.self, sch)
    if c.status != STATUS_OK:
        return False
    call(solver[0].kernel, c.self, sol)
    if c.regular == 0:
        return False
    y = fvec(c.y, c.nx)
    for i in range(c.nx):
        x[i] = -y[i]
    call(scheme[0].kernel, c.self, sch)
    return c.status == STATUS_OK


@functools.lru_cache(maxsize=1)
def entry_types():
    """{name: argument types} of the loop's entry points as :class:`~skfem_flex.schemes.stepper.Stepper`
    calls them. The types do not depend on the scene (sizes live in the context), so one compile of each
    serves every scene; this lets them be compiled before a scene's arrays exist (:mod:`.ahead`)."""
    ctx, rec = np.zeros(1, dtype=CONTEXT), np.zeros(1, dtype=FAMILY)
    vector, table = np.zeros(1), np.zeros((1, 1))
    records = Records.empty(1, 1, 1, 1, np.zeros(1, dtype=np.int64))

    def types(*args):
        return tuple(numba.typeof(a) for a in args)
    return {"run_steps": types(ctx, rec, rec, vector, vector, np.zeros(1, dtype=np.bool_), records,
                               NewtonArrays.empty(1), 0, False, table, False),
            "record_at": types(ctx, records, 0.0, table),
            "start_state": types(ctx, rec, rec, table, 0.0)}
