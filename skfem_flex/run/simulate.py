"""simulate(scene, t_end, dt, integrator=...) -> Result."""
from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np

from ..compiled import single_body_loop as compiled_loop
from ..compiled import scene_loop as compiled_scene
from ..errors import DivergenceError, Interrupted, OutputError
from ..scene_initial import consistent_initial_state
from ..schemes.integrators import ConvergenceError, SimulationError, State, make_integrator
from ..numerics.resources import check_fits
from .result import Result
from ..scene import Scene

__all__ = ["simulate", "SignalStop"]


class _Recorder:
    """Collects histories step by step or a compiled chunk at a time; builds a Result at any time.

    Each history is a list of blocks (arrays whose first axis runs over records), joined once when
    a Result is built: a chunk of a thousand records is stored as one array, not a thousand rows."""

    _KEYS = ("t", "q", "v", "lam", "kinetic", "potential", "external_work", "constraint_residual",
             "velocity_constraint_residual", "newton_iterations", "prescribed_force", "linear_momentum",
             "angular_momentum")

    def __init__(self, scene):
        self.scene = scene
        self.rows = {k: [] for k in self._KEYS}
        self.probes = {k: [] for k in scene.probes}
        self.with_momentum = None
        self.reactions = _reaction_maps(scene)
        self.reaction_rows = {k: [] for k, _ in self.reactions}
        self.count = 0

    def prefill(self, prior):
        """Start from the histories of an earlier run (``simulate(..., resume=...)``)."""
        for k in self.rows:
            val = getattr(prior, k, None)
            if val is not None:
                self.rows[k] = [np.asarray(val)]
        self.count = int(np.size(prior.t))
        self.with_momentum = prior.linear_momentum is not None
        for k in self.probes:
            if k not in prior.probes:
                raise ValueError(f"cannot resume: the earlier run has no probe {k!r}")
            self.probes[k] = [np.asarray(prior.probes[k])]
        for k in self.reaction_rows:
            if k in prior.reactions:
                self.reaction_rows[k] = [np.asarray(prior.reactions[k])]

    def first(self, key):
        """The first record of history ``key``."""
        return self.rows[key][0][0]

    def last(self, key):
        """The last record of history ``key``."""
        return self.rows[key][-1][-1]

    def last_energy(self):
        """(kinetic energy, potential energy, work done) of the last record, J."""
        return tuple(float(self.last(k)) for k in ("kinetic", "potential", "external_work"))

    def history(self, key):
        """History ``key`` as one array."""
        blocks = self.rows[key]
        return np.concatenate(blocks) if blocks else np.zeros(0)

    def record(self, state, work, iterations, vres):
        """Append one state of the Python path (energies, momenta, constraints and probes from the scene)."""
        s = self.scene
        q, v, t = state.q, state.v, state.t
        one = {"t": t, "q": q, "v": v, "lam": state.lam, "kinetic": s.kinetic_energy(q, v),
               "potential": s.potential_energy(q), "external_work": work,
               "constraint_residual": float(np.max(np.abs(s.constraint_value(q, t)))) if s.n_constraints else 0.0,
               "velocity_constraint_residual": vres, "newton_iterations": iterations,
               "prescribed_force": state.prescribed_force}
        if self.with_momentum is None:
            self.with_momentum = s.linear_momentum(q, v) is not None
        if self.with_momentum:
            one.update(linear_momentum=s.linear_momentum(q, v), angular_momentum=s.angular_momentum(q, v))
        for k, val in one.items():
            self.rows[k].append(np.array(val, dtype=int if k == "newton_iterations" else float)[None])
        for k, val in s.evaluate_probes(t, q, v).items():
            self.probes[k].append(np.asarray(val)[None])
        if self.reactions:
            lam = np.asarray(state.lam, dtype=float)
            for k, fn in self.reactions:
                self.reaction_rows[k].append(fn(q, lam)[None])
        self.count += 1

    def record_block(self, recs):
        """Append the recorded steps of a compiled chunk at once (``recs``: the ``records`` arrays of
        :func:`skfem_flex.compiled.single_body_loop.run_chunk`, one row per step)."""
        s, r = self.scene, self.rows
        n_rec = recs["t"].size
        if n_rec == 0:
            return
        q, v, lam, derived = recs["q"], recs["v"], recs["lam"], recs["derived"]
        block = {"t": recs["t"], "q": q, "v": v, "lam": lam, "kinetic": derived[:, 0], "potential": derived[:, 1],
                 "external_work": recs["work"], "constraint_residual": derived[:, 5],
                 "velocity_constraint_residual": derived[:, 6], "newton_iterations": recs["iterations"],
                 "prescribed_force": recs["reaction"]}
        if self.with_momentum is None:
            self.with_momentum = s.linear_momentum(q[0], v[0]) is not None
        if self.with_momentum:
            block.update(linear_momentum=derived[:, 2:4], angular_momentum=derived[:, 4])
        for k, val in block.items():
            r[k].append(val)
        for k, fn in s.probes.items():
            if k in recs["probes"]:
                self.probes[k].append(recs["probes"][k])
            else:
                self.probes[k].append(np.array([np.asarray(fn(s, t, qi, vi), dtype=float)
                                                for t, qi, vi in zip(recs["t"], q, v)]))
        if self.reactions:
            for (k, _), c, (idx, rows) in zip(self.reactions, s.constraints, s.constraint_layout):
                self.reaction_rows[k].append(np.asarray(c.reaction_history(q[:, idx], lam[:, rows]), dtype=float))
        self.count += n_rec

    def result(self, **meta):
        r = {k: np.asarray(self.history(k), dtype=float) for k in self.rows}
        r["newton_iterations"] = np.asarray(self.history("newton_iterations"), dtype=int)
        kin, pot = r["kinetic"], r["potential"]
        if not self.with_momentum:
            r["linear_momentum"] = None
            r["angular_momentum"] = None
        reactions = {k: np.asarray(np.concatenate(val) if val else np.zeros(0), dtype=float)
                     for k, val in self.reaction_rows.items()}
        probes = {k: np.concatenate(val) if val else np.zeros(0) for k, val in self.probes.items()}
        return Result(total_energy=kin + pot, probes=probes, reactions=reactions, **r, **meta)


