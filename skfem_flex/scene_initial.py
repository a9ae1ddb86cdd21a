r"""Consistent initial conditions and redundant-constraint detection.

Before a run, the initial state must satisfy the constraints at position
and velocity level,

.. math::  Φ(q_0, 0) = 0, \qquad Φ_q(q_0, 0)\, v_0 = −Φ_t(q_0, 0),

and the constraint Jacobian must have full row rank (otherwise the
multipliers are not unique and the bordered Newton matrix is singular).

:func:`find_redundant` reads the rank of Φ_q (restricted to the free
coordinates; rows scaled to unit length) from its singular values and names
the joints whose equations are linearly dependent (those with weight in the
left null space). :func:`consistent_initial_state` projects q0 by
minimum-norm Gauss–Newton, Δq = −Φ_q⁺ Φ (the smallest change of the free
coordinates that satisfies Φ = 0), then v0 by the minimum-norm correction
Δv = −Φ_q⁺ (Φ_q v0 + Φ_t); prescribed coordinates and their rates are kept.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .bodies.base import to_dense

#: above this many entries (rows × free coordinates) the constraint Jacobian is kept sparse: the rank test
#: and the projections solve the bordered system [[I, Φ_qᵀ], [Φ_q, 0]] by sparse LU (a chain of 400 spatial
#: bodies: 0.3 s instead of 50 s of dense SVD and least squares)
SPARSE_START = 10 ** 6


def _bordered_lu(cq):
    """Sparse LU of [[I, Aᵀ], [A, 0]] for A = ``cq`` (m, n), or None when it is (numerically) singular."""
    m, n = cq.shape
    k = sps.bmat([[sps.identity(n, format="csr"), cq.T], [cq, None]], format="csc")
    try:
        lu = spla.splu(k)
    except RuntimeError:                    # exactly singular
        return None
    piv = np.abs(lu.U.diagonal())
    return lu if piv.min(initial=np.inf) > 1e-8 * piv.max(initial=0.0) else None


def _min_norm(cq, rhs):
    """The minimum-norm x with cq x = rhs (cq of full row rank: the rank test came first)."""
    if not sps.issparse(cq):
        return np.linalg.lstsq(cq, rhs, rcond=None)[0]
    lu = _bordered_lu(cq)
    if lu is None:
        return np.linalg.lstsq(cq.toarray(), rhs, rcond=None)[0]
    n = cq.shape[1]
    return lu.solve(np.concatenate([np.zeros(n), rhs]))[:n]


def _jacobian(scene, q, t):
    """Φ_q: dense, or sparse CSR above :data:`SPARSE_START` entries."""
    cq = scene.constraint_jacobian(q, t)
    if scene.n_constraints * scene.free_index.size > SPARSE_START:
        return sps.csr_matrix(cq)
    return to_dense(cq)

__all__ = ["drop_redundant_constraints", "RedundantConstraintsError", "InconsistentInitialConditionsError", "constraint_rows",
           "find_redundant", "consistent_initial_state"]


class RedundantConstraintsError(ValueError):
    """Φ_q has dependent rows at the start. ``names`` lists the joints involved."""

    def __init__(self, message, names=(), rank=None, n_equations=None):
        super().__init__(message)
        self.names, self.rank, self.n_equations = tuple(names), rank, n_equations


class InconsistentInitialConditionsError(ValueError):
    """The initial state cannot be brought onto Φ = 0 (or only by a large change). ``names`` lists the joints."""

    def __init__(self, message, names=()):
        super().__init__(message)
        self.names = tuple(names)


def constraint_rows(scene):
    """[(constraint name, row indices)] in the order of the scene's multipliers."""
    out, row = [], 0
    for c in scene.constraints:
        out.append((c.name, np.arange(row, row + c.n_equations)))
        row += c.n_equations
    return out


def _names_of_rows(scene, mask):
    names = []
    for name, rows in constraint_rows(scene):
        if np.any(mask[rows]) and name not in names:
            names.append(name)
    return names


