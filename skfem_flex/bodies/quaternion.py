r"""A spatial rigid body turned by a unit quaternion (Euler parameters), free or about a fixed pivot.

Coordinates q = (x, e) (seven: the centre of mass x and the Euler parameters e), or q = e about a pivot p.
A material point at body coordinates s sits at r = x + R(e) s (or p + R(e) s), quadratic in e
(``numerics.quaternions``: R(e) = (e₀² − ε·ε) I + 2 ε εᵀ + 2 e₀ ε̂). The scene holds e·e = 1 with one
quadratic constraint (:class:`~skfem_flex.elements.constraints.quadratic.UnitQuaternion`).

The kinetic energy is ½ m ẋ·ẋ + ½ ėᵀM(e)ė with M(e) = 4 E(e)ᵀ J₄ E(e) (:mod:`.quaternion_kernel`).
Under energy–momentum the compiled family steps the rotation in Hamiltonian form, with a discrete gradient
built on invariants of the kinetic energy (:mod:`.quaternion_kernel`): with the single constraint e·e = 1,
which a turn about any axis keeps, the step conserves energy, the angular momentum components the loads
leave free, *and*, for a body with an axis of symmetry, its angular momentum about that axis (the spin of
a symmetric top), to round-off. That last one is what the director formulation of
:class:`~skfem_flex.bodies.spatial.SpatialRigidBody` keeps only to O(Δt²). The price: the body's points are
quadratic in q, so joints, springs and point loads (built on points affine in q) are not offered on it; a
top about its pivot, a free body and gravity are.
On the Python path (``compiled=False``) the energy–momentum step is the Lagrangian one of bodies whose
mass matrix depends on q: energy is conserved, the momenta to O(Δt²).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import quaternion_kernel as qk
from .base import Body, BodyGeometry, BodyPoint, check_finite_vector
from .spatial import rigid_start
from ..numerics.quaternions import matrix_quaternion, quaternion_matrix

__all__ = ["QuaternionRigidBody", "QuaternionPoint", "QuaternionKernelData", "rotation_quadratics"]

_CELLS_BOX = np.array([[0, 1], [1, 3], [3, 2], [2, 0], [4, 5], [5, 7], [7, 6], [6, 4], [0, 4], [1, 5], [2, 6],
                       [3, 7]])
_WHY_NO_JOINTS = ("its points are quadratic in q, and joints, springs and point loads are built on points affine "
                  "in q: use a SpatialRigidBody (directors) for a body with joints")


def rotation_quadratics(s):
    """Q (3, 4, 4) symmetric with (R(e) s)_i = eᵀ Q_i e for every e (not only unit ones)."""
    s = np.asarray(s, dtype=float)
    U = np.eye(4)
    Q = np.zeros((3, 4, 4))
    for a in range(4):
        for b in range(4):
            both = quaternion_matrix(U[a] + U[b]) @ s
            Q[:, a, b] = 0.5 * (both - quaternion_matrix(U[a]) @ s - quaternion_matrix(U[b]) @ s)
    for a in range(4):
        Q[:, a, a] = quaternion_matrix(U[a]) @ s
    return Q


class QuaternionKernelData(NamedTuple):
    """What the compiled family needs of one body."""

    n: np.ndarray           # (1,) int: 7 (free) or 4 (about a pivot)
    mass: np.ndarray        # (1,) m, kg
    J4: np.ndarray          # (4, 4) diag(j₀, J), kg m²
    J4i: np.ndarray         # (4, 4) its inverse
    kin: np.ndarray         # (2,) c₀, λ_r of the kinetic energy's invariants (quaternion_kernel)
    U: np.ndarray           # (3, 4) their directions u_i (zero rows unused)
    cu: np.ndarray          # (3,) their coefficients c_i
    Qc: np.ndarray          # (3, 4, 4) m Q_i(c): the first moment m R(e) c = m eᵀQ_i e (zero for a free body)
    anchor: np.ndarray      # (3,) the pivot (zero for a free body), m
    g: np.ndarray           # (3,) gravity on the body, m/s²
    W: np.ndarray           # (4, 4) gravity's quadratic in e, V = eᵀWe − m g·x (set with g by the family)


class QuaternionRigidBody(Body):
    """A rigid body in space with q = (x, e₀, e₁, e₂, e₃), or q = e about a pivot (module docstring).

    Parameters
    ----------
    mass : float
        m in kg, finite and positive.
    inertia : array_like, (3,) or (3, 3)
        Inertia tensor in body axes, kg m²: about the centre of mass, or about the pivot when one is given.
    position, velocity : array_like (3,), optional
        Initial centre of mass (m) and its velocity (m/s); not with a pivot.
    orientation : array_like, (4,) or (3, 3)
        Initial Euler parameters (normalized; zero is an error) or rotation matrix (body to space axes).
    angular_velocity, body_angular_velocity : array_like (3,), optional
        Initial angular velocity in space axes or in body axes, rad/s; give one of the two.
    pivot : array_like (3,), optional
        A fixed point, m, about which the body turns; body coordinates are then measured from it.
    center_of_mass : array_like (3,), optional
        With a pivot: the centre of mass in body coordinates from the pivot, m.
    size : array_like (3,), optional
        Edge lengths of the box drawn for output, m (default: the uniform box of this inertia).
    name : str
    """

    constant_mass = False
    has_potential = False
    dimension = 3
    inertia_family = "quaternion rigid body"

    def __init__(self, mass, inertia, position=None, orientation=None, velocity=None, angular_velocity=None,
                 body_angular_velocity=None, pivot=None, center_of_mass=None, size=None, name="rigid body"):
        st = rigid_start(mass, inertia, position, orientation, velocity, angular_velocity, body_angular_velocity,
                         pivot, center_of_mass, size)
        self.mass, self.inertia, self.pivot, self.center, self.size = st.mass, st.inertia, st.pivot, st.center, st.size
        e = matrix_quaternion(st.R)
        edot = 0.5 * qk.omega_matrix(e).T @ (st.R.T @ st.omega)     # ė = ½ G(e)ᵀ Ω on e·e = 1
        if self.pivot is not None:
            self.q0, self.v0, self.quaternion = e, edot, 0
        else:
            self.q0, self.v0, self.quaternion = np.concatenate([st.position, e]), np.concatenate([st.velocity, edot]), 3
        self.n_dofs = self.q0.size
        self.name = name
        # j₀ only fills M along e, where the unit-norm constraint holds the motion: the mean principal value
        # keeps M's eigenvalues together
        self.J4 = np.zeros((4, 4))
        self.J4[0, 0] = np.trace(self.inertia) / 3.0
        self.J4[1:, 1:] = self.inertia
        self.J4i = np.linalg.inv(self.J4)
        self._invariants = qk.invariant_terms(self.inertia, self.J4[0, 0])
        self._Qc = self.mass * rotation_quadratics(self.center)

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        own = () if self.pivot is not None else ("x", "y", "z")
        return own + ("e0", "e1", "e2", "e3")

    @property
    def unit_quaternions(self):
        """The local offset of e, which the scene holds at e·e = 1."""
        return (self.quaternion,)

    def _split(self, q):
        q = np.asarray(q, dtype=float)
        o = self.quaternion
        return q[:o], np.ascontiguousarray(q[o:o + 4])

    def rotation_matrix(self, q):
        """R(e) (3, 3), orthonormal up to the constraint tolerance."""
        return quaternion_matrix(self._split(q)[1])

    def euler_parameters(self, q, reference=None):
        """e normalized, with the sign nearer ``reference`` (e and −e are one rotation)."""
        e = self._split(q)[1]
        e = e / np.linalg.norm(e)
        if reference is not None and float(e @ np.asarray(reference, dtype=float)) < 0.0:
            e = -e
        return e

    def body_angular_velocity(self, q, v):
        """Ω = 2 G(e) ė, rad/s."""
        return 2.0 * qk.omega_matrix(self._split(q)[1]) @ self._split(v)[1]

    def reference_point(self, q):
        """The centre of mass x, or the pivot, m."""
        return self._split(q)[0].copy() if self.pivot is None else self.pivot.copy()

    # --------------------------------------------------------------- kinetic
    def mass_matrix(self, q):
        M = np.zeros((self.n_dofs, self.n_dofs))
        o = self.quaternion
        M[:o, :o] = self.mass * np.eye(o)
        M[o:, o:] = qk.mass(self.J4, self._split(q)[1])
        return M

    def momentum_jacobian(self, q, v):
        B = np.zeros((self.n_dofs, self.n_dofs))
        o = self.quaternion
        B[o:, o:] = qk.mass_jacobian(self.J4, self._split(q)[1], self._split(v)[1])
        return B

    def quadratic_velocity_force(self, q, v):
        n, o = self.n_dofs, self.quaternion
        f, fq, fv = np.zeros(n), np.zeros((n, n)), np.zeros((n, n))
        f[o:], fq[o:, o:], fv[o:, o:] = qk.quadratic_velocity_force(self.J4, self._split(q)[1], self._split(v)[1])
        return f, fq, fv

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        """The Lagrangian discrete gradient of G = ½ v₀ᵀM(q)v₁ (the Python path's energy–momentum step; the
        compiled family takes the Hamiltonian step of the module docstring instead: it also keeps the momenta)."""
        n, o = self.n_dofs, self.quaternion
        em = 0.5 * (self._split(q0)[1] + self._split(q1)[1])
        a, b = self._split(v0)[1], self._split(v1)[1]
        g, gq, gv = np.zeros(n), np.zeros((n, n)), np.zeros((n, n))
        g[o:] = 0.5 * qk.mass_jacobian(self.J4, em, b).T @ a
        U = np.eye(4)
        for k in range(4):
            # G is quadratic in q and linear in v₁: both derivatives are exact columns
            gq[o:, o + k] = 0.25 * (qk.mass_jacobian(self.J4, U[k], b).T @ a)
            gv[o:, o + k] = 0.5 * qk.mass_jacobian(self.J4, em, U[k]).T @ a
        return g, gq, gv

    def linear_momentum(self, q, v):
        x_dot = self._split(v)[0]
        if self.pivot is None:
            return self.mass * x_dot
        e, edot = self._split(q)[1], self._split(v)[1]
        return qk.moment_rate(self._Qc, e, edot)

    def angular_momentum(self, q, v):
        """About the origin: ½ Ḡ(e) π (the rotation's, π = M(e) ė) plus r × (linear momentum), r = x or the pivot."""
        e, edot = self._split(q)[1], self._split(v)[1]
        L = qk.rotation_momentum(self.J4, e, edot)
        return L + np.cross(self.reference_point(q), self.linear_momentum(q, v))

    # --------------------------------------------------------------- gravity
    def mass_moment(self):
        raise NotImplementedError(f"body {self.name!r}: positions are quadratic in its Euler parameters")

    def gravity_potential(self, q, g):
        g = check_finite_vector("g", g, 3)
        x, e = self._split(q)
        W = qk.gravity_quadratic(self._Qc, g)
        n, o = self.n_dofs, self.quaternion
        grad, hess = np.zeros(n), np.zeros((n, n))
        grad[:o] = -self.mass * g[:o]
        grad[o:] = 2.0 * W @ e
        hess[o:, o:] = 2.0 * W
        V = float(e @ W @ e) - self.mass * float(g @ self.reference_point(q))
        return V, grad, hess

    def gravity_discrete_gradient(self, q0, q1, g):
        _, grad, hess = self.gravity_potential(0.5 * (np.asarray(q0, dtype=float) + np.asarray(q1, dtype=float)), g)
        return grad, 0.5 * hess

    # ---------------------------------------------------------- compiled
    def compiled_kernel_data(self):
        """The body's :class:`QuaternionKernelData` (gravity added by the family)."""
        kin, U, cu = self._invariants
        return QuaternionKernelData(np.array([self.n_dofs], dtype=np.int64), np.array([self.mass]), self.J4.copy(),
                                    self.J4i.copy(), kin.copy(), U.copy(), cu.copy(), self._Qc.copy(),
                                    np.zeros(3) if self.pivot is None else self.pivot.copy(), np.zeros(3),
                                    np.zeros((4, 4)))

    # ---------------------------------------------------------- body points
    def point(self, locator=None):
        """The material point at body coordinates ``locator`` (m from the centre of mass, or the pivot)."""
        s = np.zeros(3) if locator is None else check_finite_vector("spatial body point", locator, 3)
        return QuaternionPoint(self, s)

    def point_affine(self, s):
        raise ValueError(f"body {self.name!r} (a QuaternionRigidBody) cannot take joints: {_WHY_NO_JOINTS}")

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        a, b, c = 0.5 * self.size
        corners = self.center + np.array([[i * a, j * b, k * c] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
        pts = self.reference_point(q) + corners @ self.rotation_matrix(q).T
        vel = np.array([QuaternionPoint(self, s).velocity(q, v) for s in corners])
        return BodyGeometry(pts, [("line", _CELLS_BOX.copy())], {"velocity": vel})


class QuaternionPoint(BodyPoint):
    """A material point of a :class:`QuaternionRigidBody`: r = x + R(e) s, quadratic in q, so its mid-point
    Jacobian is its exact discrete gradient. For probes, loads written in Python and output; not for joints."""

    dimension = 3

    def __init__(self, body, s):
        self.body = body
        self.s = np.asarray(s, dtype=float)
        self.Q = rotation_quadratics(self.s)

    def affine(self):
        raise ValueError(f"a point of body {self.body.name!r} (a QuaternionRigidBody) cannot take joints: "
                         f"{_WHY_NO_JOINTS}")

    def position(self, q):
        e = self.body._split(q)[1]
        return self.body.reference_point(q) + np.einsum("iab,a,b->i", self.Q, e, e)

    def position_jacobian(self, q):
        o = self.body.quaternion
        J = np.zeros((3, self.body.n_dofs))
        J[:, :o] = np.eye(3)[:, :o] if o else J[:, :o]
        J[:, o:] = 2.0 * np.einsum("iab,b->ia", self.Q, self.body._split(q)[1])
        return J

    def position_hessian_product(self, q, f):
        o = self.body.quaternion
        H = np.zeros((self.body.n_dofs, self.body.n_dofs))
        H[o:, o:] = 2.0 * np.einsum("i,iab->ab", np.asarray(f, dtype=float), self.Q)
        return H

    def position_discrete_gradient(self, q0, q1):
        return self.position_jacobian(0.5 * (np.asarray(q0, dtype=float) + np.asarray(q1, dtype=float)))

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return 0.5 * self.position_hessian_product(q1, f)
