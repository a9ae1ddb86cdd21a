r"""The force balance of a scene at rest, its residual in the unknowns, and the state where it vanishes.

.. math::  F(q) + Φ_q(q)ᵀ λ = 0, \qquad Φ(q, t) = 0,

with F(q) = M(q) a − Q_v(q, v) + ∇V(q) − Q(q, v, t) (:func:`force_balance`);
:class:`StaticResidual` is R(x) = (F_free + (Φ_qᵀλ)_free, Φ) in the unknowns x = (q_free, λ), which
the load path of :mod:`skfem_flex.analysis.load_path` drives to zero; :class:`EquilibriumState` is
the answer.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps

from ..numerics.linear_solver import linear_solve
from ..scene import add_matrices
from .matrix_tools import EPS, TINY, abs_entries, inf_norm, submatrix

__all__ = ["force_balance", "EquilibriumState", "equilibrium_state", "StaticResidual", "initial_multipliers"]


def force_balance(scene, q, v, a, t, loads=None):
    r"""The generalized force balance without constraint forces and its derivatives.

    .. math::  F = M(q) a − Q_v(q, v) + ∇V(q) − Q(q, v, t)

    Parameters
    ----------
    scene : Scene
    q, v, a : ndarray (n,)
        Coordinates, velocities and accelerations (global vectors).
    t : float
        Time, s.
    loads : list, optional
        Receives ``scene.external_force``'s (Q, ∂Q/∂q, ∂Q/∂v) (or None): the non-potential loads on their own.

    Returns
    -------
    F : ndarray (n,)
    K : matrix (n, n)
        ∂F/∂q = ∂(M a)/∂q − ∂Q_v/∂q + ∇²V − ∂Q/∂q (tangent stiffness: elastic, geometric,
        centrifugal and load-stiffness parts).
    C : matrix (n, n) or None
        ∂F/∂v = −∂Q_v/∂v − ∂Q/∂v (gyroscopic and damping parts), None when zero.
    scale : float
        Largest single term (N), the scale of a converged residual.
    floor : ndarray (n,)
        abs(∇²V) abs(q), the round-off floor of the internal forces.
    """
    grad = scene.potential_gradient(q)
    hess = scene.potential_hessian(q)
    force = grad.copy()
    stiff = hess
    damp = None
    scale = inf_norm(grad)
    if np.any(a):
        inertia = scene.mass_matrix(q) @ a
        force += inertia
        scale = max(scale, inf_norm(inertia))
        stiff = add_matrices(stiff, scene.momentum_jacobian(q, a))
    qv = scene.quadratic_velocity_force(q, v)
    if qv is not None:
        force -= qv[0]
        scale = max(scale, inf_norm(qv[0]))
        stiff = add_matrices(stiff, -qv[1])
        damp = -qv[2]
    ext = scene.external_force(q, v, t)
    if loads is not None:
        loads.append(ext)
    if ext is not None:
        force -= ext[0]
        scale = max(scale, inf_norm(ext[0]))
        stiff = add_matrices(stiff, -ext[1])
        damp = add_matrices(damp, -ext[2])
    floor = abs_entries(hess) @ np.abs(q)
    return force, stiff, damp, scale, floor


# ======================================================================= statics
@dataclass
class EquilibriumState:
    """A state of a scene in static (or steady) equilibrium.

    Attributes
    ----------
    t : float
        Time, s (prescribed coordinates and drivers take their values at t).
    q, v : ndarray (n,)
        Coordinates and the velocities the equilibrium holds with (zero at rest; the
        prescribed rates and the velocities the constraints demand for ``steady``).
    lam : ndarray (n_constraints,)
        Lagrange multipliers λ.
    acc : ndarray (n,)
        Accelerations (zero except prescribed accelerations of a steady motion).
    reactions : dict of str to ndarray
        Reaction of every constraint (``Constraint.reaction``; a :class:`~skfem_flex.Pin`
        gives the force (F_x, F_y) in N it exerts on the body).
    prescribed_force : ndarray (n_prescribed,)
        Generalized force the prescribed coordinates' laws exert (N or N m).
    load_factor : float
        1 when converged (the scene's full loads).
    steps : int
        Continuation steps taken.
    iterations : int
        Newton iterations over all steps.
    steady : bool
        True for a relative equilibrium under the scene's steady motion.
    residual_tolerance : float
        The largest force imbalance (N) the solve accepted as zero:
        rtol · max(largest force term, start imbalance) + 16 ε ‖abs(∇²V) abs(q)‖∞ (0 if unknown).
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    acc: np.ndarray
    reactions: dict = field(default_factory=dict)
    prescribed_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    load_factor: float = 1.0
    steps: int = 0
    iterations: int = 0
    steady: bool = False
    residual_tolerance: float = 0.0


class StaticResidual:
    """Residual R(x) = (F_free + (Φ_qᵀλ)_free, Φ) of a scene at fixed v, a and t, x = (q_free, λ)."""

    def __init__(self, scene, q, v, a, t, settings):
        self.scene, self.q, self.v, self.a, self.t = scene, q.copy(), v, a, float(t)
        self.free = scene.free_index
        self.nf, self.m = self.free.size, scene.n_constraints
        self.settings = settings
        self.rows = np.arange(self.m)
        #: E(x₀), the configuration-dependent loads at the start of a load path (set by its homotopy), or None
        self.external_start = None
        #: (E, ∂E/∂x) of the last :meth:`evaluate`: the non-potential loads there, or (None, None)
        self.last_external = (None, None)

    def full_q(self, x):
        q = self.q.copy()
        q[self.free] = x[:self.nf]
        return q

    def evaluate(self, x):
        """(R, ∂R/∂x, scales) at x; scales = (force scale, round-off floor, constraint scale) for :meth:`error`."""
        s, free, nf, m = self.scene, self.free, self.nf, self.m
        q = self.full_q(x)
        lam = x[nf:]
        loads = []
        force, stiff, _, scale, floor = force_balance(s, q, self.v, self.a, self.t, loads)
        self.last_external = self._padded(loads[0])
        if m:
            cq = s.constraint_jacobian(q, self.t)
            ctl = cq.T @ lam
            force = force + ctl
            scale = max(scale, inf_norm(ctl))
            stiff = add_matrices(stiff, s.constraint_hessian_product(q, lam, self.t))
            phi = s.constraint_value(q, self.t)
            c_scale = max(inf_norm(abs_entries(cq) @ np.abs(q)), inf_norm(abs_entries(cq)) * s.length_scale, TINY)
            cqf = submatrix(cq, self.rows, free)
            kff = submatrix(stiff, free, free)
            if sps.issparse(kff) or sps.issparse(cqf):
                jac = sps.bmat([[sps.csr_matrix(kff), sps.csr_matrix(cqf).T], [sps.csr_matrix(cqf), None]],
                               format="csr")
            else:
                jac = np.block([[kff, cqf.T], [cqf, np.zeros((m, m))]])
            res = np.concatenate([force[free], phi])
        else:
            c_scale = 1.0
            jac = submatrix(stiff, free, free)
            if sps.issparse(jac):
                jac = jac.tocsr()
            res = force[free]
        self.last_force = force
        return res, jac, (scale, inf_norm(floor[free]) if nf else 0.0, c_scale)

    def _padded(self, ext):
        """(E, ∂E/∂x) of the scene's non-potential loads Q(q) (``external_force``'s (Q, ∂Q/∂q, …)) on the free
        rows, zero on the constraint rows; (None, None) without such loads."""
        if ext is None:
            return None, None
        free, nf, m = self.free, self.nf, self.m
        e = np.zeros(nf + m)
        e[:nf] = ext[0][free]
        de = submatrix(ext[1], free, free)
        if m:
            de = (sps.block_diag([sps.csr_matrix(de), sps.csr_matrix((m, m))], format="csr") if sps.issparse(de)
                  else np.block([[de, np.zeros((nf, m))], [np.zeros((m, nf)), np.zeros((m, m))]]))
        return e, de

    def error(self, res, scales):
        scale, floor, c_scale = scales
        st = self.settings
        e_r = inf_norm(res[:self.nf]) / (st.rtol * max(scale, TINY) + 16 * EPS * floor + TINY)
        e_c = inf_norm(res[self.nf:]) / (st.ctol * c_scale) if self.m else 0.0
        return max(e_r, e_c)


def initial_multipliers(scene, q, v, a, t):
    """Least-squares λ: minimizes |F_free + Φ_q,freeᵀ λ| at the start state."""
    m = scene.n_constraints
    if m == 0:
        return np.zeros(0)
    free = scene.free_index
    force = force_balance(scene, q, v, a, t)[0]
    cqf = submatrix(scene.constraint_jacobian(q, t), np.arange(m), free)
    if sps.issparse(cqf):
        try:
            return linear_solve(sps.csr_matrix(cqf @ cqf.T), -(cqf @ force[free]))
        except np.linalg.LinAlgError:
            cqf = cqf.toarray()
    return np.linalg.lstsq(cqf.T, -force[free], rcond=None)[0]


def equilibrium_state(scene, t, q, v, a, lam, s, steps, its, steady, force, tolerance):
    """The :class:`EquilibriumState` of (q, λ) reached at load factor s; ``force`` is the balance at q (its
    prescribed entries are the prescribed coordinates' forces)."""
    pres = scene.prescribed_index
    return EquilibriumState(t=t, q=q, v=v.copy(), lam=np.array(lam, dtype=float), acc=a.copy(),
                            reactions=scene.constraint_reactions(q, lam), prescribed_force=force[pres].copy(),
                            load_factor=float(s), steps=steps, iterations=its, steady=bool(steady),
                            residual_tolerance=float(tolerance))