def find_redundant(scene, q, t=0.0, rtol=1e-9):
    """Dependent constraint equations at q.

    Parameters
    ----------
    scene : Scene
    q : ndarray
        Global coordinates.
    t : float
        Time, s.
    rtol : float
        A singular value below ``rtol`` times the largest counts as zero.

    Returns
    -------
    rank : int
        Rank of Φ_q restricted to the free coordinates.
    names : list of str
        Names of the constraints with equations in the left null space
        (empty when Φ_q has full row rank).
    """
    m = scene.n_constraints
    if m == 0:
        return 0, []
    cq = _jacobian(scene, q, t)[:, scene.free_index]
    if sps.issparse(cq):
        norms = np.sqrt(np.asarray(cq.multiply(cq).sum(axis=1)).ravel())
        if np.all(np.isfinite(norms)) and np.all(norms > 0.0):
            if _bordered_lu(sps.diags(1.0 / norms) @ cq) is not None:
                return m, []                # full row rank: the sparse factorization has no small pivot
        cq = cq.toarray()                   # possibly deficient: the SVD names the joints
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.linalg.norm(cq, axis=1)
    if not np.all(np.isfinite(norms)):
        big = float(np.max(np.abs(cq))) if np.all(np.isfinite(cq)) else np.inf
        raise ValueError(f"the constraint Jacobian at t = {t:g} s overflows double precision (entries up to "
                         f"{big:.3g}): give the scene's lengths and positions in SI units of a physical size")
    empty = norms == 0.0
    scaled = cq / np.where(empty, 1.0, norms)[:, None]
    if cq.shape[1] == 0:
        return 0, _names_of_rows(scene, np.ones(m, dtype=bool))
    # the left null space needs all m columns of U, never the n × n V (n may be 10⁵ coordinates)
    u, sv, _ = np.linalg.svd(scaled, full_matrices=m > cq.shape[1])
    smax = sv[0] if sv.size else 0.0
    rank = int(np.sum(sv > rtol * max(smax, 1e-300)))
    if rank == m:
        return rank, []
    null = u[:, rank:]
    weight = np.sqrt(np.sum(null ** 2, axis=1))
    involved = (weight > 1e-6) | empty
    return rank, _names_of_rows(scene, involved)


def _check_rank(scene, q, t, rtol):
    rank, names = find_redundant(scene, q, t, rtol)
    if names:
        m = scene.n_constraints
        raise RedundantConstraintsError(
            f"redundant constraints: the constraint Jacobian has rank {rank} for {m} equations at t = {t:g} s "
            f"({m - rank} dependent equation(s)) among the joints {', '.join(repr(n) for n in names)}; remove "
            f"or replace the duplicated conditions (or move away from a singular configuration)",
            names, rank, m)


def _scale(scene, q, t):
    cq = _jacobian(scene, q, t)
    return np.maximum(np.asarray(abs(cq) @ np.abs(q)).ravel(), 1e-12), cq


