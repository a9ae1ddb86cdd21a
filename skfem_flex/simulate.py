"""simulate(scene, t_end, dt, integrator=...) -> Result."""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

from . import compiled_loop
from .initial_conditions import consistent_initial_state
from .integrators import ConvergenceError, SimulationError, State, make_integrator
from .result import Result

__all__ = ["simulate"]


class _Recorder:
    """Collects histories step by step; builds a Result at any time."""

    def __init__(self, scene):
        self.scene = scene
        self.rows = {k: [] for k in ("t", "q", "v", "lam", "kinetic", "potential", "external_work",
                                     "constraint_residual", "velocity_constraint_residual",
                                     "newton_iterations", "prescribed_force", "linear_momentum",
                                     "angular_momentum")}
        self.probes = {k: [] for k in scene.probes}
        self.with_momentum = None
        self.reactions = _reaction_maps(scene)
        self.reaction_rows = {k: [] for k, _ in self.reactions}

    def record(self, state, work, iterations, vres, derived=None):
        """Append one state. ``derived`` = (T, V, p_x, p_y, L), when the caller computed them already
        (the compiled loop), replaces the scene's kinetic/potential energy and momenta calls."""
        s = self.scene
        q, v, t = state.q, state.v, state.t
        r = self.rows
        r["t"].append(t)
        r["q"].append(q.copy())
        r["v"].append(v.copy())
        r["lam"].append(np.array(state.lam, dtype=float))
        r["kinetic"].append(s.kinetic_energy(q, v) if derived is None else float(derived[0]))
        r["potential"].append(s.potential_energy(q) if derived is None else float(derived[1]))
        r["external_work"].append(work)
        r["constraint_residual"].append(float(np.max(np.abs(s.constraint_value(q, t)))) if s.n_constraints else 0.0)
        r["velocity_constraint_residual"].append(vres)
        r["newton_iterations"].append(iterations)
        r["prescribed_force"].append(np.array(state.prescribed_force, dtype=float))
        if self.with_momentum is None:
            self.with_momentum = s.linear_momentum(q, v) is not None
        if self.with_momentum:
            if derived is None:
                r["linear_momentum"].append(s.linear_momentum(q, v))
                r["angular_momentum"].append(s.angular_momentum(q, v))
            else:
                r["linear_momentum"].append(np.array(derived[2:4], dtype=float))
                r["angular_momentum"].append(float(derived[4]))
        for k, val in s.evaluate_probes(t, q, v).items():
            self.probes[k].append(val)
        if self.reactions:
            lam = np.asarray(state.lam, dtype=float)
            for k, fn in self.reactions:
                self.reaction_rows[k].append(fn(q, lam))

    def result(self, **meta):
        r = {k: np.asarray(val, dtype=float) for k, val in self.rows.items()}
        r["newton_iterations"] = np.asarray(self.rows["newton_iterations"], dtype=int)
        kin, pot = r["kinetic"], r["potential"]
        if not self.with_momentum:
            r["linear_momentum"] = None
            r["angular_momentum"] = None
        reactions = {k: np.asarray(val, dtype=float) for k, val in self.reaction_rows.items()}
        return Result(total_energy=kin + pot, probes={k: np.asarray(v) for k, v in self.probes.items()},
                      reactions=reactions, **r, **meta)


def _reaction_maps(scene):
    """[(unique name, fn(q, lam) -> reaction)] for the scene's constraints (names made unique with #2, #3...)."""
    out = []
    for name, c, idx, rows in zip(scene.reaction_names, scene.constraints, scene._con_idx, scene._con_rows):
        def fn(q, lam, c=c, idx=idx, rows=rows):
            if lam.size != scene.n_constraints:
                return np.full(len(c.reaction_labels) or c.n_equations, np.nan)
            return np.atleast_1d(np.asarray(c.reaction(q[idx], lam[rows]), dtype=float))
        out.append((name, fn))
    return out


