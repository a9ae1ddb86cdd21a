"""Motion laws: a function of time with its first and second derivatives.

Used for prescribed coordinates (a driven hub angle) and for drivers.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["MotionLaw", "Prescribed", "spin_up_law"]


@dataclass(frozen=True)
class MotionLaw:
    """x(t), ẋ(t), ẍ(t) of a prescribed quantity.

    Parameters
    ----------
    position, velocity, acceleration : callable float -> float
        The law and its first two time derivatives (SI units of the
        quantity, per s, per s²). All three are required: the integrators
        need the velocity and acceleration to start and to step consistently.
    """

    position: Callable
    velocity: Callable
    acceleration: Callable

    def __post_init__(self):
        for field_name in ("position", "velocity", "acceleration"):
            if not callable(getattr(self, field_name)):
                raise ValueError(
                    f"MotionLaw needs callables for position, velocity and acceleration; "
                    f"{field_name} is {getattr(self, field_name)!r}")
        for field_name in ("position", "velocity", "acceleration"):
            val = getattr(self, field_name)(0.0)
            if not np.isfinite(float(val)):
                raise ValueError(f"MotionLaw {field_name}(0) is not finite: {val!r}")

    def __call__(self, t):
        """(x, ẋ, ẍ) at time t."""
        return float(self.position(t)), float(self.velocity(t)), float(self.acceleration(t))

    @classmethod
    def constant_rate(cls, rate, start=0.0):
        """x = start + rate · t."""
        return cls(lambda t: start + rate * t, lambda t: rate, lambda t: 0.0)


@dataclass(frozen=True)
class Prescribed:
    """A coordinate of a body that follows a motion law instead of being solved for.

    Parameters
    ----------
    body : Body
    coordinate : str or int
        Name (e.g. ``"theta"``) or local index of the coordinate.
    law : MotionLaw
    """

    body: object
    coordinate: object
    law: MotionLaw

    def __post_init__(self):
        if not isinstance(self.law, MotionLaw):
            raise ValueError(f"Prescribed needs a MotionLaw with derivatives, got {self.law!r}")
        self.body.coordinate_index(self.coordinate)


def spin_up_law(omega=4.0, period=15.0):
    """Hub angle of the spin-up manoeuvre of Simo & Vu-Quoc (1986).

    θ(t) = (ω_s/T_s)(t²/2 + (T_s/2π)²(cos(2πt/T_s) − 1)) for t < T_s and
    θ(t) = ω_s (t − T_s/2) after (docs/scenes.md). The rate rises smoothly
    from 0 to ω_s (rad/s) within T_s (s).
    """
    w, ts = float(omega), float(period)
    if not np.isfinite(w):
        raise ValueError(f"omega must be finite, got {omega!r}")
    if not np.isfinite(ts) or ts <= 0:
        raise ValueError(f"spin-up period T must be finite and positive, got {period!r}")
    c = ts / (2 * np.pi)

    def pos(t):
        if t < ts:
            return w / ts * (0.5 * t * t + c * c * (np.cos(t / c) - 1.0))
        return w * (t - 0.5 * ts)

    def vel(t):
        if t < ts:
            return w / ts * (t - c * np.sin(t / c))
        return w

    def acc(t):
        if t < ts:
            return w / ts * (1.0 - np.cos(t / c))
        return 0.0

    return MotionLaw(pos, vel, acc)
