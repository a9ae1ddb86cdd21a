r"""The rotating beam on exudyn's modally reduced floating-frame body: our reduced spatial floating-frame beam
(:class:`~skfem_flex.bodies.floating_spatial.body.FloatingBeam3D` on a basis of
:mod:`~skfem_flex.bodies.floating_spatial.reduction`) and exudyn's ``ObjectFFRFreducedOrder`` given the same
reduced model, for side-by-side timing at equal error.

The conventions of :mod:`skfem_flex.apps.peer_reduced` (exudyn optional, imported only when a model is run;
:func:`peer_available`): :func:`rotating_beam` returns ``run() -> (t, tip, seconds)``, the recorded times (s),
the probe ``"tip"`` of our scene at every step and the wall time of exudyn's solve (s); after a run
``run.stats`` holds ``steps``, ``newton``, ``jacobians`` and ``cpu_seconds`` (:func:`time.process_time`
around ``SolveSystem``, s). :func:`beam_data` gives the arrays both sides share and :func:`scene` our side.

**The scene** (:data:`ROTATING_BEAM`): the cantilever of ``rotating_beam_3d`` (L = 10 m, EA = 2.8e7 N,
EI = 1.4e4 N m² about both section axes, GJ = 1.4e4 N m², kGA = 1e7 N, ρA = 1.2 kg/m; 8 two-node Timoshenko
elements) clamped to a hub that turns about the vertical z at the constant rate Ω = 2 rad/s (a hinge and a
rotation driver), with the *linear* axial strain: exudyn's reduced body is linear-elastic, it has no
geometric stiffening. At Ω = 2 rad/s, λ = Ω √(ρA L⁴/EI) = 1.85, well below the ≈ 3.5 where the lead-lag
mode of the linear-strain cantilever goes unstable. The beam starts in its steady spin plus the first
flapwise (along z) and first lead-lag (in the plane of rotation) bending modes, each with a tip deflection of
0.05 m, at rest in the spinning frame: both bending planes vibrate (3.8 rad/s flapwise, about 3.2 rad/s
lead-lag, softened by the spin). Probe ``"tip"``: the tip's displacement in the hub frame (axial, in-plane,
out of plane), m.

**One model in both codes.** exudyn's body is a cloud of nodes with three translations each: its kinetic
energy is ½ u̇ᵀ M u̇ of the nodes' velocities with a 3N × 3N mass matrix M, and its inertia invariants are
products of M with the node positions and the mode basis. Ours interpolates the axis' displacement *and*
the sections' rotations; its consistent mass is block-diagonal, ρA on the translations and ρI on the
rotations. With ρI = 0 the rotations carry no kinetic energy, and what is left is ½ u̇ᵀ M_t u̇ with M_t the
translational block, the same form exudyn integrates. So our beam has ρI = 0 exactly: the section accepts
it and the body's invariants (``inertia.py``) simply lose their rotary terms. exudyn gets

* the beam's nodes (0, 0, s) — in exudyn's body axes, see below — and M_t, node-major (x, y, z);
* the translational rows Φ_t of our basis Φ (the rows of the rotations are dropped: no mass sees them);
* a 3N × 3N stiffness K_t = M_tΦ_t G⁻¹ K_r G⁻¹ Φ_tᵀM_t, G = Φ_tᵀM_tΦ_t, built so that exudyn's Φ_tᵀK_tΦ_t is
  our K_r = ΦᵀKΦ exactly (K the beam's full stiffness: shear and bending act through the rotations, which
  exudyn's nodes do not have; only the reduced stiffness enters the motion, since both codes integrate η).

Then both codes have the same configurations (frame, plus Φ_t η on the nodes), the same kinetic and strain
energy, the same coordinates η: the same reduced ODE. The basis is :func:`~skfem_flex.bodies.floating_spatial.reduction.reduction_basis` of the
ρI = 0 beam itself: its modes condense the massless rotations out statically (exact when they carry no
inertia). The basis: the 8 lowest clamped modes (pairs of equal frequency, 3.8, 24.7, 74.5 and 164 rad/s) and
the centrifugal stretch shape (``centrifugal=True``), 9 columns.

**Axes.** Our frame has the beam along d₃, flapwise along d₁ = z and d₂ = −y (``HUB_FRAME``); exudyn's
body axes are the hub's, beam along x, so that its frame starts at the identity and turns about z alone.
Nodes and basis rows are mapped by H = ``HUB_FRAME`` (a vector with components v in our frame has
components Hv in the hub's; H is symmetric and H² = I), and M_t, a scalar mass per pair of nodes times the
identity, is the same in both.

**Rigid-body modes.** exudyn's frame carries the rigid motions: Φ_t must not span any (its mass matrix
would be singular). The clamped basis vanishes at the root node, and the M-Gram matrix of [R Φ_t] is regular,
R the nodes' rigid fields (tested): Φ_t spans none. The nodes lie on a line, so a turn about the beam's
axis moves none of them: that rotation has no inertia, in exudyn's body as in ours with ρI = 0; the hinge
holds it in both.

**Drive.** Ours: ``Revolute3D`` at the root about z and a ``RotationDriver`` at the constant rate Ω, or
(``hub="driven"``) the frame's motion prescribed, the spatial form of a driven hub angle. exudyn's:
the reference node a ``NodeRigidBodyRxyz`` (its frame is then Rz(ψ) with the third angle ψ alone), held by
``CoordinateConstraint`` on the position and the first two angles, and ψ̇ = Ω by a velocity-level
``CoordinateConstraint``: no Python user function runs in exudyn's solve. Both start with the frame at
the identity turning at Ω and the same η, η̇ = 0.

Schemes: exudyn's generalized-α with spectral radius ρ∞ (``rho_inf``) or its trapezoidal (Newmark) rule
with index-2 constraints; Newton as exudyn's default (modified Newton, relative tolerance 1e-8), one thread.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse

from .peer import exudyn_modules, peer_available, simulation_settings, solve_recorded, version

__all__ = ["peer_available", "version", "ROTATING_BEAM", "HUBS", "hub_beam", "beam_data", "tip_map", "scene", "rotating_beam"]

#: the scene (module docstring): hub rate (rad/s), beam data (m, N, N m², kg/m), mesh, basis and the initial
#: tip deflection of each perturbing mode (m)
ROTATING_BEAM = dict(omega=2.0, length=10.0, EA=2.8e7, EI=1.4e4, GJ=1.4e4, kGA=1e7, rhoA=1.2, n_elements=8,
                     order=1, n_modes=8, perturbation=0.05)


def hub_beam(p):
    """The full (unreduced) linear-strain beam of the parameters ``p`` (:data:`ROTATING_BEAM`) with ρI = 0, on
    its hub frame."""
    from ..scenes.spatial_rotors import floating_hub_beam_3d
    return floating_hub_beam_3d(p["length"], p["EA"], p["EI"], p["GJ"], p["kGA"], p["rhoA"], 0.0,
                                p["n_elements"], p["order"], strain="linear")


def beam_data(**parameters):
    """The reduced beam and the arrays exudyn gets (module docstring); ``parameters`` override
    :data:`ROTATING_BEAM`.

    Returns
    -------
    dict
        ``body`` (our reduced FloatingBeam3D with ρI = 0, at rest in its initial state), ``basis`` (Φ on the
        body's elastic DOFs), ``nodes`` (N, 3) in exudyn's body axes (m), ``M`` (3N × 3N csr, kg), ``K`` (3N ×
        3N, N/m), ``modes`` (Φ_t, 3N × m, exudyn's axes), ``K_reduced`` (ΦᵀKΦ), ``eta`` (initial η), ``tip``
        (the tip's node index), ``H`` (our frame's components to the hub's), ``parameters``.
    """
    from ..bodies.floating_spatial.body import FloatingBeam3D
    from ..bodies.floating_spatial.reduction import reduction_basis
    from ..scenes.spatial_rotors import HUB_FRAME

    p = dict(ROTATING_BEAM)
    unknown = set(parameters) - set(p)
    if unknown:
        raise ValueError(f"unknown parameters {sorted(unknown)}; known: {sorted(p)}")
    p.update(parameters)
    full = hub_beam(p)
    Phi = reduction_basis(full, p["n_modes"], centrifugal=True)
    body = FloatingBeam3D(full.beam, "clamped", "linear", orientation=HUB_FRAME, basis=Phi)
    beam = full.beam
    nd = beam.node_dofs                                    # (N, 6), nodes ascending in s
    shapes = body.mesh_shapes(np.eye(Phi.shape[1]))        # Φ on all the beam's DOFs (zero at the root)
    H = np.asarray(HUB_FRAME, dtype=float)
    n = nd.shape[0]
    t_rows = nd[:, :3].ravel()                             # node-major (u₁, u₂, u₃)
    modes = np.einsum("ij,ajm->aim", H, shapes[t_rows].reshape(n, 3, -1)).reshape(3 * n, -1)
    M = beam.mass().tocsr()[t_rows][:, t_rows].tocsr()    # M_t: a scalar per node pair times I, so H M H = M
    K_reduced = shapes.T @ (beam.stiffness() @ shapes)
    K_reduced = 0.5 * (K_reduced + K_reduced.T)
    MP = M @ modes
    G = modes.T @ MP
    A = np.linalg.solve(G, MP.T)                           # G⁻¹ Φ_tᵀ M_t
    K = A.T @ K_reduced @ A
    nodes = np.column_stack([beam.x_nodes, np.zeros(n), np.zeros(n)])   # H (0, 0, s) = (s, 0, 0)
    # initial state: the steady spin about d₁ (z) plus the first flapwise and lead-lag modes (the lowest pair
    # of the basis spans both: equal EI), each scaled to a tip deflection of ``perturbation``
    eta = body.steady_spin(p["omega"])
    tip_rows = body.shape_at(beam.x_nodes[-1])[0][:2, :2]  # (flap u₁, lag u₂) of the first two columns
    eta[:2] += np.linalg.solve(tip_rows, np.full(2, p["perturbation"]))
    body.q0[12:] = eta
    return dict(body=body, basis=Phi, nodes=nodes, M=M, K=scipy.sparse.csr_matrix(0.5 * (K + K.T)), modes=modes,
                K_reduced=K_reduced, eta=eta, tip=n - 1, H=H, parameters=p)


def tip_map(data):
    """G (3, m): the probe ``"tip"`` is G η (the tip's displacement in the hub frame is H S_tip η: the frame
    origin is the clamped root, and H X₀(L) = (L, 0, 0)), so ``q[:, 12:] @ G.T`` gives it from recorded
    coordinates."""
    body = data["body"]
    return data["H"] @ body.shape_at(body.s_tip)[0]


#: how :func:`scene` holds the hub: a hinge and a rate driver (constraint rows), or the frame's motion
#: prescribed (:func:`~skfem_flex.elements.motion.driven_frame`)
HUBS = ("joints", "driven")


def scene(data=None, probe=True, hub="joints", **parameters):
    """Our side: the reduced beam of :func:`beam_data` (``data``, or built from ``parameters``) started spinning
    at Ω about z. Probe ``"tip"`` (module docstring; none with ``probe=False``: :func:`tip_map` gives it from
    the recorded coordinates, without a Python call per recorded step).

    ``hub="joints"``: a ``Revolute3D`` at the root about z and a ``RotationDriver`` at the constant rate Ω
    (12 constraint rows with the frame's rigidity: 33 Newton unknowns). ``hub="driven"``: the frame's origin
    and directors prescribed, turning about z at Ω (:func:`~skfem_flex.elements.motion.driven_frame`, the
    spatial form of a prescribed hub angle): no rows, the 9 elastic coordinates are the only unknowns. The
    two are one motion (``tests/test_driven_frame.py``)."""
    from ..bodies.floating_spatial.body import FloatingBeam3D
    from ..elements.constraints.spatial_joints import Revolute3D, RotationDriver
    from ..elements.motion import MotionLaw, driven_frame
    from ..scene import Scene
    from ..scenes.spatial_rotors import hub_frame_displacement

    if hub not in HUBS:
        raise ValueError(f"hub must be one of {HUBS}, got {hub!r}")
    data = beam_data(**parameters) if data is None else data
    p, proto = data["parameters"], data["body"]
    body = FloatingBeam3D(proto.beam, "clamped", "linear", orientation=data["H"], elastic=data["eta"],
                          basis=data["basis"], name="beam")
    om, z = float(p["omega"]), np.array([0.0, 0.0, 1.0])
    body.v0[3:12] = np.cross(om * z, data["H"].T).ravel()
    rate = MotionLaw.constant_rate(om)
    joints, prescribed = [], []
    if hub == "joints":
        joints = [Revolute3D(body.point(0.0), axis=z, name="hub hinge"),
                  RotationDriver(body, None, z, rate, name="hub drive")]
    else:
        prescribed = driven_frame(body, z, rate)
    return Scene([body], constraints=joints, prescribed=prescribed, name="ffrf_rotating_beam",
                 probes={"tip": hub_frame_displacement(body, body.point(body.s_tip), body.beam.length)} if probe else {},
                 parameters=dict(p, hub=hub))


def exudyn_body(exu, mbs, data):
    """exudyn's ObjectFFRFreducedOrder of ``data`` (:func:`beam_data`) on a NodeRigidBodyRxyz at the origin,
    spinning at Ω about z with η = ``data["eta"]``; returns (interface, body, rigid node, modal node)."""
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface

    fem = FEMinterface()
    fem.nodes = {"Position": data["nodes"]}
    fem.massMatrix, fem.stiffnessMatrix = data["M"], data["K"]
    fem.modeBasis = {"matrix": data["modes"], "type": "CraigBamptonModes"}
    cms = ObjectFFRFreducedOrderInterface(fem, rigidBodyNodeType="NodeType.RotationRxyz")
    made = cms.AddObjectFFRFreducedOrderWithUserFunctions(
        exu, mbs, positionRef=[0.0, 0.0, 0.0], initialAngularVelocity=[0.0, 0.0, float(data["parameters"]["omega"])],
        UFforce=0, UFmassMatrix=0)
    modal = made["nGenericODE2"]
    mbs.SetNodeParameter(modal, "initialCoordinates", [float(e) for e in data["eta"]])
    return cms, made["oFFRFreducedOrder"], made["nRigidBody"], modal


def rotating_beam(dt=1e-2, t_end=10.0, scheme="generalized-alpha", rho_inf=0.9, data=None, **parameters):
    """The rotating beam on exudyn's reduced floating-frame body; returns run() -> (t, tip, seconds).

    Parameters
    ----------
    dt, t_end : float
        Time step and end time, s.
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α.
    data : dict, optional
        :func:`beam_data` (built from ``parameters`` otherwise).

    Returns
    -------
    callable
        ``run()`` builds and solves the model: (t (n,) s, tip (n, 3) m: the tip's displacement in the hub frame,
        seconds: wall time of the solve). ``run.stats``: ``steps``, ``newton``, ``jacobians``, ``cpu_seconds``,
        and exudyn's reduced ``mass_reduced``, ``stiffness_reduced`` (m × m), ``mass`` (kg), ``inertia`` (3, 3)
        kg m² about the frame origin. ``run.data``: the :func:`beam_data` arrays.
    """
    data = beam_data(**parameters) if data is None else data
    omega = float(data["parameters"]["omega"])

    def run():
        exu, ei = exudyn_modules()
        mbs = exu.SystemContainer().AddSystem()
        cms, beam, node, _ = exudyn_body(exu, mbs, data)
        ground = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=mbs.AddNode(ei.NodePointGround()), coordinate=0))
        for c in range(6):      # the hinge (position, the first two angles) and the drive ψ̇ = Ω
            coordinate = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
            mbs.AddObject(ei.CoordinateConstraint(markerNumbers=[ground, coordinate], offset=omega if c == 5 else 0.0,
                                                  velocityLevel=c == 5))
        tip = mbs.AddSensor(ei.SensorSuperElement(bodyNumber=beam, meshNodeNumber=int(data["tip"]), storeInternal=True,
                                                  outputVariableType=exu.OutputVariableType.DisplacementLocal))
        settings = simulation_settings(t_end, dt, scheme, rho_inf, threads=1)
        t, (displacement,), wall = solve_recorded(mbs, [tip], settings, run.stats)
        run.stats.update(mass_reduced=np.asarray(cms.massMatrixReduced, dtype=float),
                         stiffness_reduced=np.asarray(cms.stiffnessMatrixReduced, dtype=float),
                         mass=float(cms.totalMass), inertia=np.asarray(cms.inertiaLocal, dtype=float))
        return t, displacement, wall
    run.stats, run.data = {}, data
    return run