def _reaction_maps(scene):
    """[(unique name, fn(q, lam) -> reaction)] for the scene's constraints (names made unique with #2, #3...)."""
    out = []
    for name, c, (idx, rows) in zip(scene.reaction_names, scene.constraints, scene.constraint_layout):
        def fn(q, lam, c=c, idx=idx, rows=rows):
            if lam.size != scene.n_constraints:
                return np.full(len(c.reaction_labels) or c.n_equations, np.nan)
            return np.atleast_1d(np.asarray(c.reaction(q[idx], lam[rows]), dtype=float))
        out.append((name, fn))
    return out


#: a checkpoint that took s seconds to save is followed by at least CHECKPOINT_COST · s seconds of run
#: (and ``checkpoint_every``): saving costs at most 1 / (CHECKPOINT_COST + 1) ≈ 5 % of the wall time
CHECKPOINT_COST = 20.0


def simulate(scene, t_end, dt, integrator="energy-momentum", rho_inf=None, newton=None, record_every=1,
             output=(), progress=False, max_halvings=8, project=True, compiled=None, start="initial", checkpoint=None,
             checkpoint_every=5.0, resume=None, handle_signals=True):
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
    output : sink or sequence of sinks
        Objects with ``write(scene, t, q, v)`` and ``close()``, called at the
        recorded steps (e.g. :class:`skfem_flex.run.output.VTKSeries`).
    progress : bool
        Show a tqdm progress bar on stderr, and say so on stderr before a
        first run compiles the Numba kernels (once per machine).
    max_halvings : int
        A step whose Newton iteration fails is split in two, recursively,
        at most this deep (≥ 0), before the run is given up.
    project : bool
        True (default): project the initial state onto the constraints
        (minimum-norm Gauss–Newton for q0, minimum-norm correction for v0,
        prescribed coordinates kept; see
        :func:`skfem_flex.scene_initial.consistent_initial_state`).
        False: only check it. Either way redundant constraints raise.
    compiled : bool, optional
        Run eligible scenes through a compiled loop (:mod:`skfem_flex.compiled.single_body_loop`: one
        floating-frame body alone under energy-momentum, dense or banded;
        :mod:`skfem_flex.compiled.scene_loop`: small scenes of built-in parts under energy-momentum,
        trapezoidal and generalized-α; docs/user_elements.md, "What is fast") — the same
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
    checkpoint : str or Path, optional
        File to which the histories so far and the integrator state are
        saved (:meth:`Result.save`, atomically) every ``checkpoint_every``
        seconds of wall time, so that a run killed outright (SIGKILL, power)
        can be read back with :meth:`Result.load` and continued with ``resume``.
    checkpoint_every : float
        Wall-clock seconds between checkpoints (> 0; default 5). Each save
        writes the whole history, so saves take longer as the run grows: after a
        save that took s seconds the next one waits max(checkpoint_every, 20·s)
        seconds (``CHECKPOINT_COST`` = 20), which keeps checkpointing below
        about 5 % of the run's wall time however long the run is.
    resume : Result or str or Path, optional
        Continue an earlier run (a Result, or the path of its saved result or
        checkpoint) from its last saved state: same scene, scheme and dt; the
        histories continue the earlier ones and output sinks with a ``resume``
        method (VTKSeries) append to their series. The result equals that of
        an uninterrupted run to round-off.
    handle_signals : bool
        While the loop runs (in the main thread), Ctrl-C (SIGINT) and SIGTERM
        finish the current step (or compiled chunk) and stop the run with
        :class:`~skfem_flex.errors.Interrupted`; a second signal stops at once.

    Returns
    -------
    Result

    Raises
    ------
    TypeError
        If ``scene`` is not a Scene or an output sink lacks ``write``/``close``.
    ValueError
        On bad arguments, redundant constraints
        (:class:`~skfem_flex.scene_initial.RedundantConstraintsError`) or
        initial conditions that cannot be made consistent
        (:class:`~skfem_flex.scene_initial.InconsistentInitialConditionsError`).
    ConvergenceError
        When a step fails even after halving.
    DivergenceError
        When the state becomes non-finite, a coordinate exceeds 10⁶ times the
        scene's size (:func:`_divergence_bounds`), or the energy exceeds 10⁶
        times its initial scale plus the work done.
    Interrupted
        On SIGINT/SIGTERM (``exc.signal``).

    Each of these SimulationErrors carries ``exc.result``, the history up to
    the last good step (``completed`` False, ``stopped`` saying why), and
    output sinks keep what they wrote.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a skfem_flex.Scene, got {type(scene).__name__} {scene!r:.60}"
                        + (" (build a catalogue scene with skfem_flex.scenes.get(name)())"
                           if isinstance(scene, str) else ""))
    t_end, dt = _finite_number("t_end", t_end), _finite_number("dt", dt)
    if dt <= 0:
        raise ValueError(f"dt must be finite and positive, got {dt!r}")
    if t_end < 0:
        raise ValueError(f"t_end must be finite and >= 0, got {t_end!r}")
    record_every = _count("record_every", record_every, 1)
    max_halvings = _count("max_halvings", max_halvings, 0)
    checkpoint_every = _finite_number("checkpoint_every", checkpoint_every)
    if checkpoint_every <= 0:
        raise ValueError(f"checkpoint_every must be a positive number of seconds, got {checkpoint_every!r}")
    sinks = _sinks(output)
    scheme = make_integrator(integrator, rho_inf=rho_inf, newton=newton)
    if compiled is None:
        compiled = os.environ.get("SKFEM_FLEX_COMPILED", "1").strip() != "0"
    elif not isinstance(compiled, (bool, np.bool_)):
        raise ValueError(f"compiled must be True, False or None, got {compiled!r}")
    # the compiled loop that runs this scene, if any: one floating-frame body alone, or a small mechanism
    loop = None
    if compiled:
        loop = next((m for m in (compiled_loop, compiled_scene) if m.eligible(scene, scheme)), None)
    use_compiled = loop is not None
    cold = compiled_loop.jit_cache_cold(scene)
    if cold and progress:
        print(compiled_loop.COMPILE_NOTICE, file=sys.stderr, flush=True)
    compile_start = time.perf_counter()
    n_steps = _step_count(scene, t_end, dt, record_every)
    rec = _Recorder(scene)
    prior = _resume_source(resume, scene, scheme, dt)
    if prior is None:
        q, v = _start_state(scene, start)
        q, v = consistent_initial_state(scene, q, v, 0.0, project=bool(project))
        state = scheme.start(scene, State(0.0, q, v))
        step, work, halvings = 0, 0.0, 0
        rec.record(state, 0.0, 0, 0.0)
        _write_sinks(sinks, scene, state)
    else:
        fs = prior.final_state
        # acc and pseudo are saved empty for the schemes that carry none
        state = scheme.make_state(float(fs["t"]), **{
            k: np.array(fs[k], dtype=float) if np.size(fs.get(k, ())) or k in ("lam", "prescribed_force") else None
            for k in ("q", "v", "acc", "pseudo", "lam", "prescribed_force")})
        step, work, halvings = int(fs["step"]), float(fs["work"]), int(fs["halvings"])
        rec.prefill(prior)
        for s in sinks:
            if hasattr(s, "resume"):
                s.resume(scene, prior)
    guard = _DivergenceGuard(scene, rec.first("q"), rec.history("kinetic"), rec.history("potential"),
                             rec.history("external_work"))
    bar, bar_its = None, 0

    def open_bar():
        from tqdm import tqdm
        # shown only for runs longer than a second (delay); steps/s is tqdm's rate, counted from the
        # steps done when the bar opens (initial)
        return tqdm(total=n_steps, initial=min(step, n_steps), unit="step", desc=f"{scene.name} [{scheme.name}]",
                    leave=False, file=sys.stderr, delay=1.0, mininterval=0.25, dynamic_ncols=True)

    # a first run that compiles opens its bar after the compiling step, so that no rate it shows
    # includes the compile time ("18 s/step")
    if progress and not cold:
        bar = open_bar()
    start = time.perf_counter()
    compile_time = 0.0
    meta = dict(scheme=scheme.name, dt=dt)
    last_checkpoint = start
    checkpoint_wait = checkpoint_every          # grows with the time a save takes (CHECKPOINT_COST)

    def recorded(state, work, its, vres):
        # the sinks first: a step whose output failed is not in the histories either, so that
        # the histories and the final state of the result stay those of one step
        _write_sinks(sinks, scene, state)
        rec.record(state, work, its, vres)
        guard.check_energy(state.t, *rec.last_energy())

    def advanced(n, its):
        nonlocal bar_its
        bar_its += its
        if bar is not None:
            bar.set_postfix_str(f"t={state.t:.4g}/{t_end:.4g} s, Newton {bar_its / max(step, 1):.1f}/step",
                                refresh=False)
            bar.update(n)

    def result(**extra):
        fs = {k: np.zeros(0) if getattr(state, k, None) is None else np.array(getattr(state, k), dtype=float)
              for k in ("q", "v", "acc", "pseudo", "lam", "prescribed_force")}
        fs.update(t=np.float64(state.t), work=np.float64(work), step=np.int64(step), halvings=np.int64(halvings))
        if not resumable:
            fs = None
        # start was reset after a compiling first step: wall_time is the loop's own time
        return rec.result(wall_time=time.perf_counter() - start, steps=step, halvings=halvings,
                          compile_time=compile_time, final_state=fs, **meta, **extra)

    resumable = True
    stop = SignalStop(handle_signals)
    try:
        first = True
        while step < n_steps:
            python_step = not use_compiled
            if use_compiled:
                chunk = min(1 if first and cold else loop.chunk_steps(scene), n_steps - step)
                out = loop.run_chunk(scene, scheme, state, dt, t_end, step + 1, chunk, n_steps, record_every, work)
                recs = out["records"]
                if sinks:                        # each state to the sinks first, then to the histories
                    for i in range(recs["t"].size):
                        s_r = State(float(recs["t"][i]), recs["q"][i], recs["v"][i], lam=recs["lam"][i],
                                    prescribed_force=recs["reaction"][i])
                        try:
                            _write_sinks(sinks, scene, s_r)
                        except OutputError:
                            if record_every == 1 and i:   # the result ends at the last step recorded
                                state, work, step = prev, float(recs["work"][i - 1]), step + i
                            elif record_every != 1:
                                resumable = False
                            raise
                        rec.record_block(_first_records(recs, i + 1, start=i))
                        guard.check_energy(s_r.t, *rec.last_energy())
                        prev = s_r
                else:
                    bad = guard.first_energy_violation(recs["t"], recs["derived"][:, 0], recs["derived"][:, 1],
                                                       recs["work"])
                    if bad is None:
                        rec.record_block(recs)
                    else:                        # the histories end at the record the rule stops at
                        rec.record_block(_first_records(recs, bad + 1))
                        guard.check_energy(float(recs["t"][bad]), *rec.last_energy())
                if out["done"]:
                    state = scheme.make_state(out["t"], out["q"], out["v"], acc=out["acc"], pseudo=out.get("pseudo"),
                                              lam=out["lam"], prescribed_force=out["reaction"])
                    work = out["work"]
                    step += out["done"]
                    advanced(out["done"], out["iterations"])
                # a step the compiled loop could not finish goes the Python way (which halves or raises)
                python_step = out["status"] != loop.OK
            if python_step:
                state, work, halvings, its = _python_step(scheme, scene, state, dt, t_end, step + 1, n_steps,
                                                          max_halvings, work, halvings, record_every, recorded)
                step += 1
                advanced(1, its)
            if first:
                first = False
                if cold:                     # the first call compiled the kernels: report it on its own
                    compile_time = time.perf_counter() - compile_start
                    start = last_checkpoint = time.perf_counter()
                    if progress:
                        bar = open_bar()
                        advanced(0, 0)       # the postfix (t, Newton/step), no steps
            guard.check_state(state)
            if stop.signum is not None:
                raise Interrupted(f"interrupted at t = {state.t:.6g} s by {signal.Signals(stop.signum).name}",
                                  signal=stop.signum)
            if checkpoint is not None and time.perf_counter() - last_checkpoint >= checkpoint_wait:
                saving = time.perf_counter()
                try:
                    result(completed=False, stopped=f"checkpoint at t = {state.t:.6g} s").save(checkpoint)
                except OSError as exc:
                    raise _output_error(exc, state.t) from None
                last_checkpoint = time.perf_counter()
                checkpoint_wait = max(checkpoint_every, CHECKPOINT_COST * (last_checkpoint - saving))
    except SimulationError as exc:
        if not isinstance(exc, (Interrupted, DivergenceError, OutputError)):
            exc.args = (f"{exc.args[0]} [step {step + 1} of {n_steps}]",) + exc.args[1:]
        exc.info.update(step=step, time=state.t)
        exc.signal = exc.info.get("signal")
        exc.result = result(completed=False, stopped=str(exc.args[0]))
        raise
    finally:
        stop.restore()
        if bar is not None:
            bar.close()
        for s in sinks:
            s.close()
    return result()


