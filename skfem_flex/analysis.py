r"""Statics and linearized modes of any scene; Campbell diagrams.

Beside the time loop, on the same scene assembly (docs/linearization.md):

:func:`static_equilibrium`
    The nonlinear equilibrium of a scene,

    .. math::  F(q) + Φ_q(q)ᵀ λ = 0, \qquad Φ(q, t) = 0,

    with F(q) = M(q) a_p − Q_v(q, v) + ∇V(q) − Q(q, v, t) the generalized force balance at
    rest (or at the steady velocities, ``steady=True``), found by path following from the
    start state: the homotopy H(x, s) = R(x) − (1 − s) R(x₀), x = (q_free, λ), runs the load
    factor s from 0 (the start, a solution by construction) to 1 (the scene's loads). From a
    stress-free start with loads that do not depend on q this is exactly proportional load
    stepping. The path is followed by pseudo-arc-length continuation with automatic step
    control (predictor along the tangent, Newton corrector on the hyperplane orthogonal to
    it, step halved on failure and doubled after quick convergence), so it passes turning
    points of the load; the last step lands on s = 1 by a Newton solve at fixed load.
:func:`linearize`
    Mass, damping/gyroscopic and stiffness matrices about any state (q, v, t) with
    multipliers λ and accelerations a, reduced to the independent coordinates by a sparse
    null-space basis of Φ_q (:func:`null_space_basis`).
:func:`modes`
    Eigenvalues s, frequencies, damping ratios and shapes of the linearized system about
    the static equilibrium, the steady motion, the initial state or any given state.
:func:`campbell`
    Modes of a scene against a parameter (spin rate, crank angle, ...).

See ``docs/linearization.md`` for the equations.
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .errors import ConvergenceError
from .scene_initial import RedundantConstraintsError, consistent_initial_state
from .numerics.linear_solver import linear_solve
from .numerics.newton import NewtonSettings, newton_solve
from .scene import add_matrices

__all__ = ["EquilibriumState", "LinearSystem", "Modes", "CampbellDiagram", "static_equilibrium", "linearize",
           "modes", "campbell", "null_space_basis", "write_mode_series", "force_balance", "ABOUT", "DENSE_EIGEN_LIMIT"]

_EPS = np.finfo(float).eps
_TINY = 1e-300
#: reduced systems with at most this many coordinates are solved by dense LAPACK eigensolvers, larger
#: ones by ARPACK in shift-invert mode (which finds a few modes of a 200-coordinate beam several
#: times faster than a dense solve finds all)
DENSE_EIGEN_LIMIT = 120
#: the states ``modes(about=...)`` accepts by name
ABOUT = ("static", "steady", "initial")


def _inf(x):
    return float(np.abs(x).max()) if np.size(x) else 0.0


def _dense(a):
    return a.toarray() if sps.issparse(a) else np.asarray(a, dtype=float)


def _sub(a, rows, cols):
    if sps.issparse(a):
        return a.tocsr()[rows][:, cols]
    return np.asarray(a)[np.ix_(rows, cols)]


def _abs(a):
    return abs(a) if sps.issparse(a) else np.abs(a)


# ======================================================================= force balance
def force_balance(scene, q, v, a, t):
    r"""The generalized force balance without constraint forces and its derivatives.

    .. math::  F = M(q) a − Q_v(q, v) + ∇V(q) − Q(q, v, t)

    Parameters
    ----------
    scene : Scene
    q, v, a : ndarray (n,)
        Coordinates, velocities and accelerations (global vectors).
    t : float
        Time, s.

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
        |∇²V| |q|, the round-off floor of the internal forces.
    """
    grad = scene.potential_gradient(q)
    hess = scene.potential_hessian(q)
    force = grad.copy()
    stiff = hess
    damp = None
    scale = _inf(grad)
    if np.any(a):
        inertia = scene.mass_matrix(q) @ a
        force += inertia
        scale = max(scale, _inf(inertia))
        stiff = add_matrices(stiff, scene.momentum_jacobian(q, a))
    qv = scene.quadratic_velocity_force(q, v)
    if qv is not None:
        force -= qv[0]
        scale = max(scale, _inf(qv[0]))
        stiff = add_matrices(stiff, -qv[1])
        damp = -qv[2]
    ext = scene.external_force(q, v, t)
    if ext is not None:
        force -= ext[0]
        scale = max(scale, _inf(ext[0]))
        stiff = add_matrices(stiff, -ext[1])
        damp = add_matrices(damp, -ext[2])
    floor = _abs(hess) @ np.abs(q)
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
        rtol · max(largest force term, start imbalance) + 16 ε ‖|∇²V| |q|‖∞ (0 if unknown).
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


class _Statics:
    """Residual R(x) = (F_free + (Φ_qᵀλ)_free, Φ) of a scene at fixed v, a and t, x = (q_free, λ)."""

    def __init__(self, scene, q, v, a, t, settings):
        self.scene, self.q, self.v, self.a, self.t = scene, q.copy(), v, a, float(t)
        self.free = scene.free_index
        self.nf, self.m = self.free.size, scene.n_constraints
        self.settings = settings
        self.rows = np.arange(self.m)

    def full_q(self, x):
        q = self.q.copy()
        q[self.free] = x[:self.nf]
        return q

    def evaluate(self, x):
        """(R, ∂R/∂x, scales) at x; scales = (force scale, round-off floor, constraint scale) for :meth:`error`."""
        s, free, nf, m = self.scene, self.free, self.nf, self.m
        q = self.full_q(x)
        lam = x[nf:]
        force, stiff, _, scale, floor = force_balance(s, q, self.v, self.a, self.t)
        if m:
            cq = s.constraint_jacobian(q, self.t)
            ctl = cq.T @ lam
            force = force + ctl
            scale = max(scale, _inf(ctl))
            stiff = add_matrices(stiff, s.constraint_hessian_product(q, lam, self.t))
            phi = s.constraint_value(q, self.t)
            c_scale = max(_inf(_abs(cq) @ np.abs(q)), _inf(_abs(cq)) * s.length_scale, _TINY)
            cqf = _sub(cq, self.rows, free)
            kff = _sub(stiff, free, free)
            if sps.issparse(kff) or sps.issparse(cqf):
                jac = sps.bmat([[sps.csr_matrix(kff), sps.csr_matrix(cqf).T], [sps.csr_matrix(cqf), None]],
                               format="csr")
            else:
                jac = np.block([[kff, cqf.T], [cqf, np.zeros((m, m))]])
            res = np.concatenate([force[free], phi])
        else:
            c_scale = 1.0
            jac = _sub(stiff, free, free)
            if sps.issparse(jac):
                jac = jac.tocsr()
            res = force[free]
        self.last_force = force
        return res, jac, (scale, _inf(floor[free]) if nf else 0.0, c_scale)

    def error(self, res, scales):
        scale, floor, c_scale = scales
        st = self.settings
        e_r = _inf(res[:self.nf]) / (st.rtol * max(scale, _TINY) + 16 * _EPS * floor + _TINY)
        e_c = _inf(res[self.nf:]) / (st.ctol * c_scale) if self.m else 0.0
        return max(e_r, e_c)


class _SingularStart(ValueError):
    """The load path cannot start at the given state: no stiffness meets the loads there."""


def _translation_fields(scene, q):
    """W (2, n) with rows the generalized rigid translations t_x, t_y of the whole scene, or None.

    For bodies whose linear momentum is p = G v with M t = Gᵀ (every body of the package: a
    rigid translation moves every mass element by the same vector), W = G M⁻¹, and W f is the
    resultant (N) of a generalized force f. None when a body gives no momentum or M is singular.
    """
    g = np.zeros((2, scene.n))
    for b in scene.bodies:
        sl = scene.slice(b)
        qb, e = q[sl], np.zeros(b.n_dofs)
        for j in range(b.n_dofs):
            e[j] = 1.0
            p = b.linear_momentum(qb, e)
            e[j] = 0.0
            if p is None:
                return None
            g[:, sl.start + j] = p
    mass = scene.mass_matrix(q)
    try:
        w = np.array([linear_solve(mass, row) for row in g])
    except np.linalg.LinAlgError:
        return None
    return w if np.all(np.isfinite(w)) else None


def _check_held(scene, q, v, a, t):
    """ValueError if nothing holds the scene against the resultant of its loads (no rest state).

    A direction d of rigid translation is free when no constraint, prescribed coordinate or
    stiffness to the ground can exert a force along it: d · W Φ_qᵀ = 0, d · W e_p = 0 for the
    prescribed coordinates p, and d · W K = 0 (internal forces and joints between bodies have no
    resultant). If the loads' resultant W(Q − F_internal) has a component along a free direction,
    the scene accelerates whatever its configuration (a free-flying body under a load, a body
    falling freely): there is no state at rest to find or to linearize about.
    """
    w = _translation_fields(scene, q)
    if w is None:
        return
    force, stiff = force_balance(scene, q, v, a, t)[:2]
    absw = np.abs(w)
    cols = [(stiff.T @ w.T).T, (_abs(stiff).T @ absw.T).T]
    if scene.n_constraints:
        cq = scene.constraint_jacobian(q, t)
        cols += [(cq @ w.T).T, (_abs(cq) @ absw.T).T]
    pres = scene.prescribed_index
    cols += [w[:, pres], absw[:, pres]]
    held = np.hstack(cols[0::2])
    size = np.linalg.norm(np.hstack(cols[1::2]), axis=0)
    norm = np.linalg.norm(held, axis=0)
    keep = norm > 1e-8 * np.maximum(size, _TINY)       # forces a support exerts on a rigid translation
    free = np.eye(2)
    if np.any(keep):
        u, sv, _ = np.linalg.svd(held[:, keep] / norm[keep], full_matrices=True)
        free = u[:, sv.size:] if sv.size < 2 else u[:, sv <= 1e-6 * sv[0]]
    size = max(float(np.linalg.norm(absw @ np.abs(force))), _TINY)
    free = free[:, [_translates_freely(scene, q, v, a, t, w, force, d, size) for d in free.T]]
    if free.shape[1] == 0:
        return
    resultant = -(w @ force) + 0.0                    # + 0.0: no "-0" in the message
    along = free.T @ resultant
    if np.linalg.norm(along) <= 1e-8 * size:
        return
    what = ("in any direction" if free.shape[1] == 2 else
            f"along ({free[0, 0]:.3g}, {free[1, 0]:.3g})")
    raise ValueError(f"scene {scene.name!r} has no rest state: nothing holds it {what} (no support, prescribed "
                     f"coordinate or stiffness to the ground), and its loads at t = {t:g} s have a resultant "
                     f"force ({resultant[0]:.4g}, {resultant[1]:.4g}) N, so it accelerates (a free-flying body "
                     f"under loads, or a body falling freely); linearize it about its initial state "
                     f"(about='initial') or about a state of a run instead")


def _translates_freely(scene, q, v, a, t, w, force, d, size):
    """True if a finite rigid translation along d changes neither Φ nor the loads' resultant along d.

    The first-order test of :func:`_check_held` is local: a pendulum held horizontal has a rod whose
    Jacobian is blind to a vertical translation (Φ changes by ½δ² only), yet the rod holds it. A
    translation by a tenth of the scene's size tells supports that act at some distance from
    ones that never act (joints between bodies, internal forces: translation invariant exactly).
    """
    td = d @ w
    delta = 0.1 * scene.length_scale
    q1 = q + delta * td
    if scene.n_constraints:
        dphi = scene.constraint_value(q1, t) - scene.constraint_value(q, t)
        reach = _inf(_abs(scene.constraint_jacobian(q, t)) @ np.abs(td)) + _inf(td) * scene.length_scale
        if _inf(dphi) > 1e-8 * delta * max(reach, _TINY):
            return False
    try:
        force1 = force_balance(scene, q1, v, a, t)[0]
    except (ValueError, ConvergenceError):     # a body that cannot be moved there is held somehow
        return False
    return abs(float(d @ (w @ (force1 - force)))) <= 1e-8 * size


def _initial_multipliers(scene, q, v, a, t):
    """Least-squares λ: minimizes |F_free + Φ_q,freeᵀ λ| at the start state."""
    m = scene.n_constraints
    if m == 0:
        return np.zeros(0)
    free = scene.free_index
    force = force_balance(scene, q, v, a, t)[0]
    cqf = _sub(scene.constraint_jacobian(q, t), np.arange(m), free)
    if sps.issparse(cqf):
        try:
            return linear_solve(sps.csr_matrix(cqf @ cqf.T), -(cqf @ force[free]))
        except np.linalg.LinAlgError:
            cqf = cqf.toarray()
    return np.linalg.lstsq(cqf.T, -force[free], rcond=None)[0]


def _steady_velocity(scene, q, t):
    """Prescribed rates, and the smallest free velocities with Φ_q v + Φ_t = 0."""
    v = np.zeros(scene.n)
    _, vp, _ = scene.prescribed_state(t)
    v[scene.prescribed_index] = vp
    if scene.n_constraints:
        cq = _dense(scene.constraint_jacobian(q, t))
        rhs = -scene.constraint_time_derivative(q, t) - cq @ v
        if np.any(rhs):
            v[scene.free_index] = np.linalg.lstsq(cq[:, scene.free_index], rhs, rcond=None)[0]
    return v


def _bordered_matrix(jac, col, row, corner):
    """The bordered matrix [[J, col], [rowᵀ, corner]] (dense or sparse)."""
    if sps.issparse(jac):
        return sps.bmat([[jac, sps.csr_matrix(col[:, None])], [sps.csr_matrix(row[None, :]),
                          sps.csr_matrix(np.array([[corner]]))]], format="csr")
    n = jac.shape[0]
    out = np.empty((n + 1, n + 1))
    out[:n, :n] = jac
    out[:n, n] = col
    out[n, :n] = row
    out[n, n] = corner
    return out


def static_equilibrium(scene, t=0.0, q=None, steady=False, newton=None, max_steps=500, min_step=1e-8):
    r"""Static (or steady) equilibrium of a scene under its loads.

    Parameters
    ----------
    scene : Scene
    t : float
        Time, s: prescribed coordinates, drivers and time-dependent loads take their values at t.
    q : array_like (n,), optional
        Start state (default: the scene's initial coordinates), brought onto the
        constraints first. The path from it to the equilibrium is followed by load stepping.
    steady : bool
        False (default): equilibrium at rest, every velocity zero. True: relative
        equilibrium under the scene's steady motion: prescribed coordinates move at their
        laws' rates and accelerations, the other coordinates at the smallest velocities the
        constraints demand (zero without rheonomic constraints), and the balance holds with
        the velocity-dependent forces of that motion (centrifugal forces of a constant spin).
    newton : NewtonSettings, optional
        Tolerances (``rtol`` of the force balance, ``ctol`` of the constraints) and the
        iteration cap of each corrector (default 15).
    max_steps : int
        Cap on continuation steps.
    min_step : float
        Smallest step of the load path (in units of the start's load factor and its linear
        response) before giving up.

    Returns
    -------
    EquilibriumState

    Raises
    ------
    ConvergenceError
        When the load path cannot be followed to the full load: the message names the
        load factor reached; ``exc.state`` holds the last equilibrium on the path.
    ValueError
        On bad arguments, redundant constraints, or a scene without a rest state (settling
        from a singular start does not come to rest, e.g. a body falling freely).

    Notes
    -----
    The homotopy H(x, s) = R(x) − (1 − s) R(x₀) with x = (q_free, λ) and R the balance and
    constraint residuals starts at the solution x₀ (λ₀ by least squares) and ends at the
    equilibrium. Its tangent (∂x/∂s, 1) from J ∂x/∂s = −R(x₀) is normalized in the
    scaled norm ‖Δq‖²/σ² + Δs² (σ = ‖∂q/∂s‖ at the start, the linear response to the
    full load), so a linear problem is solved in one step and stiff or large-rotation
    problems take as many steps as their curvature needs.

    A start where no stiffness meets the loads (a mechanism at rest in a position where the
    loads would turn it, e.g. a pendulum held horizontal) is a singular point of that path:
    the scene is then first settled under its full loads by pseudo-transient continuation
    (see ``_settle``), which descends to a stable rest state, and the path is finished from
    there.
    """
    settings = NewtonSettings(max_iterations=15) if newton is None else newton
    if not isinstance(settings, NewtonSettings):
        raise ValueError(f"newton must be NewtonSettings, got {settings!r}")
    t = float(t)
    if not math.isfinite(t):
        raise ValueError(f"t must be finite, got {t!r}")
    if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
        raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
    q0, _ = scene.initial_state()
    if q is not None:
        q_in = np.asarray(q, dtype=float).ravel()
        if q_in.size != scene.n or not np.all(np.isfinite(q_in)):
            raise ValueError(f"q must be a finite vector of {scene.n} coordinates, got {q!r}")
        q0 = q_in.copy()
    q0[scene.prescribed_index] = scene.prescribed_state(t)[0]
    q0, _ = consistent_initial_state(scene, q0, np.zeros(scene.n), t, max_correction=None)
    v = _steady_velocity(scene, q0, t) if steady else np.zeros(scene.n)
    a = np.zeros(scene.n)
    if steady:
        a[scene.prescribed_index] = scene.prescribed_state(t)[2]
    if not steady:
        try:
            return _continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
        except _SingularStart as exc:
            # no stiffness meets the loads at the start: either nothing ever will (a free-flying
            # body under loads: say so), or the scene has a rest state elsewhere (a pendulum held
            # horizontal): let it settle to rest under its loads first, then finish from there
            _check_held(scene, q0, v, a, t)
            q0 = _settle(scene, q0, t, settings, exc)
            return _continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
    for _ in range(4):                     # steady: the constraint velocities follow the solution
        try:
            state = _continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
        except _SingularStart:
            _check_held(scene, q0, v, a, t)
            raise
        if not steady or not scene.n_constraints:
            break
        v_new = _steady_velocity(scene, state.q, t)
        if _inf(v_new - v) <= 1e-12 * max(_inf(v), _TINY):
            break
        v, q0 = v_new, state.q
    if steady:
        _check_steady(scene, state)
    return state


def _settle(scene, q0, t, settings, why, max_steps=400):
    r"""Bring a scene from a singular start towards rest under its full loads (pseudo-transient continuation).

    Each step is one Newton step of the heavily damped motion
    (M_ff/τ²) Δq + R(q + Δq) + Φ_qᵀ λ = 0, Φ = 0, with the pseudo-time step τ grown as the
    residual falls (switched evolution relaxation, τ² ∝ 1/‖R‖), so that the iteration follows
    the loads downhill while the residual is large and turns into Newton's method near rest
    (Kelley & Keyes 1998). Descending, it finds a stable rest state, not an unstable one (the
    inverted pendulum). Returns the coordinates reached once the scaled residual is small
    enough for the load-path continuation to finish; raises ``ValueError`` (the original
    refusal ``why``) if it does not get there.
    """
    v = a = np.zeros(scene.n)
    sys_ = _Statics(scene, q0, v, a, t, settings)
    nf, free = sys_.nf, scene.free_index
    x = np.concatenate([q0[free], _initial_multipliers(scene, q0, v, a, t)])
    res, jac, sc = sys_.evaluate(x)
    mass = _sub(scene.mass_matrix(q0), free, free)
    m_diag = np.abs(mass.diagonal() if sps.issparse(mass) else np.diag(mass))
    # the first pseudo-step moves the most accelerated coordinate by a tenth of the scene's size
    acc = _inf(res[:nf] / np.maximum(m_diag, _TINY))
    tau2 = 0.1 * max(scene.length_scale, 1.0) / max(acc, _TINY)
    norm = float(np.linalg.norm(res))
    for _ in range(max_steps):
        err = sys_.error(res, sc)
        if err <= 1e3:                              # near rest: the continuation finishes in a step or two
            return sys_.full_q(x)
        damped = add_matrices(jac, _pad(mass / tau2, sys_.m))
        try:
            dx = -linear_solve(damped, res)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(dx)):
            break
        x = x + dx
        res, jac, sc = sys_.evaluate(x)
        new_norm = float(np.linalg.norm(res))
        if not math.isfinite(new_norm):
            break
        tau2 *= min(max(norm / max(new_norm, _TINY), 0.1), 100.0)
        norm = new_norm
    raise ValueError(f"{why}; settling under the loads from there did not come to rest within {max_steps} "
                     f"pseudo-time steps") from None


def _pad(mat, m):
    """``mat`` bordered with m zero rows and columns (the multipliers carry no inertia)."""
    if m == 0:
        return mat
    if sps.issparse(mat):
        return sps.block_diag([mat, sps.csr_matrix((m, m))], format="csr")
    out = np.zeros((mat.shape[0] + m, mat.shape[1] + m))
    out[:mat.shape[0], :mat.shape[1]] = mat
    return out


def _check_steady(scene, state):
    """ValueError unless the unknown coordinates stay at rest in the steady state (a relative equilibrium).

    The inertia force M_ff a_f the steady velocities demand must vanish: it may not exceed 10⁻⁶ of
    the largest force of the steady motion, nor a hundred times the imbalance the equilibrium
    solve accepted as zero. The second bound is the scene's own scale where the forces of the
    motion are tiny (a spin of 10⁻⁶ rad/s gives centrifugal forces 10¹² times smaller than the
    stiff internal forces whose round-off and start imbalance set the solve's tolerance); an
    absolute comparison with the forces of the motion alone took that round-off for an
    acceleration.
    """
    if not np.any(state.v):
        return
    try:
        acc = _consistent(scene, state.t, state.q, state.v)[0]
    except ValueError:                      # no inertia in some direction: nothing to check against
        return
    free = scene.free_index
    inertia = _sub(scene.mass_matrix(state.q), free, free) @ acc[free]
    scale = force_balance(scene, state.q, state.v, state.acc, state.t)[3]
    if _inf(inertia) > max(1e-6 * scale, 100.0 * state.residual_tolerance, _TINY):
        raise ValueError(f"scene {scene.name!r} has no steady state: with the velocities of its steady motion "
                         f"the unknown coordinates must accelerate (inertia force {_inf(inertia):.3g} against "
                         f"forces of {scale:.3g}); a relative equilibrium needs a steady motion along "
                         f"coordinates the equations do not depend on (a prescribed spin)")


def _continuation(scene, q0, v, a, t, settings, max_steps, min_step, steady):
    sys_ = _Statics(scene, q0, v, a, t, settings)
    nf, m = sys_.nf, sys_.m
    x0 = np.concatenate([q0[scene.free_index], _initial_multipliers(scene, q0, v, a, t)])
    r0, jac0, sc0 = sys_.evaluate(x0)
    name = "static equilibrium"

    def done(x, s, steps, its):
        # the force balance at x, for the prescribed coordinates' forces and the accepted imbalance
        _, _, (scale, floor, _) = sys_.evaluate(x)
        tolerance = settings.rtol * max(scale, _inf(r0[:nf])) + 16 * _EPS * floor
        q = sys_.full_q(x)
        lam = x[nf:]
        return _equilibrium_state(scene, t, q, v, a, lam, s, steps, its, steady, sys_.last_force, tolerance)

    if sys_.error(r0, sc0) <= 1.0:
        return done(x0, 1.0, 0, 0)
    try:
        dxds = -linear_solve(jac0, r0)
    except np.linalg.LinAlgError:
        raise _SingularStart(f"{name}: the start state of {scene.name!r} is a singular point of the load path (a "
                         f"coordinate without stiffness or a redundant constraint at the load-free start); "
                         f"start nearer the rest state (q=...)") from None
    if not np.all(np.isfinite(dxds)):
        raise ValueError(f"{name}: the tangent of the load path is not finite at the start of {scene.name!r}")
    # the linear response to the full load: a coordinate moving by more than a hundred sizes of
    # the scene (or turns) means no stiffness meets the load at the start
    reach = 100.0 * max(scene.length_scale, 2.0 * np.pi)
    if _inf(dxds[:nf]) > reach:
        raise _SingularStart(f"{name}: the start state of {scene.name!r} is (nearly) a singular point of the load "
                         f"path: the linear response to the loads moves a coordinate by {_inf(dxds[:nf]):.3g} "
                         f"(no stiffness meets the load there, e.g. a pendulum held horizontal); start nearer "
                         f"the rest state (q=...)")
    sigma = max(float(np.linalg.norm(dxds[:nf])), _TINY)
    weight = np.zeros(nf + m + 1)
    weight[:nf] = 1.0 / sigma ** 2
    weight[-1] = 1.0

    def unit(tau):
        return tau / math.sqrt(float(tau @ (weight * tau)))

    tau = unit(np.concatenate([dxds, [1.0]]))
    y = np.concatenate([x0, [0.0]])
    h = math.sqrt(2.0)               # a linear problem lands on s = 1 in one step
    h_max = 4.0 * h
    steps = its_total = 0

    def level(s):
        return lambda x: _homotopy(sys_, x, s, r0)

    while steps < max_steps:
        s = float(y[-1])
        y_pred = y + h * tau
        final = tau[-1] > 0 and y_pred[-1] >= 1.0 - 1e-12
        try:
            if final:                # land on the full load: Newton at s = 1 from the predictor there
                y_pred = y + ((1.0 - s) / tau[-1]) * tau
                x, _, its = newton_solve(level(1.0), y_pred[:-1], settings, name, "load factor 1")
                y_new = np.concatenate([x, [1.0]])
            else:
                y_new, its = _corrector(sys_, y_pred, tau, weight, r0, settings, name)
        except (ConvergenceError, np.linalg.LinAlgError):     # includes an element folding inside out
            y_new = None
        if y_new is not None:
            # accept a step only if Newton corrected the predictor by less than half the step:
            # a larger correction means the path curves more than the step resolves (or Newton
            # jumped to another branch)
            dist = math.sqrt(float((y_new - y_pred) @ (weight * (y_new - y_pred))))
            if dist > 0.5 * math.sqrt(float((y_pred - y) @ (weight * (y_pred - y)))):
                y_new = None
        if y_new is None:
            h *= 0.5
            if h < min_step:
                break
            continue
        steps += 1
        its_total += its
        if final:
            return done(y_new[:-1], 1.0, steps, its_total)
        res, jac, _ = _homotopy(sys_, y_new[:-1], float(y_new[-1]), r0)
        try:
            aug = _bordered_matrix(jac, r0, weight[:-1] * tau[:-1], weight[-1] * tau[-1])
            rhs = np.zeros(nf + m + 1)
            rhs[-1] = 1.0
            tau_new = linear_solve(aug, rhs)
        except np.linalg.LinAlgError:
            tau_new = y_new - y
        if not np.all(np.isfinite(tau_new)):
            tau_new = y_new - y
        tau, y = unit(tau_new), y_new
        if its <= 4:
            h = min(2.0 * h, h_max)
        elif its >= 10:
            h *= 0.5
    s = float(y[-1])
    why = (f"{max_steps} steps taken (max_steps)" if steps >= max_steps else
           f"the step size fell below {min_step:g}: the load path cannot be followed further, e.g. a limit "
           f"load, an element folding or a mechanism that moves freely")
    exc = ConvergenceError(f"{name} of {scene.name!r} failed: reached load factor {s:.9g} of 1 after {steps} "
                           f"steps ({why})",
                           load_factor=s, steps=steps)
    exc.state = done(y[:-1], s, steps, its_total)
    raise exc


def _homotopy(sys_, x, s, r0):
    res, jac, (scale, floor, c_scale) = sys_.evaluate(x)
    h = res - (1.0 - s) * r0
    # the start's imbalance is a force scale of the path too: an equilibrium without loads
    # (all forces → 0) is then found to rtol of the forces that were out of balance
    return h, jac, sys_.error(h, (max(scale, _inf(r0[:sys_.nf])), floor, c_scale))


def _corrector(sys_, y_pred, tau, weight, r0, settings, name):
    """Newton on H(x, s) = 0 and (y − y_pred)·W τ = 0."""
    wt = weight * tau

    def fun(y):
        h, jac, err = _homotopy(sys_, y[:-1], float(y[-1]), r0)
        row = float(wt @ (y - y_pred))
        return np.concatenate([h, [row]]), _bordered_matrix(jac, r0, wt[:-1], wt[-1]), err

    y, _, its = newton_solve(fun, y_pred, settings, name, f"load factor {y_pred[-1]:.4g}")
    return y, its


def _equilibrium_state(scene, t, q, v, a, lam, s, steps, its, steady, force, tolerance):
    pres = scene.prescribed_index
    return EquilibriumState(t=t, q=q, v=v.copy(), lam=np.array(lam, dtype=float), acc=a.copy(),
                            reactions=scene.constraint_reactions(q, lam), prescribed_force=force[pres].copy(),
                            load_factor=float(s), steps=steps, iterations=its, steady=bool(steady),
                            residual_tolerance=float(tolerance))


# ======================================================================= linearization
def null_space_basis(jacobian, rtol=1e-10):
    r"""A sparse basis N of the null space of a constraint Jacobian: Φ_q N = 0.

    The coordinates are split into m dependent ones (a well-conditioned m × m block Φ_D of
    Φ_q, chosen by a pivoted QR factorization of the columns that constraints touch) and
    n − m independent ones, and

    .. math::  N = P \begin{bmatrix} −Φ_D^{-1} Φ_I \\ I \end{bmatrix},

    so independent coordinates that no constraint touches keep unit columns and N has
    about as many entries as Φ_q plus n − m: it stays sparse for large meshes.

    Parameters
    ----------
    jacobian : matrix (m, n)
        Φ_q (dense or sparse), restricted to the unknown coordinates.
    rtol : float
        A pivot of the QR factorization below ``rtol`` times the largest counts as zero.

    Returns
    -------
    scipy.sparse.csr_matrix (n, n − m)

    Raises
    ------
    RedundantConstraintsError
        When Φ_q does not have full row rank.
    """
    m, n = jacobian.shape
    if m == 0:
        return sps.identity(n, format="csr")
    a = sps.csc_matrix(jacobian)
    a.eliminate_zeros()
    touched = np.flatnonzero(np.diff(a.indptr))
    sub = a[:, touched].toarray()
    norms = np.linalg.norm(sub, axis=1)
    if np.any(norms == 0.0):
        raise RedundantConstraintsError(f"a constraint equation has a zero Jacobian row (rows "
                                        f"{np.flatnonzero(norms == 0.0).tolist()})")
    _, r, piv = sla.qr(sub / norms[:, None], mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > rtol * diag[0])) if diag.size else 0
    if rank < m:
        raise RedundantConstraintsError(f"redundant constraints: the constraint Jacobian has rank {rank} for {m} "
                                        f"equations", rank=rank, n_equations=m)
    dep = np.sort(touched[piv[:m]])
    ind = np.setdiff1d(np.arange(n), dep)
    ind_touched = np.intersect1d(ind, touched)
    lu = spla.splu(sps.csc_matrix(a[:, dep]))
    x = -lu.solve(a[:, ind_touched].toarray()) if ind_touched.size else np.zeros((m, 0))
    col_of = np.full(n, -1)
    col_of[ind] = np.arange(ind.size)
    rows = [ind, np.repeat(dep, ind_touched.size)]
    cols = [col_of[ind], np.tile(col_of[ind_touched], m)]
    vals = [np.ones(ind.size), x.ravel()]
    basis = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n, n - m))
    basis.eliminate_zeros()
    return basis


@dataclass
class LinearSystem:
    r"""The linearized equations M z̈ + C ż + K z = 0 in independent coordinates z.

    Perturbations of the unknown coordinates are δq_free = N z; prescribed coordinates do
    not vary. Matrices are dense for small systems and sparse otherwise.

    Attributes
    ----------
    mass, damping, stiffness : matrix (n_z, n_z)
        Nᵀ M N, Nᵀ C N (gyroscopic and damping parts together; ``None`` when zero) and
        Nᵀ (K + ∂(Φ_qᵀλ)/∂q) N.
    basis : scipy.sparse matrix (n, n_z)
        Maps z to all coordinates (rows of prescribed coordinates are zero).
    t : float
    q, v, lam, acc : ndarray
        The reference state.
    """

    mass: object
    damping: object
    stiffness: object
    basis: object
    t: float
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    acc: np.ndarray

    @property
    def n(self):
        """Number of independent coordinates."""
        return self.basis.shape[1]

    @property
    def gyroscopic(self):
        """Skew part of the velocity matrix, (C − Cᵀ)/2 (None without velocity terms)."""
        if self.damping is None:
            return None
        return 0.5 * (self.damping - self.damping.T)


def _reduce(mat, basis, dense):
    out = basis.T @ (sps.csr_matrix(mat) if sps.issparse(mat) else mat) @ basis
    if dense:
        return _dense(out)
    return sps.csr_matrix(out)


def linearize(scene, q, v, t=0.0, lam=None, acc=None):
    r"""Linearize the equations of motion of a scene about the state (q, v, t).

    .. math::

        M δq̈ + C δq̇ + (K + ∂(Φ_qᵀλ)/∂q) δq = 0, \qquad Φ_q δq = 0,

    M = M(q), C = −∂(Q_v + Q)/∂v, K = ∂(M a)/∂q − ∂Q_v/∂q + ∇²V − ∂Q/∂q (see
    :func:`force_balance`): the tangent stiffness with the geometric terms of the current
    stresses, the centrifugal terms of the motion, and the constraint curvature λ·Φ_qq.
    The constraints are removed by δq_free = N z with N = :func:`null_space_basis` of
    Φ_q at q: exact for equilibria and for steady motions whose constraints do not involve
    the moving coordinates; about a general moving state it is the linearization with the
    constraint directions frozen at q.

    Parameters
    ----------
    scene : Scene
    q, v : array_like (n,)
        Reference state.
    t : float
        Time, s.
    lam : array_like, optional
        Multipliers of the state; default: those of the consistent accelerations
        (as a time integration would start from (q, v)).
    acc : array_like, optional
        Accelerations of the state (default: consistent with (q, v) and λ as above).

    Returns
    -------
    LinearSystem
    """
    q = np.asarray(q, dtype=float).ravel()
    v = np.asarray(v, dtype=float).ravel()
    for label, x in (("q", q), ("v", v)):
        if x.size != scene.n or not np.all(np.isfinite(x)):
            raise ValueError(f"{label} must be a finite vector of {scene.n} coordinates")
    t = float(t)
    if lam is None or acc is None:
        start = _Start(*_consistent(scene, t, q, v))
        lam = start.lam if lam is None else lam
        acc = start.acc if acc is None else acc
    lam = np.asarray(lam, dtype=float).ravel()
    acc = np.asarray(acc, dtype=float).ravel()
    if lam.size != scene.n_constraints:
        raise ValueError(f"lam must have {scene.n_constraints} entries, got {lam.size}")
    free = scene.free_index
    _, stiff, damp, _, _ = force_balance(scene, q, v, acc, t)
    m = scene.n_constraints
    if m:
        stiff = add_matrices(stiff, scene.constraint_hessian_product(q, lam, t))
        cqf = _sub(scene.constraint_jacobian(q, t), np.arange(m), free)
    else:
        cqf = np.zeros((0, free.size))
    basis_free = null_space_basis(cqf)
    rows = sps.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(scene.n, free.size))
    basis = (rows @ basis_free).tocsr()
    dense = basis.shape[1] <= DENSE_EIGEN_LIMIT
    mass = _reduce(_sub(scene.mass_matrix(q), free, free), basis_free, dense)
    stiffness = _reduce(_sub(stiff, free, free), basis_free, dense)
    damping = None
    if damp is not None:
        damping = _reduce(_sub(damp, free, free), basis_free, dense)
        if _inf(_dense(damping) if dense else damping.data) == 0.0:
            damping = None
    return LinearSystem(mass, damping, stiffness, basis, t, q.copy(), v.copy(), lam.copy(), acc.copy())


# ======================================================================= modes
@dataclass
class Modes:
    r"""Modes of a linearized scene, lowest first.

    Each mode is one eigenvalue s of M z̈ + C ż + K z = 0 (solutions z = φ e^{st}): one of
    each complex-conjugate pair (Im s > 0), every real one (a conservative unstable pair
    ±σ gives two modes), s = 0 once per rigid-body or mechanism motion.

    Attributes
    ----------
    eigenvalues : ndarray of complex
        s, 1/s, ordered by abs(s) (of a real pair ±σ the growing one first).
    shapes : ndarray (n, n_modes)
        Shapes on all coordinates (real for undamped conservative systems, complex
        otherwise), scaled to largest entry 1 (phase of that entry 0).
    reduced_shapes : ndarray (n_z, n_modes)
        The same in the independent coordinates z.
    system : LinearSystem
        The linearized system (matrices and reference state).
    scene_name : str
    about : str
        What the reference state is ("static", "steady", "initial" or "given").
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    reduced_shapes: np.ndarray
    system: LinearSystem
    scene_name: str = "scene"
    about: str = "given"

    @property
    def omega(self):
        """Angular frequencies Im s, rad/s (0 for real eigenvalues)."""
        return np.abs(self.eigenvalues.imag)

    @property
    def frequency_hz(self):
        """Frequencies Im s / 2π, Hz."""
        return self.omega / (2.0 * np.pi)

    @property
    def natural_omega(self):
        """Undamped natural angular frequencies abs(s), rad/s."""
        return np.abs(self.eigenvalues)

    @property
    def growth_rate(self):
        """Re s, 1/s (positive: the mode grows, the state is unstable)."""
        return self.eigenvalues.real.copy()

    @property
    def damping_ratio(self):
        """ζ = −Re s / abs(s) (0 for s = 0; −1 for a real growing mode)."""
        mag = np.abs(self.eigenvalues)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(mag > 0, -self.eigenvalues.real / np.where(mag > 0, mag, 1.0), 0.0) + 0.0

    @property
    def period(self):
        """2π/ω, s (inf for ω = 0)."""
        with np.errstate(divide="ignore"):
            return np.where(self.omega > 0, 2.0 * np.pi / np.where(self.omega > 0, self.omega, 1.0), np.inf)

    @property
    def stable(self):
        """True when no mode grows (Re s ≤ 0 for all computed modes, to round-off)."""
        return bool(np.all(self.growth_rate <= 1e-9 * max(1.0, float(np.max(self.natural_omega, initial=0.0)))))

    def table(self):
        """[{mode, omega_rad_s, frequency_hz, damping_ratio, growth_rate_1_s}] one dict per mode."""
        return [dict(mode=i + 1, omega_rad_s=float(w), frequency_hz=float(f), damping_ratio=float(z),
                     growth_rate_1_s=float(g))
                for i, (w, f, z, g) in enumerate(zip(self.omega, self.frequency_hz, self.damping_ratio,
                                                      self.growth_rate))]


def _zero_tolerance(k, m):
    """|s|² below this is round-off of a zero eigenvalue: 1e3 ε ‖K‖/‖M‖."""
    nk = float(abs(k).sum(axis=1).max()) if k.shape[0] else 0.0
    nm = float(abs(m).sum(axis=1).max()) if m.shape[0] else 1.0
    return 1e3 * _EPS * nk / max(nm, _TINY)


def _symmetric(k, tol=1e-10):
    d = k - k.T
    big = _inf(k.data if sps.issparse(k) else k)
    return _inf(d.data if sps.issparse(d) else d) <= tol * max(big, _TINY)


def _solve_symmetric(sysm, n_modes, zero_tol):
    """Eigenpairs of K φ = ω² M φ: eigenvalues s = √(−ω²) with shapes."""
    k, m = sysm.stiffness, sysm.mass
    n = sysm.n
    if sps.issparse(k) and n_modes < n - 1:
        trace = float(k.diagonal().sum()) / max(float(m.diagonal().sum()), _TINY)
        shift = -max(1e-6 * abs(trace), 1e3 * zero_tol, _TINY)
        lam, vec = spla.eigsh(sps.csc_matrix(k), k=min(n_modes + 2, n - 1), M=sps.csc_matrix(m), sigma=shift,
                              which="LM")
    else:
        try:
            lam, vec = sla.eigh(_dense(k), _dense(m), subset_by_index=[0, min(n_modes + 1, n - 1)])
        except np.linalg.LinAlgError:
            raise ValueError("the mass matrix of the independent coordinates is not positive definite: a "
                             "coordinate has no inertia (zero density or rotary inertia rhoI = 0?)") from None
    lam = np.where(np.abs(lam) <= zero_tol, 0.0, lam)
    s, shapes = [], []
    for li, phi in zip(lam, vec.T):
        if li >= 0:
            s.append(1j * math.sqrt(li))
            shapes.append(phi)
        else:                              # a conservative unstable pair ±σ, both modes of motion
            sig = math.sqrt(-li)
            s += [sig + 0j, -sig + 0j]
            shapes += [phi, phi]
    return np.array(s, dtype=complex), np.array(shapes).T


def _solve_first_order(sysm, n_modes, zero_tol):
    """Eigenpairs of the quadratic problem (s² M + s C + K) φ = 0 via the first-order form."""
    k, m, c = sysm.stiffness, sysm.mass, sysm.damping
    n = sysm.n
    if c is None:
        c = sps.csr_matrix((n, n)) if sps.issparse(k) else np.zeros((n, n))
    if sps.issparse(k) and 2 * n_modes + 4 < 2 * n - 1:
        eye = sps.identity(n, format="csr")
        a = sps.bmat([[None, eye], [-k, -c]], format="csc")
        b = sps.bmat([[eye, None], [None, m]], format="csc")
        trace = float(k.diagonal().sum()) / max(float(m.diagonal().sum()), _TINY)
        shift = -math.sqrt(max(1e-6 * abs(trace), 1e3 * zero_tol, _TINY))
        lam, vec = spla.eigs(a, k=min(2 * n_modes + 4, 2 * n - 2), M=b, sigma=shift, which="LM")
    else:
        kd, md, cd = _dense(k), _dense(m), _dense(c)
        eye, zero = np.eye(n), np.zeros((n, n))
        lam, vec = sla.eig(np.block([[zero, eye], [-kd, -cd]]), np.block([[eye, zero], [zero, md]]))
    ok = np.isfinite(lam)
    lam, vec = lam[ok], vec[:n, ok]
    mag = np.abs(lam)
    scale = max(float(mag.max(initial=0.0)), _TINY)
    lam = np.where(mag ** 2 <= zero_tol, 0.0, lam)
    real = np.abs(lam.imag) <= 1e-9 * np.maximum(np.abs(lam), 1e-12 * scale)
    lam = np.where(real, lam.real + 0j, lam)
    keep = real | (lam.imag > 0)
    zeros = np.flatnonzero(keep & (lam == 0))
    # s = 0 of a motion without stiffness is a double root of det(s²M + sC + K) with one shape:
    # the first-order form returns it twice, one mode is kept per pair
    keep[zeros[(zeros.size + 1) // 2:]] = False
    return lam[keep], vec[:, keep]


def _normalize(shapes, reduced):
    """Both scaled column by column so that the largest entry of ``shapes`` is 1 (real when they are)."""
    if shapes.size == 0:
        return shapes, reduced
    idx = np.argmax(np.abs(shapes), axis=0)
    piv = shapes[idx, np.arange(shapes.shape[1])]
    piv = np.where(np.abs(piv) > 0, piv, 1.0)
    out, red = shapes / piv, reduced / piv
    if np.iscomplexobj(out) and np.all(np.abs(out.imag) <= 1e-12 * np.maximum(np.abs(out).max(axis=0), _TINY)):
        out, red = out.real, red.real
    return out, red


def _reference(scene, about, t, newton):
    if isinstance(about, EquilibriumState):
        return about.q, about.v, about.t, about.lam, about.acc, "steady" if about.steady else "static"
    if isinstance(about, str):
        if about not in ABOUT:
            raise ValueError(f"about must be one of {', '.join(ABOUT)} or a state, got {about!r}")
        if about in ("static", "steady"):
            st = static_equilibrium(scene, t, steady=(about == "steady"), newton=newton)
            return st.q, st.v, st.t, st.lam, st.acc, about
        q, v = scene.initial_state()
        q, v = consistent_initial_state(scene, q, v, 0.0)
        return q, v, 0.0, None, None, "initial"
    if isinstance(about, tuple) and len(about) == 2:
        return np.asarray(about[0], float), np.asarray(about[1], float), t, None, None, "given"
    q, v = getattr(about, "q", None), getattr(about, "v", None)
    if q is None or v is None:
        raise ValueError(f"about must be one of {', '.join(ABOUT)}, an EquilibriumState, a (q, v) pair or an "
                         f"object with q and v, got {about!r}")
    return (np.asarray(q, float), np.asarray(v, float), float(getattr(about, "t", t)), getattr(about, "lam", None),
            getattr(about, "acc", None), "given")


def modes(scene, about="static", n_modes=6, t=0.0, solver="auto", newton=None):
    r"""Lowest modes of a scene linearized about a state.

    Parameters
    ----------
    scene : Scene
    about : {"static", "steady", "initial"}, EquilibriumState, (q, v) or an object with q, v
        ``"static"``: the equilibrium at rest (:func:`static_equilibrium`); ``"steady"``:
        the relative equilibrium under the scene's prescribed steady motion (e.g. a
        constant spin; frequencies are then those seen in the moving frame);
        ``"initial"``: the scene's initial state (frozen linearization of a moving state).
    n_modes : int
        How many modes (lowest abs(s) first); fewer when the system has fewer.
    t : float
        Time of the static/steady state, s.
    solver : {"auto", "symmetric", "first-order"}
        ``"auto"``: the real symmetric generalized problem K φ = ω² M φ when there are no
        velocity terms and K is symmetric, otherwise the quadratic problem through its
        first-order form. Dense LAPACK up to :data:`DENSE_EIGEN_LIMIT` independent
        coordinates, else scipy's ARPACK in shift-invert mode near zero.
    newton : NewtonSettings, optional
        For the static/steady solve.

    Returns
    -------
    Modes
        Zero modes (a free body's rigid motions, a mechanism's free motion) come out as
        s = 0, not as an error.
    """
    if isinstance(n_modes, bool) or int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
    if solver not in ("auto", "symmetric", "first-order"):
        raise ValueError(f"solver must be 'auto', 'symmetric' or 'first-order', got {solver!r}")
    q, v, t_ref, lam, acc, label = _reference(scene, about, float(t), newton)
    sysm = linearize(scene, q, v, t_ref, lam=lam, acc=acc)
    n_modes = int(n_modes)
    if sysm.n == 0:
        empty = np.zeros(0, dtype=complex)
        return Modes(empty, np.zeros((scene.n, 0)), np.zeros((0, 0)), sysm, scene.name, label)
    zero_tol = _zero_tolerance(sysm.stiffness, sysm.mass)
    symmetric = sysm.damping is None and _symmetric(sysm.stiffness)
    if solver == "symmetric" and not symmetric:
        raise ValueError("solver='symmetric' needs a system without velocity terms and with a symmetric "
                         "stiffness matrix; use 'first-order' or 'auto'")
    if solver == "symmetric" or (solver == "auto" and symmetric):
        s, z = _solve_symmetric(sysm, n_modes, zero_tol)
    else:
        s, z = _solve_first_order(sysm, n_modes, zero_tol)
    mag = np.abs(s)
    # by |s|; of a pair ±σ (equal |s| to round-off) the growing mode first
    order = np.lexsort((-s.real, np.round(mag / max(float(mag.max(initial=0.0)), _TINY), 10)))[:n_modes]
    s, z = s[order], z[:, order]
    shapes, z = _normalize(sysm.basis @ z, z)
    return Modes(s, shapes, z, sysm, scene.name, label)


# ======================================================================= output
def write_mode_series(scene, result, directory, frames=24, amplitude=0.1, prefix=None):
    """Write every mode as a VTK series that animates it (one ``.pvd`` per mode).

    Frame j of mode k shows q* + a Re(φ_k e^{iψ_j}), ψ_j = 2π j/frames; the series' time is
    the phase ψ/2π (one cycle from 0 to 1). ``a`` makes the largest displacement of the
    output geometry ``amplitude`` times the scene's size (``Scene.length_scale``).

    Returns
    -------
    list of Path
        The ``.pvd`` file of each mode.
    """
    from .io.output import VTKSeries

    if isinstance(frames, bool) or int(frames) != frames or frames < 2:
        raise ValueError(f"frames must be an integer >= 2, got {frames!r}")
    amplitude = float(amplitude)
    if not math.isfinite(amplitude) or amplitude <= 0:
        raise ValueError(f"amplitude must be finite and positive, got {amplitude!r}")
    prefix = prefix or scene.name
    q0, v0 = result.system.q, result.system.v
    size = scene.length_scale
    paths = []
    for k in range(result.shapes.shape[1]):
        phi = result.shapes[:, k].astype(complex)
        a = amplitude * size / max(_geometry_gain(scene, q0, v0, phi.real) if np.any(phi.real) else 0.0,
                                   _geometry_gain(scene, q0, v0, phi.imag) if np.any(phi.imag) else 0.0,
                                   _TINY)
        if not math.isfinite(a):
            a = amplitude
        sink = VTKSeries(directory, f"{prefix}_mode{k + 1:02d}")
        w = float(result.omega[k])
        for j in range(int(frames) + 1):
            psi = 2.0 * np.pi * j / int(frames)
            rot = np.exp(1j * psi)
            sink.write(scene, j / int(frames), q0 + a * (phi * rot).real, v0 + a * w * (1j * phi * rot).real)
        sink.close()
        paths.append(sink.pvd_path)
    return paths


def _geometry_gain(scene, q, v, direction):
    """max |Δx| of the output points per unit step along ``direction`` (finite difference)."""
    eps = 1e-6 * scene.length_scale / max(_inf(direction), _TINY)

    def points(qq):
        return np.vstack([np.asarray(b.geometry(qq[scene.slice(b)], v[scene.slice(b)]).points, float)[:, :2]
                          for b in scene.bodies])
    try:
        d = points(q + eps * direction) - points(q)
    except (ValueError, NotImplementedError):
        return 0.0
    return float(np.abs(d).max()) / eps


# ======================================================================= Campbell
@dataclass
class CampbellDiagram:
    """Modes of a scene against one parameter.

    Attributes
    ----------
    parameter : str
    values : ndarray (p,)
    omega : ndarray (p, n_modes)
        Frequencies Im s, rad/s, lowest first at every value (NaN where fewer modes).
    damping_ratio, growth_rate : ndarray (p, n_modes)
    about : str
    scene_name : str
    unit : str
        Unit of the parameter (from the catalogue, when known).
    """

    parameter: str
    values: np.ndarray
    omega: np.ndarray
    damping_ratio: np.ndarray
    growth_rate: np.ndarray
    about: str = "steady"
    scene_name: str = "scene"
    unit: str = ""

    @property
    def frequency_hz(self):
        """Frequencies in Hz."""
        return self.omega / (2.0 * np.pi)

    def rows(self):
        """One dict per (value, mode): parameter value, mode, omega, Hz, damping ratio, growth rate."""
        out = []
        for i, val in enumerate(self.values):
            for k in range(self.omega.shape[1]):
                if np.isfinite(self.omega[i, k]):
                    out.append({self.parameter: float(val), "mode": k + 1, "omega_rad_s": float(self.omega[i, k]),
                                "frequency_hz": float(self.frequency_hz[i, k]),
                                "damping_ratio": float(self.damping_ratio[i, k]),
                                "growth_rate_1_s": float(self.growth_rate[i, k])})
        return out

    def write_table(self, stem):
        """Write ``STEM.csv`` and ``STEM.md`` (frequencies in Hz, one column per mode); returns both paths."""
        stem = Path(stem)
        stem.parent.mkdir(parents=True, exist_ok=True)
        nm = self.omega.shape[1]
        head = [self.parameter] + [f"f{k + 1}_hz" for k in range(nm)] + [f"zeta{k + 1}" for k in range(nm)]
        lines = [",".join(head)]
        md = ["| " + " | ".join([f"{self.parameter} ({self.unit})" if self.unit else self.parameter]
                                 + [f"f{k + 1} (Hz)" for k in range(nm)]) + " |",
              "|" + "---|" * (nm + 1)]
        for i, val in enumerate(self.values):
            f = self.frequency_hz[i]
            lines.append(",".join([repr(float(val))] + [repr(float(x)) for x in f]
                                  + [repr(float(x)) for x in self.damping_ratio[i]]))
            md.append("| " + " | ".join([f"{val:.6g}"] + [f"{x:.6g}" for x in f]) + " |")
        csv_path, md_path = stem.with_suffix(".csv"), stem.with_suffix(".md")
        csv_path.write_text("\n".join(lines) + "\n")
        md_path.write_text("\n".join(md) + "\n")
        return csv_path, md_path

    def plot(self, path=None, orders=None):
        """Frequencies against the parameter (:func:`skfem_flex.io.plots.plot_campbell`)."""
        from .io.plots import plot_campbell

        return plot_campbell(self, path, orders)


def campbell(build, parameter, values, n_modes=6, about="steady", t=0.0, **fixed):
    """Frequencies of a scene against one parameter, each point linearized about its own state.

    Parameters
    ----------
    build : str or callable
        A catalogue scene name or a factory ``build(**params) -> Scene``.
    parameter : str
        The factory's keyword varied (e.g. ``"omega"``).
    values : sequence of float
    n_modes : int
    about : {"steady", "static", "initial"}
    t : float
    **fixed
        Other keywords of the factory.

    Returns
    -------
    CampbellDiagram
        Modes are sorted by frequency at every value (not tracked by shape).

    Raises
    ------
    ValueError
        For an unknown scene or a parameter the factory does not take.
    """
    from . import scenes

    unit = ""
    if isinstance(build, str):
        name = build
        factory = scenes.get(build)
        unit = getattr(factory, "units", {}).get(parameter, "")
    elif callable(build):
        factory, name = build, getattr(build, "__name__", "scene")
    else:
        raise ValueError(f"build must be a catalogue scene name or a callable, got {build!r}")
    params = inspect.signature(factory).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    for key in [parameter, *fixed]:
        if key not in params and not takes_any:
            raise ValueError(f"scene {name!r} has no parameter {key!r}; it has: {', '.join(params) or 'none'}")
    values = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"values must be a non-empty list of finite numbers, got {values!r}")
    n_modes = int(n_modes)
    om = np.full((values.size, n_modes), np.nan)
    zeta, grow = om.copy(), om.copy()
    for i, val in enumerate(values):
        res = modes(factory(**{**fixed, parameter: float(val)}), about=about, n_modes=n_modes, t=t)
        k = res.eigenvalues.size
        om[i, :k], zeta[i, :k], grow[i, :k] = res.omega, res.damping_ratio, res.growth_rate
    label = about if isinstance(about, str) else "given"
    return CampbellDiagram(parameter, values, om, zeta, grow, label, name, unit)


class _Start:
    """(acc, lam, prescribed_force) of a consistent start as attributes."""

    def __init__(self, acc, lam, prescribed_force):
        self.acc, self.lam, self.prescribed_force = acc, lam, prescribed_force


def _consistent(scene, t, q, v):
    """(q̈, λ, prescribed forces) consistent with (q, v) at time t, from the compiled step's start."""
    from .schemes.stepper import Stepper
    from .schemes import EnergyMomentum
    return Stepper(scene, EnergyMomentum()).start(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
