"""simulate(scene, t_end, dt, scheme=...) -> Result: the one entry point of a run."""
from __future__ import annotations

import numpy as np

from ..scene import Scene
from ..schemes import make_scheme
from .driver import Run, resume_source
from .options import Checkpointing, Control, Recording, finite_number
from .signals import SignalStop

__all__ = ["simulate", "SignalStop", "Recording", "Checkpointing", "Control"]


def simulate(scene, t_end, dt, scheme="energy-momentum", *, start="initial", project=True, record=None,
             checkpoint=None, resume=None, control=None, integrator=None, rho_inf=None, newton=None,
             record_every=None, output=None, progress=None, checkpoint_every=None, max_halvings=None, compiled=None,
             handle_signals=None):
    """Integrate a scene in time.

    Parameters
    ----------
    scene : Scene
    t_end : float
        End time, s (≥ 0).
    dt : float
        Step, s (> 0). The last step is shortened to land on t_end.
    scheme : str or scheme object
        ``"energy-momentum"`` (default), ``"trapezoidal"``, ``"generalized-alpha"``, or a scheme object
        (``sf.EnergyMomentum()``, ``sf.Trapezoidal()``, ``sf.GeneralizedAlpha(rho_inf=0.8)``, each taking
        ``newton=sf.NewtonSettings(...)``).
    start : "initial", "static", (q, v) or a state with ``q`` and ``v``
        ``"initial"`` (default): the scene's initial state. ``"static"``: the static equilibrium under
        the loads at t = 0 (:func:`~skfem_flex.static_equilibrium`) with the scene's initial velocities.
        A pair (q, v) or an object with ``q`` and ``v`` (an :class:`~skfem_flex.EquilibriumState`): that state.
    project : bool
        True (default): project the initial state onto the constraints (minimum-norm corrections of q0 and
        v0, prescribed coordinates kept; :func:`~skfem_flex.consistent_initial_state`); False: only check it.
        Either way redundant constraints raise.
    record : Recording, optional
        What is kept: ``Recording(every=1, output=(), progress=False)``.
    checkpoint : str, Path or Checkpointing, optional
        Save the histories and the scheme's state to this file every few seconds, on an interruption or
        error, and at the end, so that even a run killed outright can be read back
        (:meth:`~skfem_flex.Result.load`) and continued (``resume``).
    resume : Result, str or Path, optional
        Continue an earlier run (a Result, or the path of its saved result or checkpoint) from its last
        state: same scene, scheme and dt; the histories continue and sinks with a ``resume`` method append.
        The result equals that of an uninterrupted run to round-off.
    control : Control, optional
        How the run steps: ``Control(max_halvings=8, compiled=None, handle_signals=True)``.
    integrator, rho_inf, newton
        Shorthands: ``integrator`` names the scheme (as ``scheme``); ``rho_inf`` and ``newton`` build it
        (``rho_inf`` for generalized-α only).
    record_every, output, progress
        Shorthands for the fields of ``record``.
    checkpoint_every
        Seconds between checkpoints (shorthand for ``Checkpointing(path, every)``).
    max_halvings, compiled, handle_signals
        Shorthands for the fields of ``control``.

    Returns
    -------
    Result
        The histories; ``result.run_path`` says which code ran (the compiled loop, the solver, and every
        element that ran through its own Python methods, with the reason).

    Raises
    ------
    TypeError
        If ``scene`` is not a Scene or an output sink lacks ``write``/``close``.
    ValueError
        On bad arguments, redundant constraints or initial conditions that cannot be made consistent, or
        ``compiled=True`` with an element that has no compiled form (named).
    SimulationError
        Every way a run can stop early is one of its subclasses, each carrying ``exc.result`` (the histories
        up to the last good step, ``completed`` False, ``stopped`` saying why) with the output written so far
        kept: :class:`~skfem_flex.ConvergenceError` (a step failed even after halving),
        :class:`~skfem_flex.DivergenceError` (the state left every sane bound),
        :class:`~skfem_flex.Interrupted` (Ctrl-C or SIGTERM; ``exc.signal``),
        :class:`~skfem_flex.OutputError` (a file could not be written).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a skfem_flex.Scene, got {type(scene).__name__} {scene!r:.60}"
                        + (" (build a catalogue scene with skfem_flex.scenes.get(name)())"
                           if isinstance(scene, str) else ""))
    t_end, dt = finite_number("t_end", t_end), finite_number("dt", dt)
    if dt <= 0:
        raise ValueError(f"dt must be finite and positive, got {dt!r}")
    if t_end < 0:
        raise ValueError(f"t_end must be finite and >= 0, got {t_end!r}")
    if integrator is not None:
        if scheme != "energy-momentum":
            raise ValueError(f"give the scheme once: scheme={scheme!r} and integrator={integrator!r}")
        scheme = integrator
    scheme = make_scheme(scheme, rho_inf=rho_inf, newton=newton)
    record = _merged(record, Recording, every=record_every, output=output, progress=progress)
    control = _merged(control, Control, max_halvings=max_halvings, compiled=compiled, handle_signals=handle_signals)
    if checkpoint is not None and not isinstance(checkpoint, Checkpointing):
        checkpoint = Checkpointing(checkpoint, 5.0 if checkpoint_every is None else checkpoint_every)
    elif checkpoint is None and checkpoint_every is not None:
        finite_number("checkpoint_every", checkpoint_every)
    prior = resume_source(resume, scene, scheme, dt)
    state = None if prior is not None else _start_state(scene, start)
    return Run(scene, scheme, t_end, dt, record, checkpoint, control, state, project, prior).execute()


def _merged(options, cls, **shorthands):
    """``options`` (or the defaults of ``cls``) with the shorthands that were given."""
    given = {k: v for k, v in shorthands.items() if v is not None}
    if options is None:
        return cls(**given)
    if not isinstance(options, cls):
        raise TypeError(f"expected a {cls.__name__}, got {type(options).__name__}")
    if given:
        raise ValueError(f"give {', '.join(given)} inside the {cls.__name__} or as shorthands, not both")
    return options


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