def _first_records(recs, stop, start=0):
    """Records ``start … stop − 1`` of a compiled chunk's records."""
    return {k: ({p: a[start:stop] for p, a in val.items()} if k == "probes" else val[start:stop])
            for k, val in recs.items()}


def _step_count(scene, t_end, dt, record_every):
    """Steps of the run; InsufficientMemoryError if its histories cannot fit in the memory available."""
    ratio = t_end / dt
    if not math.isfinite(ratio) or ratio > 1e15:
        raise ValueError(f"t_end / dt = {t_end!r} / {dt!r} asks for {ratio:.3g} steps; that run cannot end")
    n_steps = int(math.ceil(ratio - 1e-9)) if t_end > 0 else 0
    n_records = n_steps // record_every + 2
    # q and v per record (Python lists of arrays: ~100 bytes of overhead each) plus ~16 scalars
    check_fits(n_records * (16 * scene.n + 400), f"recording {n_records:.3g} states of {scene.n} coordinates "
                                                 f"(t_end = {t_end:g} s, dt = {dt:g} s, record_every = {record_every})")
    return n_steps


def _write_sinks(sinks, scene, state):
    for s in sinks:
        try:
            s.write(scene, state.t, state.q, state.v)
        except OSError as exc:
            raise _output_error(exc, state.t) from None


