"""Exceptions shared by bodies, integrators and the simulation driver.

They live in their own module so that bodies can raise them without
importing the integrators (imports point one way: docs/ARCHITECTURE.md).
"""

__all__ = ["SimulationError", "ConvergenceError", "Interrupted", "DivergenceError", "OutputError"]


class SimulationError(RuntimeError):
    """A run that could not go on. ``result`` holds the steps done so far (set by ``simulate``)."""

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
