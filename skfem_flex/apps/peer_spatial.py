"""Spatial peer models: our spatial catalogue scenes built in exudyn, for side-by-side timing and accuracy.

The spatial counterpart of :mod:`skfem_flex.apps.peer` (same conventions; exudyn is optional and imported
only when a model is run, :func:`peer_available` says whether it can be). Each builder makes the problem
as an exudyn user would and returns a callable ``run() -> (t, probe, seconds)``: the recorded times (s),
the probe in the same form as our scene's probe (m) and the wall-clock time of exudyn's solve (s). Every
step is recorded on the exudyn side (sensors with ``storeInternal=True``). After a run, ``run.stats``
holds the steps exudyn took (``steps``; its adaptive step control, on by default, may take more than
requested), its Newton iterations (``newton``) and Jacobian evaluations (``jacobians``), the CPU time
of the solve (``cpu_seconds``, :func:`time.process_time` around ``SolveSystem``, s) and, for the heavy
top, the body's Euler parameters (e₀, e₁, e₂, e₃) at every recorded time (``euler_parameters``).

Rigid bodies are exudyn's ``ObjectRigidBody`` on Euler-parameter nodes (``NodeRigidBodyEP``: seven
coordinates and one normalisation constraint per body), made with ``mbs.CreateRigidBody``; joints are
``mbs.CreateSphericalJoint`` / ``mbs.CreateRevoluteJoint`` (``ObjectJointGeneric``), ``mbs.CreatePrismaticJoint``
(``ObjectJointPrismaticX``) and ``mbs.CreateGenericJoint`` (a universal joint: ``ObjectJointGeneric`` with
the three translations and one relative rotation locked).

* :func:`heavy_top`: the heavy tops of :func:`skfem_flex.scenes.spatial.heavy_top` (Simo–Wong, Brüls).
  Probe: the centre of mass, m.
* :func:`rigid_chain`: the chain of hinged bars of :func:`skfem_flex.scenes.spatial.rigid_chain` (the
  layout of exudyn's ``perf3DRigidBodies``). Probe: the free end of the last bar, m.
* :func:`bricard`: the IFToMM benchmark A04, Bricard's mechanism (square-section rods), whose closing
  joint is redundant. Probe: the point P3 (= joint C), m.
* :func:`beam_cantilever`: a spatial cantilever released under gravity (:data:`BEAM_CANTILEVER`) on exudyn's
  geometrically exact 3D beam (``ObjectBeamGeometricallyExact``, two nodes, constant strain, lumped mass)
  on Euler-parameter nodes. Probe: the tip, m.
* :func:`right_angle_frame`: :func:`skfem_flex.scenes.spatial_beams.right_angle_frame` (Simo and Vu-Quoc's
  right-angle cantilever) on the same beam elements, the legs welded at the elbow. Probe: the elbow's and the
  tip's positions side by side (n, 6), m.
* :func:`spatial_slider_crank`: the IFToMM spatial slider–crank of
  :func:`skfem_flex.scenes.spatial.spatial_slider_crank` (revolute, spherical, universal and prismatic
  joints). Probe: (slider position x_C m, crank angle θ rad unwrapped).

Schemes: exudyn's generalized-α with spectral radius ρ∞ (``rho_inf``; 0.9 is its default), or its
Newmark/trapezoidal rule with index-2 constraints (``scheme="trapezoidal"``: ``useNewmark``,
``useIndex2Constraints``, ρ∞ = 1). Newton is exudyn's default (modified Newton, relative tolerance 1e-8,
absolute tolerance 1e-10) unless a builder says otherwise.
"""
from __future__ import annotations


import numpy as np

from ..numerics.quaternions import rotation_vector_matrix
from .peer import exudyn_modules, peer_available, simulation_settings, solve_recorded, version

__all__ = ["peer_available", "version", "heavy_top", "rigid_chain", "bricard", "spatial_slider_crank",
           "beam_cantilever", "BEAM_CANTILEVER", "right_angle_frame"]

