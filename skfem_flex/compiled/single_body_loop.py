r"""Compiled (Numba) energy-momentum time loop for a single floating-frame body.

For the scenes the benchmark is about — one floating-frame body (a
:class:`~skfem_flex.bodies.FloatingBeam` or a reduced :class:`~skfem_flex.bodies.ModalBody`) whose
reference coordinates follow prescribed motion laws (the spin-up, the rotating beam) — the
Python per-step overhead of :class:`~skfem_flex.schemes.integrators.EnergyMomentum` (Newton loop,
scale computations, small dense solves) costs far more than the arithmetic. This module runs
many steps of the *same* scheme inside one compiled function:

* unknowns Δq of the free coordinates, q1 = q0 + Δq, v1 = 2Δq/Δt − v0, prescribed Δq from
  the laws' positions at t1 (evaluated in Python for the chunk's step times);
* residual r = p(q1, v1) − p(q0, v0) − Δt g_kin + Δt g_pot (the fused body kernel
  :func:`skfem_flex.bodies.floating.kernel.energy_momentum_terms` on the arrays the body hands
  out through its ``compiled_kernel_data()``);
* scaled error err = max(‖r_F‖∞ / (rtol · scale), |v̄_F · r_F| / (etol · E_scale)) with the
  round-off-floor acceptance :func:`skfem_flex.numerics.newton.roundoff_floor`, initial guess Δq = Δt v0;
* the Newton iteration itself is the package's one core (:mod:`skfem_flex.numerics.newton`: convergence,
  exits, line search), driven with this module's ``_evaluate`` and ``_newton_solve``;
* prescribed reaction r_P / Δt and its work Δq_P · r_P / Δt.

LAPACK solves the Newton systems (gesv through numba's ``np.linalg.solve``; gbsv from
scipy's Cython LAPACK): dense for small scenes, in band storage for large ones whose free-free
block is banded (see :func:`eligible`). On any failure — non-finite residual, update or state, singular matrix,
no convergence within ``max_iterations`` — the compiled loop stops *before* the failing step
and reports its index; :func:`skfem_flex.run.simulate` then re-runs that step on the Python path,
which halves it or raises :class:`~skfem_flex.errors.ConvergenceError` with its usual message,
and continues compiled afterwards.

The trajectory equals the Python path's to round-off (the two residuals differ only in the order
of floating-point sums; the Newton iteration is the same compiled code), so the Newton iteration
counts agree except where a scaled residual lands within round-off of a convergence threshold.
"""
from __future__ import annotations

import weakref

import llvmlite.binding as _llvm
import numba
import numpy as np
from numba.extending import get_cython_function_address

from ..bodies.floating.kernel import energy_momentum_terms, momentum, potential_energy
from ..schemes.integrators import EnergyMomentum, predictor_acceleration
from ..numerics.linear_solver import MAX_BANDWIDTH
from ..numerics.newton import (CONVERGED, EVALUATE, NONFINITE_RESIDUAL, all_finite, max_abs, newton_evaluated, newton_solved,
                     newton_start, predicted_increment, roundoff_floor)
from ..scene import Scene

__all__ = ["eligible", "run_chunk", "chunk_steps", "chunk_schedule", "record_count", "record_buffers", "record_step", "is_recorded", "chunk_records", "jit_cache_cold",
           "COMPILE_NOTICE", "OK"]

#: the line ``simulate(..., progress=True)`` prints on stderr before a first run compiles the kernels
COMPILE_NOTICE = ("skfem-flex: compiling the Numba kernels (the Newton core; with floating-frame bodies also "
                  "their kernels and the compiled loop); this happens once per machine and takes a few seconds, "
                  "about 30-60 s with floating-frame bodies; later runs load them from the cache")

_TINY = 1e-300
#: status of :func:`run_chunk` when every step was done (the Newton core's CONVERGED)
OK = CONVERGED


def eligible(scene, scheme):
    """True if ``simulate`` may run ``scene`` with ``scheme`` through the compiled loop.

    Eligible: the :class:`~skfem_flex.schemes.integrators.EnergyMomentum` class itself (not a
    subclass, which may change the step) on a plain :class:`~skfem_flex.scene.Scene` of one
    body that hands out compiled kernel data (``body.compiled_kernel_data()`` not None: a
    :class:`~skfem_flex.bodies.FloatingBeam` or a :class:`~skfem_flex.bodies.ModalBody`), no
    constraints, no force elements (loads, gravity, springs) and no incremental-rotation
    coordinates; any of its coordinates may be prescribed. Small scenes (``scene.dense``) solve
    dense; larger ones only if their free-free Newton block is banded (bandwidth l + u ≤ 64, as
    the Python path's banded LAPACK solve: e.g. the spin-up, whose frame coordinates are
    prescribed), which is solved as a band.
    """
    if type(scheme) is not EnergyMomentum:
        return False
    return _kernel_data(scene) is not None and _plan(scene) is not None


