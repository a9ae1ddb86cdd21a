"""A coordinate, a point's angle or a relative angle prescribed in time through a multiplier (:class:`Driver`)."""
from __future__ import annotations

import numpy as np

from ...bodies.base import BodyPoint, keeps_methods
from ..motion import MotionLaw
from ..point_terms import PointLayout, angle_term, coordinate_term, linear_combination
from .base import CONTRACT, TermConstraint

__all__ = ["Driver"]


class Driver(TermConstraint):
    """A coordinate, an angle or a relative angle prescribed as a function of time.

    Φ = s(q) − x(t) = 0 with s a body coordinate, the angle ϑ of a body point,
    or the relative angle ϑ_a − ϑ_b of two points (all linear in q, so the
    discrete gradient is the constant gradient of s). Unlike
    :class:`~skfem_flex.elements.motion.Prescribed`, the coordinate stays an unknown
    and the driving force is the multiplier: generalized force −λ.

    Parameters
    ----------
    target : Body or BodyPoint
        A body (then ``coordinate`` names the driven coordinate) or a body
        point whose angle is driven.
    law : MotionLaw
        x(t), ẋ(t), ẍ(t).
    coordinate : str or int, optional
        For a body target: the coordinate's name or index (e.g. ``"theta"``).
    relative_to : BodyPoint, optional
        For a point target: drive ϑ_target − ϑ_relative_to.
    name : str

    Notes
    -----
    Φ_t = −ẋ(t), acceleration equation Φ_q q̈ = ẍ(t). Reaction: the
    generalized force −λ the driver exerts on s (N m for angles, N for
    lengths); its power is −λ ṡ.
    """

    rheonomic = True
    reaction_labels = ("Q",)

    def __init__(self, target, law, coordinate=None, relative_to=None, name="driver"):
        if not isinstance(law, MotionLaw):
            raise ValueError(f"Driver needs a MotionLaw (position, velocity, acceleration), got {law!r}")
        self.law = law
        if isinstance(target, BodyPoint):
            if coordinate is not None:
                raise ValueError("coordinate applies to a body target, not to a body point (whose angle is driven)")
            layout = PointLayout([target, relative_to])
            n = layout.n
            term = angle_term(n, target, layout.slices[0])
            if relative_to is not None:
                term = linear_combination(n, [term, angle_term(n, relative_to, layout.slices[1])], [1.0, -1.0])
        else:
            if relative_to is not None:
                raise ValueError("relative_to applies to a body-point (angle) target")
            if coordinate is None:
                raise ValueError(f"Driver on body {getattr(target, 'name', target)!r} needs coordinate=...")
            index = target.coordinate_index(coordinate)
            layout = PointLayout.of_bodies([target])
            term = coordinate_term(layout.n, index)
        self._s = term
        self.set_terms(layout, [term])
        self.quadratic = True
        self.name = name

    def driven_value(self, q):
        """s(q), the driven quantity."""
        return float(self._s.value(q)[0])

    def value(self, q, t):
        return self._s.value(q) - float(self.law.position(t))

    def time_derivative(self, q, t):
        return np.array([-float(self.law.velocity(t))])

    def compiled_form(self):
        form = self._s.compiled_form()
        if form is None or not keeps_methods(self, Driver, CONTRACT):
            return None
        return "rows", [(form, self.law)]

    def time_terms(self, q, v, t):
        return np.array([-float(self.law.acceleration(t))])

    def acceleration_rhs(self, q, v, t):
        return np.array([float(self.law.acceleration(t))])