_TOP_VARIANTS = ("simo-wong", "bruls")


def _sensor(mbs, output, body=None, local=None, node=None):
    """A sensor recording ``output`` (an ``OutputVariableType`` name) of a body point or of a node."""
    exu, ei = exudyn_modules()
    kind = getattr(exu.OutputVariableType, output)
    if node is not None:
        return mbs.AddSensor(ei.SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=kind))
    return mbs.AddSensor(ei.SensorBody(bodyNumber=body, localPosition=[float(x) for x in local],
                                       storeInternal=True, outputVariableType=kind))


def heavy_top(variant="simo-wong", dt=0.009, t_end=10.0, scheme="generalized-alpha", rho_inf=0.9):
    """A heavy top about a fixed point in exudyn; returns run() -> (t, centre of mass, seconds).

    Parameters
    ----------
    variant : {"simo-wong", "bruls"}
        The data of :func:`skfem_flex.scenes.spatial.heavy_top`. ``"simo-wong"``: inertia about the
        pivot diag(5, 5, 1) kg m², m = 20 kg, centre of mass at 1 m on body axis 3, g = 1 m/s² along −z,
        initial rotation exp(skew(0.05, 0, 0)), body angular velocity (0, 0, 50) rad/s. ``"bruls"``:
        m = 15 kg, inertia about the centre of mass diag(0.234375, 0.46875, 0.234375) kg m², centre of
        mass at (0, 1, 0) m from the pivot, initial rotation the identity, body angular velocity
        (0, 150, −4.61538) rad/s, g = 9.81 m/s² along −z.
    dt, t_end : float
        Time step and end time, s.
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α (ignored by the trapezoidal rule).

    Notes
    -----
    Modelled like exudyn's ``TestModels/heavyTop.py``: the body's node sits at the pivot (the origin), its
    inertia is the inertia about the pivot (for Brüls J_C + m(‖c‖² I − c cᵀ)), a spherical joint holds it
    to the ground, and the weight m g acts as a fixed-direction force at the centre of mass c. (The
    Simo–Wong data are no body about its centre of mass, J_O,11 = 5 kg m² < m l² = 20 kg m², but about the
    fixed point only J_O matters.) Settings: exudyn's dense solver (``EXUdense``), default Newton
    (modified, tolerances 1e-8 relative / 1e-10 absolute), adaptive step on, one thread. exudyn takes the
    initial angular velocity in global axes, R₀ ω_body. ``run.stats["euler_parameters"]``: the node's
    Euler parameters (e₀ the scalar part) at every recorded time.
    """
    if variant not in _TOP_VARIANTS:
        raise ValueError(f"heavy_top: variant must be one of {_TOP_VARIANTS}, got {variant!r}")
    if variant == "simo-wong":
        mass, c, g = 20.0, np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])
        inertia = np.diag([5.0, 5.0, 1.0])
        R0, omega = rotation_vector_matrix([0.05, 0.0, 0.0]), np.array([0.0, 0.0, 50.0])
    else:
        mass, c, g = 15.0, np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -9.81])
        inertia = np.diag([0.234375, 0.46875, 0.234375]) + mass * (c @ c * np.eye(3) - np.outer(c, c))
        R0, omega = np.eye(3), np.array([0.0, 150.0, -4.61538])

    def run():
        exu, ei = exudyn_modules()
        from exudyn.utilities import RigidBodyInertia
        mbs = exu.SystemContainer().AddSystem()
        ground = mbs.CreateGround()
        top = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=mass, inertiaTensor=inertia),
                                  referencePosition=[0.0, 0.0, 0.0], referenceRotationMatrix=R0,
                                  initialAngularVelocity=list(R0 @ omega))
        weight = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=top, localPosition=list(c)))
        mbs.AddLoad(ei.LoadForceVector(markerNumber=weight, loadVector=list(mass * g)))
        mbs.CreateSphericalJoint(itemNumbers=[ground, top], position=[0.0, 0.0, 0.0])
        sensors = [_sensor(mbs, "Position", body=top, local=c),
                   _sensor(mbs, "CoordinatesTotal", node=mbs.GetObject(top)["nodeNumber"])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, linear_solver="EXUdense", threads=1)
        t, (com, q), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        run.stats["euler_parameters"] = q[:, 3:7]
        return t, com, seconds
    run.stats = {}
    return run


