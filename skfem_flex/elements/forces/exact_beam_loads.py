"""Loads on an :class:`~skfem_flex.bodies.exact.body.ExactBeam`: a point force and moment on its axis,
dead or follower (:class:`NodalLoad`), and a dead distributed load (:class:`ExactDistributedLoad`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import check_finite_number, check_finite_vector, keeps_methods, to_dense
from ...bodies.exact.body import ExactBeam
from ...bodies.rigid import E_MATRIX
from .base import ForceElement

__all__ = ["NodalLoad", "ExactDistributedLoad"]


def _time_function(fn):
    if fn is None:
        return None
    if not callable(fn):
        raise ValueError(f"time_function must be callable t -> factor, got {fn!r}")
    val = fn(0.0)
    if not np.isfinite(float(val)):
        raise ValueError(f"time_function(0) must be finite, got {val!r}")
    return fn


def _factor(fn, t):
    if fn is None:
        return 1.0
    val = float(fn(t))
    if not np.isfinite(val):
        raise ValueError(f"time_function({t!r}) is not finite: {val!r}")
    return val


class NodalLoad(ForceElement):
    """Point force and moment on an :class:`ExactBeam` axis point, dead or follower.

    Parameters
    ----------
    body : ExactBeam
    s : float
        Reference coordinate of the point (m); between nodes the load is
        shared by the shape functions.
    force : array_like, shape (2,)
        Force in N, global components (for a follower load: its components
        when the section has its reference angle).
    moment : float
        Moment in N m (counter-clockwise positive).
    time_function : callable t -> float, optional
        Dimensionless factor (default 1).
    follower : bool
        If True the force turns with the section: F(q) = A(ϑ(q) − ϑ_ref) F0,
        ϑ the section angle at the point, ϑ_ref its value in ``body.q0``.
    name : str

    Notes
    -----
    Non-conservative: the integrators evaluate it at the step midpoint (energy
    scheme) and record its work as external work. Generalized force
    f = c(t) (J_rᵀ F(q) + J_φ M), ∂f/∂q = c(t) J_rᵀ A E F0 ⊗ J_φ for a follower.
    """

    conservative = False

    def __init__(self, body, s, force=(0.0, 0.0), moment=0.0, time_function=None, follower=False,
                 name="nodal_load"):
        if not isinstance(body, ExactBeam):
            raise ValueError(f"NodalLoad acts on an ExactBeam, got {body!r}")
        self.bodies = (body,)
        self.body = body
        self.point = body.point(s)
        self.force = check_finite_vector("force", force, 2)
        self.moment = check_finite_number("moment", moment)
        self.time_function = _time_function(time_function)
        self.follower = bool(follower)
        self.name = str(name)
        self.reference_angle = self.point.angle(body.q0)
        self._dead = self.point.jr.T @ self.force + self.moment * self.point.jphi

    def force_at(self, q, t):
        """Global force vector (N) at configuration q and time t."""
        c = _factor(self.time_function, t)
        if not self.follower:
            return c * self.force
        d = self.point.angle(q) - self.reference_angle
        cd, sd = np.cos(d), np.sin(d)
        return c * np.array([cd * self.force[0] - sd * self.force[1], sd * self.force[0] + cd * self.force[1]])

    def compiled_form(self):
        if self.follower or not keeps_methods(self, NodalLoad, ("generalized_force", "force_at")):
            return None
        base = np.array([self.force[0], self.force[1], self.moment])
        return ("generalized force", np.vstack([to_dense(self.point.jr), to_dense(self.point.jphi).reshape(1, -1)]),
                lambda t: _factor(self.time_function, t) * base)

    def generalized_force(self, q, v, t):
        c = _factor(self.time_function, t)
        if not self.follower or c == 0.0:
            return c * self._dead, None, None
        f_now = self.force_at(q, t)
        f = self.point.jr.T @ f_now + c * self.moment * self.point.jphi
        df = np.outer(self.point.jr.T @ (E_MATRIX @ f_now), self.point.jphi)
        return f, df, None


class ExactDistributedLoad(ForceElement):
    """Dead distributed load (N/m of reference length) on an :class:`ExactBeam`, global components.

    Consistent load vector ∫ p · N ds assembled once by scikit-fem
    (:meth:`TimoshenkoBeam.load` with x ↔ u, y ↔ w), scaled by ``time_function``.

    Parameters
    ----------
    body : ExactBeam
    px, py : float or callable s -> value, optional
        Load per unit reference length along global x and y, N/m.
    time_function : callable t -> float, optional
    """

    conservative = False

    def __init__(self, body, px=None, py=None, time_function=None, name="distributed_load"):
        if not isinstance(body, ExactBeam):
            raise ValueError(f"ExactDistributedLoad acts on an ExactBeam, got {body!r}")
        for label, val in (("px", px), ("py", py)):
            if val is not None and not callable(val):
                check_finite_number(label, val)
        self.bodies = (body,)
        self.vector = body.beam.load(f=px, p=py)
        self.time_function = _time_function(time_function)
        self.name = str(name)

    def generalized_force(self, q, v, t):
        return _factor(self.time_function, t) * self.vector, None, None

    def compiled_form(self):
        if not keeps_methods(self, ExactDistributedLoad, ("generalized_force",)):
            return None
        return "generalized force", np.asarray(self.vector, dtype=float).reshape(1, -1), \
            lambda t: np.array([_factor(self.time_function, t)])
