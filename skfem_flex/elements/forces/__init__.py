"""Force elements: gravity, springs, dampers and loads that act on the coordinates of bodies.

=========================  =========================================================================
``base.py``                the contract (:class:`ForceElement`), :func:`split_blocks`
``gravity.py``             :class:`Gravity`
``coordinate_spring.py``   :class:`NonlinearSpring` (one body coordinate)
``two_point.py``           :class:`LinearSpring`, :class:`LinearDamper` (along the line of two points)
``torsion.py``             :class:`RotationalSpring`, :class:`RotationalDamper` (relative angles)
``point_loads.py``         :class:`PointForce`, :class:`PointMoment`, :func:`time_function`,
                           :func:`half_sine_pulse`
``floating_beam_loads.py`` :class:`DistributedLoad` on a floating-frame beam (eq. 43)
``exact_beam_loads.py``    :class:`NodalLoad`, :class:`ExactDistributedLoad` on an exact beam
``spatial.py``             on spatial bodies: :class:`SpatialSpring`, :class:`SpatialDamper`,
                           :class:`SpatialTorsionalSpring`, :class:`SpatialTorsionalDamper`,
                           :class:`SpatialPointForce`, :class:`SpatialMoment`, :class:`SpatialDistributedLoad`
=========================  =========================================================================

Every name is importable from here (``skfem_flex.elements.forces.PointForce``).
"""
from .base import CONSERVATIVE, ForceElement, split_blocks
from .coordinate_spring import MAX_SPRING_EXPONENT, NonlinearSpring
from .exact_beam_loads import ExactDistributedLoad, NodalLoad
from .floating_beam_loads import DistributedLoad
from .gravity import Gravity
from .point_loads import PointForce, PointMoment, half_sine_pulse, time_function
from .spatial import (SpatialDamper, SpatialDistributedLoad, SpatialMoment, SpatialPointForce, SpatialSpring,
                      SpatialTorsionalDamper, SpatialTorsionalSpring, distributed_moments)
from .torsion import RotationalDamper, RotationalSpring
from .two_point import LinearDamper, LinearSpring

__all__ = ["ForceElement", "Gravity", "NonlinearSpring", "split_blocks", "LinearSpring", "LinearDamper",
           "RotationalSpring", "RotationalDamper", "PointForce", "PointMoment", "time_function", "half_sine_pulse",
           "DistributedLoad", "NodalLoad", "ExactDistributedLoad", "CONSERVATIVE", "MAX_SPRING_EXPONENT",
           "SpatialSpring", "SpatialDamper", "SpatialTorsionalSpring", "SpatialTorsionalDamper", "SpatialPointForce",
           "SpatialMoment", "SpatialDistributedLoad", "distributed_moments"]