def _output_error(exc, t):
    where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
    return OutputError(f"could not write the output at t = {t:.6g} s: {exc.strerror or exc}{where}")


def _finite_number(name, x):
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, got {type(x).__name__} {x!r:.40}")
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return x


def _count(name, x, minimum):
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer, float)) or int(x) != x \
            or int(x) < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {x!r}")
    return int(x)


def _sinks(output):
    """The output sinks as a list; a single sink is accepted as well as a sequence of them."""
    if output is None:
        return []
    if hasattr(output, "write") and hasattr(output, "close"):
        return [output]
    try:
        sinks = list(output)
    except TypeError:
        raise TypeError(f"output must be a sink with write() and close() or a sequence of them, "
                        f"got {type(output).__name__}") from None
    for s in sinks:
        if not (callable(getattr(s, "write", None)) and callable(getattr(s, "close", None))):
            raise TypeError(f"output sinks need write(scene, t, q, v) and close() methods, got {type(s).__name__}")
    return sinks


def _python_step(scheme, scene, state, dt, t_end, step, n_steps, max_halvings, work, halvings, record_every,
                 recorded):
    """Step number ``step`` on the Python path (halving on failure); records it when due.

    Returns (state, work, halvings, Newton iterations of the step)."""
    h = min(dt, t_end - state.t) if step == n_steps else dt
    state, w, its, vres, nh = _advance(scheme, scene, state, h, max_halvings)
    work += w
    halvings += nh
    if step % record_every == 0 or step == n_steps:
        recorded(state, work, its, vres)
    return state, work, halvings, its


