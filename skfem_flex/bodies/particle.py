"""Point mass in one or two dimensions."""
from __future__ import annotations

import numpy as np

from .base import Body, BodyGeometry, BodyPoint, check_finite_vector

__all__ = ["PointMass"]


class PointMass(Body):
    """A point mass with Cartesian coordinates.

    Parameters
    ----------
    mass : float
        Mass m in kg, finite and positive.
    position : array_like, length 1 or 2
        Initial position in m. One entry makes a 1-dof body (a spring–mass
        system along a line), two entries a planar particle (x, y).
    velocity : array_like, optional
        Initial velocity in m/s (zero by default).
    name : str
        Name shown in messages and output.

    Notes
    -----
    T = ½ m ‖v‖², M = m I (constant).
    """

    constant_mass = True

    def __init__(self, mass, position, velocity=None, name="point"):
        mass = float(mass)
        if not np.isfinite(mass) or mass <= 0:
            raise ValueError(f"mass must be finite and positive, got {mass!r}")
        q0 = check_finite_vector("position", position)
        if q0.size not in (1, 2):
            raise ValueError(f"position must have 1 or 2 entries, got {q0.size}")
        v0 = np.zeros_like(q0) if velocity is None else check_finite_vector("velocity", velocity, q0.size)
        self.mass = mass
        self.q0, self.v0 = q0, v0
        self.n_dofs = q0.size
        self.name = name

    @property
    def coordinate_names(self):
        return ("x", "y")[: self.n_dofs]

    def mass_matrix(self, q):
        return self.mass * np.eye(self.n_dofs)

    def kinetic_energy(self, q, v):
        return 0.5 * self.mass * float(v @ v)

    def momentum(self, q, v):
        return self.mass * v

    def mass_moment(self):
        gam = np.zeros((2, self.n_dofs))
        gam[: self.n_dofs, : self.n_dofs] = self.mass * np.eye(self.n_dofs)
        return gam, np.zeros(2)

    def linear_momentum(self, q, v):
        p = np.zeros(2)
        p[: self.n_dofs] = self.mass * v
        return p

    def angular_momentum(self, q, v):
        if self.n_dofs == 1:
            return 0.0
        return self.mass * float(q[0] * v[1] - q[1] * v[0])

    def point(self, locator=None):
        """The mass itself (a point mass has one point; ``locator`` must be None)."""
        if locator is not None:
            raise ValueError(f"a point mass has a single point; got locator {locator!r}")
        if self.n_dofs != 2:
            raise ValueError(f"body points need a planar point mass; {self.name!r} has {self.n_dofs} coordinate")
        return _MassPoint(self)

    def geometry(self, q, v):
        pts = np.zeros((1, 2))
        pts[0, : self.n_dofs] = q
        vel = np.zeros((1, 2))
        vel[0, : self.n_dofs] = v
        return BodyGeometry(pts, [("vertex", np.array([[0]]))], {"velocity": vel})


class _MassPoint(BodyPoint):
    """The point of a planar point mass: r = q, linear."""

    def __init__(self, body):
        self.body = body

    def position(self, q):
        return np.array(q[:2], dtype=float)

    def position_jacobian(self, q):
        return np.eye(2)

    def compiled_map(self):
        return "linear", np.eye(2, self.body.n_dofs), np.zeros(2)

    def position_hessian_product(self, q, f):
        return np.zeros((2, 2))

    def position_discrete_gradient(self, q0, q1):
        return np.eye(2)

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return np.zeros((2, 2))
