r"""The reduced rotor of :func:`skfem_flex.scenes.rotor_3d` in exudyn: the same mesh, M, K and reduction basis
on exudyn's modally reduced floating-frame body, for side-by-side timing and accuracy.

The conventions of :mod:`skfem_flex.apps.peer_spatial` (exudyn optional, imported only when a model is run;
:func:`peer_available` says whether it can be): :func:`reduced_rotor` returns a callable
``run() -> (t, disk, seconds)`` with the recorded times (s), the probe ``"disk"`` of our scene (the disk centre's
displacement off the axis, (y, z), m, every step) and the wall-clock time of exudyn's solve (s); after a run
``run.stats`` holds ``steps``, ``newton``, ``jacobians``, ``cpu_seconds`` (:func:`time.process_time` around
``SolveSystem``, s) and ``spin`` (the probe ``"spin"``: the body's angular velocity about its axis x, rad/s, at
every recorded time). :func:`rotor_data` gives the arrays both sides share.

**The body.** exudyn's ``ObjectFFRFreducedOrder`` (through ``exudyn.FEM.FEMinterface`` filled by hand with our
arrays and ``ObjectFFRFreducedOrderInterface``, which computes the inertia invariants from M and the basis,
then ``AddObjectFFRFreducedOrderWithUserFunctions(..., UFforce=0, UFmassMatrix=0)``: the C++ path, no Python
user functions) on a ``NodeRigidBodyEP`` (Euler parameters) and a ``NodeGenericODE2`` of the elastic
coordinates. It gets our :class:`~skfem_flex.fem.elasticity3d.ElasticSolid3D`'s node positions (P2 nodes
included, relative to the frame origin, m), its consistent mass M (kg) and stiffness K (N/m), both in
node-major (x, y, z) order, and our :class:`~skfem_flex.bodies.floating_spatial.solid.FloatingSolid3D`'s
Craig–Bampton basis Φ (8 fixed-interface modes and the 6 static modes of each end face, 20 columns): the same
reduced M and K, the same strain energy ½ηᵀΦᵀKΦη.

**Rigid-body modes.** exudyn's reference frame carries the six rigid-body motions, so the basis must not span
any of them, or its mass matrix is singular (the span of a Craig–Bampton basis with the static modes of every
interface and no clamp does hold them). Ours has none: the disk's nodes are clamped to the frame, so Φ
vanishes on them, while a rigid motion that vanishes on the disk is zero (the M-Gram matrix of [R Φ], R the
six rigid fields, is regular; a test checks it). So Φ goes in as it is (``frame="disk"``, the default): exudyn's frame is then our frame, the
disk's clamp, and the two models have the same configurations x + D(X₀ + Φη) and the same coordinates η.

With ``frame="mean axes"`` the rigid part is projected out M-orthogonally, Φ' = Φ − R(RᵀMR)⁻¹RᵀMΦ (the
linearized mean-axis, Tisserand, condition: Φ'ᵀMR = 0), as one does for a basis that spans rigid motion. The
deformation space is then the same: span[R Φ'] = span[R Φ], and Φ' − Φ is a rigid field, so Φ'η strains the
body exactly as Φη does (same K-energy, RᵀK = 0); what changes is only which small rigid motion the frame
takes over (the mean axes instead of the disk), a difference in the configuration of second order in η.
Then the torque acts on the frame, not the disk (the disk turns against the mean axes by a small rotation
linear in η) and the probe is the mesh node at the disk centre.

The two codes converge to one motion: exudyn's disk probe approaches our energy-momentum run at a small
step as its step is refined (``examples/benchmark.py --only "reduced rotor"`` gives the errors), and the
mean-axes frame changes exudyn's motion by a fraction of a per cent of the whirl
(``tests/test_peer_reduced.py``).

**Joints and loads, as in** :func:`~skfem_flex.scenes.rotor_3d`:

* the two ball bearings: ``SphericalJoint`` between the ground and a ``MarkerSuperElementPosition`` on each
  end face, uniform weights 1/n over its 9 nodes. Our interfaces are rigid (RBE2): on a face every column of
  Φ is a rigid motion t + θ × (X − c) about the face's centre c (the mean of its nodes), so the mean of the
  face's node displacements is t exactly, our interface point's displacement. A position marker is
  therefore exact, and cheaper than a ``MarkerSuperElementRigid`` (whose rotation a ball joint does not use);
* the unbalance: a ``MassPoint`` on a ``NodePoint`` at the rim point (0, D/2, 0) from the disk centre, on a
  ``SphericalJoint`` to a ``MarkerSuperElementPosition`` on the mesh node there (a disk node: it moves
  rigidly with the frame, as our frame point does);
* the drive: ``LoadTorqueVector`` (global axes, N m) on a ``MarkerNodeRigid`` of the reference node, (τ, 0, 0)
  for t ≤ T and zero after (a pre-step function switches it off when the run goes past T);
* the same initial state (at rest, frame origin at the world origin, axes the mesh's); no gravity (our scene
  has none).

Schemes: exudyn's generalized-α with spectral radius ρ∞ (``rho_inf``) or its Newmark/trapezoidal rule with
index-2 constraints (``scheme="trapezoidal"``); Newton is exudyn's default (modified Newton, relative tolerance
1e-8, absolute 1e-10), ``round(t_end/dt)`` steps (adaptive step control on, as by default), one thread, the
rotation node's Euler parameters. ρ∞ = 0.9 is exudyn's default and ours here; a lower ρ∞ (exudyn's own
performance test uses 0.5) damps the spin more.
"""
from __future__ import annotations

