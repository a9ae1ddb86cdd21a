"""Exceptions shared by bodies, integrators and the simulation driver: one family.

Every way a computation of the package can fail *after* its input was accepted is a
:class:`SimulationError`, so that one ``except sf.SimulationError`` catches all of them
(and the command line maps each to its exit status)::

    SimulationError (RuntimeError)       a run, solve or output that could not go on
    ├── ConvergenceError                 Newton–Raphson failed (time step, static solve, load step)
    │   └── ElementInversionError        an exact-beam element folds inside out
    │                                    (skfem_flex.bodies.exact.strain; also a ValueError)
    ├── DivergenceError                  the solution left every sane bound (non-finite, blown up)
    ├── Interrupted                      stopped by a signal (Ctrl-C, SIGTERM) after a whole step
    └── OutputError                      an output (VTK frame, checkpoint) could not be written

Bad input is not in the family: arguments that cannot be used raise ``ValueError`` (or
``TypeError``) before anything is computed, naming the value and what was expected
(:class:`~skfem_flex.scene_initial.RedundantConstraintsError`,
:class:`~skfem_flex.scene_initial.InconsistentInitialConditionsError` and
:class:`~skfem_flex.numerics.resources.InsufficientMemoryError` are such value errors).

The classes are defined here and nowhere else; the package root re-exports them
(``sf.SimulationError`` is this class), as may modules that raise them. They live in their own
module so that bodies can raise them without importing the integrators (imports point one
way: docs/ARCHITECTURE.md).

Attributes common to the family
-------------------------------
info : dict
    What the raiser knew (iterations, residual, time, step, load factor ...).
result : Result or None
    The steps done before the failure, set by :func:`~skfem_flex.simulate` (None elsewhere).
"""

__all__ = ["SimulationError", "ConvergenceError", "Interrupted", "DivergenceError", "OutputError"]


class SimulationError(RuntimeError):
    """A run that could not go on: the base of every failure of the package (see the module notes).

    Parameters
    ----------
    message : str
        One line saying what failed, where (time, step, load factor) and why.
    **info
        What the raiser knew, kept as :attr:`info`.

    Attributes
    ----------
    info : dict
    result : Result or None
        The steps done so far (set by ``simulate``; None elsewhere).
    """

    def __init__(self, message, **info):
        super().__init__(message)
        self.info = info
        self.result = None


class ConvergenceError(SimulationError):
    """Newton–Raphson failed: the message names scheme, time, step, residual and iterations."""


class Interrupted(SimulationError):
    """The run was stopped by a signal (Ctrl-C, SIGTERM) after finishing its current step.

    ``signal`` is the signal number; ``result`` holds every step done (``completed`` False).
    """


class DivergenceError(SimulationError):
    """The solution left every sane bound (non-finite, coordinates or energy grown by orders of
    magnitude): the run is stopped rather than reported as a success."""


class OutputError(SimulationError):
    """An output (VTK frame, checkpoint) could not be written: disk full, no permission."""