def consistent_initial_state(scene, q, v, t=0.0, project=True, tol=1e-12, max_iterations=50,
                             max_correction=1e-2, rank_rtol=1e-9):
    """Bring (q, v) onto the constraints, or check them; detect redundant joints.

    Parameters
    ----------
    scene : Scene
    q, v : ndarray
        Initial coordinates and velocities (global vectors); prescribed
        entries already set by their laws.
    t : float
        Initial time, s.
    project : bool
        True (default): project q onto Φ = 0 by minimum-norm Gauss–Newton
        and v onto Φ_q v = −Φ_t by a minimum-norm correction, changing only
        the free coordinates. False: only check, raising on a violation
        larger than 1e-8 of the constraint's scale.
    tol : float
        Position projection ends when abs(Φ_i) ≤ tol · (abs(Φ_q) abs(q))_i for every row.
    max_iterations : int
        Gauss–Newton iterations before giving up.
    max_correction : float or None
        Largest accepted change of any coordinate, relative to the larger of
        max|q| and the scene's ``length_scale`` (default 1 %). A larger correction means the given q0 is not what
        the user meant, and raises; ``None`` accepts any correction.
    rank_rtol : float
        Relative singular-value threshold of the rank test.

    Returns
    -------
    q, v : ndarray
        Consistent copies.

    Raises
    ------
    RedundantConstraintsError
        (a ``ValueError``) when Φ_q does not have full row rank; the message
        names the joints involved.
    InconsistentInitialConditionsError
        (a ``ValueError``) when Φ = 0 cannot be reached from q (the
        mechanism cannot be assembled) or only by more than ``max_correction``.
    """
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    if not np.all(np.isfinite(q)) or not np.all(np.isfinite(v)):
        raise ValueError("initial state is not finite (NaN or inf in q0 or v0)")
    m = scene.n_constraints
    if m == 0:
        return q, v
    _check_rank(scene, q, t, rank_rtol)
    free = scene.free_index
    rows = constraint_rows(scene)

    if not project:
        _check_only(scene, q, v, t, rows)
        return q, v

    q_start = q.copy()
    phi = scene.constraint_value(q, t)
    qsize = max(float(np.max(np.abs(q[free]))) if free.size else 0.0, 1e-3)
    for it in range(max_iterations):
        scale, cq = _scale(scene, q, t)
        if np.all(np.abs(phi) <= tol * scale):
            break
        step = _min_norm(cq[:, free], -phi)
        if not np.all(np.isfinite(step)) or np.max(np.abs(step)) <= 4 * np.finfo(float).eps * qsize:
            break
        # damped Gauss–Newton: halve the step while ‖Φ‖ grows
        norm0 = float(np.linalg.norm(phi / scale))
        for _ in range(30):
            q_try = q.copy()
            q_try[free] += step
            phi_try = scene.constraint_value(q_try, t)
            if np.all(np.isfinite(phi_try)) and np.linalg.norm(phi_try / scale) < norm0:
                break
            step *= 0.5
        else:
            break
        q, phi = q_try, phi_try
    scale, cq = _scale(scene, q, t)
    ratio = np.abs(phi) / np.maximum(scale, 1.0e-3)
    accept = 1e-8
    if not np.all(ratio <= accept):
        bad = ratio > accept
        names = _names_of_rows(scene, bad)
        worst = {name: float(np.max(np.abs(phi[r]))) for name, r in rows if np.any(bad[r])}
        detail = ", ".join(f"{k!r} (|Φ| = {val:.3g})" for k, val in worst.items())
        raise InconsistentInitialConditionsError(
            f"inconsistent initial conditions: the constraints cannot be satisfied near the given q0 — "
            f"the Gauss–Newton projection stalled with {detail}; the mechanism cannot be assembled from this "
            f"configuration (check lengths, anchors and the initial coordinates)", names)
    dq = q - q_start
    size = max(float(np.max(np.abs(q_start))) if q_start.size else 0.0, float(getattr(scene, "length_scale", 0.0)),
               1e-12)
    if max_correction is not None and np.max(np.abs(dq)) > max_correction * size:
        phi0 = scene.constraint_value(q_start, t)
        bad = np.abs(phi0) > 1e-8 * _scale(scene, q_start, t)[0]
        names = _names_of_rows(scene, bad)
        raise InconsistentInitialConditionsError(
            f"inconsistent initial conditions: satisfying the constraints {', '.join(repr(n) for n in names)} "
            f"would move the coordinates by up to {np.max(np.abs(dq)):.3g} (more than max_correction = "
            f"{max_correction:g} of the configuration's size {size:.3g}); fix q0, or pass a larger "
            f"max_correction to accept the projection", names)

    # velocities: minimum-norm correction of the free rates
    vel = cq @ v + scene.constraint_time_derivative(q, t)
    if np.any(vel != 0.0):
        dv = _min_norm(cq[:, free], -vel)
        v[free] += dv
    return q, v


