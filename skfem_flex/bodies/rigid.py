r"""Planar rigid body.

Coordinates q = (x, y, θ): the centre of mass R = (x, y) in the global frame
(m) and the angle θ of the body frame (rad). A material point given by its
body-frame coordinates s (measured from the centre of mass) sits at

.. math::  r(q) = R + A(θ) s,   A(θ) = [[cos θ, −sin θ], [sin θ, cos θ]].

The mass matrix is constant, M = diag(m, m, J) with J the moment of inertia
about the centre of mass, so the energy-conserving scheme needs no kinetic
discrete gradient; gravity is linear in q (∫ r dm = m R).

The exact discrete gradient of a point's position between q0 and q1 uses
the two identities of the rotation matrix (``docs/energy_scheme.md``)

.. math::  A(θ_1) − A(θ_0) = \operatorname{sinc}(Δθ/2)\, Δθ\, A(θ_m) E,
           \qquad (A_0 + A_1)/2 = \cos(Δθ/2) A(θ_m),

with E = [[0, −1], [1, 0]], θ_m = (θ0 + θ1)/2 and Δθ = θ1 − θ0; so
D = [I, sinc(Δθ/2) A(θ_m) E s] satisfies D (q1 − q0) = r(q1) − r(q0) to
round-off for any step.
"""
from __future__ import annotations

import math

import numpy as np

from .base import Body, BodyGeometry, BodyPoint, check_finite_vector
from ..numerics.rotations import dsinc, sinc

__all__ = ["RigidBody", "rotation", "E_MATRIX"]

#: the planar "cross" matrix E = A(π/2): E v is v turned by +90°
E_MATRIX = np.array([[0.0, -1.0], [1.0, 0.0]])


def rotation(theta):
    """A(θ) = [[cos θ, −sin θ], [sin θ, cos θ]]."""
    theta = float(theta)
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def _positive(name, value):
    value = float(value)
    if not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be finite and positive, got {value!r}")
    return value


