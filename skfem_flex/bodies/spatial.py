r"""Spatial rigid bodies in the director formulation, and spatial point masses.

A :class:`SpatialRigidBody` has the twelve coordinates q = (x, d₁, d₂, d₃): the centre of mass x and
the three directors d_i (the body's axes in space axes, the columns of its rotation matrix
R = [d₁ d₂ d₃]). A material point at body coordinates s (from the centre of mass) sits at

.. math::  r(q) = x + s_1 d_1 + s_2 d_2 + s_3 d_3 ,

linear in q; a body-fixed direction a = a_i d_i is linear in q too. The kinetic energy

.. math::  T = \tfrac12 m\,\dot x\cdot\dot x + \tfrac12 E_{ij}\,\dot d_i\cdot\dot d_j,
           \qquad E = \tfrac12\operatorname{tr}(J)\,I - J = \int s\,s^T\,dm ,

has the *constant* mass matrix M = diag(m I₃, E ⊗ I₃) (J: the inertia tensor about the centre of mass
in body axes, E: the Euler tensor). A body that turns about a fixed ``pivot`` p (a top) has only the
directors, q = (d₁, d₂, d₃), r = p + s_i d_i with s measured from the pivot, J and E about the pivot,
M = E ⊗ I₃: the data of a top are often given that way and need not describe a free body. Rigidity is the six quadratic constraints

.. math::  \tfrac12 (d_i\cdot d_i - 1) = 0 \;(i = 1, 2, 3), \qquad d_1\cdot d_2 = d_1\cdot d_3 = d_2\cdot d_3 = 0,

which the scene adds for every body that names its ``directors`` (``elements.constraints.Rigidity``). Every joint between such
bodies is at most quadratic in q, gravity is linear: so the mid-point Jacobian of each constraint is its
exact discrete gradient, and the energy–momentum scheme conserves energy and angular momentum without
any rotation algebra in the step (``docs/spatial.md``).

The linear momentum is Γ v (∫ r dm = Γ q + c: m ẋ, or m c_i ḋ_i about a pivot), the angular momentum
about the origin L = x × m ẋ + E_ij d_i × ḋ_j (= x × m ẋ + R J Ω for orthonormal directors; about a
pivot p × Γ v + E_ij d_i × ḋ_j).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .base import Body, BodyGeometry, BodyPoint, check_finite_number, check_finite_vector
from ..numerics.quaternions import check_quaternion, check_rotation_matrix, matrix_quaternion, quaternion_matrix

__all__ = ["DirectorFrame", "RigidStart", "rigid_start", "SpatialRigidBody", "SpatialPointMass", "SpatialPoint", "SpatialAxis", "SpatialDirection",
           "check_inertia_tensor"]

_CELLS_BOX = np.array([[0, 1], [1, 3], [3, 2], [2, 0], [4, 5], [5, 7], [7, 6], [6, 4], [0, 4], [1, 5], [2, 6],
                       [3, 7]])


def check_inertia_tensor(inertia):
    """The inertia tensor J (3, 3) about the centre of mass from a (3,) diagonal or a (3, 3) matrix.

    Raises ``ValueError`` unless J is finite, symmetric and positive definite and its principal values
    obey the triangle inequality J₁ < J₂ + J₃ (strictly: the Euler tensor must be positive definite).
    """
    arr = np.asarray(inertia, dtype=float)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3):
        raise ValueError(f"inertia must be 3 principal values or a (3, 3) tensor in kg m², got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"inertia must be finite, got {inertia!r}")
    scale = float(np.abs(arr).max())
    if scale == 0.0 or float(np.abs(arr - arr.T).max()) > 1e-12 * scale:
        raise ValueError(f"inertia must be a symmetric positive definite tensor in kg m², got {inertia!r}")
    lam = np.linalg.eigvalsh(arr)
    if lam[0] <= 1e-14 * scale:
        raise ValueError(f"inertia must be positive definite, its principal values are {lam} kg m²")
    if lam[2] >= lam[0] + lam[1]:
        raise ValueError(f"inertia principal values {lam} kg m² break the triangle inequality "
                         f"J3 < J1 + J2: no mass distribution has them")
    return 0.5 * (arr + arr.T)


def orientation_matrix(orientation):
    """R from a quaternion (4,) or a rotation matrix (3, 3)."""
    arr = np.asarray(orientation, dtype=float)
    if arr.shape == (3, 3):
        return check_rotation_matrix("orientation", arr)
    return quaternion_matrix(check_quaternion("orientation", arr))


class RigidStart(NamedTuple):
    """A spatial rigid body's checked data and initial state, whatever carries its rotation."""

    mass: float               # kg
    inertia: np.ndarray       # (3, 3) kg m², about the centre of mass or the pivot
    R: np.ndarray             # (3, 3) initial rotation, body to space axes
    omega: np.ndarray         # (3,) initial angular velocity in space axes, rad/s
    pivot: np.ndarray         # (3,) m, or None (a free body)
    center: np.ndarray        # (3,) centre of mass from the pivot in body coordinates (zero for a free body), m
    position: np.ndarray      # (3,) initial centre of mass (free body), m
    velocity: np.ndarray      # (3,) its velocity, m/s
    size: np.ndarray          # (3,) edge lengths of the box drawn for output, m