def _kernel_data(scene):
    """The compiled kernel data of the scene's one body if the scene has the form the loop runs
    (plain Scene, one body with kernel data, no constraints, forces or incremental rotations), else None."""
    if type(scene) is not Scene or len(scene.bodies) != 1:
        return None
    if scene.n_constraints or scene.forces or len(getattr(scene, "cayley_index", ())):
        return None
    get = getattr(scene.bodies[0], "compiled_kernel_data", None)
    return None if get is None else get()


def jit_cache_cold(scene):
    """True if running ``scene`` will compile Numba kernels first (no usable on-disk cache yet).

    The kernels are compiled with ``cache=True`` into ``__pycache__`` next to their source: a
    kernel is cold when this process has not compiled it and its cache index is missing or
    stale (the index records the stamp of `jit_cache.source_stamp`). Every scene runs the Newton
    core (:mod:`skfem_flex.numerics.newton`); scenes with a body that hands out compiled kernel data (a
    :class:`~skfem_flex.bodies.FloatingBeam`, a :class:`~skfem_flex.bodies.ModalBody`) also the
    floating-frame kernels and this module's loop; small mechanisms the loop of
    :mod:`skfem_flex.compiled.scene_loop`.
    """
    from . import scene_loop as compiled_scene
    kernels = [newton_start, newton_evaluated, newton_solved]
    if any(getattr(b, "compiled_kernel_data", lambda: None)() is not None for b in getattr(scene, "bodies", ())):
        kernels += [_run, energy_momentum_terms, momentum, potential_energy]
    if isinstance(scene, Scene) and compiled_scene.pack(scene) is not None:
        kernels += [compiled_scene.run_loop]
    for kernel in kernels:
        if kernel.signatures:
            continue
        try:
            if not kernel._cache._cache_file._load_index():      # numba's own index reader
                return True
        except Exception:                                        # an unreadable index compiles too
            return True
    return False


_PLANS = weakref.WeakKeyDictionary()


def _plan(scene):
    """(target, size, kl, ku): where each entry of the body's CSR pattern goes in the storage of the
    free-free Newton block — dense row-major (kl = ku = −1) or LAPACK band storage with kl
    sub- and ku superdiagonals, column-major (LAPACK gbsv, :func:`_solve`); −1 for entries outside the block.
    None if the scene is too large for dense and its block is not banded. Built once per scene."""
    body = scene.bodies[0]
    kd, n = body.compiled_kernel_data(), body.n_dofs
    hit = _PLANS.get(scene)
    if hit is not None and hit[0] is kd:
        return hit[1]
    free = scene.free_index
    nfr = free.size
    fpos = -np.ones(n, dtype=np.int64)
    fpos[free] = np.arange(nfr)
    fr = fpos[np.repeat(np.arange(n), np.diff(kd.pat_ptr))]
    fc = fpos[kd.pat_idx]
    both = (fr >= 0) & (fc >= 0)
    if scene.dense:
        plan = (np.where(both, fr * nfr + fc, -1), nfr * nfr, -1, -1)
    else:
        off = fc[both] - fr[both]
        kl, ku = (int(max(0, -off.min())), int(max(0, off.max()))) if off.size else (0, 0)
        if kl + ku > MAX_BANDWIDTH:
            plan = None
        else:
            plan = (np.where(both, fc * (2 * kl + ku + 1) + kl + ku + fr - fc, -1), (2 * kl + ku + 1) * nfr, kl, ku)
    if plan is not None:
        plan = (np.ascontiguousarray(plan[0], dtype=np.int64),) + plan[1:]
    _PLANS[scene] = (kd, plan)
    return plan