def simulate(scene, t_end, dt, integrator="energy-momentum", rho_inf=None, newton=None, record_every=1,
             output=(), progress=False, max_halvings=8, project=True, compiled=None, start="initial"):
    """Integrate a scene in time.

    Parameters
    ----------
    scene : Scene
    t_end : float
        End time, s (≥ 0).
    dt : float
        Step, s (> 0). The last step is shortened to land on t_end.
    integrator : str or Integrator
        ``"energy-momentum"`` (default), ``"trapezoidal"`` or ``"generalized-alpha"``.
    rho_inf : float, optional
        Spectral radius for generalized-α (default 0.9).
    newton : NewtonSettings, optional
    record_every : int
        Record every n-th step (the first and last are always recorded).
    output : sequence
        Sinks with ``write(scene, t, q, v)`` and ``close()``, called at the
        recorded steps (e.g. :class:`skfem_flex.output.VTKSeries`).
    progress : bool
        Show a tqdm progress bar on stderr.
    max_halvings : int
        A step whose Newton iteration fails is split in two, recursively,
        at most this deep, before the run is given up.
    project : bool
        True (default): project the initial state onto the constraints
        (minimum-norm Gauss–Newton for q0, minimum-norm correction for v0,
        prescribed coordinates kept; see
        :func:`skfem_flex.initial_conditions.consistent_initial_state`).
        False: only check it. Either way redundant constraints raise.
    compiled : bool, optional
        Run eligible scenes through the compiled energy-momentum loop
        (:mod:`skfem_flex.compiled_loop`: one floating-frame beam, prescribed
        coordinates, no constraints or force elements, a dense or banded Newton
        block) — the same
        scheme and Newton rules, so the same trajectory to round-off, many times
        faster. Default: True, unless the environment variable
        ``SKFEM_FLEX_COMPILED`` is ``0``. False forces the Python path; other
        scenes and schemes always take it. A step the compiled loop cannot
        finish is re-run on the Python path (halving, errors as there).
    start : "initial", "static", (q, v) or a state with ``q`` and ``v``
        ``"initial"`` (default): the scene's initial state. ``"static"``: the static
        equilibrium under the loads at t = 0 (:func:`skfem_flex.analysis.static_equilibrium`)
        with the scene's initial velocities. A pair (q, v) or an object with ``q`` and ``v``
        (e.g. an :class:`~skfem_flex.analysis.EquilibriumState`, whose velocities are those
        of the equilibrium, zero at rest): that state.

    Returns
    -------
    Result

    Raises
    ------
    ValueError
        On bad arguments, redundant constraints
        (:class:`~skfem_flex.initial_conditions.RedundantConstraintsError`) or
        initial conditions that cannot be made consistent
        (:class:`~skfem_flex.initial_conditions.InconsistentInitialConditionsError`).
    ConvergenceError
        When a step fails even after halving; ``exc.result`` holds the
        history up to the last good step, and output sinks keep what they
        wrote.
    """
    t_end, dt = float(t_end), float(dt)
    if not math.isfinite(dt) or dt <= 0:
        raise ValueError(f"dt must be finite and positive, got {dt!r}")
    if not math.isfinite(t_end) or t_end < 0:
        raise ValueError(f"t_end must be finite and >= 0, got {t_end!r}")
    if isinstance(record_every, bool) or int(record_every) != record_every or int(record_every) < 1:
        raise ValueError(f"record_every must be a positive integer, got {record_every!r}")
    record_every = int(record_every)
    scheme = make_integrator(integrator, rho_inf=rho_inf, newton=newton)
    q, v = _start_state(scene, start)
    q, v = consistent_initial_state(scene, q, v, 0.0, project=bool(project))
    state = scheme.start(scene, State(0.0, q, v))
    n_steps = int(math.ceil(t_end / dt - 1e-9)) if t_end > 0 else 0
    rec = _Recorder(scene)
    sinks = list(output)
    rec.record(state, 0.0, 0, 0.0)
    for s in sinks:
        s.write(scene, state.t, state.q, state.v)
    work, halvings = 0.0, 0
    bar, bar_its = None, 0
    if progress:
        from tqdm import tqdm
        # shown only for runs longer than a second (delay); steps/s is tqdm's rate
        bar = tqdm(total=n_steps, unit="step", desc=f"{scene.name} [{scheme.name}]", leave=False,
                   file=sys.stderr, delay=1.0, mininterval=0.25, dynamic_ncols=True)
    if compiled is None:
        compiled = os.environ.get("SKFEM_FLEX_COMPILED", "1").strip() != "0"
    elif not isinstance(compiled, (bool, np.bool_)):
        raise ValueError(f"compiled must be True, False or None, got {compiled!r}")
    use_compiled = bool(compiled) and compiled_loop.eligible(scene, scheme)
    start = time.perf_counter()
    meta = dict(scheme=scheme.name, dt=dt)
    step = 0

    def recorded(state, work, its, vres, derived=None):
        rec.record(state, work, its, vres, derived)
        for s in sinks:
            s.write(scene, state.t, state.q, state.v)

    def advanced(n, its):
        nonlocal bar_its
        if bar is not None:
            bar_its += its
            bar.set_postfix_str(f"t={state.t:.4g}/{t_end:.4g} s, Newton {bar_its / step:.1f}/step", refresh=False)
            bar.update(n)
    try:
        while step < n_steps:
            if use_compiled:
                chunk = min(compiled_loop.chunk_steps(scene), n_steps - step)
                out = compiled_loop.run_chunk(scene, scheme, state, dt, t_end, step + 1, chunk, n_steps, record_every,
                                              work)
                for t_r, q_r, v_r, w_r, its_r, reac_r, derived in out["records"]:
                    recorded(State(t_r, q_r, v_r, lam=np.zeros(0), prescribed_force=reac_r), w_r, its_r, 0.0,
                             derived)
                if out["done"]:
                    state = State(out["t"], out["q"], out["v"], lam=np.zeros(0), prescribed_force=out["reaction"])
                    work = out["work"]
                    step += out["done"]
                    advanced(out["done"], out["iterations"])
                if out["status"] == compiled_loop.OK:
                    continue
            # the Python path: every step of ineligible runs, and a step the compiled loop could not finish
            step += 1
            h = min(dt, t_end - state.t) if step == n_steps else dt
            state, w, its, vres, nh = _advance(scheme, scene, state, h, max_halvings)
            work += w
            halvings += nh
            if step % record_every == 0 or step == n_steps:
                recorded(state, work, its, vres)
            advanced(1, its)
    except SimulationError as exc:
        exc.args = (f"{exc.args[0]} [step {step} of {n_steps}]",) + exc.args[1:]
        exc.info.update(step=step, time=state.t)
        res = rec.result(wall_time=time.perf_counter() - start, steps=step - 1, halvings=halvings,
                         completed=False, **meta)
        exc.result = res
        raise
    finally:
        if bar is not None:
            bar.close()
        for s in sinks:
            s.close()
    return rec.result(wall_time=time.perf_counter() - start, steps=n_steps, halvings=halvings, **meta)


