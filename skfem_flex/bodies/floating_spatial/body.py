r"""Spatial floating frame of reference: a 3D Timoshenko beam in large overall motion.

A :class:`FloatingBeam3D` carries the coordinates of a body frame, its origin x and its directors
d₁, d₂, d₃ (the frame of a :class:`~skfem_flex.bodies.spatial.SpatialRigidBody`, held orthonormal by the
scene's rigidity constraints), and elastic coordinates y of a
:class:`~skfem_flex.fem.spatial_beam.TimoshenkoBeam3D` measured in that frame. The beam lies along d₃;
d₁, d₂ are its section's principal axes. A point of the axis at arc length s is at

.. math::  r(s) = x + D\,(X_0(s) + S(s)\,y),\qquad X_0 = (0, 0, s),\quad D = [d_1\ d_2\ d_3],

and its section turns by θ(s) = N_θ(s) y relative to the frame (small). Reference conditions remove the
six rigid modes from y: ``"clamped"`` eliminates the six DOFs of the root (the frame is the root
section), ``"chord"`` eliminates u₁, u₂, u₃ and the twist θ₃ at the root and u₁, u₂ at the tip (the
frame's axis d₃ runs through both ends).

The kinetic energy (``kinetics.py``, on the invariants of ``inertia.py``, assembled once) and the gravity
potential are polynomials of degree two in q, and the strain energy (``strain.py``) depends on y only:
every discrete gradient is exact, and the energy–momentum scheme conserves energy to the Newton
tolerance. Coriolis, centrifugal and Euler forces are the quadratic-velocity force of M(q); with the
Green–Lagrange axis (``strain="green-lagrange"``) the centrifugal tension stiffens bending in both planes,
with ``strain="linear"`` it does not (and the lead-lag mode of a fast rotor diverges).

This is a Python body: scenes that hold it run on the Python-assembled path (``Result.run_path`` says so).
"""
from __future__ import annotations

import numpy as np

from ...fem.spatial_beam import FIELDS_3D, TimoshenkoBeam3D
from ..base import BodyGeometry, check_finite_vector
from ..spatial import SpatialPoint
from . import kinetics
from .frame import ElasticPoint, FloatingFrame3D
from .inertia import projected_inertia, spatial_frame_inertia
from .reduction import reduction_basis
from .rotation import spinning_modes, steady_spin
from .strain import SpatialBeamStrain

__all__ = ["FloatingBeam3D"]

_REFERENCES = {"clamped": (("root", (0, 1, 2, 3, 4, 5)),),
               "chord": (("root", (0, 1, 2, 5)), ("tip", (0, 1)))}


