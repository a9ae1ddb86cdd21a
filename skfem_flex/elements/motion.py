"""Motion laws: a function of time with its first and second derivatives.

Used for prescribed coordinates (a driven hub angle) and for drivers.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["MotionLaw", "Prescribed", "spin_up_law", "driven_frame"]


@dataclass(frozen=True)
class MotionLaw:
    """x(t), ẋ(t), ẍ(t) of a prescribed quantity.

    Parameters
    ----------
    position, velocity, acceleration : callable float -> float
        The law and its first two time derivatives (SI units of the
        quantity, per s, per s²). All three are required: the integrators
        need the velocity and acceleration to start and to step consistently.
    vectorized : bool
        The three also take an array of times and return the values there (numpy arithmetic, no
        branch on t; a constant may stay a scalar). :meth:`table` then evaluates a run's steps in
        three calls instead of three per step. Default False.
    """

    position: Callable
    velocity: Callable
    acceleration: Callable
    vectorized: bool = False

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

    def table(self, times):
        """(3, len(times)) array: x, ẋ, ẍ at each of ``times`` (s); one call per row when ``vectorized``."""
        times = np.asarray(times, dtype=float)
        if not self.vectorized:
            return np.array([self(float(t)) for t in times], dtype=float).reshape(times.size, 3).T
        return np.array([np.broadcast_to(np.asarray(f(times), dtype=float), times.shape)
                         for f in (self.position, self.velocity, self.acceleration)])

    @classmethod
    def constant_rate(cls, rate, start=0.0):
        """x = start + rate · t."""
        return cls(lambda t: start + rate * t, lambda t: rate, lambda t: 0.0, vectorized=True)


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


def driven_frame(body, axis, angle):
    r"""Prescribed entries that drive the frame of a spatial body with director coordinates (a spatial rigid
    body, a floating-frame beam or solid): its origin stays where it starts and its directors turn about the
    fixed unit ``axis`` a (global axes) by the angle law θ(t) (rad, θ(0) = 0 for a start in the initial state),

    .. math::

        d_i(t) = R(a, θ)\, d_i(0),\quad \dot d_i = \dotθ\, a × d_i,\quad
        \ddot d_i = \ddotθ\, a × d_i + \dotθ^2\, a × (a × d_i),

    with R(a, θ) the rotation by θ about a (Rodrigues). The twelve frame coordinates then follow laws, not
    Newton's equations: the body's elastic coordinates are the only unknowns it adds, and its rigidity
    equations, which the laws keep, are left out of the scene
    (:meth:`~skfem_flex.elements.constraints.quadratic.Rigidity.of_body`). This is the spatial form of a
    prescribed hub angle; the work of the laws enters the energy balance as for any prescribed coordinate.

    Parameters
    ----------
    body : Body
        With ``directors`` (the local offsets of d₁, d₂, d₃) and the origin x at local 0…2.
    axis : array_like (3,)
        Nonzero, finite; normalized here.
    angle : MotionLaw
        θ(t), θ̇(t), θ̈(t).

    Returns
    -------
    list of Prescribed
        Twelve, for ``Scene(..., prescribed=...)``.

    Raises
    ------
    ValueError
        If the body has no directors, ``axis`` is not a finite nonzero 3-vector or ``angle`` is not a
        MotionLaw.
    """
    offs = tuple(getattr(body, "directors", ()) or ())
    if len(offs) != 3:
        raise ValueError(f"driven_frame needs a body with three director coordinates, got {type(body).__name__}")
    a = np.asarray(axis, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0.0:
        raise ValueError(f"axis must be a finite nonzero 3-vector, got {axis!r}")
    if not isinstance(angle, MotionLaw):
        raise ValueError(f"angle must be a MotionLaw (θ and its two derivatives), got {angle!r}")
    a = a / np.linalg.norm(a)
    q0 = np.asarray(body.q0, dtype=float)
    out = [Prescribed(body, c, MotionLaw.constant_rate(0.0, float(q0[c]))) for c in range(3)]
    for o in offs:
        d = q0[o:o + 3]
        along, across, normal = a * (a @ d), d - a * (a @ d), np.cross(a, d)
        for c in range(3):
            # d(θ) = a(a·d) + cos θ (d − a(a·d)) + sin θ (a × d): its derivatives by the chain rule
            # the defaults bind this coordinate's numbers (a closure would see the loop's last ones)
            def pos(t, p=along[c], u=across[c], w=normal[c]):
                th = angle.position(t)
                return p + np.cos(th) * u + np.sin(th) * w

            def vel(t, u=across[c], w=normal[c]):
                th, rate = angle.position(t), angle.velocity(t)
                return rate * (-np.sin(th) * u + np.cos(th) * w)

            def acc(t, u=across[c], w=normal[c]):
                th, rate, al = angle.position(t), angle.velocity(t), angle.acceleration(t)
                return al * (-np.sin(th) * u + np.cos(th) * w) - rate * rate * (np.cos(th) * u + np.sin(th) * w)
            out.append(Prescribed(body, o + c, MotionLaw(pos, vel, acc, vectorized=angle.vectorized)))
    return out