def rigid_chain(n_bodies=10, dt=1e-3, t_end=1.0, scheme="generalized-alpha", rho_inf=0.9):
    """The spatial chain of hinged rigid bars in exudyn; returns run() -> (t, free end, seconds).

    Parameters
    ----------
    n_bodies : int
        Number of bars (exudyn's ``perf3DRigidBodies`` uses 400).
    dt, t_end : float
        Time step and end time, s.
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α.

    Notes
    -----
    The layout of :func:`skfem_flex.scenes.spatial.rigid_chain`: bars of 0.4 m × 0.1 m × 0.1 m, density
    1000 kg/m³ (``InertiaCuboid``, m = 4 kg), end to end from the origin; bar k + 1 is turned against bar k
    by R_x(δ) R_z(2δ), δ = 0.01π; each bar is hinged at its start about its own local z (a revolute joint
    in global axes), the first to the ground at the origin; gravity 9.81 m/s² along −z (``CreateRigidBody``'s
    ``gravity``); released at rest. Settings: ``EigenSparse``, one thread, exudyn's default Newton
    (modified, tolerances 1e-8 relative / 1e-10 absolute), adaptive step on. The probe is the free end of
    the last bar (local (0.2, 0, 0) m from its centre of mass).
    """
    n = int(n_bodies)
    if n < 1:
        raise ValueError(f"rigid_chain: n_bodies must be a positive integer, got {n_bodies!r}")
    length, width, density = 0.4, 0.1, 1000.0
    delta = 0.01 * np.pi
    turn = rotation_vector_matrix([delta, 0.0, 0.0]) @ rotation_vector_matrix([0.0, 0.0, 2 * delta])

    def run():
        exu, _ = exudyn_modules()
        from exudyn.utilities import InertiaCuboid
        mbs = exu.SystemContainer().AddSystem()
        inertia = InertiaCuboid(density=density, sideLengths=[length, width, width])
        previous = mbs.CreateGround()
        R, start = np.eye(3), np.zeros(3)
        for _ in range(n):
            bar = mbs.CreateRigidBody(inertia=inertia, referencePosition=list(start + R @ [0.5 * length, 0, 0]),
                                      referenceRotationMatrix=R, gravity=[0.0, 0.0, -9.81])
            mbs.CreateRevoluteJoint(itemNumbers=[previous, bar], position=list(start), axis=list(R[:, 2]),
                                    useGlobalFrame=True)
            previous, start, R = bar, start + R @ [length, 0.0, 0.0], R @ turn
        sensors = [_sensor(mbs, "Position", body=previous, local=[0.5 * length, 0.0, 0.0])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, linear_solver="EigenSparse", threads=1)
        t, (tip,), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        return t, tip, seconds
    run.stats = {}
    return run