def _check_only(scene, q, v, t, rows, tol=1e-8):
    phi = scene.constraint_value(q, t)
    cq = to_dense(scene.constraint_jacobian(q, t))
    vel = cq @ v + scene.constraint_time_derivative(q, t)
    acq = np.abs(cq)
    pos_scale = np.maximum(acq @ np.abs(q), 1.0)
    vel_scale = np.maximum(acq @ np.abs(v), 1.0)
    for name, r in rows:
        if np.any(np.abs(phi[r]) > tol * pos_scale[r]):
            raise InconsistentInitialConditionsError(
                f"inconsistent initial conditions: constraint {name!r} has |Φ| = {np.max(np.abs(phi[r])):.3g} "
                f"at t = {t:g} s (simulate with project=True to project q0 onto the constraints)", [name])
        if np.any(np.abs(vel[r]) > tol * vel_scale[r]):
            raise InconsistentInitialConditionsError(
                f"inconsistent initial velocities: constraint {name!r} has |Φ_q v + Φ_t| = "
                f"{np.max(np.abs(vel[r])):.3g} at t = {t:g} s (simulate with project=True to project v0)", [name])


def drop_redundant_constraints(scene, q=None, t=0.0, rtol=1e-9):
    """The scene without its redundant constraint equations, and what was dropped (said once, as a warning).

    A mechanism whose joints are dependent everywhere along its motion (Bricard's six-hinge loop: 60
    equations of rank 59 in director coordinates) has undetermined multipliers and a singular Newton
    matrix. Its motion is fixed by any maximal independent subset of the equations: the others then hold by
    themselves. The rows are taken in the scene's order (the bodies' rigidity first, then the joints as
    given) and a row is kept when it is independent of those kept before it (scaled to unit length, a
    residual above ``rtol``), so the last dependent rows go: the closing joint loses an equation. Only
    equations of :class:`~skfem_flex.elements.constraints.quadratic.QuadraticConstraint` (the spatial joints)
    can be dropped.

    Parameters
    ----------
    scene : Scene
    q : ndarray, optional
        Where to test (default the initial state).
    t : float
        Time, s.
    rtol : float

    Returns
    -------
    Scene, list of (str, int)
        The same scene when nothing is redundant; else a new one, and (constraint name, equation index)
        of each dropped equation.

    Raises
    ------
    RedundantConstraintsError
        When a dependent equation belongs to a constraint that cannot drop rows.
    """
    import warnings

    from .elements.constraints.quadratic import QuadraticConstraint, Rigidity
    from .scene import Scene

    q = scene.initial_state()[0] if q is None else np.asarray(q, dtype=float)
    rank, names = find_redundant(scene, q, t, rtol)
    if not names:
        return scene, []
    cq = to_dense(scene.constraint_jacobian(q, t))[:, scene.free_index]
    basis, drop = [], np.zeros(scene.n_constraints, dtype=bool)
    for i, row in enumerate(cq):
        nrm = float(np.linalg.norm(row))
        r = row / nrm if nrm > 0.0 else row
        for b in basis:
            r = r - (b @ r) * b
        res = float(np.linalg.norm(r))
        if res > rtol ** 0.5:
            basis.append(r / res)
        else:
            drop[i] = True
    dropped, constraints = [], []
    for c, (name, rows) in zip(scene.constraints, constraint_rows(scene)):
        gone = np.flatnonzero(drop[rows])
        if gone.size and (not isinstance(c, QuadraticConstraint) or isinstance(c, Rigidity)):
            raise RedundantConstraintsError(
                f"redundant constraints: equation(s) {gone.tolist()} of {name!r} depend on the others, and "
                f"only spatial joints can drop equations; remove or replace the duplicated conditions", [name],
                rank, scene.n_constraints)
        dropped += [(name, int(k)) for k in gone]
        if not isinstance(c, Rigidity):
            constraints.append(c.without_equations(gone) if gone.size else c)
    warnings.warn(f"scene {scene.name!r}: {len(dropped)} redundant constraint equation(s) dropped ("
                  + ", ".join(f"equation {k} of {n!r}" for n, k in dropped)
                  + f"); the constraint Jacobian has rank {rank} for {scene.n_constraints} equations, and the "
                  "motion is fixed by the others", stacklevel=2)
    new = Scene(scene.bodies, constraints, scene.forces, scene.prescribed, scene.probes, scene.name,
                dict(scene.parameters))
    return new, dropped
