"""Bodies: point masses, rigid bodies, floating-frame beams, reduced and plane-stress floating-frame bodies,
geometrically exact beams. (Loads on bodies are force elements: :mod:`skfem_flex.elements.forces`.)"""
from .base import Body, BodyGeometry, BodyPoint
from .exact.body import ExactBeam
from .exact.strain import ElementInversionError
from .ffr import FloatingFrame, FramePoint
from .floating.body import FloatingBeam
from .modal.body import ElasticModel, Interface, ModalBody
from .modal.plane_stress import PlaneStress, load_mesh
from .modal.reduction import craig_bampton, free_modes, full_body, reduce
from .particle import PointMass
from .probes import CombinedProbe, LinearProbe, PointProbe
from .rigid import RigidBody

__all__ = ["Body", "BodyGeometry", "BodyPoint", "PointMass", "RigidBody", "PointProbe", "LinearProbe", "CombinedProbe"]
