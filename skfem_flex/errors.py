"""Exceptions shared by bodies, integrators and the simulation driver.

They live in their own module so that bodies can raise them without
importing the integrators (imports point one way: DESIGN.md §2).
"""

__all__ = ["SimulationError", "ConvergenceError"]


class SimulationError(RuntimeError):
    """A run that could not go on. ``result`` holds the steps done so far (set by ``simulate``)."""

    def __init__(self, message, **info):
        super().__init__(message)
        self.info = info
        self.result = None


class ConvergenceError(SimulationError):
    """Newton–Raphson failed: the message names scheme, time, step, residual and iterations."""