def bricard(dt=1e-3, t_end=10.0, scheme="generalized-alpha", rho_inf=0.9):
    """Bricard's mechanism (IFToMM benchmark A04, square-section rods) in exudyn; returns
    run() -> (t, P3, seconds).

    Parameters
    ----------
    dt, t_end : float
        Time step and end time, s (the benchmark runs 10 s).
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α.

    Notes
    -----
    Five rods of 1 m and 1 kg, each a cuboid 1 m × 0.1 m × 0.1 m (``InertiaCuboid``, density 100 kg/m³)
    with its local x along the rod, between the joints A (0, 0, 0) axis y, B (1, 0, 0) axis z,
    C (1, −1, 0) axis x, D (1, −1, 1) axis y, E (0, −1, 1) axis z, F (0, 0, 1) axis x (m, global axes);
    A and F join the first and the last rod to the ground. Six revolute joints; gravity 9.81 m/s² along
    −y; released at rest. The closed loop has one degree of freedom although its constraints count none:
    one constraint is redundant and the constraint Jacobian is singular. Settings: exudyn's dense LU
    (``EigenDense``) with ``ignoreSingularJacobian = True``, default Newton (modified, tolerances 1e-8
    relative / 1e-10 absolute), adaptive step on, one thread. Probe: P3 = C, the end of the second rod.
    With ``scheme="trapezoidal"`` (index-2 constraints) exudyn's Newton stalls at its tolerance on the
    singular Jacobian near t = 0.36 s (Δt = 1e-3 s) and the run stops (``RuntimeError``); use
    generalized-α (index 3) beyond that.
    """
    joints = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]], dtype=float)
    axes = np.eye(3)[[1, 2, 0, 1, 2, 0]]

    def run():
        exu, _ = exudyn_modules()
        from exudyn.utilities import InertiaCuboid
        mbs = exu.SystemContainer().AddSystem()
        ground = mbs.CreateGround()
        inertia = InertiaCuboid(density=100.0, sideLengths=[1.0, 0.1, 0.1])
        rods = []
        for a, b in zip(joints[:-1], joints[1:]):
            ex = b - a                                     # unit length
            ey = np.cross([0.0, 0.0, 1.0] if abs(ex[2]) < 0.9 else [1.0, 0.0, 0.0], ex)
            frame = np.column_stack([ex, ey, np.cross(ex, ey)])
            rods.append(mbs.CreateRigidBody(inertia=inertia, referencePosition=list(0.5 * (a + b)),
                                            referenceRotationMatrix=frame, gravity=[0.0, -9.81, 0.0]))
        for pair, point, axis in zip(zip([ground] + rods, rods + [ground]), joints, axes):
            mbs.CreateRevoluteJoint(itemNumbers=list(pair), position=list(point), axis=list(axis),
                                    useGlobalFrame=True)
        sensors = [_sensor(mbs, "Position", body=rods[1], local=[0.5, 0.0, 0.0])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, linear_solver="EigenDense",
                                       ignore_singular=True, threads=1)
        t, (p3,), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        return t, p3, seconds
    run.stats = {}
    return run


