r"""The generic spatial floating-frame body: a director frame plus elastic coordinates on inertia invariants.

:class:`FloatingFrame3D` holds what every spatial floating-frame body shares, whatever its elastic model:
the coordinates q = (x, d₁, d₂, d₃, y) (the frame of a spatial rigid body, :class:`~..spatial.DirectorFrame`,
and the elastic coordinates y), the kinetic energy on the invariants of :class:`~.inertia.SpatialFrameInertia`
(``kinetics.py``), the strain energy of an object with ``energy``, ``gradient``, ``hessian`` and
``discrete_gradient`` on y, gravity −g·(m x + D s(y)), the momenta, and the points of the body
(:class:`ElasticPoint`: r = x + D(X₀ + S y), quadratic in q). A subclass (the beam, ``body.py``; the meshed
solid, ``solid.py``) builds the invariants, the strain energy and its points, and calls
:meth:`FloatingFrame3D.set_initial_state`.
"""
from __future__ import annotations

import numpy as np

from ..base import Body, BodyPoint, check_finite_vector
from ..spatial import DirectorFrame, SpatialPoint, orientation_matrix
from . import kernel, kinetics

__all__ = ["FloatingFrame3D", "ElasticPoint"]


class FloatingFrame3D(DirectorFrame, Body):
    """Base of the spatial floating-frame bodies (module docstring).

    A subclass sets ``inertia`` (:class:`~.inertia.SpatialFrameInertia` on y), ``strain_energy``,
    ``n_elastic``, ``n_dofs = 12 + n_elastic``, ``name`` and the initial state.
    """

    constant_mass = False
    has_potential = True
    dimension = 3
    directors = (3, 6, 9)
    #: the compiled family that packs ``compiled_kernel_data()`` (inertia, strain and gravity)
    inertia_family = "spatial floating frame"

    def _compiled_strain(self):
        """The strain energy's compiled form, or None (a strain object without ``compiled_strain``: a user's)."""
        form = getattr(self.strain_energy, "compiled_strain", None)
        return None if form is None else form()

    def compiled_kernel_data(self):
        """The body's arrays for the compiled core (:class:`~.kernel.SpatialBodyData`), or None when its
        strain energy has no compiled form (:attr:`compiled_refusal`)."""
        strain = self._compiled_strain()
        return None if strain is None else kernel.kernel_data(self.inertia, **strain)

    @property
    def compiled_refusal(self):
        """Why the body runs on the Python path, or None."""
        if self._compiled_strain() is None:
            return f"its strain energy ({type(self.strain_energy).__name__}) has no compiled form"
        return None

    def set_initial_state(self, position, orientation, velocity, angular_velocity, elastic, elastic_velocity):
        """q0 and v0 from the frame's origin (m), orientation (Euler parameters or a rotation matrix), velocity
        (m/s), angular velocity in space axes (rad/s) and the elastic y, ẏ (zero when None)."""
        R = np.eye(3) if orientation is None else orientation_matrix(orientation)
        omega = check_finite_vector("angular_velocity", angular_velocity, 3)
        y0 = np.zeros(self.n_elastic) if elastic is None else check_finite_vector("elastic", elastic, self.n_elastic)
        w0 = (np.zeros(self.n_elastic) if elastic_velocity is None
              else check_finite_vector("elastic_velocity", elastic_velocity, self.n_elastic))
        self.q0 = np.concatenate([check_finite_vector("position", position, 3), R.T.ravel(), y0])
        self.v0 = np.concatenate([check_finite_vector("velocity", velocity, 3), np.cross(omega, R.T).ravel(), w0])

    # ================================================================ kinetic
    def mass_matrix(self, q):
        return kinetics.mass_matrix(self.inertia, q)

    def momentum_jacobian(self, q, v):
        return kinetics.momentum_jacobian(self.inertia, q, v)

    def quadratic_velocity_force(self, q, v):
        return kinetics.quadratic_velocity_force(self.inertia, q, v)

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        return kinetics.kinetic_discrete_gradient(self.inertia, q0, q1, v0, v1)

    def linear_momentum(self, q, v):
        """m ẋ + Σ_i s_i ḋ_i + D S̄ ẏ (the x rows of M(q) v), kg m/s."""
        return self.momentum(q, v)[:3]

    def angular_momentum(self, q, v):
        """L = x × p_x + Σ_i d_i × p_{d_i} about the origin (p = M(q) v; Noether's momentum of the turning
        invariance), kg m²/s."""
        p = self.momentum(q, v)
        q = np.asarray(q, dtype=float)
        return sum(np.cross(q[3 * k:3 * k + 3], p[3 * k:3 * k + 3]) for k in range(4))

    # ================================================================ strain and gravity
    def potential_energy(self, q):
        return self.strain_energy.energy(np.asarray(q, dtype=float)[12:])

    def potential_gradient(self, q):
        g = np.zeros(self.n_dofs)
        g[12:] = self.strain_energy.gradient(np.asarray(q, dtype=float)[12:])
        return g

    def potential_hessian(self, q):
        H = np.zeros((self.n_dofs, self.n_dofs))
        H[12:, 12:] = self.strain_energy.hessian(np.asarray(q, dtype=float)[12:])
        return H

    def potential_discrete_gradient(self, q0, q1):
        g = np.zeros(self.n_dofs)
        H = np.zeros((self.n_dofs, self.n_dofs))
        g[12:], H[12:, 12:] = self.strain_energy.discrete_gradient(np.asarray(q0, dtype=float)[12:],
                                                                   np.asarray(q1, dtype=float)[12:])
        return g, H

    def gravity_potential(self, q, g):
        """V = −g · (m x + D s(y)), s = S₀ + S̄ y (quadratic in q); (V, ∇V, ∇²V)."""
        g = np.asarray(g, dtype=float)
        x, D, y = kinetics.split(q)
        inv = self.inertia
        s = inv.S0 + inv.Sbar @ y
        grad = np.zeros(self.n_dofs)
        grad[:3] = -inv.mass * g
        grad[3:12] = -np.outer(s, g).ravel()
        grad[12:] = -inv.Sbar.T @ (D.T @ g)
        H = np.zeros((self.n_dofs, self.n_dofs))
        for i in range(3):
            H[3 + 3 * i:6 + 3 * i, 12:] = -np.outer(g, inv.Sbar[i])
        H[12:, 3:12] = H[3:12, 12:].T
        return -float(g @ (inv.mass * x + D @ s)), grad, H

    def gravity_discrete_gradient(self, q0, q1, g):
        """The gradient at the mid-point (exact: the potential is quadratic) and half the Hessian."""
        _, grad, H = self.gravity_potential(0.5 * (np.asarray(q0, dtype=float) + np.asarray(q1, dtype=float)), g)
        return grad, 0.5 * H

    def frame_point(self, s):
        """The point at frame coordinates ``s`` (3,), m: it moves with the frame, not with the elastic body."""
        return SpatialPoint(self, check_finite_vector("frame point", s, 3))

    def spatial_momentum_layout(self):
        """Not a constant-mass body: the compiled constant-mass family does not take it."""
        raise NotImplementedError(f"body {self.name!r} has a configuration-dependent mass")


