r"""Spatial rotations: unit quaternions (Euler parameters), rotation vectors and rotation matrices.

Conventions (used by every spatial body and scene):

* a rotation matrix R maps body axes to space axes, r = R s; its columns are the body's directors
  d₁, d₂, d₃ in space axes;
* the Euler parameters e = (e₀, e₁, e₂, e₃) = (cos(φ/2), sin(φ/2) n) of a turn by φ about the unit
  axis n give

  .. math::  R(e) = (e_0^2 - \mathbf e\cdot\mathbf e)\,I + 2\,\mathbf e\mathbf e^T + 2 e_0\,\widehat{\mathbf e},

  with :math:`\widehat{a}\,b = a \times b` (:func:`skew`); e and −e are the same rotation;
* the rotation vector φ n turns by exp(skew(φ n)) (Rodrigues' formula, :func:`rotation_vector_matrix`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["skew", "quaternion_matrix", "matrix_quaternion", "rotation_vector_matrix", "check_quaternion",
           "check_rotation_matrix"]


def skew(a):
    """The cross-product matrix: ``skew(a) @ b == np.cross(a, b)``."""
    a = np.asarray(a, dtype=float)
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def check_quaternion(name, e):
    """``e`` as a unit quaternion (4,): normalized, or ``ValueError`` for a wrong size, non-finite or zero one."""
    arr = np.asarray(e, dtype=float).ravel()
    if arr.size != 4:
        raise ValueError(f"{name} must have 4 entries (e0, e1, e2, e3), got {arr.size}: {e!r}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {e!r}")
    nrm = float(np.linalg.norm(arr))
    if nrm < 1e-12:
        raise ValueError(f"{name} must not be zero (a rotation needs a unit quaternion), got {e!r}")
    return arr / nrm


def check_rotation_matrix(name, R, tol=1e-9):
    """``R`` as a proper orthogonal (3, 3) matrix, or ``ValueError`` naming how far it is from one."""
    arr = np.asarray(R, dtype=float)
    if arr.shape != (3, 3):
        raise ValueError(f"{name} must be a (3, 3) rotation matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {R!r}")
    err = float(np.abs(arr.T @ arr - np.eye(3)).max())
    if err > tol or np.linalg.det(arr) <= 0.0:
        raise ValueError(f"{name} must be a rotation matrix (RᵀR = I, det R = +1): |RᵀR − I| = {err:.3g}, "
                         f"det R = {np.linalg.det(arr):.6g}")
    return arr


def quaternion_matrix(e):
    """R(e) of a unit quaternion e = (e₀, e₁, e₂, e₃) (module docstring)."""
    e0, v = float(e[0]), np.asarray(e[1:4], dtype=float)
    return (e0 * e0 - v @ v) * np.eye(3) + 2.0 * np.outer(v, v) + 2.0 * e0 * skew(v)


def matrix_quaternion(R, reference=None):
    """Euler parameters of a rotation matrix (Shepperd's stable choice of the largest component).

    Parameters
    ----------
    R : array_like (3, 3) or (N, 3, 3)
    reference : array_like (4,) or (N, 4), optional
        The sign of each result is chosen so that its dot product with the reference is not negative (e
        and −e are the same rotation: pass the previous value to follow a path continuously). Without it
        e₀ ≥ 0.

    Returns
    -------
    ndarray (4,) or (N, 4)
    """
    R = np.asarray(R, dtype=float)
    one = R.ndim == 2
    Rs = R.reshape(-1, 3, 3)
    out = np.empty((Rs.shape[0], 4))
    for k, m in enumerate(Rs):
        tr = np.trace(m)
        cand = np.array([tr, m[0, 0], m[1, 1], m[2, 2]])
        i = int(np.argmax(cand))
        if i == 0:
            e0 = 0.5 * np.sqrt(max(1.0 + tr, 0.0))
            e = [e0, (m[2, 1] - m[1, 2]) / (4 * e0), (m[0, 2] - m[2, 0]) / (4 * e0), (m[1, 0] - m[0, 1]) / (4 * e0)]
        else:
            a = i - 1
            b, c = (a + 1) % 3, (a + 2) % 3
            ea = 0.5 * np.sqrt(max(1.0 + 2.0 * m[a, a] - tr, 0.0))
            e = np.zeros(4)
            e[1 + a] = ea
            e[0] = (m[c, b] - m[b, c]) / (4 * ea)
            e[1 + b] = (m[b, a] + m[a, b]) / (4 * ea)
            e[1 + c] = (m[c, a] + m[a, c]) / (4 * ea)
        out[k] = e
    if reference is None:
        out[out[:, 0] < 0] *= -1.0
    else:
        ref = np.broadcast_to(np.asarray(reference, dtype=float).reshape(-1, 4), out.shape)
        out[np.einsum("ij,ij->i", out, ref) < 0] *= -1.0
    return out[0] if one else out


def rotation_vector_matrix(phi):
    """exp(skew(φ)): the turn by ‖φ‖ about φ/‖φ‖ (Rodrigues' formula), φ in rad."""
    phi = np.asarray(phi, dtype=float).reshape(3)
    ang = float(np.linalg.norm(phi))
    K = skew(phi)
    if ang < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + np.sin(ang) / ang * K + (1.0 - np.cos(ang)) / ang ** 2 * K @ K