def spatial_slider_crank(dt=1e-3, t_end=5.0, scheme="generalized-alpha", rho_inf=0.9):
    """The IFToMM spatial rigid slider–crank in exudyn; returns run() -> (t, (x_C, θ), seconds).

    Parameters
    ----------
    dt, t_end : float
        Time step and end time, s (the benchmark runs 5 s).
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α.

    Notes
    -----
    The model of :func:`skfem_flex.scenes.spatial.spatial_slider_crank` (ω = 6 rad/s). Crank (0.08 m,
    0.12 kg, inertia about its centre of mass diag(1e-4, 1e-4, 1e-5) kg m², body axis 3 along the crank,
    centre of mass at mid-crank) on a revolute joint about global x at A = (0, 0.1, 0.12) m, upright at
    t = 0 (B = (0, 0.1, 0.2) m); rod (0.3 m, 0.5 kg, centre of mass at its midpoint, inertia 4e-4 kg m²
    about its axis and 4e-3 across) on a spherical joint at B; a universal joint at C = (0.2, 0, 0) m
    between the slider (marker 0) and the rod (marker 1): ``mbs.CreateGenericJoint`` with
    ``constrainedAxes = [1, 1, 1, 0, 0, 1]`` in the joint frame (x, a, x × a), a = e × x / ‖e × x‖ with e
    the unit vector from B to C, which keeps the slider's arm (its x) perpendicular to the rod's arm (a,
    fixed in the rod); slider (2 kg, inertia diag(1e-4) kg m²) on a prismatic joint along global x with
    the ground (``ObjectJointPrismaticX``: no rotation). Gravity 9.81 m/s² along −z (``CreateRigidBody``'s
    ``gravity``). Initial velocities: crank ω = (6, 0, 0) rad/s and its centre of mass ω × (B − A)/2; rod
    centre of mass (0.12, −0.24, 0) m/s and ω = (1.92, −0.96, 0.48) rad/s; slider (0.24, 0, 0) m/s.
    Settings: ``EXUdense``, default Newton (modified, tolerances 1e-8 relative / 1e-10 absolute),
    adaptive step on, one thread. Probe: x_C (the slider's position) and the crank angle
    θ = atan2(−d₃,y, d₃,z) of the crank's body axis 3, unwrapped (``np.unwrap``).
    """
    A, B, C = np.array([0.0, 0.1, 0.12]), np.array([0.0, 0.1, 0.2]), np.array([0.2, 0.0, 0.0])
    x, omega, gravity = np.array([1.0, 0.0, 0.0]), np.array([6.0, 0.0, 0.0]), [0.0, 0.0, -9.81]
    e = (C - B) / np.linalg.norm(C - B)
    arm = np.cross(e, x) / np.linalg.norm(np.cross(e, x))
    cross_frame = np.column_stack([x, arm, np.cross(x, arm)])     # joint x: slider arm, joint y: rod arm

    def run():
        exu, _ = exudyn_modules()
        from exudyn.utilities import RigidBodyInertia
        mbs = exu.SystemContainer().AddSystem()
        ground = mbs.CreateGround()
        crank = mbs.CreateRigidBody(inertia=RigidBodyInertia(0.12, np.diag([1e-4, 1e-4, 1e-5])),
                                    referencePosition=list(0.5 * (A + B)), gravity=gravity,
                                    initialVelocity=list(np.cross(omega, 0.5 * (B - A))),
                                    initialAngularVelocity=list(omega))
        rod_inertia = 4e-3 * np.eye(3) + (4e-4 - 4e-3) * np.outer(e, e)
        rod = mbs.CreateRigidBody(inertia=RigidBodyInertia(0.5, rod_inertia), referencePosition=list(0.5 * (B + C)),
                                  gravity=gravity, initialVelocity=[0.12, -0.24, 0.0],
                                  initialAngularVelocity=[1.92, -0.96, 0.48])
        slider = mbs.CreateRigidBody(inertia=RigidBodyInertia(2.0, 1e-4 * np.eye(3)), referencePosition=list(C),
                                     gravity=gravity, initialVelocity=[0.24, 0.0, 0.0])
        mbs.CreateRevoluteJoint(itemNumbers=[ground, crank], position=list(A), axis=list(x), useGlobalFrame=True)
        mbs.CreateSphericalJoint(itemNumbers=[crank, rod], position=list(B))
        mbs.CreateGenericJoint(itemNumbers=[slider, rod], position=list(C), rotationMatrixAxes=cross_frame,
                               constrainedAxes=[1, 1, 1, 0, 0, 1], useGlobalFrame=True)
        mbs.CreatePrismaticJoint(itemNumbers=[ground, slider], position=list(C), axis=list(x), useGlobalFrame=True)
        sensors = [_sensor(mbs, "Position", body=slider, local=[0.0, 0.0, 0.0]),
                   _sensor(mbs, "RotationMatrix", body=crank, local=[0.0, 0.0, 0.0])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, linear_solver="EXUdense", threads=1)
        t, (position, rotation), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        theta = np.unwrap(np.arctan2(-rotation[:, 5], rotation[:, 8]))     # row-major: d3 = entries 2, 5, 8
        return t, np.column_stack([position[:, 0], theta]), seconds
    run.stats = {}
    return run


#: the spatial cantilever of :func:`beam_cantilever`: length (m), EA, kGA about both axes (N), GJ, EI about both
#: axes (N m²), ρA (kg/m), ρI about each section axis (kg m), gravity (m/s², along −z)
BEAM_CANTILEVER = dict(length=2.0, EA=1e6, GA=4e5, GJ=1e3, EI=1e3, rhoA=1.0, rhoI=1e-3, g=9.81)


