"""Peer models: our benchmark problems built in the established C++ code exudyn, for comparison.

Used by the work–precision study (:func:`skfem_flex.apps.studies.work_precision`, exudyn's curves
beside ours) and by ``examples/benchmark.py`` (side-by-side timing). exudyn is optional
(``pip install ".[bench]"``): it is imported only when a model is run, and
:func:`peer_available` says whether it can be.

Each builder makes the problem as an exudyn user would set it up and returns a
callable ``run() -> (t, probe, seconds)``: the recorded times, the probe in the
same form as our scene's probe, and the time the solver took. Every step is
recorded on the exudyn side (a sensor with ``storeInternal=True``), as on
ours (``record_every=1``). After a run, ``run.stats`` holds the number of steps
exudyn took (``steps``; its adaptive step control, on by default, may take
more than requested) and of its Newton iterations (``newton``).

* ``spin_up``: the Simo & Vu-Quoc spin-up (L = 10 m, EA = 2.8e7 N,
  EI = 1.4e4 N m², GA = 1e7 N, ρA = 1.2 kg/m, ρI = 6e-4 kg m) with exudyn's
  planar geometrically exact beam (``ObjectBeamGeometricallyExact2D``, two
  nodes per element). The root node is held at the origin by coordinate
  constraints and its angle follows the hub law through a coordinate
  constraint whose offset a pre-step function sets. Probe: the tip
  displacement in the hub frame (axial, transverse), m.
* ``flexible_pendulum``: the same beam element, L = 1 m, EA = 1e6 N,
  EI = 1e2 N m², GA = 3.205e5 N, ρA = 1 kg/m, ρI = 1e-4 kg m, root pinned
  at the origin, released horizontal under gravity 9.81 m/s². Probe: the tip
  position, m.
* ``pendulum``: a point mass (1 kg) on a rod (``DistanceConstraint``,
  l = 0.5 m), started at the bottom with 1.695 m/s. Probe: the position, m.

Schemes: exudyn's generalized-α with spectral radius ρ∞ (``rho_inf``; 0.9 is
its default), or its Newmark/trapezoidal rule with index-2 constraints
(``scheme="trapezoidal"``: ``useNewmark``, ``useIndex2Constraints``, ρ∞ = 1).
Newton tolerances are exudyn's defaults, except the absolute tolerance of the
spin-up (see :func:`spin_up`).
"""
from __future__ import annotations

import time

import numpy as np

from ..elements.motion import spin_up_law

__all__ = ["peer_available", "version", "exudyn_modules", "simulation_settings", "solve_recorded", "spin_up", "flexible_pendulum",
           "pendulum"]


def exudyn_modules():
    """(exudyn, exudyn.itemInterface); ImportError with the install hint when exudyn is missing."""
    try:
        import exudyn as exu
        from exudyn import itemInterface as ei
    except ImportError as exc:
        raise ImportError('the peer models need exudyn: pip install ".[bench]"') from exc
    return exu, ei


def peer_available():
    """True when exudyn can be imported (then the peer models can run)."""
    try:
        exudyn_modules()
    except ImportError:
        return False
    return True


def version():
    """exudyn's version, or ``"not installed"``."""
    try:
        return exudyn_modules()[0].__version__
    except ImportError:
        return "not installed"


