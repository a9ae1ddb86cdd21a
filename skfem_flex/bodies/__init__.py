"""Bodies: point masses, rigid bodies, floating-frame beams and geometrically exact beams."""
from .base import Body, BodyGeometry, BodyPoint
from .exact import ElementInversionError, ExactBeam, ExactDistributedLoad, NodalLoad
from .floating import DistributedLoad, FloatingBeam
from .particle import PointMass
from .rigid import RigidBody

__all__ = ["Body", "BodyGeometry", "BodyPoint", "PointMass", "RigidBody"]
