"""Result of a simulation: time histories as arrays."""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

__all__ = ["Result"]


@dataclass
class Result:
    """Histories recorded at the output steps of a run (SI units).

    Attributes
    ----------
    t : ndarray (n,)
        Times, s.
    q, v : ndarray (n, n_dofs)
        Coordinates and velocities.
    lam : ndarray (n, n_constraints)
        Lagrange multipliers (energy-momentum: mean over the step ending there).
    kinetic, potential, total_energy : ndarray (n,)
        T, V and T + V, J.
    external_work : ndarray (n,)
        Work done since t = 0 by non-conservative loads, prescribed motion and
        drivers, J; the energy balance is total_energy − total_energy[0] = external_work.
    constraint_residual : ndarray (n,)
        max |Φ(q, t)| after each step.
    velocity_constraint_residual : ndarray (n,)
        max |Φ_q v + Φ_t|.
    newton_iterations : ndarray (n,)
        Newton iterations spent on the steps ending at each output time.
    prescribed_force : ndarray (n, n_prescribed)
        Generalized force exerted by prescribed-coordinate laws.
    linear_momentum : ndarray (n, 2) or None
    angular_momentum : ndarray (n,) or None
        About the global origin; None when a body does not provide it.
    probes : dict of str to ndarray
        Probe histories, first axis time.
    wall_time : float
        Seconds spent in the time loop.
    scheme : str
    dt : float
        Nominal step, s.
    steps : int
        Steps taken (halved steps count as one).
    halvings : int
        Steps that had to be split to converge.
    completed : bool
        False when the run stopped early (the exception carries this result).
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    total_energy: np.ndarray
    external_work: np.ndarray
    constraint_residual: np.ndarray
    velocity_constraint_residual: np.ndarray
    newton_iterations: np.ndarray
    prescribed_force: np.ndarray
    linear_momentum: np.ndarray = None
    angular_momentum: np.ndarray = None
    probes: dict = field(default_factory=dict)
    wall_time: float = 0.0
    scheme: str = ""
    dt: float = 0.0
    steps: int = 0
    halvings: int = 0
    completed: bool = True

    @property
    def energy_balance_error(self):
        """total_energy − total_energy[0] − external_work, J."""
        return self.total_energy - self.total_energy[0] - self.external_work

    def relative_energy_error(self, reference=None):
        """max |energy balance error| / reference (default: max(|T| + |V|) over the run)."""
        if reference is None:
            reference = float(np.max(np.abs(self.kinetic) + np.abs(self.potential)))
        return float(np.max(np.abs(self.energy_balance_error))) / max(reference, 1e-300)

    def array_fields(self):
        """Names of the array-valued attributes."""
        return [f.name for f in fields(self) if isinstance(getattr(self, f.name), np.ndarray)]
