r"""Compiled (Numba) energy-momentum time loop for a single floating-frame body.

For the scenes the benchmark is about — one floating-frame body (a
:class:`~skfem_flex.bodies.FloatingBeam` or a reduced :class:`~skfem_flex.bodies.ModalBody`) whose
reference coordinates follow prescribed motion laws (the spin-up, the rotating beam) — the
Python per-step overhead of :class:`~skfem_flex.integrators.EnergyMomentum` (Newton loop,
scale computations, small dense solves) costs far more than the arithmetic. This module runs
many steps of the *same* scheme inside one compiled function:

* unknowns Δq of the free coordinates, q1 = q0 + Δq, v1 = 2Δq/Δt − v0, prescribed Δq from
  the laws' positions at t1 (evaluated in Python for the chunk's step times);
* residual r = p(q1, v1) − p(q0, v0) − Δt g_kin + Δt g_pot (the fused body kernel
  :func:`skfem_flex.bodies.floating_kernel.energy_momentum_terms` on the arrays the body hands
  out through its ``compiled_kernel_data()``);
* convergence err = max(‖r_F‖∞ / (rtol · scale), |v̄_F · r_F| / (etol · E_scale)) ≤ 1, with the
  round-off-floor acceptance, the update-below-round-off and stagnation exits and the line
  search of :meth:`Integrator._newton`, initial guess Δq = Δt v0;
* prescribed reaction r_P / Δt and its work Δq_P · r_P / Δt.

LAPACK solves the Newton systems (gesv through numba's ``np.linalg.solve``; gbsv from
scipy's Cython LAPACK): dense for small scenes, in band storage for large ones whose free-free
block is banded (see :func:`eligible`). On any failure — non-finite residual, update or state, singular matrix,
no convergence within ``max_iterations`` — the compiled loop stops *before* the failing step
and reports its index; :func:`skfem_flex.simulate` then re-runs that step on the Python path,
which halves it or raises :class:`~skfem_flex.errors.ConvergenceError` with its usual message,
and continues compiled afterwards.

The trajectory equals the Python path's to round-off (the two differ only in the order of
floating-point sums), so the Newton iteration counts agree except where a scaled residual
lands within round-off of a convergence threshold.
"""
from __future__ import annotations

import weakref

import llvmlite.binding as _llvm
import numba
import numpy as np
from numba.extending import get_cython_function_address

from .bodies.floating import FloatingBeam
from .bodies.floating_kernel import energy_momentum_terms, momentum, potential_energy
from . import integrators
from .integrators import EnergyMomentum
from .scene import Scene

__all__ = ["eligible", "run_chunk", "chunk_steps", "jit_cache_cold", "COMPILE_NOTICE", "OK", "NONFINITE",
           "NOT_CONVERGED", "SINGULAR"]

#: the line ``simulate(..., progress=True)`` prints on stderr before a first run compiles the kernels
COMPILE_NOTICE = ("skfem-flex: compiling the floating-frame kernels (Numba); this happens once per "
                  "machine and takes about 30-60 s, later runs load them from the cache")

_EPS = np.finfo(float).eps
_TINY = 1e-300
_NEAR_FLOOR = 1e4
#: widest band (l + u) solved as a band, as the Python path's banded LAPACK solve
_MAX_BANDWIDTH = getattr(integrators, "_MAX_BANDWIDTH", 64)
#: status codes of :func:`run_chunk`
OK, NONFINITE, NOT_CONVERGED, SINGULAR = 0, 1, 2, 3


def eligible(scene, scheme):
    """True if ``simulate`` may run ``scene`` with ``scheme`` through the compiled loop.

    Eligible: the :class:`~skfem_flex.integrators.EnergyMomentum` class itself (not a
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
    stale (the index records the stamp of `jit_cache.source_stamp`). Scenes with a
    :class:`~skfem_flex.bodies.FloatingBeam` run these kernels on every path; other bodies with
    compiled kernel data (a :class:`~skfem_flex.bodies.ModalBody`) only in the compiled loop, i.e. in
    scenes of the form :func:`eligible` accepts.
    """
    if not (any(isinstance(b, FloatingBeam) for b in getattr(scene, "bodies", ()))
            or _kernel_data(scene) is not None):
        return False
    for kernel in (_run, energy_momentum_terms, momentum, potential_energy):
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
        if kl + ku > _MAX_BANDWIDTH:
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


@numba.njit(cache=True)
def _inf(x):
    m = 0.0
    for i in range(x.size):
        a = abs(x[i])
        if a > m:
            m = a
    return m