class ElasticPoint(BodyPoint):
    """A material point of a floating-frame body: r = x + D(X₀ + S y), quadratic in q.

    Its Jacobian [I, ρ₁I, ρ₂I, ρ₃I, D S] (ρ = X₀ + S y) at the mid-point is its exact discrete gradient.

    Parameters
    ----------
    body : FloatingFrame3D
    X0 : array_like (3,)
        The point in the frame's axes, undeformed, m.
    S : ndarray (3, n_elastic)
        Its elastic displacement per unit y, in the frame's axes.
    Theta : ndarray (3, n_elastic), optional
        The small elastic rotation of the material there per unit y, in the frame's axes (a beam's section, a
        rigid interface): a direction e of the material turns into D (e + (Θ y) × e), the body's linear
        elastic kinematics (:meth:`turned`). None: the point has no orientation of its own.
    """

    dimension = 3
    triad = None

    def __init__(self, body, X0, S, Theta=None):
        self.body, self.X0, self.S = body, np.asarray(X0, dtype=float), np.asarray(S, dtype=float)
        self.Theta = None if Theta is None else np.asarray(Theta, dtype=float)

    def direction(self, e_space):
        """The material direction that lies along ``e_space`` (space axes) at the body's initial state, as it turns:
        u(q) = D (e₀ + (Θ y) × e₀), e₀ = D₀ᵀ e_space, quadratic in q (``quadratic()``: spatial joints against the
        ground take it); ValueError without Θ."""
        if self.Theta is None:
            raise ValueError("this material point has no orientation of its own (no elastic rotation field)")
        _, D0, _ = kinetics.split(np.asarray(self.body.q0, dtype=float))
        return _TurnedDirection(self, D0.T @ np.asarray(e_space, dtype=float))

    def turned(self, q, f):
        """F = D (f + (Θ y) × f) = D (f − f̂ Θ y), the material vector f (frame axes) at the point as it has
        turned with the frame and the elastic rotation, and ∂F/∂q (3, n); ValueError without Θ."""
        if self.Theta is None:
            raise ValueError("this material point has no orientation of its own (no elastic rotation field)")
        _, D, y = kinetics.split(q)
        f = np.asarray(f, dtype=float)
        fhat = np.array([[0.0, -f[2], f[1]], [f[2], 0.0, -f[0]], [-f[1], f[0], 0.0]])
        g = f - fhat @ (self.Theta @ y)
        J = np.zeros((3, self.body.n_dofs))
        for i in range(3):
            J[:, 3 + 3 * i:6 + 3 * i] = g[i] * np.eye(3)
        J[:, 12:] = -D @ fhat @ self.Theta
        return D @ g, J

    def position(self, q):
        x, D, y = kinetics.split(q)
        return x + D @ (self.X0 + self.S @ y)

    def velocity(self, q, v):
        _, D, y = kinetics.split(q)
        vx, V, vy = kinetics.split(v)
        return vx + V @ (self.X0 + self.S @ y) + D @ (self.S @ vy)

    def position_jacobian(self, q):
        _, D, y = kinetics.split(q)
        rho = self.X0 + self.S @ y
        J = np.zeros((3, self.body.n_dofs))
        J[:, :3] = np.eye(3)
        for i in range(3):
            J[:, 3 + 3 * i:6 + 3 * i] = rho[i] * np.eye(3)
        J[:, 12:] = D @ self.S
        return J

    def position_hessian_product(self, q, f):
        f = np.asarray(f, dtype=float)
        H = np.zeros((self.body.n_dofs, self.body.n_dofs))
        for i in range(3):
            H[3 + 3 * i:6 + 3 * i, 12:] = np.outer(f, self.S[i])
        H[12:, 3:12] = H[3:12, 12:].T
        return H

    def quadratic(self):
        """(H (3, n, n), A (3, n), a (3,)) with r_c = ½ qᵀ H_c q + A_c·q + a_c: the products d_i[c] S_ij y_j make
        H, x and X₀ make A (a = 0). Spatial joints that need only positions (``Spherical``) take it."""
        n = self.body.n_dofs
        H = np.zeros((3, n, n))
        A = np.zeros((3, n))
        for c in range(3):
            A[c, c] = 1.0
            for i in range(3):
                A[c, 3 + 3 * i + c] = self.X0[i]
                H[c, 3 + 3 * i + c, 12:] = self.S[i]
                H[c, 12:, 3 + 3 * i + c] = self.S[i]
        return H, A, np.zeros(3)

    def factored(self):
        """r = x + Σ_i ρ_i(y) d_i, ρ = X₀ + S y, as (A₀, a₀, ((β_i, γ_i, W_i))): A₀ q = x, t_i = β_i·q + γ_i = ρ_i and
        W_i q = d_i (:func:`~skfem_flex.elements.constraints.product_rows.product_dot`: joints whose rows are
        products of invariants)."""
        n = self.body.n_dofs
        A0 = np.zeros((3, n))
        A0[:, :3] = np.eye(3)
        return A0, np.zeros(3), tuple((_on_elastic(n, self.S[i]), float(self.X0[i]), _director(n, i)) for i in range(3))

    def position_discrete_gradient(self, q0, q1):
        return self.position_jacobian(0.5 * (np.asarray(q0, dtype=float) + np.asarray(q1, dtype=float)))

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return 0.5 * self.position_hessian_product(q0, f)

    def compiled_map(self):
        return None


