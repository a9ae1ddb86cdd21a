"""Bodies: point masses, rigid bodies, floating-frame beams and geometrically exact beams."""
from .base import Body, BodyGeometry, BodyPoint
from .particle import PointMass

__all__ = ["Body", "BodyGeometry", "BodyPoint", "PointMass"]