import inspect

import numpy as np

from .peer import exudyn_modules, peer_available, simulation_settings, solve_recorded, version

__all__ = ["peer_available", "version", "rotor_data", "rigid_fields", "reduced_rotor", "FRAMES"]

#: the frames :func:`reduced_rotor` offers (module docstring)
FRAMES = ("disk", "mean axes")


def rigid_fields(X):
    """The six rigid motions (3 translations, 3 small rotations about the origin) of nodes at ``X`` (n, 3), m,
    as (3n, 6) columns in node-major (x, y, z) order (m per m and m per rad)."""
    X = np.asarray(X, dtype=float)
    R = np.zeros((X.shape[0], 3, 6))
    for c in range(3):
        R[:, c, c] = 1.0
    # θ × X: e_x × X = (0, −z, y), e_y × X = (z, 0, −x), e_z × X = (−y, x, 0)
    R[:, 1, 3], R[:, 2, 3] = -X[:, 2], X[:, 1]
    R[:, 0, 4], R[:, 2, 4] = X[:, 2], -X[:, 0]
    R[:, 0, 5], R[:, 1, 5] = -X[:, 1], X[:, 0]
    return R.reshape(-1, 6)


def rotor_data(torque=20.0, T=1.0, unbalance=0.01, n_modes=8, frame="disk"):
    """The arrays of :func:`skfem_flex.scenes.rotor_3d` in exudyn's form (node-major (x, y, z) DOFs).

    Parameters
    ----------
    torque, T, unbalance, n_modes :
        As :func:`~skfem_flex.scenes.rotor_3d`: drive torque (N m) on during [0, T] (s), unbalance mass (kg),
        fixed-interface modes.
    frame : {"disk", "mean axes"}
        The basis as ours (the frame clamped to the disk) or with its rigid part projected out M-orthogonally
        (module docstring).

    Returns
    -------
    dict
        ``scene`` (our scene), ``body`` (its FloatingSolid3D), ``nodes`` (n, 3) positions from the frame origin
        (m), ``M``, ``K`` (csr, kg and N/m), ``basis`` (3n, m), ``faces`` {interface name: node indices},
        ``rim`` (the mesh node at the unbalance's point), ``centre`` (the mesh node at the disk centre),
        ``rim_point`` (3,) m, ``torque``, ``T``, ``unbalance``.
    """
    from ..scenes import rotor_3d
    from ..scenes.spatial_rotors import ROTOR_3D

    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}, got {frame!r}")
    scene = rotor_3d(torque=torque, T=T, unbalance=unbalance, n_modes=n_modes)
    body = scene.bodies[0]
    solid = body.solid
    order = solid.component_dofs.T.ravel()              # node-major: (x, y, z) of node 0, node 1, …
    X = solid.node_positions - body.origin
    M, K = solid.mass[order][:, order].tocsr(), solid.stiffness[order][:, order].tocsr()
    basis = body.basis[order]
    if frame == "mean axes":
        R = rigid_fields(X)
        MR = M @ R
        basis = basis - R @ np.linalg.solve(R.T @ MR, MR.T @ basis)
    # the end faces, selected as rotor_3d selects its interfaces; their node means are its interface points
    x = solid.node_positions[:, 0]
    faces = {"driven end": np.flatnonzero(np.isclose(x, 0.0)), "far end": np.flatnonzero(np.isclose(x, ROTOR_3D["length"]))}
    for name, nodes in faces.items():
        if not np.allclose(X[nodes].mean(axis=0), body.centres[name], atol=1e-12):
            raise ValueError(f"interface {name!r}: its nodes are not the scene's")
    rim_point = np.array([0.0, ROTOR_3D["disk"] / 2, 0.0])
    nearest = [int(np.argmin(np.linalg.norm(X - p, axis=1))) for p in (rim_point, np.zeros(3))]
    for node, p in zip(nearest, (rim_point, np.zeros(3))):
        if np.linalg.norm(X[node] - p) > 1e-9:
            raise ValueError(f"the rotor's mesh has no node at {p} m from the disk centre")
    return dict(scene=scene, body=body, nodes=X, M=M, K=K, basis=basis, faces=faces, rim=nearest[0],
                centre=nearest[1], rim_point=rim_point, torque=float(torque), T=float(T), unbalance=float(unbalance))