def rigid_start(mass, inertia, position, orientation, velocity, angular_velocity, body_angular_velocity, pivot,
                center_of_mass, size):
    """The :class:`RigidStart` of a spatial rigid body's arguments (those of :class:`SpatialRigidBody`), or a
    ``ValueError`` naming the argument that is wrong."""
    m = check_finite_number("mass", mass)
    if m <= 0.0:
        raise ValueError(f"mass must be positive, got {mass!r}")
    J = check_inertia_tensor(inertia)
    R = np.eye(3) if orientation is None else orientation_matrix(orientation)
    if angular_velocity is not None and body_angular_velocity is not None:
        raise ValueError("give angular_velocity (space axes) or body_angular_velocity, not both")
    if body_angular_velocity is not None:
        omega = R @ check_finite_vector("body_angular_velocity", body_angular_velocity, 3)
    else:
        omega = np.zeros(3) if angular_velocity is None else check_finite_vector("angular_velocity",
                                                                                 angular_velocity, 3)
    x = xd = None
    if pivot is not None:
        if position is not None or velocity is not None:
            raise ValueError("a body about a pivot has no position or velocity of its own (give the pivot "
                             "and center_of_mass)")
        pivot = check_finite_vector("pivot", pivot, 3)
        center = np.zeros(3) if center_of_mass is None else check_finite_vector("center_of_mass", center_of_mass, 3)
    else:
        if center_of_mass is not None:
            raise ValueError("center_of_mass is measured from a pivot: give it only with pivot=...")
        center = np.zeros(3)
        x = check_finite_vector("position", (0.0, 0.0, 0.0) if position is None else position, 3)
        xd = check_finite_vector("velocity", (0.0, 0.0, 0.0) if velocity is None else velocity, 3)
    if size is None:
        # the uniform box with this inertia about its centre: J_1 = m (b² + c²)/12, …
        jc = J - m * (center @ center * np.eye(3) - np.outer(center, center))
        e = np.clip(0.5 * np.trace(jc) - np.diag(jc), 0.0, None)
        size = np.sqrt(12.0 * e / m)
    return RigidStart(m, J, R, omega, pivot, center, x, xd, check_finite_vector("size", size, 3))