class FloatingBeam3D(FloatingFrame3D):
    """A spatial Timoshenko beam in the floating frame of reference (module docstring).

    Coordinates q = (x, d₁, d₂, d₃, y), named ``"x", "y", "z", "d1x", ..., "d3z"`` and then
    ``"u1_1", ..., "theta3_<node>"`` (field and node number from the root) for the elastic DOFs left by
    the reference condition.

    Parameters
    ----------
    beam : TimoshenkoBeam3D
        A straight beam over the arc length s (its mesh), along the frame's d₃.
    reference : {"clamped", "chord"}
    strain : {"green-lagrange", "linear"}
        Axial strain measure (``strain.py``).
    position : array_like (3,)
        Initial frame origin x, m (the point s = 0 of the axis).
    orientation : array_like, (4,) or (3, 3)
        Initial frame: Euler parameters or rotation matrix [d₁ d₂ d₃] (the beam along its third column).
    velocity, angular_velocity : array_like (3,)
        Initial ẋ (m/s) and frame angular velocity ω in space axes (rad/s).
    elastic, elastic_velocity : array_like (n_elastic,), optional
        Initial y and ẏ (η and η̇ of a reduced body).
    name : str
    basis : array_like (n_beam_elastic, m), optional
        A reduction basis Φ: the elastic coordinates are then η with y = Φ η, named ``"eta1", ...``
        (``reduction.py``; :meth:`reduced` builds one).

    Raises
    ------
    ValueError
        For a beam that is not a TimoshenkoBeam3D, an unknown reference condition or strain measure, a
        rotation that is not a rotation, or non-finite or wrongly sized initial data.
    """

    def __init__(self, beam, reference="clamped", strain="green-lagrange", position=(0.0, 0.0, 0.0),
                 orientation=None, velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), elastic=None,
                 elastic_velocity=None, name="beam", basis=None):
        if not isinstance(beam, TimoshenkoBeam3D):
            raise ValueError(f"FloatingBeam3D needs a TimoshenkoBeam3D, got {beam!r}")
        if reference not in _REFERENCES:
            raise ValueError(f"reference must be one of {sorted(_REFERENCES)}, got {reference!r}")
        self.beam, self.section, self.reference, self.strain, self.name = beam, beam.section, reference, strain, name
        self.s_root, self.s_tip = float(beam.x_nodes[0]), float(beam.x_nodes[-1])
        ends = {"root": beam.node_dofs[0], "tip": beam.node_dofs[-1]}
        fixed = np.array(sorted(int(ends[end][k]) for end, fields in _REFERENCES[reference] for k in fields))
        self.fixed_dofs = fixed
        self.free_dofs = np.setdiff1d(np.arange(beam.n_dofs), fixed)
        self.inertia = spatial_frame_inertia(beam, self.free_dofs)
        self.strain_energy = SpatialBeamStrain(beam, self.free_dofs, strain)
        frame_names = ("x", "y", "z") + tuple(f"d{i}{c}" for i in (1, 2, 3) for c in "xyz")
        if basis is None:
            self.basis = None
            node_of = {int(d): (node, k) for node, row in enumerate(beam.node_dofs) for k, d in enumerate(row)}
            elastic_names = tuple(f"{FIELDS_3D[node_of[int(d)][1]]}_{node_of[int(d)][0] + 1}" for d in self.free_dofs)
        else:
            Phi = np.asarray(basis, dtype=float)
            if Phi.ndim != 2 or Phi.shape[0] != self.free_dofs.size or not np.all(np.isfinite(Phi)) \
                    or np.linalg.matrix_rank(Phi) < Phi.shape[1]:
                raise ValueError(f"basis must be a finite ({self.free_dofs.size}, m) array of independent columns, "
                                 f"got shape {Phi.shape}")
            self.basis = Phi
            self.inertia = projected_inertia(self.inertia, Phi)
            self.strain_energy = self.strain_energy.projected(Phi)
            elastic_names = tuple(f"eta{k + 1}" for k in range(Phi.shape[1]))
        self.n_elastic = len(elastic_names)
        self.n_dofs = 12 + self.n_elastic
        self._names = frame_names + elastic_names

        self.set_initial_state(position, orientation, velocity, angular_velocity, elastic, elastic_velocity)

    # ================================================================ coordinates
    @property
    def coordinate_names(self):
        return self._names

    def elastic_vector(self, full):
        """y from a vector over all the beam's DOFs (``beam.node_dofs`` numbering); ValueError if it is not
        zero where the reference condition eliminates a DOF (a reduced body: ValueError)."""
        if self.basis is not None:
            raise ValueError(f"body {self.name!r} is reduced: its elastic coordinates are modal amplitudes")
        full = check_finite_vector("elastic field", full, self.beam.n_dofs)
        bad = np.abs(full[self.fixed_dofs])
        if bad.size and bad.max() > 1e-12 * max(1.0, np.abs(full).max()):
            raise ValueError(f"elastic field is not zero at the DOFs the reference condition {self.reference!r} "
                             f"eliminates: {full[self.fixed_dofs]}")
        return full[self.free_dofs].copy()

    def full_elastic(self, q):
        """The beam's DOF vector (u₁, u₂, u₃, θ₁, θ₂, θ₃ per node, in the frame's axes) of q."""
        d = np.zeros(self.beam.n_dofs)
        y = np.asarray(q, dtype=float)[12:]
        d[self.free_dofs] = y if self.basis is None else self.basis @ y
        return d

    # ================================================================ points
    def shape_at(self, s):
        """S(s) (3, n_elastic) and N_θ(s) (3, n_elastic) at arc length s (m); ValueError off the beam."""
        if isinstance(s, bool) or not np.isscalar(s) or not np.isfinite(s):
            raise ValueError(f"a point of beam {self.name!r}: arc length s must be a finite number, got {s!r}")
        tol = 1e-9 * self.beam.length
        if not self.s_root - tol <= s <= self.s_tip + tol:
            raise ValueError(f"s = {s!r} lies outside beam {self.name!r} [{self.s_root}, {self.s_tip}]")
        s = float(np.clip(s, self.s_root, self.s_tip))
        beam = self.beam
        pr = beam.field_basis.probes(np.array([[s]])).tocsr()
        field_dofs = np.array(beam.basis.split_indices())
        full = np.zeros((6, beam.n_dofs))
        for k in range(6):
            full[k, field_dofs[k][pr.indices]] = pr.data
        full = full[:, self.free_dofs]
        if self.basis is not None:
            full = full @ self.basis
        return full[:3].copy(), full[3:].copy()

    def point(self, locator=None):
        """The material point of the axis at arc length ``locator`` (m; default the tip). Where the
        reference condition clamps the beam it is the frame's own point (affine in q, with the frame's
        orientation, so spatial joints take it); elsewhere an :class:`~.frame.ElasticPoint` (loads and probes),
        which turns with the section's elastic rotation (following forces)."""
        s = self.s_tip if locator is None else locator
        S, Nth = self.shape_at(s)
        if not S.any() and not Nth.any():
            return SpatialPoint(self, np.array([0.0, 0.0, float(s)]))
        return ElasticPoint(self, np.array([0.0, 0.0, float(s)]), S, Theta=Nth)

    def mesh_shapes(self, vectors):
        """Columns on the elastic coordinates as columns on the beam's DOFs (zero where the reference condition
        holds them)."""
        vectors = np.asarray(vectors)
        out = np.zeros((self.beam.n_dofs,) + vectors.shape[1:], dtype=vectors.dtype)
        out[self.free_dofs] = vectors if self.basis is None else self.basis @ vectors
        return out

    def motion_rows(self, axis):
        """The beam DOFs of the displacement along frame axis ``axis`` (0, 1, 2) at every node."""
        return self.beam.node_dofs[:, int(axis)]

    # ================================================================ reduction
    def reduced(self, n_modes, interfaces=("root",), n_derivatives=None, centrifugal=None, name=None):
        """This beam on a reduction basis (:func:`.reduction.reduction_basis`: Craig–Bampton for the clamped
        frame, free-interface modes for the chord frame, with stiffening derivatives and centrifugal shapes
        for the Green–Lagrange axis): a new :class:`FloatingBeam3D` in the same initial frame state, its
        elastic state the M-projection of this one's."""
        Phi = reduction_basis(self, n_modes, interfaces, n_derivatives, centrifugal)
        M = self.mass_matrix(self.q0)[12:, 12:]
        x, D, _ = kinetics.split(self.q0)
        out = FloatingBeam3D(self.beam, self.reference, self.strain, position=x, orientation=D,
                             elastic=Phi.T @ M @ self.q0[12:], elastic_velocity=Phi.T @ M @ self.v0[12:],
                             name=self.name if name is None else name, basis=Phi)
        out.v0[:12] = self.v0[:12]
        return out

    # ================================================================ steady spin
    def steady_spin(self, omega, axis=(1.0, 0.0, 0.0)):
        """The elastic state y (n_elastic,) of the beam spinning at ``omega`` (rad/s) about ``axis`` (frame axes)
        with its frame origin fixed (:func:`.rotation.steady_spin`)."""
        return steady_spin(self, omega, axis)

    def spinning_modes(self, omega, axis=(1.0, 0.0, 0.0), n_modes=8):
        """Modes about that steady spin in the spinning frame, flapwise along d₁, lead-lag along d₂
        (:func:`.rotation.spinning_modes`; a :class:`~skfem_flex.fem.spatial_beam.RotatingModes`)."""
        return spinning_modes(self, omega, axis, n_modes, flap_axis=0, lag_axis=1)

    # ================================================================ output
    def strains(self, q):
        """u' (3, n_points) of the axis and the axial strain ε at the Gauss points."""
        return self.strain_energy.strains(np.asarray(q, dtype=float)[12:])

    def geometry(self, q, v):
        """The axis through the nodes (line cells) with displacement and velocity, and the section frame
        (d₁, d₂ of each node turned by its θ)."""
        x, D, y = kinetics.split(q)
        vx, V, vy = kinetics.split(v)
        full = self.full_elastic(q)
        fv = self.full_elastic(np.concatenate([np.zeros(12), vy]))
        nd = self.beam.node_dofs
        rho = np.stack([full[nd[:, 0]], full[nd[:, 1]], self.beam.x_nodes + full[nd[:, 2]]], axis=1)
        pts = x + rho @ D.T
        vel = vx + rho @ V.T + np.stack([fv[nd[:, k]] for k in range(3)], axis=1) @ D.T
        x0, D0, _ = kinetics.split(self.q0)
        ref = x0 + np.stack([np.zeros_like(self.beam.x_nodes), np.zeros_like(self.beam.x_nodes),
                             self.beam.x_nodes], axis=1) @ D0.T
        theta = np.stack([full[nd[:, k]] for k in range(3, 6)], axis=1)
        d1 = (np.eye(3)[0] + np.cross(theta, np.eye(3)[0])) @ D.T
        d2 = (np.eye(3)[1] + np.cross(theta, np.eye(3)[1])) @ D.T
        order = np.argsort(self.beam.x_nodes)
        conn = np.stack([order[:-1], order[1:]], axis=1)
        return BodyGeometry(pts, [("line", conn)], {"displacement": pts - ref, "velocity": vel, "d1": d1, "d2": d2},
                            {})
