"""skfem_flex: flexible multibody dynamics on scikit-fem.

Timoshenko beams (linear, floating frame of reference, geometrically exact),
rigid bodies and point masses in the plane, spatial rigid bodies (directors),
point masses and geometrically exact spatial beams, joined by constraints and integrated in time by an
energy-conserving scheme, the trapezoidal rule or generalized-α.
"""
from .numerics import jit_cache  # noqa: F401  (first: compiled kernels must see the package's cache rule)
from .fem.section import Section
from .fem.beam import TimoshenkoBeam
from .bodies import Body, BodyGeometry, BodyPoint, PointMass
from .bodies.floating.body import FloatingBeam
from .bodies.exact.body import ExactBeam
from .bodies.exact.strain import ElementInversionError
from .elements.forces import DistributedLoad, ExactDistributedLoad, NodalLoad
from .elements.constraints import Constraint, Distance, UserConstraint
from .bodies.rigid import RigidBody
from .bodies.spatial import SpatialPointMass, SpatialRigidBody
from .bodies.quaternion import QuaternionRigidBody
from .fem.spatial_section import SpatialSection
from .fem.spatial_beam import TimoshenkoBeam3D
from .bodies.exact.spatial_body import SpatialExactBeam
from .bodies.floating_spatial.body import FloatingBeam3D
from .bodies.floating_spatial.solid import FloatingSolid3D
from .fem.elasticity3d import ElasticSolid3D
from .elements.constraints.quadratic import QuadraticConstraint
from .elements.constraints.spatial_joints import (Cylindrical, Distance3D, Prismatic3D, Revolute3D, RotationDriver,
                                                  Spherical, TranslationDriver, Universal, Weld3D)
from .elements.constraints import Driver, Pin, Prismatic, Revolute, Slider, Weld
from .elements.forces import LinearDamper, LinearSpring, PointForce, PointMoment, RotationalDamper, RotationalSpring
from .scene_initial import (InconsistentInitialConditionsError, RedundantConstraintsError,
                                 consistent_initial_state)
from .elements.forces import ForceElement, Gravity, NonlinearSpring
from .elements.forces import (SpatialDamper, SpatialDistributedLoad, SpatialMoment, SpatialPointForce, SpatialSpring,
                              SpatialTorsionalDamper, SpatialTorsionalSpring, distributed_moments)
from .elements.motion import MotionLaw, Prescribed, driven_frame, spin_up_law
from .scene import Scene
from .schemes import EnergyMomentum, GeneralizedAlpha, Newmark, NewtonSettings, Trapezoidal
from .errors import ConvergenceError, DivergenceError, Interrupted, OutputError, SimulationError
from .numerics.resources import InsufficientMemoryError
from .io.result import Result
from .run.simulate import Checkpointing, Control, Recording, simulate
from .apps.sweep import open_sweep, sweep
from .io.output import VTKSeries
from .analysis import (CampbellDiagram, EquilibriumState, LinearSystem, Modes, campbell, linearize, modes,
                       static_equilibrium)
from . import scenes

__version__ = "0.1.0"