def beam_cantilever(n_elements=16, dt=2e-3, t_end=1.0, scheme="trapezoidal", rho_inf=0.9):
    """A straight cantilever along x (:data:`BEAM_CANTILEVER`), clamped at the origin and released straight
    under gravity along −z, on exudyn's 3D geometrically exact beam; returns run() -> (t, tip, seconds).

    Notes
    -----
    ``n_elements`` ``ObjectBeamGeometricallyExact`` elements (two-node, constant strain per element, lumped
    mass: ρA h/2 and the section's inertia h/2 at each node) on ``NodeRigidBodyEP`` nodes. Section data:
    ``BeamSection.stiffnessMatrix = diag(EA, GA, GA, GJ, EI, EI)`` (axial, shear y, shear z, torsion, bending y,
    bending z), ``inertia = diag(2ρI, ρI, ρI)`` (polar first), ``massPerLength = ρA``. The clamp is an
    ``ObjectJointGeneric`` locking all six relative coordinates of node 0 against the ground; gravity acts as
    nodal forces ρA g h (half at the tip), the lumped mass's own weight. On exudyn's rotation-vector
    Lie-group nodes the same model runs, but its Newton iteration stalls and the adaptive step control cuts
    the step (10–40× the cost), so they are not used.
    """
    n = int(n_elements)
    if n < 1:
        raise ValueError(f"beam_cantilever: n_elements must be a positive integer, got {n_elements!r}")
    c = BEAM_CANTILEVER
    h = c["length"] / n

    def run():
        exu, ei = exudyn_modules()
        mbs = exu.SystemContainer().AddSystem()
        section = exu.BeamSection()
        section.stiffnessMatrix = np.diag([c["EA"], c["GA"], c["GA"], c["GJ"], c["EI"], c["EI"]])
        section.inertia = np.diag([2 * c["rhoI"], c["rhoI"], c["rhoI"]])
        section.massPerLength = c["rhoA"]
        nodes = [mbs.AddNode(ei.NodeRigidBodyEP(referenceCoordinates=[i * h, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))
                 for i in range(n + 1)]
        for i in range(n):
            mbs.AddObject(ei.ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=h,
                                                          sectionData=section,
                                                          visualization=ei.VBeam3D(show=False)))
        ground = mbs.AddObject(ei.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        markers = [mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0])),
                   mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=nodes[0]))]
        mbs.AddObject(ei.ObjectJointGeneric(markerNumbers=markers, constrainedAxes=[1] * 6,
                                            visualization=ei.VObjectJointGeneric(show=False)))
        for i in range(1, n + 1):
            weight = c["rhoA"] * c["g"] * (0.5 * h if i == n else h)
            mbs.AddLoad(ei.Force(markerNumber=mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=nodes[i])),
                                 loadVector=[0.0, 0.0, -weight]))
        sensors = [_sensor(mbs, "Position", node=nodes[-1])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, threads=1)
        t, (tip,), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        return t, tip, seconds
    run.stats = {}
    return run


def _turn_about_z(angle):
    """Euler parameters (e₀, e₁, e₂, e₃) of a turn by ``angle`` (rad) about z."""
    return [float(np.cos(0.5 * angle)), 0.0, 0.0, float(np.sin(0.5 * angle))]