def _reduced_body(exu, mbs, data):
    """exudyn's ObjectFFRFreducedOrder of ``data`` (:func:`rotor_data`) at rest at the origin; returns
    (interface object, body number, rigid node, modal node)."""
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface

    fem = FEMinterface()
    fem.nodes = {"Position": data["nodes"]}
    fem.massMatrix, fem.stiffnessMatrix = data["M"], data["K"]
    fem.modeBasis = {"matrix": data["basis"], "type": "CraigBamptonModes"}
    cms = ObjectFFRFreducedOrderInterface(fem)
    made = cms.AddObjectFFRFreducedOrderWithUserFunctions(exu, mbs, positionRef=[0.0, 0.0, 0.0],
                                                          UFforce=0, UFmassMatrix=0)
    return cms, made["oFFRFreducedOrder"], made["nRigidBody"], made["nGenericODE2"]


def reduced_rotor(dt=1e-3, t_end=1.0, scheme="generalized-alpha", rho_inf=0.9, torque=20.0, T=1.0, unbalance=0.01,
                  n_modes=8, frame="disk"):
    """The rotor of :func:`skfem_flex.scenes.rotor_3d` on exudyn's reduced floating-frame body; returns
    run() -> (t, disk, seconds).

    Parameters
    ----------
    dt, t_end : float
        Time step and end time, s.
    scheme : {"generalized-alpha", "trapezoidal"}
    rho_inf : float
        Spectral radius of generalized-α (exudyn's default 0.9; module docstring).
    torque, T, unbalance, n_modes :
        As :func:`~skfem_flex.scenes.rotor_3d`: drive torque about the shaft axis x (N m) during [0, T] (s),
        unbalance mass on the rim (kg), fixed-interface modes.
    frame : {"disk", "mean axes"}
        exudyn's frame: our frame (the disk's clamp; the same model) or the mean axes (the basis's rigid part
        projected out; module docstring).

    Returns
    -------
    callable
        ``run()`` builds and solves the model: (t (n,) s, disk (n, 2) m: the disk centre's y, z, seconds: wall
        time of the solve). ``run.stats``: ``steps``, ``newton``, ``jacobians``, ``cpu_seconds`` (s), ``spin``
        (n,) rad/s (angular velocity about the body's x), ``mass`` (kg) and ``inertia`` (3, 3) kg m² of exudyn's
        body about the frame origin (from its reduced invariants), ``n_elastic``. ``run.data``: the
        :func:`rotor_data` arrays.
    """
    data = rotor_data(torque, T, unbalance, n_modes, frame)
    tau, duration, mass = data["torque"], data["T"], data["unbalance"]

    def run():
        exu, ei = exudyn_modules()
        mbs = exu.SystemContainer().AddSystem()
        cms, rotor, node, modal = _reduced_body(exu, mbs, data)
        ground = mbs.AddObject(ei.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        for name, nodes in data["faces"].items():              # the ball bearings
            face = mbs.AddMarker(ei.MarkerSuperElementPosition(bodyNumber=rotor, meshNodeNumbers=nodes.tolist(),
                                                               weightingFactors=[1.0 / nodes.size] * nodes.size))
            at = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground,
                                                     localPosition=list(data["nodes"][nodes].mean(axis=0))))
            mbs.AddObject(ei.SphericalJoint(markerNumbers=[at, face], visualization=ei.VSphericalJoint(show=False)))
        if mass > 0.0:                                             # the unbalance on its spherical joint
            point = mbs.AddNode(ei.NodePoint(referenceCoordinates=list(data["rim_point"])))
            # exudyn ≥ 1.12 names the mass ``mass``; older versions ``physicsMass`` (deprecated since)
            named = "mass" if "mass" in inspect.signature(ei.MassPoint).parameters else "physicsMass"
            mbs.AddObject(ei.MassPoint(nodeNumber=point, **{named: mass}))
            rim = mbs.AddMarker(ei.MarkerSuperElementPosition(bodyNumber=rotor, meshNodeNumbers=[data["rim"]],
                                                              weightingFactors=[1.0]))
            mbs.AddObject(ei.SphericalJoint(markerNumbers=[rim, mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=point))],
                                            visualization=ei.VSphericalJoint(show=False)))
        drive = mbs.AddLoad(ei.LoadTorqueVector(markerNumber=mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=node)),
                                                loadVector=[tau, 0.0, 0.0]))
        if t_end > duration:
            def switch_off(mbs, t):                # exudyn calls it with the time at the end of the step
                if t > duration:
                    mbs.SetLoadParameter(drive, "loadVector", [0.0, 0.0, 0.0])
                return True
            mbs.SetPreStepUserFunction(switch_off)
        if frame == "disk":                        # the frame origin is the disk centre
            disk = mbs.AddSensor(ei.SensorNode(nodeNumber=node, storeInternal=True,
                                               outputVariableType=exu.OutputVariableType.Position))
        else:
            disk = mbs.AddSensor(ei.SensorSuperElement(bodyNumber=rotor, meshNodeNumber=data["centre"],
                                                       storeInternal=True,
                                                       outputVariableType=exu.OutputVariableType.Position))
        spin = mbs.AddSensor(ei.SensorNode(nodeNumber=node, storeInternal=True,
                                           outputVariableType=exu.OutputVariableType.AngularVelocityLocal))
        settings = simulation_settings(t_end, dt, scheme, rho_inf, threads=1)
        t, (position, rates), wall = solve_recorded(mbs, [disk, spin], settings, run.stats)
        run.stats.update(mass=float(cms.totalMass), inertia=np.asarray(cms.inertiaLocal, dtype=float),
                         n_elastic=int(cms.nModes), spin=rates[:, 0])
        return t, position[:, 1:3], wall
    run.stats, run.data = {}, data
    return run
