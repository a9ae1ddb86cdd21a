r"""A run from start to end: chunks of compiled steps, halving of the steps that fail, records, output sinks,
checkpoints, progress and signals — everything :func:`~skfem_flex.simulate` does around the loop.
"""
from __future__ import annotations

import math
import signal
import sys
import time
from pathlib import Path

import numpy as np

from ..compiled import registry
from ..compiled.abi import vector_view
from ..compiled.loop import REFUSED
from ..compiled.tasks import REFUSAL_ENERGY, REFUSAL_TURN, STATUS_PYTHON_ERROR
from ..errors import ConvergenceError, DivergenceError, Interrupted, OutputError, SimulationError
from ..numerics.newton import NONFINITE_RESIDUAL, NONFINITE_UPDATE, SINGULAR
from ..numerics.resources import check_fits
from ..numerics.rotations import MAX_INCREMENT
from ..scene_initial import consistent_initial_state
from .guard import DivergenceGuard
from .recorder import Recorder
from ..io.result import Result
from .signals import SignalStop
from ..schemes.stepper import Stepper

__all__ = ["Run", "CHECKPOINT_COST", "CHUNK_SECONDS"]

#: a checkpoint that took s seconds to save is followed by at least CHECKPOINT_COST · s seconds of run
CHECKPOINT_COST = 20.0
#: wall time a chunk of compiled steps aims at (Ctrl-C, progress and checkpoints are served between chunks)
CHUNK_SECONDS = 0.1
#: a chunk is at most this many times longer than the one before (its cost per step is estimated from that
#: one); each chunk costs some 30 µs of Python, so a short run of a small scene pays per chunk it takes
CHUNK_GROWTH = 16
_FAILURES = {NONFINITE_RESIDUAL: "residual is not finite (the solution escaped or the step is far too large)",
             NONFINITE_UPDATE: "Newton update is not finite", SINGULAR: "singular Newton matrix (redundant "
             "constraints or a coordinate without inertia or stiffness)"}
#: why a scheme refused a converged step itself (``ctx.refusal``, :mod:`skfem_flex.compiled.acceptance`)
_SCHEME_REFUSALS = {
    REFUSAL_TURN: f"an angle coordinate turned by {MAX_INCREMENT / np.pi:.1f}π or more in one step (too large a "
                  f"step for the rotation)",
    REFUSAL_ENERGY: "its energy rose by far more than the work of the loads explains (an implausible jump: too "
                    "large a step for the motion)"}


def _output_error(exc, t):
    where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
    return OutputError(f"could not write the output at t = {t:.6g} s: {exc.strerror or exc}{where}")