class DirectorFrame:
    """The frame of a body with the directors d₁, d₂, d₃ at local offsets ``directors`` (and its reference point
    x at offsets 0..2, or a fixed ``pivot``): its rotation, body-fixed directions and the affine maps of points
    that turn with it. Shared by :class:`SpatialRigidBody` and the spatial floating-frame beam, whose
    reference frame is such a triad."""

    pivot = None

    def point_affine(self, s):
        """(G, a) with r = G q + a for the body coordinates s (m, from the centre of mass or the pivot)."""
        G = np.zeros((3, self.n_dofs))
        o = self.directors[0]
        if o:
            G[:, :3] = np.eye(3)
        for i in range(3):
            G[:, o + 3 * i:o + 3 * i + 3] = s[i] * np.eye(3)
        return G, (np.zeros(3) if self.pivot is None else self.pivot.copy())

    @property
    def director_triads(self):
        """The body's one triad of directors (local offsets of d₁, d₂, d₃), which the scene holds rigid."""
        return (tuple(self.directors),)

    def vector_layout(self):
        """(positions, directors): local offsets of the position vectors (x, or none about a pivot) and of
        the directors, for the force and moment a constraint exerts (``spatial_reaction``)."""
        return ((0,) if self.pivot is None else ()), tuple(self.directors)

    def point_triad(self, s):
        """The directors' offsets a point at body coordinates s turns with: the body's."""
        return tuple(self.directors)

    def axis_affine(self, s, components):
        """G with a = G q: the body-fixed direction of body ``components`` (the same at every point s)."""
        return self.axis(components).G

    def rotation_matrix(self, q):
        """R = [d₁ d₂ d₃] (3, 3); orthonormal up to the constraint tolerance."""
        o = self.directors[0]
        q = np.asarray(q, dtype=float)
        return np.column_stack([q[o:o + 3], q[o + 3:o + 6], q[o + 6:o + 9]])

    def euler_parameters(self, q, reference=None):
        """The Euler parameters of :meth:`rotation_matrix` (``numerics.quaternions.matrix_quaternion``)."""
        return matrix_quaternion(self.rotation_matrix(q), reference)

    def body_angular_velocity(self, q, v):
        """Ω in body axes, rad/s: Ω̂ = Rᵀ Ṙ (its skew part, exact for orthonormal directors)."""
        W = self.rotation_matrix(q).T @ self.rotation_matrix(v)
        W = 0.5 * (W - W.T)
        return np.array([W[2, 1], W[0, 2], W[1, 0]])

    def reference_point(self, q):
        """The centre of mass x, or the pivot, m."""
        return np.asarray(q[:3], dtype=float) if self.pivot is None else self.pivot.copy()

    def axis(self, direction):
        """The body-fixed direction a = a_i d_i of body components ``direction`` (not normalized here)."""
        a = check_finite_vector("body axis", direction, 3)
        if float(np.linalg.norm(a)) == 0.0:
            raise ValueError("a body axis must not have zero length")
        return SpatialAxis(self, a)

    def body_coordinates(self, point):
        """Body coordinates s of a point given in space at the initial state, m."""
        x = check_finite_vector("point", point, 3)
        return self.rotation_matrix(self.q0).T @ (x - self.reference_point(self.q0))

    def body_direction(self, direction):
        """Body components of a direction given in space axes at the initial state."""
        return self.rotation_matrix(self.q0).T @ check_finite_vector("direction", direction, 3)