def simulation_settings(t_end, dt, scheme, rho_inf, absolute_tolerance=None, linear_solver=None,
                        ignore_singular=False, threads=None):
    """exudyn's simulation settings of every peer model: ``round(t_end / dt)`` steps, no solution file,
    sensors every step, the scheme (``"generalized-alpha"`` with ``rho_inf``, or ``"trapezoidal"``: its
    Newmark rule with index-2 constraints), and optionally the Newton absolute tolerance, the linear solver
    (a ``LinearSolverType`` name), whether a singular Jacobian is ignored, and the number of threads."""
    exu, _ = exudyn_modules()
    s = exu.SimulationSettings()
    if absolute_tolerance is not None:
        s.timeIntegration.newton.absoluteTolerance = absolute_tolerance
    s.timeIntegration.numberOfSteps = int(round(t_end / dt))
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 0
    if threads is not None:
        s.parallel.numberOfThreads = threads
    if linear_solver is not None:
        solver_type = getattr(exu.LinearSolverType, linear_solver)
        if hasattr(s, "linearSolver"):      # exudyn ≥ 1.13 names; the old ones warn there
            s.linearSolver.solverType = solver_type
            s.linearSolver.ignoreSingularJacobian = ignore_singular
        else:
            s.linearSolverType = solver_type
            s.linearSolverSettings.ignoreSingularJacobian = ignore_singular
    if hasattr(s, "solution"):          # exudyn ≥ 1.10 names; the old ones warn there
        s.solution.file.write = False
        s.solution.sensors.writePeriod = dt
    else:
        s.solutionSettings.writeSolutionToFile = False
        s.solutionSettings.sensorsWritePeriod = dt
    ga = s.timeIntegration.generalizedAlpha
    if scheme == "trapezoidal":
        ga.useNewmark = True
        ga.useIndex2Constraints = True
        ga.spectralRadius = 1.0
    elif scheme == "generalized-alpha":
        ga.spectralRadius = rho_inf
    else:
        raise ValueError(f"scheme must be 'generalized-alpha' or 'trapezoidal', got {scheme!r}")
    return s


def solve_recorded(mbs, sensors, settings, stats):
    """Assemble and solve with exudyn's implicit second-order solver; returns (t, [recorded values of each
    sensor], wall seconds). ``stats`` (a dict) receives ``steps``, ``newton``, ``jacobians`` and
    ``cpu_seconds`` (:func:`time.process_time` around the solve, s)."""
    exu, _ = exudyn_modules()
    mbs.Assemble()
    solver = exu.MainSolverImplicitSecondOrder()
    cpu, wall = time.process_time(), time.perf_counter()
    ok = solver.SolveSystem(mbs, settings)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    it = solver.it
    stats.update(steps=max(int(it.currentStepIndex) - 1, 0), newton=int(it.newtonStepsCount),  # index 0: t = 0
                 jacobians=int(it.newtonJacobiCount), cpu_seconds=cpu)
    if not ok:
        raise RuntimeError(f"exudyn's solver stopped before the end time (at t = {it.currentTime} s)")
    data = [np.asarray(mbs.GetSensorStoredData(s)) for s in sensors]
    return data[0][:, 0], [d[:, 1:] for d in data], wall


def _beam(mbs, length, n_elements, EA, EI, GA, rhoA, rhoI):
    """Nodes along +x from the origin and the beam elements between them; returns the node numbers."""
    _, ei = exudyn_modules()
    nodes = [mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[length * i / n_elements, 0.0, 0.0]))
             for i in range(n_elements + 1)]
    elements = [mbs.AddObject(ei.ObjectBeamGeometricallyExact2D(
        nodeNumbers=[nodes[i], nodes[i + 1]], length=length / n_elements, massPerLength=rhoA,
        crossSectionInertia=rhoI, bendingStiffness=EI, axialStiffness=EA, shearStiffness=GA))
        for i in range(n_elements)]
    return nodes, elements


def _hold(mbs, node, coordinates):
    """Coordinate constraints node[c] = 0 for c in ``coordinates``; returns the constraint objects."""
    _, ei = exudyn_modules()
    ground = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=mbs.AddNode(ei.NodePointGround()), coordinate=0))
    return [mbs.AddObject(ei.CoordinateConstraint(markerNumbers=[
        ground, mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=node, coordinate=c))]))
        for c in coordinates]


def _solve(mbs, node, output, settings, stats=None):
    """Record ``output`` ("Position", "Displacement") of ``node``, assemble and solve; returns (t,
    recorded values, seconds). ``stats`` (a dict) receives the steps exudyn took (``steps``: its
    adaptive step control may cut Δt below the requested one) and its Newton iterations (``newton``)."""
    exu, ei = exudyn_modules()
    sensor = mbs.AddSensor(ei.SensorNode(nodeNumber=node, storeInternal=True,
                                         outputVariableType=getattr(exu.OutputVariableType, output)))
    mbs.Assemble()
    start = time.perf_counter()
    exu.SolveDynamic(mbs, settings, storeSolver=True)
    seconds = time.perf_counter() - start
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    if stats is not None:
        it = mbs.sys["dynamicSolver"].it
        stats.update(steps=max(int(it.currentStepIndex) - 1, 0), newton=int(it.newtonStepsCount))   # index 0: t = 0
    return data[:, 0], data[:, 1:], seconds