def chunk_steps(scene):
    """Steps per compiled call: up to 1000, fewer for large bodies (about 0.1–0.2 s of work per call),
    so that recorded steps, output files and the progress bar follow the run closely."""
    return int(min(1000, max(10, 200_000 // max(scene.n, 1))))


# LAPACK's band solver dgbsv, from scipy's Cython LAPACK, callable from compiled code: its address
# is registered under a fixed symbol name at import, so cached machine code links to it again
_llvm.add_symbol("skfem_flex_dgbsv", get_cython_function_address("scipy.linalg.cython_lapack", "dgbsv"))
_dgbsv = numba.types.ExternalFunction("skfem_flex_dgbsv", numba.types.void(*([numba.types.voidptr] * 10)))


@numba.njit(cache=True)
def _solve(mat, kl, ku, b):
    """Solve the free-free Newton system stored by :func:`_evaluate`; (x, False) if it is singular.

    Dense (kl < 0): LAPACK gesv through ``np.linalg.solve``. Banded: LAPACK gbsv on the band
    storage (Fortran layout, leading dimension 2 kl + ku + 1; ``mat`` is overwritten).
    """
    n = b.size
    if kl < 0:
        try:
            return np.linalg.solve(mat.reshape(n, n), b), True
        except Exception:                # singular: numba raises LinAlgError
            return b.copy(), False
    ints = np.empty(6, dtype=np.int32)
    ints[0], ints[1], ints[2], ints[3], ints[4], ints[5] = n, kl, ku, 1, 2 * kl + ku + 1, n
    ipiv = np.empty(n, dtype=np.int32)
    info = np.zeros(1, dtype=np.int32)
    x = b.copy()
    _dgbsv(ints[0:1].ctypes, ints[1:2].ctypes, ints[2:3].ctypes, ints[3:4].ctypes, mat.ctypes, ints[4:5].ctypes,
           ipiv.ctypes, x.ctypes, ints[5:6].ctypes, info.ctypes)
    return x, info[0] == 0


@numba.njit(cache=True)
def _evaluate(system, x):
    """``evaluate`` of the Newton core for one energy-momentum step (EnergyMomentum.step's ``fun``).

    Keeps r_F, the flat storage of the free-free block J_FF (dense or banded; ``target`` maps the
    body's CSR pattern entries to it), Δq, q1, v1, p1 and r in the system's work arrays and
    returns the scaled error."""
    (kd, q0, v0, dq_base, free, target, h, p0, p0_inf, e_scale0, rtol, etol, kl, ku,
     rf, jf, dq, q1, v1, p1, r) = system
    dq[:] = dq_base
    for i in range(free.size):
        dq[free[i]] = x[i]
    q1[:] = q0 + dq
    v1[:] = (2.0 / h) * dq - v0
    p1_, gk, gp, data, floor = energy_momentum_terms(kd, q0, q1, v0, v1, h)
    p1[:] = p1_
    kin1 = 0.5 * np.dot(v1, p1)
    r[:] = p1 - p0
    scale = max(max_abs(p1), p0_inf)
    r -= h * gk
    scale = max(scale, h * max_abs(gk))
    r += h * gp
    scale = max(scale, h * max_abs(gp))
    e_scale = max(e_scale0, abs(kin1), abs(np.dot(dq, gp)), _TINY)
    vr, fl_inf, vfl = 0.0, 0.0, 0.0
    for i in range(free.size):
        j = free[i]
        rf[i] = r[j]
        vb = dq[j] / h
        vr += vb * r[j]
        fl_inf = max(fl_inf, abs(floor[j]))
        vfl += abs(vb) * floor[j]
    vr = abs(vr)
    r_inf = max_abs(rf)
    err = roundoff_floor(max(r_inf / (rtol * max(scale, _TINY)), vr / (etol * e_scale)), 0.0, r_inf, fl_inf, vr, vfl)
    jf[:] = 0.0
    for k in range(data.size):
        if target[k] >= 0:
            jf[target[k]] = data[k]
    return err if all_finite(rf) else np.nan


@numba.njit(cache=True)
def _newton_solve(system):
    """``solve`` of the Newton core: J_FF⁻¹ r_F of the last evaluation (overwrites the stored block)."""
    kl, ku, rf, jf = system[12], system[13], system[14], system[15]
    return _solve(jf, kl, ku, rf)


@numba.njit(cache=True)
def _step(kd, q0, v0, a0, p0, h, qp1, pres, free, target, mat_size, kl, ku, rtol, etol, max_iterations,
          line_search):
    """One energy-momentum step by the Newton core; (status, iterations, dq, q1, v1, p1, r)."""
    n = q0.size
    dq_base = np.zeros(n)
    for i in range(pres.size):
        dq_base[pres[i]] = qp1[i] - q0[pres[i]]
    x = np.empty(free.size)
    predicted_increment(v0, a0, h, free, x)
    x_scale = 0.0
    for i in range(free.size):
        x_scale = max(x_scale, abs(q0[free[i]]))
    dq, q1, v1, p1, r = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    system = (kd, q0, v0, dq_base, free, target, h, p0, max_abs(p0), abs(0.5 * np.dot(v0, p0)), rtol, etol, kl, ku,
              np.zeros(free.size), np.zeros(mat_size), dq, q1, v1, p1, r)
    state = newton_start(x, x_scale, max_iterations, line_search)
    action = EVALUATE
    while action < 0:                  # do what the Newton core asks; its rules are all in the core
        if action == EVALUATE:
            action = newton_evaluated(state, _evaluate(system, state[2]))
        else:
            y, regular = _newton_solve(system)
            action = newton_solved(state, y, regular)
    return action, state[4][0], dq, q1, v1, p1, r


@numba.njit(cache=True)
def _run(kd, q, v, acc, t, hs, qp, pres, free, target, mat_size, kl, ku, rtol, etol, max_iterations, line_search,
         work, first_step, record_every, n_steps):
    n, ns, npr = q.size, hs.size, pres.size
    n_rec = record_count(first_step, ns, record_every, n_steps)
    buffers = record_buffers(n_rec, n, npr)
    # T, V, p_R (2) and L about the origin of the recorded states, as the body's kinetic_energy,
    # potential_energy, linear_momentum and angular_momentum (R × p_R + p_θ) give them
    rec_derived = np.empty((n_rec, 5))
    reaction = np.zeros(npr)
    its_total = 0
    p = momentum(kd, q, v)
    i_rec = 0
    for k in range(ns):
        h = hs[k]
        status, its, dq, q1, v1, p1, r = _step(kd, q, v, acc, p, h, qp[k], pres, free, target, mat_size, kl, ku,
                                               rtol, etol, max_iterations, line_search)
        if status == OK and not (all_finite(q1) and all_finite(v1)):
            status = NONFINITE_RESIDUAL
        if status != OK:
            return status, k, t, q, v, acc, reaction, work, its_total, i_rec, buffers, rec_derived
        w = 0.0
        for i in range(npr):
            j = pres[i]
            reaction[i] = r[j] / h
        for i in range(npr):
            w += dq[pres[i]] * reaction[i]
        work += w
        t = t + h
        acc = (v1 - v) / h
        q, v, p = q1, v1, p1
        its_total += its
        s = first_step + k
        if is_recorded(s, record_every, n_steps):
            record_step(buffers, i_rec, t, q, v, work, its, reaction)
            rec_derived[i_rec, 0] = 0.5 * np.dot(v, p)
            rec_derived[i_rec, 1] = potential_energy(kd, q)
            rec_derived[i_rec, 2] = p[0]
            rec_derived[i_rec, 3] = p[1]
            rec_derived[i_rec, 4] = q[0] * p[1] - q[1] * p[0] + p[2]
            i_rec += 1
    return OK, ns, t, q, v, acc, reaction, work, its_total, i_rec, buffers, rec_derived


def chunk_schedule(scene, t, dt, t_end, first_step, n_chunk, n_steps):
    """Step sizes (n_chunk,) of steps ``first_step …`` of a run from time ``t`` (the last step of the run,
    number ``n_steps``, shortened to land on ``t_end``; times summed step by step as the Python loop
    does), and the prescribed coordinates' positions at their end times (n_chunk, n_prescribed),
    evaluated here in Python."""
    hs, times = np.empty(n_chunk), np.empty(n_chunk)
    for k in range(n_chunk):              # the same sequence of sums as the Python loop's state.t + h
        h = min(dt, t_end - t) if first_step + k == n_steps else dt
        t = t + h
        hs[k], times[k] = h, t
    laws = [p.law.position for p in scene.prescribed]
    if not laws:
        return hs, np.zeros((n_chunk, 0))
    qp = np.array([[float(f(tk)) for f in laws] for tk in times], dtype=float).reshape(n_chunk, len(laws))
    return hs, qp


@numba.njit(cache=True)
def record_count(first_step, n_chunk, record_every, n_steps):
    """How many of steps ``first_step … first_step + n_chunk − 1`` are recorded (step s is when
    ``s % record_every == 0 or s == n_steps``)."""
    n_rec = 0
    for k in range(n_chunk):
        if is_recorded(first_step + k, record_every, n_steps):
            n_rec += 1
    return n_rec


@numba.njit(cache=True)
def record_buffers(n_rec, n, npr):
    """Arrays for the recorded steps of a chunk: t, q, v, work, Newton iterations, prescribed reactions."""
    return (np.empty(n_rec), np.empty((n_rec, n)), np.empty((n_rec, n)), np.empty(n_rec),
            np.empty(n_rec, dtype=np.int64), np.empty((n_rec, npr)))


@numba.njit(cache=True, _nrt=False)
def is_recorded(s, record_every, n_steps):
    """Step s (1-based) of a run of ``n_steps`` is recorded."""
    return s % record_every == 0 or s == n_steps


@numba.njit(cache=True, _nrt=False)
def record_step(buffers, i, t, q, v, work, iterations, reaction):
    """Row i of the :func:`record_buffers` of a chunk: the state after a step."""
    rec_t, rec_q, rec_v, rec_work, rec_its, rec_reac = buffers
    rec_t[i] = t
    for j in range(q.size):
        rec_q[i, j] = q[j]
        rec_v[i, j] = v[j]
    rec_work[i] = work
    rec_its[i] = iterations
    for j in range(reaction.size):
        rec_reac[i, j] = reaction[j]


def chunk_records(buffers, n_rec, derived, lam, probes):
    """The records of a chunk as :func:`run_chunk` returns them: its first ``n_rec`` rows."""
    rec_t, rec_q, rec_v, rec_work, rec_its, rec_reac = buffers
    return dict(t=rec_t[:n_rec], q=rec_q[:n_rec], v=rec_v[:n_rec], work=rec_work[:n_rec], iterations=rec_its[:n_rec],
                reaction=rec_reac[:n_rec], derived=derived, lam=lam, probes=probes)


def run_chunk(scene, scheme, state, dt, t_end, first_step, n_chunk, n_steps, record_every, work):
    """Run steps ``first_step … first_step + n_chunk − 1`` of a run through the compiled loop.

    Step sizes follow :func:`skfem_flex.run.simulate`: ``dt`` (s), the last step of the run
    (number ``n_steps``) shortened to land on ``t_end`` (s); times are summed step by step
    exactly as the Python loop does. The prescribed coordinates' laws are evaluated here, in
    Python, at the chunk's step end times.

    Parameters
    ----------
    scene, scheme
        An eligible pair (:func:`eligible`).
    state : State
        Start state (t, q, v).
    dt, t_end : float
    first_step, n_chunk, n_steps : int
        Number of the first step of the chunk (1-based), steps in the chunk, steps in the run.
    record_every : int
        Step s is recorded when ``s % record_every == 0 or s == n_steps``.
    work : float
        External work accumulated so far, J (the loop adds each step's work in order).

    Returns
    -------
    dict
        ``status`` (OK or the failure code of the step after the completed ones), ``done``
        (steps completed), ``t, q, v, acc, reaction`` (state after them; ``acc`` is the last step's mean
        acceleration (:func:`~skfem_flex.schemes.integrators.predictor_acceleration`), ``reaction`` the mean
        generalized force of the prescribed laws over the last step), ``work`` (accumulated),
        ``iterations`` (Newton iterations summed over the completed steps) and ``records``, the
        recorded steps as arrays with one row per record: dict(t, q, v, work, iterations, reaction,
        derived, lam, probes), ``derived`` = (kinetic energy J, strain energy J, linear momentum (2)
        kg m/s, angular momentum about the origin kg m²/s, ‖Φ‖∞, ‖Φ_q v‖∞), computed in the loop;
        λ with no columns and ``probes`` {} (the form :func:`skfem_flex.compiled.scene_loop.run_chunk`
        shares).
    """
    body = scene.bodies[0]
    s = scheme.newton
    hs, qp = chunk_schedule(scene, state.t, dt, t_end, first_step, n_chunk, n_steps)
    target, size, kl, ku = _plan(scene)
    out = _run(body.compiled_kernel_data(), np.ascontiguousarray(state.q, dtype=float),
               np.ascontiguousarray(state.v, dtype=float), predictor_acceleration(state), float(state.t), hs, qp,
               scene.prescribed_index.astype(np.int64), scene.free_index.astype(np.int64), target, size, kl, ku,
               float(s.rtol), float(s.etol), int(s.max_iterations), bool(s.line_search), float(work),
               int(first_step), int(record_every), int(n_steps))
    status, done, t, q, v, acc, reaction, work, its_total, n_rec, buffers, rec_derived = out
    # the records of both compiled loops have one form: no constraints here (‖Φ‖ = ‖Φ_q v‖ = 0, no λ)
    # and no probe evaluated in the loop
    no_lam = np.zeros(0)
    derived = np.zeros((n_rec, 7))
    derived[:, :5] = rec_derived[:n_rec]
    records = chunk_records(buffers, n_rec, derived, np.zeros((n_rec, 0)), {})
    return dict(status=int(status), done=int(done), t=float(t), q=q, v=v, acc=acc, lam=no_lam, reaction=reaction,
                work=float(work), iterations=int(its_total), records=records)