@numba.njit(cache=True)
def _all_finite(x):
    for i in range(x.size):
        if not np.isfinite(x[i]):
            return False
    return True


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
def _evaluate(kd, x, q0, v0, dq_base, free, target, mat_size, h, p0, p0_inf, e_scale0, rtol, etol):
    """One Newton evaluation of the energy-momentum step (EnergyMomentum.step's ``fun``).

    Returns (r_F, J_FF, err, dq, q1, v1, p1, r); J_FF is the flat storage of the free-free block
    (dense or banded) that ``target`` maps the body's CSR pattern entries to."""
    dq = dq_base.copy()
    for i in range(free.size):
        dq[free[i]] = x[i]
    q1 = q0 + dq
    v1 = (2.0 / h) * dq - v0
    p1, gk, gp, data, floor = energy_momentum_terms(kd, q0, q1, v0, v1, h)
    kin1 = 0.5 * np.dot(v1, p1)
    r = p1 - p0
    scale = max(_inf(p1), p0_inf)
    r -= h * gk
    scale = max(scale, h * _inf(gk))
    r += h * gp
    scale = max(scale, h * _inf(gp))
    e_scale = max(e_scale0, abs(kin1), abs(np.dot(dq, gp)), _TINY)
    nfr = free.size
    rf = np.empty(nfr)
    vr, fl_inf, vfl = 0.0, 0.0, 0.0
    for i in range(nfr):
        j = free[i]
        rf[i] = r[j]
        vb = dq[j] / h
        vr += vb * r[j]
        fl_inf = max(fl_inf, abs(floor[j]))
        vfl += abs(vb) * floor[j]
    vr = abs(vr)
    r_inf = _inf(rf)
    err = max(r_inf / (rtol * max(scale, _TINY)), 0.0, vr / (etol * e_scale))
    # round-off floor acceptance (see EnergyMomentum.step)
    if err > 1.0 and r_inf <= 16 * _EPS * fl_inf and vr <= 2 * _EPS * vfl:
        err = min(err, 1e3)
    # the free-free block of the tangent, gathered from the body's CSR pattern
    jf = np.zeros(mat_size)
    for k in range(data.size):
        if target[k] >= 0:
            jf[target[k]] = data[k]
    return rf, jf, err, dq, q1, v1, p1, r


@numba.njit(cache=True)
def _step(kd, q0, v0, p0, h, qp1, pres, free, target, mat_size, kl, ku, rtol, etol, max_iterations, line_search):
    """One energy-momentum step; (status, iterations, dq, q1, v1, p1, r) as EnergyMomentum.step and _newton."""
    n = q0.size
    dq_base = np.zeros(n)
    for i in range(pres.size):
        dq_base[pres[i]] = qp1[i] - q0[pres[i]]
    p0_inf = _inf(p0)
    e_scale0 = abs(0.5 * np.dot(v0, p0))
    x = np.empty(free.size)
    for i in range(free.size):
        x[i] = h * v0[free[i]]
    rf, jf, err, dq, q1, v1, p1, r = _evaluate(kd, x, q0, v0, dq_base, free, target, mat_size, h, p0, p0_inf,
                                               e_scale0, rtol, etol)
    err_prev = np.inf
    for it in range(max_iterations + 1):
        if not (_all_finite(rf) and np.isfinite(err)):
            return NONFINITE, it, dq, q1, v1, p1, r
        if err <= 1.0:
            return OK, it, dq, q1, v1, p1, r
        if it == max_iterations:
            break
        sol, regular = _solve(jf, kl, ku, rf)
        if not regular:
            return SINGULAR, it, dq, q1, v1, p1, r
        dx = -sol
        if not _all_finite(dx):
            return NONFINITE, it, dq, q1, v1, p1, r
        dx_inf, x_inf = _inf(dx), _inf(x)
        if dx_inf <= 8 * _EPS * max(x_inf, _TINY) and err < 1e6:
            return OK, it + 1, dq, q1, v1, p1, r          # update below round-off
        if it >= 2 and err >= 0.25 * err_prev and dx_inf <= 1.5e-8 * x_inf and err < 1e4:
            return OK, it + 1, dq, q1, v1, p1, r          # stagnated at the round-off floor
        err_prev = err
        step = 1.0
        for _ in range(7 if line_search else 1):
            x_try = x + step * dx
            rf_t, jf_t, err_t, dq_t, q1_t, v1_t, p1_t, r_t = _evaluate(kd, x_try, q0, v0, dq_base, free, target,
                                                                       mat_size, h, p0, p0_inf, e_scale0, rtol, etol)
            if not line_search or (np.isfinite(err_t) and (err_t < max(err, 1.0) or err_t <= _NEAR_FLOOR)):
                break
            step *= 0.5
        x, rf, jf, err, dq, q1, v1, p1, r = x_try, rf_t, jf_t, err_t, dq_t, q1_t, v1_t, p1_t, r_t
    return NOT_CONVERGED, max_iterations, dq, q1, v1, p1, r


