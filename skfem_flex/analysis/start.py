"""The consistent start of a state: accelerations, multipliers and prescribed forces that agree with (q, v)."""
from __future__ import annotations

import numpy as np

__all__ = ["consistent_start"]


def consistent_start(scene, t, q, v):
    """(q̈, λ, prescribed forces) consistent with (q, v) at time t, from the compiled step's start."""
    from ..schemes.stepper import Stepper
    from ..schemes import EnergyMomentum
    return Stepper(scene, EnergyMomentum()).start(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