def right_angle_frame(n_elements=10, dt=0.05, t_end=30.0, scheme="generalized-alpha", rho_inf=1.0):
    """Simo and Vu-Quoc's right-angle cantilever of :func:`skfem_flex.scenes.spatial_beams.right_angle_frame` on
    exudyn's 3D geometrically exact beam; returns run() -> (t, [elbow, tip] positions (n, 6), seconds).

    Notes
    -----
    Each leg (length 10) is ``n_elements`` ``ObjectBeamGeometricallyExact`` elements (two nodes, constant
    strain, lumped mass) on ``NodeRigidBodyEP`` nodes whose local x runs along the leg: the first leg from the
    origin along +y (a quarter turn about z), the second from the elbow (0, 10, 0) along −x (a half turn).
    Section: ``stiffnessMatrix = diag(EA, GA, GA, GJ, EI, EI) = diag(1e6, 1e6, 1e6, 1e3, 1e3, 1e3)``,
    ``inertia = diag(20, 10, 10)``, ``massPerLength = 1``. The clamp at the root and the weld of the two legs
    at the elbow are ``ObjectJointGeneric`` locking all six relative coordinates (the elbow's markers turned
    so that the two nodes' frames coincide). The elbow force along +z, 50 t for t < 1 and 50 (2 − t) for
    1 ≤ t < 2, is a user function on the first leg's last node. ρ∞ = 1 by default: generalized-α without
    numerical damping, as the energy of the free motion after t = 2 is the point of this problem; exudyn's
    full Newton with relative and absolute tolerances 1e-8 and its sparse solver (with its defaults the
    finer meshes stop in the first steps).
    """
    n = int(n_elements)
    if n < 1:
        raise ValueError(f"right_angle_frame: n_elements must be a positive integer, got {n_elements!r}")
    h, L = 10.0 / n, 10.0

    def run():
        exu, ei = exudyn_modules()
        mbs = exu.SystemContainer().AddSystem()
        section = exu.BeamSection()
        section.stiffnessMatrix = np.diag([1e6, 1e6, 1e6, 1e3, 1e3, 1e3])
        section.inertia = np.diag([20.0, 10.0, 10.0])
        section.massPerLength = 1.0
        legs = []
        for start, step, angle in (((0.0, 0.0), (0.0, h), 0.5 * np.pi), ((0.0, L), (-h, 0.0), np.pi)):
            legs.append([mbs.AddNode(ei.NodeRigidBodyEP(referenceCoordinates=[
                start[0] + i * step[0], start[1] + i * step[1], 0.0] + _turn_about_z(angle))) for i in range(n + 1)])
            for i in range(n):
                mbs.AddObject(ei.ObjectBeamGeometricallyExact(nodeNumbers=[legs[-1][i], legs[-1][i + 1]], length=h,
                                                              sectionData=section,
                                                              visualization=ei.VBeam3D(show=False)))
        ground = mbs.AddObject(ei.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])     # the first leg's frame
        # each joint's first marker turned into the frame of the node it holds (exudyn's localHT)
        joints = ((mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localHT=exu.HT(rotation=quarter))),
                   mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=legs[0][0]))),
                  (mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=legs[0][-1], localHT=exu.HT(
                      rotation=quarter.T @ np.diag([-1.0, -1.0, 1.0])))),
                   mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=legs[1][0]))))
        for m0, m1 in joints:
            mbs.AddObject(ei.ObjectJointGeneric(markerNumbers=[m0, m1], constrainedAxes=[1] * 6,
                                                visualization=ei.VObjectJointGeneric(show=False)))

        def force(mbs, t, load):
            f = 50.0 * t if t < 1.0 else (50.0 * (2.0 - t) if t < 2.0 else 0.0)
            return [0.0, 0.0, f]
        mbs.AddLoad(ei.Force(markerNumber=mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=legs[0][-1])),
                             loadVector=[0.0, 0.0, 0.0], loadVectorUserFunction=force))
        sensors = [_sensor(mbs, "Position", node=legs[0][-1]), _sensor(mbs, "Position", node=legs[1][-1])]
        settings = simulation_settings(t_end, dt, scheme, rho_inf, absolute_tolerance=1e-8,
                                       linear_solver="EigenSparse", threads=1)
        settings.timeIntegration.newton.useModifiedNewton = False
        settings.timeIntegration.newton.relativeTolerance = 1e-8
        t, (elbow, tip), seconds = solve_recorded(mbs, sensors, settings, run.stats)
        return t, np.hstack([elbow, tip]), seconds
    run.stats = {}
    return run
