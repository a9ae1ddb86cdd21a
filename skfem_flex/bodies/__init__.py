"""Bodies: point masses, rigid bodies, floating-frame beams, reduced and plane-stress floating-frame bodies,
geometrically exact beams."""
from .base import Body, BodyGeometry, BodyPoint
from .exact import ElementInversionError, ExactBeam, ExactDistributedLoad, NodalLoad
from .ffr import FloatingFrame, FramePoint
from .floating import FloatingBeam
from .floating_loads import DistributedLoad
from .modal import ElasticModel, Interface, ModalBody
from .plane_stress import PlaneStress, load_mesh
from .reduction import craig_bampton, free_modes, full_body, reduce
from .particle import PointMass
from .probes import CombinedProbe, LinearProbe, PointProbe
from .rigid import RigidBody

__all__ = ["Body", "BodyGeometry", "BodyPoint", "PointMass", "RigidBody", "PointProbe", "LinearProbe", "CombinedProbe"]