def _resume_source(resume, scene, scheme, dt):
    """The earlier Result to continue (None for a fresh run), checked against this run's settings."""
    if resume is None:
        return None
    prior = resume if isinstance(resume, Result) else Result.load(Path(resume))
    fs = prior.final_state
    if not isinstance(fs, dict) or not {"t", "q", "v", "step", "work", "halvings"} <= set(fs):
        raise ValueError("cannot resume: the earlier result holds no final integrator state "
                         "(saved by a version without resume support?)")
    if np.shape(fs["q"]) != (scene.n,):
        raise ValueError(f"cannot resume: the earlier run has {np.size(fs['q'])} coordinates, this scene {scene.n}")
    if prior.scheme != scheme.name:
        raise ValueError(f"cannot resume: the earlier run used {prior.scheme!r}, this one {scheme.name!r}")
    if not math.isclose(float(prior.dt), dt, rel_tol=1e-12):
        raise ValueError(f"cannot resume: the earlier run used dt = {prior.dt!r} s, this one {dt!r} s")
    return prior


class SignalStop:
    """While alive (main thread only), SIGINT/SIGTERM set ``signum`` instead of stopping the program;
    a second signal raises KeyboardInterrupt at once. ``restore()`` puts the earlier handlers back.

    The time loop polls ``signum`` between steps; the CLI also holds signals this way while it
    writes a run's outputs, so that they are complete."""

    def __init__(self, enabled):
        self.signum, self.old = None, {}
        if enabled and threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                if signal.getsignal(sig) is signal.SIG_IGN:     # e.g. SIGINT of a background job: keep ignoring
                    continue
                self.old[sig] = signal.signal(sig, self._handler)

    def _handler(self, signum, frame):
        if self.signum is not None:
            self.restore()
            raise KeyboardInterrupt(f"second {signal.Signals(signum).name}")
        self.signum = signum

    def restore(self):
        for sig, handler in self.old.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
        self.old = {}