def spin_up(n_elements=8, dt=1e-3, t_end=30.0, omega=4.0, T=15.0, scheme="generalized-alpha", rho_inf=0.9,
            absolute_tolerance=1e-6):
    """The spin-up beam in exudyn; returns run() -> (t, tip displacement in the hub frame, seconds).

    ``absolute_tolerance``: exudyn's Newton absolute tolerance on the residual, N. Its default,
    1e-10, lies below the round-off floor of this stiff beam's residual (about 1e-8 N with
    EA = 2.8e7 N): Newton then stalls in the first second, when the loads are still tiny, and
    the adaptive step control cuts Δt to about 1e-5 s (some 45 000 steps whatever Δt was asked,
    ``run.stats["steps"]``). 1e-6 N keeps the requested Δt; ``None`` restores exudyn's default.
    """
    length = 10.0
    law = spin_up_law(omega, T)

    def run():
        exu, ei = exudyn_modules()
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        nodes, _ = _beam(mbs, length, n_elements, 2.8e7, 1.4e4, 1e7, 1.2, 6e-4)
        hub = _hold(mbs, nodes[0], (0, 1, 2))[2]

        def prescribe(mbs, t):          # exudyn calls it with the time at the end of the step
            mbs.SetObjectParameter(hub, "offset", float(law.position(t)))
            return True
        mbs.SetPreStepUserFunction(prescribe)
        t, disp, seconds = _solve(mbs, nodes[-1], "Displacement",
                                  simulation_settings(t_end, dt, scheme, rho_inf, absolute_tolerance), run.stats)
        theta = np.array([law.position(x) for x in t])
        x, y = length + disp[:, 0], disp[:, 1]
        c, s = np.cos(theta), np.sin(theta)
        return t, np.stack([c * x + s * y - length, -s * x + c * y], axis=1), seconds
    run.stats = {}
    return run


def flexible_pendulum(n_elements=16, dt=1e-3, t_end=2.0, EI=1e2, scheme="generalized-alpha", rho_inf=0.9):
    """The flexible pendulum in exudyn; returns run() -> (t, tip position, seconds)."""
    length, g = 1.0, 9.81

    def run():
        exu, ei = exudyn_modules()
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        nodes, elements = _beam(mbs, length, n_elements, 1e6, EI, 3.205e5, 1.0, 1e-4)
        _hold(mbs, nodes[0], (0, 1))
        for e in elements:
            mbs.AddLoad(ei.LoadMassProportional(markerNumber=mbs.AddMarker(ei.MarkerBodyMass(bodyNumber=e)),
                                                loadVector=[0.0, -g, 0.0]))
        t, pos, seconds = _solve(mbs, nodes[-1], "Position", simulation_settings(t_end, dt, scheme, rho_inf), run.stats)
        return t, pos[:, :2], seconds
    run.stats = {}
    return run


def pendulum(dt=1e-2, t_end=10.0, length=0.5, v0=1.695, g=9.81, scheme="trapezoidal", rho_inf=0.9):
    """The rigid pendulum (point mass on a rod) in exudyn; returns run() -> (t, position, seconds)."""
    def run():
        exu, ei = exudyn_modules()
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        ground = mbs.AddObject(ei.ObjectGround())
        node = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=[0.0, -length], initialVelocities=[v0, 0.0]))
        mass = mbs.AddObject(ei.MassPoint2D(physicsMass=1.0, nodeNumber=node))
        anchor = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
        bob = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=mass))
        mbs.AddObject(ei.DistanceConstraint(markerNumbers=[anchor, bob], distance=length))
        mbs.AddLoad(ei.LoadCoordinate(markerNumber=mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=node,
                                                                                         coordinate=1)), load=-g))
        t, pos, seconds = _solve(mbs, node, "Position", simulation_settings(t_end, dt, scheme, rho_inf), run.stats)
        return t, pos[:, :2], seconds
    run.stats = {}
    return run
