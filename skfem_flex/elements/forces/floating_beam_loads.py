r"""Loads on a :class:`~skfem_flex.bodies.floating.body.FloatingBeam`: distributed and point loads of eq. (43).

A load F on the axis does the virtual work ∫ δrᵀ F dx with δr = δR + A E (x_0 + S q_f) δθ + A S δq_f,
so its generalized force is fixed by a few integrals of the load against the beam's shape
functions, all assembled once with ``TimoshenkoBeam.load``: only cos θ, sin θ and q_f change in
the time loop. Body-frame loads turn with the frame (follower loads); global-frame loads keep
their direction (eq. 44 rotates them into the body frame).
"""
from __future__ import annotations

import math

import numpy as np

from ...bodies.floating.body import FloatingBeam
from ...bodies.rigid import E_MATRIX, rotation
from .base import ForceElement

__all__ = ["DistributedLoad"]


class DistributedLoad(ForceElement):
    """Loads of eq. (43) on a :class:`~skfem_flex.bodies.FloatingBeam`, in the body frame or in the global frame.

    Generalized force Q = ∫ (∂r/∂q)ᵀ F dx (+ point terms), i.e. Q_R = ∫F, Q_θ = moment about the
    frame origin, Q_f = ∫Sᵀ F_body (eq. 43); eq. (44) rotates global loads into the body frame.
    All integrals are assembled once with ``TimoshenkoBeam.load``.

    Parameters
    ----------
    body : FloatingBeam
    f, p : float or callable of x, optional
        Distributed load, N/m. ``frame="body"``: axial f and transverse p along the body-frame
        axes (they turn with the frame). ``frame="global"``: f along global x, p along global y.
    h, Q : (x, value) or sequence of (x, value), optional
        Point forces, N, in the same components as (f, p).
    M : (x, value) or sequence of (x, value), optional
        Point moments, N m (frame-independent in the plane).
    frame : {"body", "global"}
    time_function : callable t -> float, optional
        Scales the load in time (default 1).
    name : str

    Notes
    -----
    Body frame: Q_R = A F̄, Q_θ = m_0 + g_θᵀ q_f, Q_f = L. Global frame, (c, s) = (cos θ, sin θ):
    Q_R = F̄, Q_f = L_M + c L_1 + s L_2, Q_θ = ΣM + c (m_y + L_2·q_f) − s (m_x + L_1·q_f).
    The element is non-conservative; its work enters ``Result.external_work``.
    """

    conservative = False

    def __init__(self, body, f=None, p=None, h=None, Q=None, M=None, frame="body", time_function=None,
                 name="distributed load"):
        if not isinstance(body, FloatingBeam):
            raise ValueError(f"DistributedLoad needs a FloatingBeam, got {body!r}")
        if frame not in ("body", "global"):
            raise ValueError(f"frame must be 'body' or 'global', got {frame!r}")
        if time_function is not None and not callable(time_function):
            raise ValueError(f"time_function must be callable, got {time_function!r}")
        self.body, self.bodies, self.frame, self.name = body, (body,), frame, name
        self.time_function = time_function
        beam, free = body.beam, body.free_dofs
        qd = beam.quadrature
        pairs = {k: beam.point_pairs(k, v) for k, v in (("h", h), ("Q", Q), ("M", M))}
        for k, arr in pairs.items():
            for x, _ in arr:
                body.axial_coordinate(x, f"point load {k}")

        def field(load):
            if load is None:
                return np.zeros_like(qd.x)
            val = load(qd.x) if callable(load) else load
            val = np.broadcast_to(np.asarray(val, dtype=float), qd.x.shape)
            if not np.all(np.isfinite(val)):
                raise ValueError(f"distributed load must be finite, got {load!r}")
            return val

        fx, px = field(f), field(p)
        hh, QQ, MM = pairs["h"], pairs["Q"], pairs["M"]
        self._Fbar = np.array([np.sum(fx * qd.dx) + hh[:, 1].sum(), np.sum(px * qd.dx) + QQ[:, 1].sum()])
        self._mx = float(np.sum(qd.x * fx * qd.dx) + np.sum(hh[:, 0] * hh[:, 1]))
        self._my = float(np.sum(qd.x * px * qd.dx) + np.sum(QQ[:, 0] * QQ[:, 1]))
        self._M = float(MM[:, 1].sum())

        def neg(load):
            if load is None:
                return None
            return (lambda x: -np.asarray(load(x), dtype=float)) if callable(load) else -float(load)

        swap = lambda arr: None if arr.size == 0 else [(x, -v) for x, v in arr]  # noqa: E731
        self._L1 = beam.load(f=f, p=p, h=hh if hh.size else None, Q=QQ if QQ.size else None)[free]
        self._L2 = beam.load(f=p, p=neg(f), h=QQ if QQ.size else None, Q=swap(hh))[free]
        self._LM = beam.load(M=MM if MM.size else None)[free]

    def _scale(self, t):
        """The time factor at t (s), 1 without ``time_function``; ValueError if it is not finite."""
        if self.time_function is None:
            return 1.0
        s = float(self.time_function(t))
        if not np.isfinite(s):
            raise ValueError(f"time_function({t}) is not finite: {s!r}")
        return s

    def generalized_force(self, q, v, t):
        """Q (N, N m and the elastic components) at (q, t) with ∂Q/∂q (the body's matrix format) and
        ∂Q/∂v = None (formulas in the class notes)."""
        body = self.body
        k = self._scale(t)
        n = body.n_dofs
        qf = q[3:]
        c, s = math.cos(q[2]), math.sin(q[2])
        out = np.empty(n)
        top = np.zeros((3, n))
        left = np.zeros((body.n_elastic, 3))
        if self.frame == "body":
            A = rotation(q[2])
            out[:2] = A @ self._Fbar
            out[2] = self._my + self._M + float(self._L2 @ qf)
            out[3:] = self._LM + self._L1
            top[:2, 2] = A @ (E_MATRIX @ self._Fbar)
            top[2, 3:] = self._L2
        else:
            a2, a1 = self._my + float(self._L2 @ qf), self._mx + float(self._L1 @ qf)
            out[:2] = self._Fbar
            out[2] = self._M + c * a2 - s * a1
            out[3:] = self._LM + c * self._L1 + s * self._L2
            top[2, 2] = -s * a2 - c * a1
            top[2, 3:] = c * self._L2 - s * self._L1
            left[:, 2] = -s * self._L1 + c * self._L2
        return k * out, k * body.compose_matrix(top, left), None
