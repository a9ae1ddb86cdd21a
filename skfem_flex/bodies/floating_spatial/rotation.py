r"""Steady spin of a :class:`~skfem_flex.bodies.floating_spatial.body.FloatingBeam3D`: the stretched state and
the modes seen in the spinning frame.

The frame origin stays put and the frame turns at a constant rate Ω about a unit axis a fixed in it
(body components; a = e₁ spins the beam about its section axis d₁, so that flapwise bending is along the
spin axis): ḋ_i = Ω w × d_i and d̈_i = Ω² w × (w × d_i), w = D a. The elastic rows of the equations of
motion are then

.. math::  M_{yy} \ddot y + [M(q)\, a_f]_y − [Q_v(q, v_f + \dot y)]_y + ∇V(y) = 0,

with the frame's velocity v_f and acceleration a_f. They do not depend on the frame's angle, so the
spinning beam has a static state y_s, [M a_f]_y − [Q_v(q, v_f)]_y + ∇V(y_s) = 0 (:func:`steady_spin`,
solved by the package's Newton core), and its small motions about it obey
M_yy δÿ + C δẏ + K δy = 0 with C = −∂Q_v,y/∂ẏ (Coriolis) and
K = ∂([M a_f]_y − Q_v,y + ∇V)/∂y (the tangent stiffness with its centrifugal stiffening from the
Green–Lagrange tension, and the centrifugal softening): :func:`spinning_modes`. All the pieces are the
body's own kinetic and strain terms: nothing here is a second model of the beam.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.linalg

from ...fem.spatial_beam import RotatingModes, repeated_pairs
from ...numerics.newton import NewtonSettings, newton_solve
from . import kinetics

__all__ = ["steady_spin", "spinning_modes", "elastic_load_of_spin"]

_EPS = np.finfo(float).eps


def _frame_motion(body, omega, axis):
    """q (at the body's initial frame, y = 0), v_f and a_f of the spin, as full-length vectors."""
    a = np.asarray(axis, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0.0:
        raise ValueError(f"axis must be a finite nonzero 3-vector in the frame's axes, got {axis!r}")
    om = float(omega)
    if not np.isfinite(om):
        raise ValueError(f"omega must be finite, got {omega!r}")
    _, D, _ = kinetics.split(body.q0)
    w = D @ (a / np.linalg.norm(a))
    q = body.q0.copy()
    q[12:] = 0.0
    v = np.zeros(body.n_dofs)
    acc = np.zeros(body.n_dofs)
    for i in range(3):
        d = D[:, i]
        v[3 + 3 * i:6 + 3 * i] = om * np.cross(w, d)
        acc[3 + 3 * i:6 + 3 * i] = om * om * np.cross(w, np.cross(w, d))
    return q, v, acc


class ElasticRows(NamedTuple):
    """The elastic rows at rest in the spinning frame (module docstring) and their parts."""

    residual: np.ndarray        #: [M a_f]_y − [Q_v]_y + ∇V
    stiffness: np.ndarray       #: ∂residual/∂y
    damping: np.ndarray         #: C = −∂Q_v,y/∂ẏ
    inertia: np.ndarray         #: [M a_f]_y
    velocity_force: np.ndarray  #: [Q_v]_y
    gradient: np.ndarray        #: ∇V
    hessian: np.ndarray         #: ∇²V


def _elastic_rows(body, q, v, acc):
    """The :class:`ElasticRows` at (q, v_f, a_f)."""
    inv = body.inertia
    Y = slice(12, body.n_dofs)
    qv, qv_q, qv_v = kinetics.quadratic_velocity_force(inv, q, v)
    inertia = kinetics.mass_matrix(inv, q) @ acc
    B = kinetics.momentum_jacobian(inv, q, acc)
    grad, hess = body.potential_gradient(q)[Y], body.potential_hessian(q)[Y, Y]
    r = inertia[Y] - qv[Y] + grad
    K = B[Y, Y] - qv_q[Y, Y] + hess
    return ElasticRows(r, K, -qv_v[Y, Y], inertia[Y], qv[Y], grad, hess)


def elastic_load_of_spin(body, axis):
    """The elastic rows [M a_f]_y − [Q_v]_y of the undeformed beam spinning at 1 rad/s about ``axis`` (frame
    axes): the inertia load whose static response is the stretch of a spinning beam (N per rad²/s²)."""
    q, v, acc = _frame_motion(body, 1.0, axis)
    rows = _elastic_rows(body, q, v, acc)
    return rows.residual - rows.gradient


def steady_spin(body, omega, axis=(1.0, 0.0, 0.0), tol=1e-12, max_iterations=25):
    """The elastic state y_s (n_elastic,) of ``body`` spinning at ``omega`` (rad/s) about ``axis`` (frame axes).

    Newton (:func:`~skfem_flex.numerics.newton.newton_solve`) from y = 0 on the elastic rows (module
    docstring); converged when the residual is at most ``tol`` times the largest of the inertia, the
    velocity forces and the internal forces, plus the round-off floor of the internal forces.

    Raises
    ------
    ValueError
        For a non-finite ω or a bad axis.
    ConvergenceError
        If Newton fails (beyond a divergence speed of the linear strain, for instance).
    """
    q, v, acc = _frame_motion(body, omega, axis)
    settings = NewtonSettings(rtol=float(tol), max_iterations=int(max_iterations))

    def fun(y):
        q[12:] = y
        rows = _elastic_rows(body, q, v, acc)
        scale = max(float(np.abs(part).max()) for part in (rows.inertia, rows.velocity_force, rows.gradient))
        floor = float(np.max(np.abs(rows.hessian) @ np.abs(y), initial=0.0))
        err = float(np.abs(rows.residual).max()) / (settings.rtol * scale + 16 * _EPS * floor + 1e-300)
        return rows.residual, rows.stiffness, err

    return newton_solve(fun, np.zeros(body.n_elastic), settings, "steady spin",
                        f"omega = {float(omega):.6g} rad/s")[0].copy()


def spinning_modes(body, omega, axis=(1.0, 0.0, 0.0), n_modes=8, flap_axis=0, lag_axis=1):
    """Modes about the steady spin, in the spinning frame (module docstring).

    Parameters
    ----------
    body : FloatingBeam3D
    omega : float
        Ω, rad/s.
    axis : array_like (3,)
        The spin axis in the frame's axes.
    n_modes : int
    flap_axis, lag_axis : int
        The frame axes (0, 1, 2) along which a mode's displacement counts as flapwise (along the spin axis)
        and as lead-lag (in the plane of rotation, across the body).

    Returns
    -------
    RotatingModes
        Frequencies (rad/s, ascending), growth rates (1/s), flapwise flags and the shapes on the body's mesh
        (``body.mesh_shapes``: the beam's or the solid's DOFs).
    """
    y = steady_spin(body, omega, axis)
    q, v, acc = _frame_motion(body, omega, axis)
    q[12:] = y
    rows = _elastic_rows(body, q, v, acc)
    K, C = rows.stiffness, rows.damping
    M = kinetics.mass_matrix(body.inertia, q)[12:, 12:]
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam, vec = scipy.linalg.eig(A)
    big = np.abs(lam).max()
    keep = (lam.imag > 1e-9 * big) | ((np.abs(lam.imag) <= 1e-9 * big) & (lam.real > 0))
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(np.abs(lam))[:int(n_modes)]
    lam, vec = lam[order], vec[:n, order]
    # a repeated frequency (no spin, equal bending stiffnesses): eig may return two nearly parallel vectors
    # for it; its two-dimensional eigenspace is the null space of A − λI, taken from the SVD
    for k in repeated_pairs(lam):
        _, _, vh = np.linalg.svd(A - 0.5 * (lam[k] + lam[k + 1]) * np.eye(2 * n))
        vec[:, k:k + 2] = vh[-2:].conj().T[:n]
    return RotatingModes.from_eigenpairs(lam, body.mesh_shapes(vec), body.motion_rows(flap_axis),
                                         body.motion_rows(lag_axis))
