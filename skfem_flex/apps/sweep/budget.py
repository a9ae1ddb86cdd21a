"""The wall-clock budget of a sweep's case: an output sink that stops a run once its time is used up."""
from __future__ import annotations

import time

from ...errors import SimulationError

__all__ = ["BudgetExceeded", "WallClockBudget"]


class BudgetExceeded(SimulationError):
    """A run stopped because it used up its wall-clock budget (``result`` keeps its history)."""


class WallClockBudget:
    """Output sink that stops a run once it has used ``seconds`` of wall time.

    The clock starts at the first record (the initial state), after the run has compiled what it
    needs, so a cold cache does not eat the budget. It raises :class:`BudgetExceeded` at the first
    recorded step past the budget; :func:`~skfem_flex.run.simulate.simulate` then attaches the
    history so far to the exception.
    """

    def __init__(self, seconds):
        self.seconds, self.start = float(seconds), None

    def write(self, scene, t, q, v):
        now = time.perf_counter()
        if self.start is None:
            self.start = now
        if now - self.start > self.seconds:
            raise BudgetExceeded(f"stopped: wall-clock budget of {self.seconds:g} s used up at t = {t:.6g} s")

    def close(self):
        pass
