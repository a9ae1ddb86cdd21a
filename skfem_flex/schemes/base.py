r"""What every time-stepping scheme is: an object that owns its step (a compiled kernel), its parameters,
its Newton settings and the dataclass of its state.

Systems::

    d/dt (M(q) q̇) − ∂T/∂q + ∇V(q) + Φ_qᵀ λ = Q(q, q̇, t),     Φ(q, t) = 0

Every scheme solves for the increment Δq = q_{n+1} − q_n (never for q_{n+1} itself, so that v_{n+1}
keeps its digits as q grows) and μ = Δt λ with the package's one Newton core
(:mod:`skfem_flex.numerics.newton`), in the compiled loop (:mod:`skfem_flex.compiled.loop`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from ..numerics.newton import NewtonSettings

__all__ = ["Scheme", "State", "NewmarkState", "NewtonSettings"]


@dataclass
class State:
    """A scheme's state at one instant (the energy-momentum scheme's; the Newmark family adds ``pseudo``).

    Attributes
    ----------
    t : float
        Time, s.
    q, v : ndarray
        Coordinates and velocities (global vectors).
    acc : ndarray
        Acceleration q̈: consistent at the start, then the energy-momentum step's mean acceleration
        (v_{n+1} − v_n)/Δt (its Newton start) or the Newmark schemes' q̈_{n+1}.
    lam : ndarray
        Lagrange multipliers λ (for the energy scheme the mean over the last step), N or N m.
    prescribed_force : ndarray
        Generalized force the prescribed coordinates' laws exert (the last step's).
    work : float
        Work done on the system by loads, prescribed motion and drivers since the start, J.
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    acc: np.ndarray = None
    lam: np.ndarray = field(default_factory=lambda: np.zeros(0))
    prescribed_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work: float = 0.0


@dataclass
class NewmarkState(State):
    """The state of the Newmark family: :class:`State` and the algorithmic acceleration.

    Attributes
    ----------
    pseudo : ndarray
        Generalized-α's algorithmic acceleration a (m/s², rad/s²); q̈ itself for α_m = α_f = 0.
    """

    pseudo: np.ndarray = None


class Scheme:
    """Base class: a named scheme that owns its compiled step.

    Parameters
    ----------
    newton : NewtonSettings, optional
        Tolerances, iteration cap and line search of the Newton core.
    """

    name = "scheme"
    #: the dataclass of this scheme's state
    state_type = State
    #: loads are evaluated at the step's mid-point (True) or at its end (False)
    mid_point_loads = False

    def __init__(self, newton=None):
        self.newton = NewtonSettings() if newton is None else newton
        if not isinstance(self.newton, NewtonSettings):
            raise ValueError(f"newton must be NewtonSettings, got {self.newton!r}")

    def kernel(self):
        """The compiled step (a ``numba.cfunc`` of :mod:`skfem_flex.compiled.abi`)."""
        raise NotImplementedError

    def pack_state(self, packed, state):
        """The scheme's data record (:class:`~skfem_flex.compiled.abi.Fields`) holding ``state``."""
        raise NotImplementedError

    def unpack_state(self, fields, t):
        """The state held in the data record, at time t (arrays copied)."""
        raise NotImplementedError

    def make_state(self, t, q, v, **values):
        """This scheme's state (:attr:`state_type`) at time ``t`` (s) from (q, v) and the named values it
        carries; values it does not carry (``pseudo`` for energy-momentum) are left out."""
        names = {f.name for f in fields(self.state_type)}
        return self.state_type(float(t), q, v, **{k: x for k, x in values.items() if k in names})

    def __repr__(self):
        return f"{type(self).__name__}()"