@numba.njit(cache=True)
def _run(kd, q, v, t, hs, qp, pres, free, target, mat_size, kl, ku, rtol, etol, max_iterations, line_search, work,
         first_step, record_every, n_steps):
    n, ns, npr = q.size, hs.size, pres.size
    n_rec = 0
    for k in range(ns):
        s = first_step + k
        if s % record_every == 0 or s == n_steps:
            n_rec += 1
    rec_t = np.empty(n_rec)
    rec_q = np.empty((n_rec, n))
    rec_v = np.empty((n_rec, n))
    rec_work = np.empty(n_rec)
    rec_its = np.empty(n_rec, dtype=np.int64)
    rec_reac = np.empty((n_rec, npr))
    # T, V, p_R (2) and L about the origin of the recorded states, as the body's kinetic_energy,
    # potential_energy, linear_momentum and angular_momentum (R × p_R + p_θ) give them
    rec_derived = np.empty((n_rec, 5))
    reaction = np.zeros(npr)
    its_total = 0
    p = momentum(kd, q, v)
    i_rec = 0
    for k in range(ns):
        h = hs[k]
        status, its, dq, q1, v1, p1, r = _step(kd, q, v, p, h, qp[k], pres, free, target, mat_size, kl, ku, rtol,
                                               etol, max_iterations, line_search)
        if status == OK and not (_all_finite(q1) and _all_finite(v1)):
            status = NONFINITE
        if status != OK:
            return (status, k, t, q, v, p, reaction, work, its_total, i_rec,
                    rec_t, rec_q, rec_v, rec_work, rec_its, rec_reac, rec_derived)
        w = 0.0
        for i in range(npr):
            j = pres[i]
            reaction[i] = r[j] / h
        for i in range(npr):
            w += dq[pres[i]] * reaction[i]
        work += w
        t = t + h
        q, v, p = q1, v1, p1
        its_total += its
        s = first_step + k
        if s % record_every == 0 or s == n_steps:
            rec_t[i_rec] = t
            rec_q[i_rec] = q
            rec_v[i_rec] = v
            rec_work[i_rec] = work
            rec_its[i_rec] = its
            rec_reac[i_rec] = reaction
            rec_derived[i_rec, 0] = 0.5 * np.dot(v, p)
            rec_derived[i_rec, 1] = potential_energy(kd, q)
            rec_derived[i_rec, 2] = p[0]
            rec_derived[i_rec, 3] = p[1]
            rec_derived[i_rec, 4] = q[0] * p[1] - q[1] * p[0] + p[2]
            i_rec += 1
    return (OK, ns, t, q, v, p, reaction, work, its_total, i_rec,
            rec_t, rec_q, rec_v, rec_work, rec_its, rec_reac, rec_derived)


def run_chunk(scene, scheme, state, dt, t_end, first_step, n_chunk, n_steps, record_every, work):
    """Run steps ``first_step … first_step + n_chunk − 1`` of a run through the compiled loop.

    Step sizes follow :func:`skfem_flex.simulate`: ``dt`` (s), the last step of the run
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
        (steps completed), ``t, q, v, reaction`` (state after them; ``reaction`` is the mean
        generalized force of the prescribed laws over the last step), ``work`` (accumulated),
        ``iterations`` (Newton iterations summed over the completed steps) and ``records``, a
        list of (t, q, v, work, iterations, reaction, derived) of the recorded steps, ``derived`` =
        (kinetic energy J, strain energy J, linear momentum (2) kg m/s, angular momentum about the
        origin kg m²/s), computed in the loop.
    """
    body = scene.bodies[0]
    s = scheme.newton
    hs, times = np.empty(n_chunk), np.empty(n_chunk)
    t = state.t
    for k in range(n_chunk):              # the same sequence of sums as the Python loop's state.t + h
        h = min(dt, t_end - t) if first_step + k == n_steps else dt
        t = t + h
        hs[k], times[k] = h, t
    laws = [p.law.position for p in scene.prescribed]
    qp = np.array([[float(f(tk)) for f in laws] for tk in times], dtype=float).reshape(n_chunk, len(laws))
    target, size, kl, ku = _plan(scene)
    out = _run(body.compiled_kernel_data(), np.ascontiguousarray(state.q, dtype=float),
               np.ascontiguousarray(state.v, dtype=float), float(state.t), hs, qp,
               scene.prescribed_index.astype(np.int64), scene.free_index.astype(np.int64), target, size, kl, ku,
               float(s.rtol), float(s.etol), int(s.max_iterations), bool(s.line_search), float(work),
               int(first_step), int(record_every), int(n_steps))
    (status, done, t, q, v, _, reaction, work, its_total, n_rec, rec_t, rec_q, rec_v, rec_work, rec_its,
     rec_reac, rec_derived) = out
    records = [(float(rec_t[i]), rec_q[i], rec_v[i], float(rec_work[i]), int(rec_its[i]), rec_reac[i],
                rec_derived[i])
               for i in range(n_rec)]
    return dict(status=int(status), done=int(done), t=float(t), q=q, v=v, reaction=reaction, work=float(work),
                iterations=int(its_total), records=records)