class _TurnedDirection:
    """u(q) = D (e₀ + (Θ y) × e₀) of an :class:`ElasticPoint` as a quadratic form, for the quadratic rows:
    ``quadratic()`` gives (H (3, n, n), A (3, n), a) with u_c = ½ qᵀ H_c q + A_c·q + a_c, read off the point's own
    :meth:`ElasticPoint.turned` (u is quadratic and u(0) = 0, so its Jacobian J(q) = H q + A: A = J(0) and
    H_c's column k is J(e_k)_c − A_c)."""

    def __init__(self, point, e0):
        self.point, self.e0 = point, e0

    def factored(self):
        """u = Σ_i g_i(y) d_i with g = e₀ − ê₀ Θ y, as (A₀ = 0, a₀ = 0, ((β_i, γ_i, W_i))) (:meth:`ElasticPoint.factored`)."""
        n = self.point.body.n_dofs
        e = self.e0
        ehat = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
        G = -ehat @ self.point.Theta
        return np.zeros((3, n)), np.zeros(3), tuple((_on_elastic(n, G[i]), float(e[i]), _director(n, i))
                                                    for i in range(3))

    def quadratic(self):
        n = self.point.body.n_dofs
        A = self.point.turned(np.zeros(n), self.e0)[1]
        H = np.stack([self.point.turned(e, self.e0)[1] - A for e in np.eye(n)], axis=2)
        return H, A, np.zeros(3)


def _on_elastic(n, row):
    """A row over the body's n coordinates that reads the elastic y (offset 12) with ``row``."""
    out = np.zeros(n)
    out[12:] = row
    return out


def _director(n, i):
    """W (3, n) with W q = d_i, the frame's i-th director (offset 3 + 3i)."""
    W = np.zeros((3, n))
    W[:, 3 + 3 * i:6 + 3 * i] = np.eye(3)
    return W