class Run:
    """One run of ``scene`` under ``scheme`` (see :func:`~skfem_flex.simulate` for the arguments)."""

    def __init__(self, scene, scheme, t_end, dt, recording, checkpointing, control, start, project, resume):
        self.scene, self.scheme, self.t_end, self.dt = scene, scheme, t_end, dt
        self.recording, self.checkpointing, self.control = recording, checkpointing, control
        self.start_spec, self.project, self.resume = start, project, resume
        self.n_steps = self._step_count()
        self.step = self.halvings = 0
        self.t = self.t_first = 0.0
        self.step_first = 0
        self.its = 0
        self.bar = None
        self.compile_time = 0.0
        self.compile0 = self.compile_loop0 = registry.compile_seconds()
        self.stepper = self.recorder = self.guard = None

    # ------------------------------------------------------------------ setup
    def _step_count(self):
        """Steps of the run; InsufficientMemoryError if its histories cannot fit in the memory available."""
        ratio = self.t_end / self.dt
        if not math.isfinite(ratio) or ratio > 1e15:
            raise ValueError(f"t_end / dt = {self.t_end!r} / {self.dt!r} asks for {ratio:.3g} steps; that run "
                             f"cannot end")
        n_steps = int(math.ceil(ratio - 1e-9)) if self.t_end > 0 else 0
        n_records = n_steps // self.recording.every + 2
        check_fits(n_records * (16 * self.scene.n + 400),
                   f"recording {n_records:.3g} states of {self.scene.n} coordinates (t_end = {self.t_end:g} s, "
                   f"dt = {self.dt:g} s, record_every = {self.recording.every})")
        return n_steps

    def _open(self, stop):
        """The stepper (compiling what this scene needs, answering Ctrl-C meanwhile) and the first state."""
        registry.set_interrupt_check(lambda: stop.signum)
        try:
            self.stepper = Stepper(self.scene, self.scheme, python_only=self.control.compiled is False)
        finally:
            registry.set_interrupt_check(None)
        if self.control.compiled is True and self.stepper.packed.python_elements:
            element, why = self.stepper.packed.python_elements[0]
            raise ValueError(f"compiled=True, but {type(element).__name__} {getattr(element, 'name', '')!r} has no "
                             f"compiled form ({why}); run it with compiled=None (through its Python methods)")
        self.recorder = Recorder(self.scene, self.stepper.packed)

    def _first_state(self):
        """The start (or the resumed state), loaded into the stepper and recorded."""
        scene, scheme = self.scene, self.scheme
        prior = self.resume
        if prior is None:
            q, v = self.start_spec
            q, v = consistent_initial_state(scene, q, v, 0.0, project=bool(self.project))
            acc, lam, reaction = self.stepper.start(0.0, q, v)
            state = scheme.make_state(0.0, q, v, acc=acc, pseudo=acc.copy(), lam=lam, prescribed_force=reaction)
            self.stepper.load(state)
            recs = self.stepper.record_now(0.0)
            self._write_sinks(0, recs)
            self.recorder.add(recs, 0, 1)
        else:
            fs = prior.final_state
            state = scheme.make_state(float(fs["t"]), **{
                k: np.array(fs[k], dtype=float) if np.size(fs.get(k, ())) or k in ("lam", "prescribed_force")
                else None for k in ("q", "v", "acc", "pseudo", "lam", "prescribed_force")})
            state.work = float(fs["work"])
            self.step, self.halvings, self.t = int(fs["step"]), int(fs["halvings"]), float(fs["t"])
            self.t_first, self.step_first = self.t, self.step
            self.stepper.load(state)
            self.recorder.prefill(prior)
            for s in self.recording.output:
                if hasattr(s, "resume"):
                    s.resume(scene, prior)
        rec = self.recorder
        self.guard = DivergenceGuard(scene, rec.first("q"), rec.history("kinetic"), rec.history("potential"),
                                     rec.history("external_work"))

    # ------------------------------------------------------------------ steps
    def _hs(self, k):
        """Sizes of the next k steps (the last step of the run lands on t_end)."""
        hs = np.full(k, self.dt)
        if self.step + k == self.n_steps:
            hs[-1] = max(self.t_end - self._time_of(self.n_steps - 1), 0.0) or self.dt
        return hs

    def _recorded(self, k):
        s = self.step + 1 + np.arange(k)
        return (s % self.recording.every == 0) | (s == self.n_steps)

    def _chunk(self, k):
        """Advance k steps (fewer if one fails: that one is halved). Returns the steps done."""
        hs, recorded = self._hs(k), self._recorded(k)
        ch = self.stepper.advance(self.t, hs, recorded, self.scheme.newton.max_iterations,
                                  self.scheme.newton.line_search, times=self._times(self.step + 1 + np.arange(k)))
        done = ch.steps
        self._stamp(self.step + 1 + np.flatnonzero(recorded[:done]), ch.records, ch.n_records)
        self._take(ch.records, ch.n_records)
        self.step += done
        self.t = self._time_of(self.step)
        self.its += ch.iterations
        if done < k:                    # step `done` failed: halve it
            self._fail_or_halve(ch, hs[done], bool(recorded[done]))
            done += 1
        return done

    def _fail_or_halve(self, ch, h, record):
        self._raise_python_error()
        if ch.status == SINGULAR and self.stepper.pivot():
            # the band plan's interior was singular (a coordinate without inertia of its own): the same step
            # again, factorized with pivoting from now on
            ch = self.stepper.advance(self.t, np.array([h]), np.array([record]), self.scheme.newton.max_iterations,
                                      self.scheme.newton.line_search, times=self._times(np.array([self.step + 1])))
            self.its += ch.iterations
            if ch.steps == 1:
                if record:
                    self._stamp(np.array([self.step + 1]), ch.records, ch.n_records)
                self._take(ch.records, ch.n_records)
                self.step += 1
                self.t = self._time_of(self.step)
                return
        recs, n_rec = self._halve(self.t, h, self.control.max_halvings, record, ch.status,
                                  end=self._time_of(self.step + 1))
        if record:
            self._stamp(np.array([self.step + 1]), recs, n_rec)
        self._take(recs, n_rec)
        self.step += 1
        self.t = self._time_of(self.step)

    def _time_of(self, step):
        """Time at the end of step ``step``: t₀ + (step − step₀) Δt, t_end for the last; the same whatever
        the chunks (a sum of step sizes would differ in its last bits from one chunking to another)."""
        return self.t_end if step == self.n_steps else self.t_first + (step - self.step_first) * self.dt

    def _times(self, steps):
        """:meth:`_time_of` of an array of step numbers (the same floating-point operations)."""
        return np.where(steps == self.n_steps, self.t_end, self.t_first + (steps - self.step_first) * self.dt)

    def _stamp(self, steps, records, n_rec):
        """The recorded steps' times from their numbers (:meth:`_times`: a Python loop over the records cost a
        third of a small scene's step)."""
        m = min(n_rec, steps.size)
        records.t[:m] = self._times(steps[:m])

    def _halve(self, t, h, depth, record, status, end=None):
        """Step (t, h) split in two halves, recursively (depth levels at most); the records of its end. ``end``:
        the exact time the step ends at (the run's time of the step; t + h by default), where its last
        half ends."""
        if depth <= 0:
            raise ConvergenceError(f"{self.scheme.name}: {self._why(status)} at t = {t + h:.6g} s — gave up after "
                                   f"halving the step down to {h:.3g} s", iterations=0, residual=float("nan"))
        self.halvings += 1
        recs = None
        end = t + h if end is None else end
        for half, rec in ((0, False), (1, record)):
            th = t + half * 0.5 * h
            stop = end if half else th + 0.5 * h
            ch = self.stepper.advance(th, np.array([0.5 * h]), np.array([rec]), self.scheme.newton.max_iterations,
                                      self.scheme.newton.line_search, times=np.array([stop]))
            self.its += ch.iterations
            if ch.steps == 1:
                recs = (ch.records, ch.n_records)
            else:
                self._raise_python_error()
                recs = self._halve(th, 0.5 * h, depth - 1, rec, ch.status, end=stop)
        return recs

    def _why(self, status):
        if status == REFUSED:
            c = self.stepper.ws.ctx[0]
            if not 0 <= int(c["bad_family"]) < len(self.stepper.packed.families):
                return f"the {self.scheme.name} step refused the step: " + _SCHEME_REFUSALS.get(
                    int(c["refusal"]), "the state is not finite")
            exc = self._refusal()
            return f"the {self.stepper.ws.family_name(int(c['bad_family']))} refused the step (" + (
                str(exc) if exc is not None else "an element folds inside out, turns by π or more in one step, "
                "or lost its direction") + ")"
        return _FAILURES.get(status, f"Newton did not converge within {self.scheme.newton.max_iterations} "
                                     f"iterations")

    def _refusal(self):
        """The error the refusing family's elements raise through their own methods at the refused state
        (at the loads' point or the step's end as the family's ``REFUSAL_STATE`` says), or None."""
        c = self.stepper.ws.ctx[0]
        k, families = int(c["bad_family"]), self.stepper.packed.families
        at_loads = 0 <= k < len(families) and getattr(families[k][0], "REFUSAL_STATE", "end") == "loads"
        q, v, t = ("qe", "ve", "te") if at_loads else ("q1", "v1", "t1")
        n = self.scene.n
        # the context holds the addresses of the vectors the refusing kernel read (the scheme's own data)
        q, v = (vector_view(c[name], n).copy() for name in (q, v))
        return self.stepper.refusal(q, v, float(c[t]))[1]

    def _raise_python_error(self):
        if self.stepper.ws.ctx[0]["status"] == STATUS_PYTHON_ERROR:
            self.stepper.raise_python_error()

    def _take(self, records, n_rec):
        """Records 0 … n_rec − 1: to the sinks, the divergence rule and the histories."""
        if n_rec == 0:
            return
        if self.recording.output:
            for i in range(n_rec):
                self._write_sinks(i, records)
                self._guarded(records, i, i + 1)
        else:
            self._guarded(records, 0, n_rec)

    def _guarded(self, records, a, b):
        beyond = self.guard.first_bound_violation(records.t[a:b], records.q[a:b])
        if beyond is not None:
            self.recorder.add(records, a, a + beyond[0] + 1)
            raise beyond[1]
        d = records.derived
        bad = self.guard.first_energy_violation(records.t[a:b], d[a:b, 0], d[a:b, 1], records.work[a:b])
        if bad is None:
            self.recorder.add(records, a, b)
            return
        self.recorder.add(records, a, a + bad + 1)
        self.guard.check_energy(float(records.t[a + bad]), *self.recorder.last_energy())

    def _write_sinks(self, i, records):
        for s in self.recording.output:
            try:
                s.write(self.scene, float(records.t[i]), records.q[i], records.v[i])
            except OSError as exc:
                raise _output_error(exc, float(records.t[i])) from None

    # ------------------------------------------------------------------ the run
    def execute(self):
        """Run; returns the :class:`Result` (raises a SimulationError carrying it when stopped early)."""
        stop = SignalStop(self.control.handle_signals)
        self.wall0, self.compile0 = time.perf_counter(), registry.compile_seconds()
        last_save, save_wait = self.wall0, self.checkpointing.every if self.checkpointing else 0.0
        try:
            self._open(stop)
            self._first_state()
            self.stepper.plan_sparse_lu(self.t, self.dt)
            self.stepper.advance(self.t, np.zeros(0), np.zeros(0, dtype=bool), 1, False)   # compiles the loop
            self.wall0, self.compile_loop0 = time.perf_counter(), registry.compile_seconds()
            self._open_bar()
            length = 1
            while self.step < self.n_steps:
                start = time.perf_counter()
                done = self._chunk(min(length, self.n_steps - self.step))
                spent = time.perf_counter() - start
                length = int(min(max(1, length * CHUNK_SECONDS / max(spent, 1e-6)), CHUNK_GROWTH * length + 1, 10_000))
                self.guard.check_state(self.t, *self.stepper.positions())
                self._progress(done)
                if stop.signum is not None:
                    raise Interrupted(f"interrupted at t = {self.t:.6g} s by {signal.Signals(stop.signum).name}",
                                      signal=stop.signum)
                if self.checkpointing and time.perf_counter() - last_save >= save_wait:
                    saving = time.perf_counter()
                    self._save_checkpoint(f"checkpoint at t = {self.t:.6g} s")
                    last_save = time.perf_counter()
                    save_wait = max(self.checkpointing.every, CHECKPOINT_COST * (last_save - saving))
        except SimulationError as exc:
            if not isinstance(exc, (Interrupted, DivergenceError, OutputError)):
                exc.args = (f"{exc.args[0]} [step {self.step + 1} of {self.n_steps}]",) + exc.args[1:]
            exc.info.update(step=self.step, time=self.t)
            exc.signal = exc.info.get("signal")
            if self.recorder is not None and self.recorder.count:
                exc.result = self._result(completed=False, stopped=str(exc.args[0]))
                if self.checkpointing and not isinstance(exc, OutputError):
                    self._save_checkpoint(str(exc.args[0]), result=exc.result)
            raise
        finally:
            stop.restore()
            if self.bar is not None:
                self.bar.close()
            for s in self.recording.output:
                s.close()
        result = self._result()
        if self.checkpointing:
            self._save_checkpoint("", result=result)
        return result

    def _save_checkpoint(self, why, result=None):
        res = result if result is not None else self._result(completed=False, stopped=why)
        try:
            res.save(Path(self.checkpointing.path))
        except OSError as exc:
            raise _output_error(exc, self.t) from None

    def _result(self, **extra):
        state = self.stepper.state(self.t)
        fs = {k: np.zeros(0) if getattr(state, k, None) is None else np.array(getattr(state, k), dtype=float)
              for k in ("q", "v", "acc", "pseudo", "lam", "prescribed_force")}
        fs.update(t=np.float64(self.t), work=np.float64(state.work), step=np.int64(self.step),
                  halvings=np.int64(self.halvings))
        pk = self.stepper.packed
        path = {"loop": "compiled", "solver": self.stepper.solver_name, "storage": "dense" if pk.storage == 0 else "sparse",
                "python_elements": [f"{type(e).__name__} {getattr(e, 'name', '')!r}: {why}"
                                    for e, why in pk.python_elements]}
        # compiles happen where a unit is first needed (building the stepper, the start, the first chunk):
        # all of them count as compile time, none as run time
        self.compile_time = registry.compile_seconds() - self.compile0
        in_loop = registry.compile_seconds() - self.compile_loop0
        return self.recorder.result(wall_time=max(time.perf_counter() - self.wall0 - in_loop, 0.0), steps=self.step,
                                    halvings=self.halvings, compile_time=self.compile_time, final_state=fs,
                                    scheme=self.scheme.name, dt=self.dt, run_path=path, **extra)

    # ------------------------------------------------------------------ progress
    def _open_bar(self):
        if not self.recording.progress:
            return
        from tqdm import tqdm
        # shown only for runs longer than a second (delay); the rate counts from the steps done when it opens
        self.bar = tqdm(total=self.n_steps, initial=min(self.step, self.n_steps), unit="step",
                        desc=f"{self.scene.name} [{self.scheme.name}]", leave=False, file=sys.stderr, delay=1.0,
                        mininterval=0.25, dynamic_ncols=True)

    def _progress(self, done):
        if self.bar is not None:
            self.bar.set_postfix_str(f"t={self.t:.4g}/{self.t_end:.4g} s, Newton "
                                     f"{self.its / max(self.step, 1):.1f}/step", refresh=False)
            self.bar.update(done)


def resume_source(resume, scene, scheme, dt):
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
