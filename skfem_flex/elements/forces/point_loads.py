"""Loads at body points: a force (global or following the body) and a moment, with their time functions
(:class:`PointForce`, :class:`PointMoment`, :func:`time_function`, :func:`half_sine_pulse`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import BodyPoint, check_finite_vector, keeps_methods
from ...bodies.rigid import E_MATRIX, rotation
from ..point_terms import PointLayout, Position, angle_term
from .base import ForceElement

__all__ = ["PointForce", "PointMoment", "time_function", "half_sine_pulse"]


def time_function(value, size, name="load"):
    """A callable t -> array (size,) from a constant or a callable.

    Parameters
    ----------
    value : float, array_like or callable
        A constant (broadcast to ``size``) or a function of time t (s).
    size : int
        1 for scalars (moments), 2 for vectors (forces).
    name : str
        Used in error messages.
    """
    if callable(value):
        probe = np.atleast_1d(np.asarray(value(0.0), dtype=float)).ravel()
        if probe.size != size:
            raise ValueError(f"{name}(t) must return {size} value(s), got {probe.size}")

        def fun(t):
            out = np.atleast_1d(np.asarray(value(t), dtype=float)).ravel()
            if not np.all(np.isfinite(out)):
                raise ValueError(f"{name}({t!r}) is not finite: {out!r}")
            return out
        # the compiled loop tabulates a chunk of steps at once and checks the whole table (``fun``
        # raises the error for the first entry that is not finite)
        fun.unchecked = value
        return fun
    const = check_finite_vector(name, value, size)
    return lambda t: const


def half_sine_pulse(amplitude, duration, start=0.0):
    """F(t) = amplitude · sin(π (t − start)/duration) for start ≤ t ≤ start + duration, zero otherwise.

    Parameters
    ----------
    amplitude : float or array_like
        Peak value (N, N m or a force vector in N).
    duration : float
        Pulse length τ in s (> 0). Its impulse is 2 τ amplitude / π.
    start : float
        Start time in s.
    """
    amp = np.asarray(amplitude, dtype=float)
    tau = float(duration)
    if not np.isfinite(tau) or tau <= 0:
        raise ValueError(f"pulse duration must be finite and positive, got {duration!r}")
    if not np.all(np.isfinite(amp)):
        raise ValueError(f"pulse amplitude must be finite, got {amplitude!r}")

    def fun(t):
        s = (t - start) / tau
        return amp * (np.sin(np.pi * s) if 0.0 <= s <= 1.0 else 0.0)
    return fun


class PointForce(ForceElement):
    """A force F(t) (N) acting at a body point, in the global frame or following the body.

    Q = r_qᵀ F. A follower force is given in the frame of the point
    (the rigid body's frame or the beam's cross-section), F = A(ϑ) F_loc(t).

    Parameters
    ----------
    point : BodyPoint
    force : array_like (2,) or callable t -> (2,)
        The force (N), constant or a function of time (s).
    follower : bool
        False (default): ``force`` is in the global frame. True: in the
        point's frame (needs a point with an angle).
    name : str
    """

    conservative = False

    def __init__(self, point, force, follower=False, name="point force"):
        if not isinstance(point, BodyPoint):
            raise ValueError(f"PointForce needs a body point (body.point(...)), got {point!r}")
        self.layout = PointLayout([point])
        n = self.layout.n
        self.bodies = self.layout.bodies
        self.force = time_function(force, 2, "force")
        self.follower = bool(follower)
        self._pos = Position(n, point, self.layout.slices[0])
        if self.follower:
            self._angle = angle_term(n, point, self.layout.slices[0])
        self.point = point
        self.name = name

    def global_force(self, q, t):
        """F in the global frame (N)."""
        f = self.force(t)
        if self.follower:
            f = rotation(self._angle.fun(q)) @ f
        return f

    def generalized_force(self, q, v, t):
        f = self.global_force(q, t)
        jac = self._pos.jacobian(q)
        fq = self._pos.hessian(q, f)
        if self.follower:
            fq = fq + np.outer(jac.T @ (E_MATRIX @ f), self._angle.grad)
        return jac.T @ f, fq, None

    def compiled_form(self):
        if not keeps_methods(self, PointForce, ("generalized_force", "global_force")):
            return None
        if self.follower:
            n = self.layout.n
            return "follower force", self.point, self._angle.grad.copy(), float(self._angle.fun(np.zeros(n))), self.force
        return "point force", self.point, self.force


class PointMoment(ForceElement):
    """A moment M(t) (N m, counter-clockwise) acting at a body point (on its frame angle ϑ).

    Q = M ∇ϑ. In the plane a moment is the same in the global frame and
    following the body.

    Parameters
    ----------
    point : BodyPoint
        A point with an angle.
    moment : float or callable t -> float
    name : str
    """

    conservative = False

    def __init__(self, point, moment, name="point moment"):
        if not isinstance(point, BodyPoint):
            raise ValueError(f"PointMoment needs a body point (body.point(...)), got {point!r}")
        self.layout = PointLayout([point])
        self.bodies = self.layout.bodies
        self.moment = time_function(moment, 1, "moment")
        self._angle = angle_term(self.layout.n, point, self.layout.slices[0])
        self.point = point
        self.name = name

    def generalized_force(self, q, v, t):
        return float(self.moment(t)[0]) * self._angle.grad, None, None

    def compiled_form(self):
        if not keeps_methods(self, PointMoment, ("generalized_force",)):
            return None
        return "generalized force", self._angle.grad.reshape(1, -1).copy(), self.moment