def _start_state(scene, start):
    """(q, v) at t = 0 for ``simulate(..., start=...)``."""
    if isinstance(start, str):
        if start == "initial":
            return scene.initial_state()
        if start == "static":
            from .analysis import static_equilibrium
            return static_equilibrium(scene, 0.0).q, scene.initial_state()[1]
        raise ValueError(f"start must be 'initial', 'static', a (q, v) pair or a state, got {start!r}")
    q, v = start if isinstance(start, tuple) and len(start) == 2 else (getattr(start, "q", None),
                                                                         getattr(start, "v", None))
    if q is None or v is None:
        raise ValueError(f"start must be 'initial', 'static', a (q, v) pair or a state with q and v, got {start!r}")
    q, v = np.array(q, dtype=float).ravel(), np.array(v, dtype=float).ravel()
    if q.size != scene.n or v.size != scene.n:
        raise ValueError(f"start state must have {scene.n} coordinates and velocities, got {q.size} and {v.size}")
    return q, v


def _advance(scheme, scene, state, dt, depth):
    """One step of size dt, split in halves (recursively) when Newton fails."""
    try:
        new, info = scheme.step(scene, state, dt)
        if not (np.all(np.isfinite(new.q)) and np.all(np.isfinite(new.v))):
            raise ConvergenceError(f"{scheme.name}: state is not finite at t = {state.t + dt:.6g} s")
        return new, info.work, info.iterations, info.velocity_residual, 0
    except ConvergenceError as exc:
        if depth <= 0:
            raise ConvergenceError(f"{exc} — gave up at t = {state.t:.6g} s after halving the step "
                                   f"down to {dt:.3g} s", **exc.info) from None
        mid, w1, i1, _, n1 = _advance(scheme, scene, state, 0.5 * dt, depth - 1)
        end, w2, i2, vres, n2 = _advance(scheme, scene, mid, 0.5 * dt, depth - 1)
        return end, w1 + w2, i1 + i2, vres, 1 + n1 + n2