class SpatialRigidBody(DirectorFrame, Body):
    """A rigid body in space with the coordinates q = (x, d₁, d₂, d₃), or q = (d₁, d₂, d₃) about a pivot.

    Parameters
    ----------
    mass : float
        m in kg, finite and positive.
    inertia : array_like, (3,) or (3, 3)
        Inertia tensor in body axes, kg m² (principal values or the tensor): about the centre of mass,
        or about the pivot when one is given.
    position : array_like (3,)
        Initial centre of mass x in m (not with a pivot).
    orientation : array_like, (4,) or (3, 3)
        Initial Euler parameters (e₀, e₁, e₂, e₃) (normalized; zero is an error) or rotation matrix R
        (body to space axes). Default: body and space axes coincide.
    velocity : array_like (3,)
        Initial velocity of the centre of mass, m/s (not with a pivot).
    angular_velocity : array_like (3,)
        Initial angular velocity ω in **space** axes, rad/s (ḋ_i = ω × d_i).
    body_angular_velocity : array_like (3,), optional
        Initial angular velocity Ω in **body** axes, rad/s (ω = R Ω); give one of the two.
    pivot : array_like (3,), optional
        A fixed point in space, m, about which the body turns (a top); then body coordinates of points
        are measured from the pivot.
    center_of_mass : array_like (3,), optional
        With a pivot: the centre of mass in body coordinates from the pivot, m.
    size : array_like (3,), optional
        Edge lengths of the box drawn for output, m, centred on the centre of mass; default the box of
        uniform density with this inertia (or a small cross where that degenerates).
    name : str
    """

    constant_mass = True
    has_potential = False
    dimension = 3

    def __init__(self, mass, inertia, position=None, orientation=None, velocity=None, angular_velocity=None,
                 body_angular_velocity=None, pivot=None, center_of_mass=None, size=None, name="rigid body"):
        st = rigid_start(mass, inertia, position, orientation, velocity, angular_velocity, body_angular_velocity,
                         pivot, center_of_mass, size)
        self.mass, self.inertia, self.pivot, self.center, self.size = st.mass, st.inertia, st.pivot, st.center, st.size
        self.euler_tensor = 0.5 * np.trace(self.inertia) * np.eye(3) - self.inertia
        R = st.R
        rates = [np.cross(st.omega, R[:, i]) for i in range(3)]
        if self.pivot is not None:
            self.q0 = np.concatenate([R[:, 0], R[:, 1], R[:, 2]])
            self.v0 = np.concatenate(rates)
            self.directors = (0, 3, 6)
        else:
            self.q0 = np.concatenate([st.position, R[:, 0], R[:, 1], R[:, 2]])
            self.v0 = np.concatenate([st.velocity] + rates)
            self.directors = (3, 6, 9)
        self.n_dofs = self.q0.size
        self.name = name
        o = self.directors[0]
        M = np.zeros((self.n_dofs, self.n_dofs))
        M[:o, :o] = self.mass * np.eye(o)
        M[o:, o:] = np.kron(self.euler_tensor, np.eye(3))
        self._mass = M
        self._moment = self.point_affine(self.center)
        self._moment = (self.mass * self._moment[0], self.mass * self._moment[1])

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        own = () if self.pivot is not None else ("x", "y", "z")
        return own + tuple(f"d{i}{c}" for i in (1, 2, 3) for c in "xyz")

    def mass_matrix(self, q):
        return self._mass

    def kinetic_energy(self, q, v):
        return 0.5 * float(v @ (self._mass @ v))

    def momentum(self, q, v):
        return self._mass @ v

    def mass_moment(self):
        return self._moment

    def linear_momentum(self, q, v):
        return self._moment[0] @ np.asarray(v, dtype=float)

    def angular_momentum(self, q, v):
        p = self._mass @ v
        L = sum(np.cross(q[3 * k:3 * k + 3], p[3 * k:3 * k + 3]) for k in range(self.n_dofs // 3))
        if self.pivot is not None:
            L = L + np.cross(self.pivot, self.linear_momentum(q, v))
        return L

    def spatial_momentum_layout(self):
        """(triples, anchor): the (k, 3) local index triples whose q × p add to the angular momentum about
        the origin, and the point a whose a × (Γ v) adds to it (Γ v, the linear momentum, from
        :meth:`mass_moment`)."""
        return np.arange(self.n_dofs).reshape(-1, 3), (np.zeros(3) if self.pivot is None else self.pivot)

    # ---------------------------------------------------------- body points
    def point(self, locator=None):
        """The material point at body coordinates ``locator`` = (s₁, s₂, s₃), m from the centre of mass
        (or from the pivot); ``None``: that reference point."""
        s = np.zeros(3) if locator is None else check_finite_vector("spatial body point", locator, 3)
        return SpatialPoint(self, s)

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        a, b, c = 0.5 * self.size
        corners = self.center + np.array([[i * a, j * b, k * c] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
        R = self.rotation_matrix(q)
        pts = self.reference_point(q) + corners @ R.T
        vel = corners @ self.rotation_matrix(v).T
        if self.pivot is None:
            vel = vel + v[:3]
        return BodyGeometry(pts, [("line", _CELLS_BOX.copy())], {"velocity": vel})


class SpatialPointMass(Body):
    """A point mass in space, q = x (3), M = m I₃.

    Parameters
    ----------
    mass : float
        kg, positive.
    position, velocity : array_like (3,)
        m and m/s.
    name : str
    """

    constant_mass = True
    has_potential = False
    dimension = 3

    def __init__(self, mass, position=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0), name="point mass"):
        self.mass = check_finite_number("mass", mass)
        if self.mass <= 0.0:
            raise ValueError(f"mass must be positive, got {mass!r}")
        self.q0 = check_finite_vector("position", position, 3)
        self.v0 = check_finite_vector("velocity", velocity, 3)
        self.n_dofs = 3
        self.name = name
        self._mass = self.mass * np.eye(3)

    @property
    def coordinate_names(self):
        return ("x", "y", "z")

    def mass_matrix(self, q):
        return self._mass

    def kinetic_energy(self, q, v):
        return 0.5 * self.mass * float(v @ v)

    def momentum(self, q, v):
        return self.mass * np.asarray(v, dtype=float)

    def mass_moment(self):
        return self.mass * np.eye(3), np.zeros(3)

    def linear_momentum(self, q, v):
        return self.mass * np.array(v, dtype=float)

    def angular_momentum(self, q, v):
        return self.mass * np.cross(q, v)

    def spatial_momentum_layout(self):
        return np.arange(3).reshape(1, 3), np.zeros(3)

    def vector_layout(self):
        return (0,), ()

    def point_triad(self, s):
        return None

    def point_affine(self, s):
        return np.eye(3), np.zeros(3)

    def point(self, locator=None):
        if locator is not None:
            raise ValueError(f"a point mass has one point (locator None), got {locator!r}")
        return SpatialPoint(self, None)

    def geometry(self, q, v):
        return BodyGeometry(np.asarray(q, dtype=float).reshape(1, 3), [("vertex", np.array([[0]]))],
                            {"velocity": np.asarray(v, dtype=float).reshape(1, 3)})


class SpatialPoint(BodyPoint):
    """A material point of a spatial body: r = G q + a, affine in q, so G is its exact discrete gradient."""

    dimension = 3

    def __init__(self, body, s):
        self.body = body
        self.s = None if s is None else np.asarray(s, dtype=float)
        self.G, self.a = body.point_affine(self.s)
        #: local offsets of the directors (d₁, d₂, d₃) the point turns with, or None (a point mass)
        self.triad = body.point_triad(self.s)

    def affine(self):
        """(G, a) with r = G q + a; what the quadratic constraints build on."""
        return self.G, self.a

    def _check_oriented(self):
        if self.triad is None:
            raise ValueError(f"body {self.body.name!r} has no orientation (a point mass): it cannot carry a "
                             f"direction")

    def axis(self, components):
        """The direction a = Σ c_i d_i fixed in the point's frame, from its components c in that frame."""
        self._check_oriented()
        a = check_finite_vector("direction components", components, 3)
        if float(np.linalg.norm(a)) == 0.0:
            raise ValueError("a direction must not have zero length")
        return SpatialDirection(self.body, self.body.axis_affine(self.s, a))

    def direction(self, e_space):
        """The direction fixed in the point's frame that lies along ``e_space`` (space axes) at the start."""
        self._check_oriented()
        q0 = np.asarray(self.body.q0, dtype=float)
        R0 = np.column_stack([self.body.axis_affine(self.s, e) @ q0 for e in np.eye(3)])
        return self.axis(R0.T @ check_finite_vector("direction", e_space, 3))

    def position(self, q):
        return self.G @ q + self.a

    def velocity(self, q, v):
        return self.G @ v

    def position_jacobian(self, q):
        return self.G

    def position_hessian_product(self, q, f):
        return np.zeros((self.body.n_dofs, self.body.n_dofs))

    def position_discrete_gradient(self, q0, q1):
        return self.G

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return np.zeros((self.body.n_dofs, self.body.n_dofs))

    def compiled_map(self):
        return None         # the compiled position maps are planar; spatial rows are packed as quadratics


class SpatialDirection:
    """A direction a = G q fixed in a spatial body's frame (at one of its points), linear in q."""

    def __init__(self, body, G):
        self.body = body
        self.G = np.asarray(G, dtype=float)

    def affine(self):
        return self.G, np.zeros(3)

    def direction(self, q):
        return self.G @ q


class SpatialAxis:
    """A body-fixed direction a = a₁ d₁ + a₂ d₂ + a₃ d₃ of a :class:`SpatialRigidBody` (linear in q)."""

    def __init__(self, body, a):
        self.body = body
        self.a = np.asarray(a, dtype=float)
        G = np.zeros((3, body.n_dofs))
        o = body.directors[0]
        for i in range(3):
            G[:, o + 3 * i:o + 3 * i + 3] = self.a[i] * np.eye(3)
        self.G = G

    def affine(self):
        return self.G, np.zeros(3)

    def direction(self, q):
        return self.G @ q