#: a run is diverged when a coordinate exceeds this many times the scene's size, or the energy this
#: many times its initial scale plus the work done
DIVERGENCE_FACTOR = 1e6
#: recorded states over which the energy scale of the divergence rule is taken
_SCALE_RECORDS = 10


class _DivergenceGuard:
    """Stops runs whose solution left every sane bound (DivergenceError, "diverged at t = …").

    * a coordinate or velocity is not finite;
    * a coordinate exceeds 10⁶ × max(scene size, largest initial coordinate, 1) — lengths in m,
      angles in rad (a body spinning at 10 rad/s needs 10⁵ s to reach it);
    * |T + V| exceeds 10⁶ × (E_s + max |W|), W the work done so far and E_s the largest |T| + |V|
      of the first :data:`_SCALE_RECORDS` recorded states (the scale a run released from rest
      establishes in its first steps; energy-conserving schemes keep T + V = E₀ + W, so this
      catches the others).
    """

    def __init__(self, scene, q0, kinetic, potential, work):
        """``q0``: the first recorded coordinates; ``kinetic``, ``potential``, ``work``: the records so far
        (J; at least one)."""
        q0 = np.asarray(q0, dtype=float)
        size = max(float(scene.length_scale), float(np.max(np.abs(q0), initial=0.0)), 1.0)
        self.q_bound = DIVERGENCE_FACTOR * size
        kinetic, potential = np.asarray(kinetic, dtype=float), np.asarray(potential, dtype=float)
        self.e_scale = float(np.max(np.abs(kinetic[:_SCALE_RECORDS]) + np.abs(potential[:_SCALE_RECORDS])))
        self.w_max = float(np.max(np.abs(np.asarray(work, dtype=float)), initial=0.0))
        self.count = kinetic.size

    def check_state(self, state):
        if not (np.all(np.isfinite(state.q)) and np.all(np.isfinite(state.v))):
            raise DivergenceError(f"diverged at t = {state.t:.6g} s: the state is not finite")
        big = float(np.max(np.abs(state.q), initial=0.0))
        if big > self.q_bound:
            raise DivergenceError(f"diverged at t = {state.t:.6g} s: a coordinate reached {big:.3g}, more than "
                                  f"{DIVERGENCE_FACTOR:.0e} times the scene's size ({self.q_bound / DIVERGENCE_FACTOR:.3g})")

    def first_energy_violation(self, t, kinetic, potential, work):
        """Index of the first record of a compiled block (not yet stored) at which :meth:`check_energy`
        would stop the run, or None; the guard's energy scale and work bound advance over the
        records before it (then store the block up to that record and call :meth:`check_energy`)."""
        first = self.count                                     # index of the block's first record
        n_early = min(t.size, max(0, _SCALE_RECORDS - first))  # these still set the scale: in order
        for i in range(n_early):
            w_max = max(self.w_max, abs(work[i]))
            e_scale = max(self.e_scale, abs(kinetic[i]) + abs(potential[i]))
            if self._violated(kinetic[i] + potential[i], e_scale + w_max):
                return i
            self.w_max, self.e_scale = w_max, e_scale
            self.count += 1
        if n_early == t.size:
            return None
        w_max = np.maximum.accumulate(np.fmax(np.abs(work[n_early:]), self.w_max))
        energy = kinetic[n_early:] + potential[n_early:]
        scale = self.e_scale + w_max
        bad = ~np.isfinite(energy) | ((scale > 0) & (np.abs(energy) > DIVERGENCE_FACTOR * scale))
        if bad.any():
            i = int(np.argmax(bad))
            if i:
                self.w_max = float(w_max[i - 1])
            self.count += i
            return n_early + i
        self.w_max = float(w_max[-1])
        self.count += t.size - n_early
        return None

    @staticmethod
    def _violated(energy, scale):
        return not math.isfinite(energy) or (scale > 0 and abs(energy) > DIVERGENCE_FACTOR * scale)

    def check_energy(self, t, kinetic, potential, work):
        """The energy rule at the next record: time ``t`` (s), kinetic and potential energy and the
        work done so far (J)."""
        self.count += 1
        self.w_max = max(self.w_max, abs(work))
        energy = kinetic + potential
        if self.count <= _SCALE_RECORDS:
            self.e_scale = max(self.e_scale, abs(kinetic) + abs(potential))
        scale = self.e_scale + self.w_max
        if self._violated(energy, scale):
            raise DivergenceError(f"diverged at t = {t:.6g} s: energy {energy:.3g} J against an initial energy "
                                  f"scale plus work done of {scale:.3g} J")


def _start_state(scene, start):
    """(q, v) at t = 0 for ``simulate(..., start=...)``."""
    if isinstance(start, str):
        if start == "initial":
            return scene.initial_state()
        if start == "static":
            from ..analysis import static_equilibrium
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
