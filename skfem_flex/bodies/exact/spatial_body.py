r"""Geometrically exact spatial beam (Simo–Reissner) in the director formulation: the body.

:class:`SpatialExactBeam` carries at every node of a scikit-fem line mesh over the reference arc length
s the position φ of the beam axis and the section's directors d₁, d₂, d₃ (principal axes and normal),
all in the inertial frame; there is no floating frame and no rotation parameter. The scene holds every
nodal triad orthonormal with six quadratic equations, as it holds a spatial rigid body
(:mod:`skfem_flex.bodies.spatial`). The kinetic energy

.. math::  T = ½ \int ρA \, \dot φ · \dot φ + ρI₂ \, \dot d_1 · \dot d_1 + ρI₁ \, \dot d_2 · \dot d_2 \; ds

with the interpolated velocities makes the mass matrix constant: scikit-fem's consistent mass
∫ N_a N_b ds of the scalar field, once for each vector (d₃ carries no inertia; the rigidity equations
fix it). The strains, the strain energy and its exact, equivariant discrete gradient are in
:mod:`skfem_flex.bodies.exact.director_strain`. With both, the energy–momentum scheme conserves energy,
linear and angular momentum of a free beam to the Newton tolerance, and the orthonormality of every
triad to round-off.

Points of the beam (:meth:`SpatialExactBeam.point`) are located by s; their position Σ N_a(s) φ_a is
linear in q, so spatial joints, point forces and gravity take them as they take a rigid body's points.
A point at a node turns with that node's directors (joint axes, welds, moments, following forces).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import skfem
from skfem import Basis, BilinearForm, ElementLineP1, ElementLineP2, asm

from ...fem.beam import line_mesh
from ...fem.spatial_section import SpatialSection
from ...numerics.quaternions import check_rotation_matrix
from ..base import DENSE_LIMIT, Body, BodyGeometry, StrainPointsPotential, check_finite_number, check_finite_vector
from ..spatial import SpatialPoint
from .director_strain import NODE_SIZE, DirectorStrainPoints
from .rotation_strain import RotationStrainPoints

__all__ = ["SpatialExactBeam", "straight_placement"]


@BilinearForm
def _scalar_mass(u, v, w):
    return u * v


def straight_placement(start, end, normal=None):
    """The placement s ↦ (position, frame) of a straight beam from ``start`` to ``end`` (m).

    d₃ points from start to end; d₁ is the part of ``normal`` perpendicular to it (default: the global z
    axis, or y for a beam along z), d₂ = d₃ × d₁. Returns (placement, length).

    Raises
    ------
    ValueError
        For coincident ends or a ``normal`` parallel to the beam axis.
    """
    a = check_finite_vector("start", start, 3)
    b = check_finite_vector("end", end, 3)
    length = float(np.linalg.norm(b - a))
    if length <= 0.0:
        raise ValueError(f"start and end must differ, got {start!r} and {end!r}")
    d3 = (b - a) / length
    if normal is None:
        normal = (0.0, 0.0, 1.0) if abs(d3[2]) < 0.9 else (0.0, 1.0, 0.0)
    n = check_finite_vector("normal", normal, 3)
    d1 = n - (n @ d3) * d3
    if float(np.linalg.norm(d1)) <= 1e-8 * max(float(np.linalg.norm(n)), 1e-300):
        raise ValueError(f"the section's reference vector normal={normal!r} is parallel to the beam axis "
                         f"{d3.tolist()}: it must have a part perpendicular to it")
    d1 /= np.linalg.norm(d1)
    frame = np.column_stack([d1, np.cross(d3, d1), d3])

    def placement(s):
        return a + s * d3, frame

    return placement, length


class SpatialExactBeam(StrainPointsPotential, Body):
    r"""Spatial geometrically exact beam with nodal positions and directors (module docstring).

    Parameters
    ----------
    section : SpatialSection
    length : float
        Reference arc length L, m; the mesh runs over s ∈ [0, L].
    placement : callable
        s ↦ (φ₀(s) (3,), R₀(s) (3, 3)): the reference position of the axis and the reference frame
        [d₁ d₂ d₃] of the section at arc length s, evaluated at the nodes. The reference configuration is
        stress-free; it may be curved and twisted (d₃ need not be the tangent: an initial shear is
        measured from it). See :func:`straight_placement` and :meth:`straight`.
    n_elements : int
        Elements on a uniform mesh (or give ``mesh``).
    order : {1, 2}
        P1 or P2 interpolation (one or two strain points per element).
    interpolation : {"rotations", "directors"}, optional
        How the section turns between nodes. ``"rotations"`` (P1 only; the default there): by the
        relative rotation of the two nodal triads, a constant curvature and twist per element
        (:mod:`.rotation_strain`); any constant curvature is then exact. ``"directors"`` (the default
        and only choice for P2): the directors interpolated like the positions (:mod:`.director_strain`),
        which represents a constant curvature κ as sin(κh)/h.
    mesh : skfem.MeshLine, optional
        Own mesh over [0, L] instead of the uniform one.
    q0, v0 : array_like, optional
        Initial coordinates and velocities (default: the reference configuration at rest); see
        :meth:`rigid_velocity`.
    name : str
    section_size : array_like (2,), optional
        Width along d₁ and height along d₂ (m) of a rectangle the VTK output sweeps along the axis as
        hexahedra (besides the polyline), carrying the segments' strains and section forces.

    Notes
    -----
    Coordinates: node i (ascending s) has q[12 i: 12 i + 12] = (φ, d₁, d₂, d₃), named ``x{i}`` … ``d3z{i}``.

    Raises
    ------
    ValueError
        For a section that is not a SpatialSection, a placement frame that is not a rotation, a
        non-positive length, or initial states of the wrong size or not finite.

    Examples
    --------
    >>> sec = SpatialSection(EA=1e4, GA1=1e4, GA2=1e4, GJ=500, EI1=500, EI2=500, rhoA=1, rhoI1=10, rhoI2=10)
    >>> beam = SpatialExactBeam.straight(sec, (0, 0, 8), (6, 0, 0), n_elements=10)
    >>> beam.n_dofs, len(beam.director_triads)
    (132, 11)
    """

    constant_mass = True
    has_potential = True
    dimension = 3

    def __init__(self, section, length, placement, n_elements=10, order=1, mesh=None, q0=None, v0=None,
                 name="spatial_beam", section_size=None, interpolation=None):
        if not isinstance(section, SpatialSection):
            raise ValueError(f"section must be a skfem_flex SpatialSection, got {section!r}")
        if order not in (1, 2):
            raise ValueError(f"order must be 1 or 2, got {order!r}")
        if interpolation is None:
            interpolation = "rotations" if order == 1 else "directors"
        if interpolation not in ("rotations", "directors"):
            raise ValueError(f"interpolation must be 'rotations' or 'directors', got {interpolation!r}")
        if interpolation == "rotations" and order != 1:
            raise ValueError("interpolation='rotations' is a two-node element: it needs order=1, "
                             f"got order={order!r}")
        #: how the section turns between nodes: "rotations" or "directors"
        self.interpolation = interpolation
        self.section, self.order, self.name = section, int(order), str(name)
        if section_size is not None:
            size = check_finite_vector("section_size", section_size, 2)
            if np.any(size <= 0.0):
                raise ValueError(f"section_size must be two positive lengths (along d₁, d₂) in m, "
                                 f"got {section_size!r}")
            section_size = size
        #: (width along d₁, height along d₂) of the rectangle the output sweeps along the axis, m, or None
        self.section_size = section_size
        self.length = check_finite_number("length", length)
        if self.length <= 0.0:
            raise ValueError(f"length must be positive, got {length!r} m")
        if mesh is None:
            mesh = line_mesh(self.length, n_elements, order)
        elif not isinstance(mesh, skfem.MeshLine1) or abs(mesh.p.max() - self.length) > 1e-9 * self.length \
                or abs(mesh.p.min()) > 1e-9 * self.length:
            raise ValueError(f"mesh must be a skfem.MeshLine over [0, length = {self.length}] m")
        self.mesh = mesh
        basis = Basis(mesh, ElementLineP1() if order == 1 else ElementLineP2())
        s_dofs = np.asarray(basis.doflocs[0], dtype=float)
        order_s = np.argsort(s_dofs, kind="stable")
        node_of_dof = np.empty(order_s.size, dtype=np.int64)
        node_of_dof[order_s] = np.arange(order_s.size)
        #: reference arc length of the nodes, ascending, m
        self.s_nodes = s_dofs[order_s]
        self.n_nodes = int(self.s_nodes.size)
        self._basis, self._node_of_dof = basis, node_of_dof
        n = self.n_dofs = NODE_SIZE * self.n_nodes
        self.dense = n <= DENSE_LIMIT

        # the reference configuration
        qref = np.zeros(n)
        for i, s in enumerate(self.s_nodes):
            pos, frame = placement(float(s))
            pos = check_finite_vector(f"placement position at s = {s:g}", pos, 3)
            frame = check_rotation_matrix(f"placement frame at s = {s:g}", frame)
            qref[NODE_SIZE * i:NODE_SIZE * i + NODE_SIZE] = np.concatenate([pos, frame.T.ravel()])
        self.q_reference = qref
        self.q0 = qref.copy() if q0 is None else check_finite_vector("q0", q0, n)
        self.v0 = np.zeros(n) if v0 is None else check_finite_vector("v0", v0, n)

        #: the strain points, strains and energy: :class:`.rotation_strain.RotationStrainPoints` or
        #: :class:`.director_strain.DirectorStrainPoints`
        if interpolation == "rotations":
            self.strain_points = RotationStrainPoints(mesh, node_of_dof, section.stiffness, qref, self.dense,
                                                      name=self.name)
        else:
            self.strain_points = DirectorStrainPoints(mesh, self.order, node_of_dof, section.stiffness, qref,
                                                      self.dense)

        # constant operators, assembled once by scikit-fem
        m = asm(_scalar_mass, basis).tocoo()
        scalar = sps.csr_matrix((m.data, (node_of_dof[m.row], node_of_dof[m.col])), shape=(self.n_nodes,) * 2)
        per_node = np.repeat([section.rhoA, section.rhoI2, section.rhoI1, 0.0], 3)
        mass = sps.kron(scalar, sps.diags(per_node)).tocsr()
        mass.eliminate_zeros()
        self._mass = mass.toarray() if self.dense else mass
        #: ∫ N_a ds of every node, m
        self.node_weights = np.asarray(scalar.sum(axis=1)).ravel()
        #: ∫ N_a N_b ds of every pair of nodes (n_nodes × n_nodes, csr), m: the consistent load of a field
        #: interpolated like the coordinates (a following force per length)
        self.node_products = scalar.tocsr()
        self._gamma = section.rhoA * self.line_integral()
        self.total_mass = float(section.rhoA * self.length)

    @classmethod
    def straight(cls, section, start, end, n_elements=10, order=1, normal=None, **kwargs):
        """A straight beam from ``start`` to ``end`` (m); ``normal`` orients d₁ (:func:`straight_placement`)."""
        placement, length = straight_placement(start, end, normal)
        return cls(section, length, placement, n_elements=n_elements, order=order, **kwargs)

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        return tuple(f"{v}{i}" for i in range(self.n_nodes)
                     for v in ("x", "y", "z", "d1x", "d1y", "d1z", "d2x", "d2y", "d2z", "d3x", "d3y", "d3z"))

    @property
    def director_triads(self):
        """The directors' offsets of every node, which the scene holds orthonormal."""
        base = NODE_SIZE * np.arange(self.n_nodes)
        return tuple((int(b) + 3, int(b) + 6, int(b) + 9) for b in base)

    def vector_layout(self):
        """(positions, directors): local offsets of the nodal positions and of every director."""
        base = NODE_SIZE * np.arange(self.n_nodes)
        return tuple(int(b) for b in base), tuple(int(b) + o for b in base for o in (3, 6, 9))

    def node_positions(self, q):
        """φ of the nodes along the beam, (n_nodes, 3), m."""
        return np.asarray(q, dtype=float).reshape(self.n_nodes, NODE_SIZE)[:, :3].copy()

    def node_frames(self, q):
        """[d₁ d₂ d₃] of the nodes along the beam, (n_nodes, 3, 3) (columns: the directors)."""
        return np.transpose(np.asarray(q, dtype=float).reshape(self.n_nodes, 4, 3)[:, 1:, :], (0, 2, 1)).copy()

    def node_index(self, s):
        """The node at arc length s (m), or ``ValueError`` if none lies there."""
        s = check_finite_number("s", s)
        i = int(np.argmin(np.abs(self.s_nodes - s)))
        if abs(self.s_nodes[i] - s) > 1e-9 * self.length:
            raise ValueError(f"no node of beam {self.name!r} at s = {s!r} m (nodes at {self.s_nodes.tolist()[:8]}…)")
        return i

    def rigid_velocity(self, velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), about=(0.0, 0.0, 0.0),
                       q=None):
        """Velocities of a rigid motion of the configuration ``q`` (default q0): φ̇ = v + ω × (φ − about),
        ḋ_i = ω × d_i (m/s, rad/s, m)."""
        v = check_finite_vector("velocity", velocity, 3)
        w = check_finite_vector("angular_velocity", angular_velocity, 3)
        c = check_finite_vector("about", about, 3)
        q = self.q0 if q is None else check_finite_vector("q", q, self.n_dofs)
        vec = q.reshape(-1, 3)
        out = np.cross(w, vec)
        out[0::4] += v - np.cross(w, c)
        return out.ravel()

    # ------------------------------------------------------------- strains
    def strains(self, q):
        """(Γ₁, Γ₂, Γ₃, K₁, K₂, K₃) at the strain points, (n_elements, n_points, 6) (1, 1/m)."""
        return self.strain_points.strains(q)

    def section_forces(self, q):
        """Shear forces and normal force (N), bending moments and torque (N m) in the directors' axes at
        the strain points, (n_elements, n_points, 6)."""
        return self.strain_points.section_forces(q)

    @property
    def strain_family(self):
        """The compiled family of its strain energy, by its interpolation
        (:mod:`skfem_flex.compiled.families.rotation_beam`, :mod:`skfem_flex.compiled.families.director_beam`)."""
        return "rotation beam" if self.interpolation == "rotations" else "director beam"

    # ------------------------------------------------------------- potential
    def potential_discrete_gradient(self, q0, q1):
        """(g, ∂g/∂q₁) with g · (q₁ − q₀) = V(q₁) − V(q₀) exactly, equivariant under rotations."""
        return self.strain_points.discrete_gradient(q0, q1)

    def compiled_strain_data(self):
        """The packed arrays of the compiled strain-energy kernels (:mod:`.rotation_kernel` or
        :mod:`.director_kernel`), built once; None
        for a subclass that changes the strain energy (it runs through its own methods)."""
        if any(getattr(type(self), m) is not getattr(SpatialExactBeam, m) for m in
               ("potential_energy", "potential_gradient", "potential_discrete_gradient")):
            return None
        if self.interpolation == "rotations":
            return self.strain_points.data
        kd = getattr(self, "_kernel_data", None)
        if kd is None:
            from .director_kernel import pack
            kd = self._kernel_data = pack(self.strain_points)
        return kd

    # --------------------------------------------------------------- kinetic
    def mass_matrix(self, q):
        """The constant consistent mass (kg for φ, kg m² for the directors)."""
        return self._mass

    def line_integral(self):
        """G (3, n) with ∫ φ ds = G q: ∫ N_a ds on every node's position (the consistent load of a force per
        length, and ρA G the first moment of the mass)."""
        G = np.zeros((3, self.n_dofs))
        for c in range(3):
            G[c, NODE_SIZE * np.arange(self.n_nodes) + c] = self.node_weights
        return G

    def mass_moment(self):
        """(Γ, c) with ∫ φ dm = Γ q + c (c = 0)."""
        return self._gamma.copy(), np.zeros(3)

    def linear_momentum(self, q, v):
        """∫ ρA φ̇ ds, kg m/s."""
        return self._gamma @ np.asarray(v, dtype=float)

    def angular_momentum(self, q, v):
        """∫ ρA φ × φ̇ + ρI₂ d₁ × ḋ₁ + ρI₁ d₂ × ḋ₂ ds about the origin = Σ_t q_t × (M v)_t, kg m²/s."""
        p = (self._mass @ np.asarray(v, dtype=float)).reshape(-1, 3)
        return np.cross(np.asarray(q, dtype=float).reshape(-1, 3), p).sum(axis=0)

    def spatial_momentum_layout(self):
        """Every 3-vector of the coordinates, about the origin (L = Σ q_t × p_t)."""
        return np.arange(self.n_dofs).reshape(-1, 3), np.zeros(3)

    # ---------------------------------------------------------- body points
    def _shape_at(self, s):
        if isinstance(s, bool) or not np.isscalar(s):
            raise ValueError(f"a point of beam {self.name!r} is located by its arc length s (a number in m), "
                             f"got {s!r}")
        s = check_finite_number("s", s)
        tol = 1e-9 * self.length
        if not -tol <= s <= self.length + tol:
            raise ValueError(f"s = {s!r} lies outside beam {self.name!r}, whose arc length runs over "
                             f"[0, {self.length}] m")
        probe = self._basis.probes(np.array([[min(max(s, 0.0), self.length)]])).tocsr()
        return self._node_of_dof[probe.indices], probe.data

    def point_affine(self, s):
        """(G, a) with r = G q + a = Σ N_a(s) φ_a at arc length s."""
        nodes, values = self._shape_at(float(s))
        G = np.zeros((3, self.n_dofs))
        for a, w in zip(nodes, values):
            G[:, NODE_SIZE * a:NODE_SIZE * a + 3] += w * np.eye(3)
        return G, np.zeros(3)

    def point_triad(self, s):
        """The directors' offsets of the node at s, or None between nodes (a point there has no frame)."""
        i = int(np.argmin(np.abs(self.s_nodes - float(s))))
        if abs(self.s_nodes[i] - float(s)) > 1e-9 * self.length:
            return None
        return NODE_SIZE * i + 3, NODE_SIZE * i + 6, NODE_SIZE * i + 9

    def axis_affine(self, s, components):
        """G with a = G q = Σ c_i d_i of the node at s."""
        triad = self.point_triad(s)
        if triad is None:
            raise ValueError(f"directions of beam {self.name!r} are carried by its nodes; s = {s!r} m is not one")
        G = np.zeros((3, self.n_dofs))
        for c, o in zip(components, triad):
            G[:, o:o + 3] = c * np.eye(3)
        return G

    def point(self, locator=None):
        """The point of the axis at arc length ``locator`` (m; ``None``: the end s = L)."""
        return SpatialPoint(self, self.length if locator is None else locator)

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        """The axis as a polyline through the nodes, with the directors, the velocity and, per segment,
        the section forces and strains at its strain points (averaged for P2)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        frames = self.node_frames(q)
        conn = np.column_stack([np.arange(self.n_nodes - 1), np.arange(1, self.n_nodes)])
        point_data = {"velocity": self.node_positions(v), "d1": frames[:, :, 0], "d2": frames[:, :, 1],
                      "d3": frames[:, :, 2]}
        e = self.strains(q)
        forces = e * self.strain_points.C
        # the strain points of element k lie in segments k·order … k·order + order − 1 (ascending s)
        seg_e = np.repeat(e.mean(axis=1), self.order, axis=0)
        seg_f = np.repeat(forces.mean(axis=1), self.order, axis=0)
        by_s = np.argsort(self.strain_points.s_points.mean(axis=1))
        seg_e = seg_e.reshape(-1, self.order, 6)[by_s].reshape(-1, 6)
        seg_f = seg_f.reshape(-1, self.order, 6)[by_s].reshape(-1, 6)
        cell_data = {"strains": [seg_e], "section_forces": [seg_f]}
        points, cells = self.node_positions(q), [("line", conn)]
        if self.section_size is not None:
            points, cells, point_data, cell_data = self._swept_section(q, v, frames, points, cells, point_data,
                                                                        cell_data)
        return BodyGeometry(points, cells, point_data, cell_data)

    def _swept_section(self, q, v, frames, points, cells, point_data, cell_data):
        """The geometry with the section's rectangle swept along the axis: four corners a node
        (±w/2 d₁ ± h/2 d₂ about φ) and a hexahedron a segment, after the polyline's points and cells; the
        corners carry their node's directors and their own velocity, the hexahedra their segment's data."""
        half = 0.5 * self.section_size
        signs = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) * half       # (4, 2)
        rates = self.node_frames(v)
        corners = points[:, None, :] + np.einsum("kc,nic->nki", signs, frames[:, :, :2])
        corner_v = point_data["velocity"][:, None, :] + np.einsum("kc,nic->nki", signs, rates[:, :, :2])
        n = self.n_nodes
        base = n + 4 * np.arange(n - 1)
        hexes = np.column_stack([base + k for k in range(4)] + [base + 4 + k for k in range(4)])
        out_points = np.vstack([points, corners.reshape(-1, 3)])
        out_data = {"velocity": np.vstack([point_data["velocity"], corner_v.reshape(-1, 3)])}
        for key in ("d1", "d2", "d3"):
            out_data[key] = np.vstack([point_data[key], np.repeat(point_data[key], 4, axis=0)])
        out_cells = cells + [("hexahedron", hexes)]
        out_cell_data = {key: blocks + [blocks[0]] for key, blocks in cell_data.items()}
        return out_points, out_cells, out_data, out_cell_data
