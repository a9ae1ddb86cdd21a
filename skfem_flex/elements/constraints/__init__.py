"""Algebraic constraints Φ(q, t) = 0 adjoined with Lagrange multipliers: joints, drivers, your own.

=================  ==========================================================================
``base.py``        the contract (:class:`Constraint`, sign convention, default discrete gradient)
                   and :class:`TermConstraint` (equations stacked from point terms)
``joints.py``      :class:`Pin`, :class:`Revolute`, :class:`Weld`, :class:`Slider`, :class:`Prismatic`
``driver.py``      :class:`Driver` (a coordinate or an angle prescribed through a multiplier)
``distance.py``    :class:`Distance` (a point mass at a fixed distance from an anchor)
``user.py``        :class:`UserConstraint` (your own callables)
=================  ==========================================================================

Every name is importable from here (``skfem_flex.elements.constraints.Pin``), and so is
:class:`~skfem_flex.elements.point_terms.PointLayout` (once defined here).
"""
from ..point_terms import PointLayout
from .base import CONTRACT, Constraint, TermConstraint
from .distance import Distance
from .driver import Driver
from .joints import Pin, Prismatic, Revolute, Slider, Weld
from .user import UserConstraint

__all__ = ["Constraint", "Distance", "UserConstraint", "Pin", "Revolute", "Slider", "Prismatic", "Weld",
           "Driver", "PointLayout", "TermConstraint", "CONTRACT"]
