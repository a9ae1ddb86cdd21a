"""skfem_flex: planar flexible multibody dynamics on scikit-fem.

Timoshenko beams (linear, floating frame of reference, geometrically exact),
rigid bodies and point masses, joined by constraints and integrated in time
by an energy-conserving scheme, the trapezoidal rule or generalized-α.
"""
from . import jit_cache  # noqa: F401  (first: compiled kernels must see the package's cache rule)
from .section import Section
from .beam import TimoshenkoBeam
from .bodies import Body, BodyGeometry, BodyPoint, PointMass
from .bodies.floating import DistributedLoad, FloatingBeam
from .bodies.exact import ElementInversionError, ExactBeam, ExactDistributedLoad, NodalLoad
from .constraints import Constraint, Distance, UserConstraint
from .bodies.rigid import RigidBody
from .constraints import Driver, Pin, Prismatic, Revolute, Slider, Weld
from .forces import LinearDamper, LinearSpring, PointForce, PointMoment, RotationalDamper, RotationalSpring
from .initial_conditions import (InconsistentInitialConditionsError, RedundantConstraintsError,
                                 consistent_initial_state)
from .forces import ForceElement, Gravity, NonlinearSpring
from .motion import MotionLaw, Prescribed, spin_up_law
from .scene import Scene
from .integrators import (ConvergenceError, EnergyMomentum, GeneralizedAlpha, NewtonSettings, SimulationError,
                          Trapezoidal)
from .errors import DivergenceError, Interrupted, OutputError
from .resources import InsufficientMemoryError
from .result import Result
from .simulate import simulate
from .sweep import open_sweep, sweep
from .output import VTKSeries
from .analysis import (CampbellDiagram, EquilibriumState, LinearSystem, Modes, campbell, linearize, modes,
                       static_equilibrium)
from . import scenes

__version__ = "0.1.0"