class RigidBody(Body):
    """A planar rigid body with coordinates (x, y, θ) of its centre of mass and angle.

    Parameters
    ----------
    mass : float
        m in kg, finite and positive.
    inertia : float
        J, moment of inertia about the centre of mass in kg m², finite and positive.
    position : array_like, shape (2,)
        Initial centre of mass R in m.
    angle : float
        Initial angle θ in rad.
    velocity : array_like, shape (2,), optional
        Initial velocity of the centre of mass in m/s (zero by default).
    angular_velocity : float
        Initial θ̇ in rad/s.
    outline : array_like, shape (k, 2), optional
        Corners of a closed polygon in body coordinates (m, from the centre
        of mass), drawn as VTK ``line`` cells. Two points draw a bar.
        Without it the body is drawn as a small cross whose arms are the
        radius of gyration sqrt(J/m) long.
    name : str

    Notes
    -----
    T = ½ m ‖Ṙ‖² + ½ J θ̇², M = diag(m, m, J) (constant). Linear momentum
    m Ṙ; angular momentum about the global origin m (x ẏ − y ẋ) + J θ̇.
    """

    constant_mass = True
    has_potential = False

    def __init__(self, mass, inertia, position=(0.0, 0.0), angle=0.0, velocity=None, angular_velocity=0.0,
                 outline=None, name="rigid"):
        self.mass = _positive("mass", mass)
        self.inertia = _positive("inertia", inertia)
        pos = check_finite_vector("position", position, 2)
        ang = check_finite_vector("angle", angle, 1)
        vel = np.zeros(2) if velocity is None else check_finite_vector("velocity", velocity, 2)
        omg = check_finite_vector("angular_velocity", angular_velocity, 1)
        self.q0 = np.concatenate([pos, ang])
        self.v0 = np.concatenate([vel, omg])
        self.n_dofs = 3
        self.name = name
        if outline is None:
            a = np.sqrt(self.inertia / self.mass)
            self.outline = np.array([[-a, 0.0], [a, 0.0], [0.0, -a], [0.0, a]])
            self._cells = np.array([[0, 1], [2, 3]])
        else:
            pts = np.asarray(outline, dtype=float)
            if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 2:
                raise ValueError(f"outline must have shape (k, 2) with k >= 2, got {np.shape(outline)}")
            if not np.all(np.isfinite(pts)):
                raise ValueError(f"outline must be finite, got {outline!r}")
            self.outline = pts
            k = pts.shape[0]
            if k == 2:
                self._cells = np.array([[0, 1]])
            else:
                self._cells = np.array([[i, (i + 1) % k] for i in range(k)])
        self._mass = np.diag([self.mass, self.mass, self.inertia])

    @classmethod
    def bar(cls, mass, length, start=(0.0, 0.0), angle=0.0, inertia=None, name="bar", **kwargs):
        """A slender bar of ``length`` (m) starting at ``start`` along ``angle``.

        The centre of mass is at the middle; the inertia defaults to the
        slender-rod value m L²/12 about it. The bar's ends are the body
        points ``(−L/2, 0)`` and ``(L/2, 0)``. Other keywords go to the constructor.
        """
        length = _positive("length", length)
        start = check_finite_vector("start", start, 2)
        centre = start + 0.5 * length * np.array([np.cos(angle), np.sin(angle)])
        j = mass * length ** 2 / 12.0 if inertia is None else inertia
        return cls(mass, j, centre, angle, outline=[[-0.5 * length, 0.0], [0.5 * length, 0.0]], name=name,
                   **kwargs)

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        return ("x", "y", "theta")

    def mass_matrix(self, q):
        return self._mass

    def kinetic_energy(self, q, v):
        return 0.5 * (self.mass * float(v[0] ** 2 + v[1] ** 2) + self.inertia * float(v[2]) ** 2)

    def momentum(self, q, v):
        return self._mass @ v

    def mass_moment(self):
        gam = np.zeros((2, 3))
        gam[0, 0] = gam[1, 1] = self.mass
        return gam, np.zeros(2)

    def linear_momentum(self, q, v):
        return self.mass * np.array(v[:2], dtype=float)

    def angular_momentum(self, q, v):
        return self.mass * float(q[0] * v[1] - q[1] * v[0]) + self.inertia * float(v[2])

    # ---------------------------------------------------------- body points
    def point(self, locator=None):
        """The material point at body coordinates ``locator`` = (sx, sy) in m from the centre of mass.

        ``None`` is the centre of mass. Any finite point is accepted (a rigid
        body may be extended by a massless arm).
        """
        s = np.zeros(2) if locator is None else check_finite_vector("rigid body point", locator, 2)
        return RigidPoint(self, s)

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        a = rotation(q[2])
        pts = q[:2] + self.outline @ a.T
        vel = v[:2] + v[2] * (self.outline @ (a @ E_MATRIX).T)
        return BodyGeometry(pts, [("line", self._cells.copy())], {"velocity": vel})


class RigidPoint(BodyPoint):
    """A material point of a :class:`RigidBody`: r = R + A(θ) s, angle θ."""

    has_angle = True

    def __init__(self, body, s):
        self.body = body
        self.s = np.asarray(s, dtype=float)
        self._es = E_MATRIX @ self.s

    def position(self, q):
        return q[:2] + rotation(q[2]) @ self.s

    def compiled_map(self):
        return "frame", 1.0, self.s, np.zeros((2, 0))

    def position_jacobian(self, q):
        jac = np.zeros((2, 3))
        jac[0, 0] = jac[1, 1] = 1.0
        jac[:, 2] = rotation(q[2]) @ self._es
        return jac

    def position_hessian_product(self, q, f):
        h = np.zeros((3, 3))
        h[2, 2] = -float(f @ (rotation(q[2]) @ self.s))
        return h

    def position_discrete_gradient(self, q0, q1):
        half = 0.5 * (q1[2] - q0[2])
        d = np.zeros((2, 3))
        d[0, 0] = d[1, 1] = 1.0
        d[:, 2] = sinc(half) * (rotation(q0[2] + half) @ self._es)
        return d

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        half = 0.5 * (q1[2] - q0[2])
        am = rotation(q0[2] + half)
        h = np.zeros((3, 3))
        h[2, 2] = 0.5 * (dsinc(half) * float(f @ (am @ self._es)) - sinc(half) * float(f @ (am @ self.s)))
        return h

    def velocity(self, q, v):
        return v[:2] + v[2] * (rotation(q[2]) @ self._es)

    def angle(self, q):
        return float(q[2])

    def angle_jacobian(self, q):
        return np.array([0.0, 0.0, 1.0])
