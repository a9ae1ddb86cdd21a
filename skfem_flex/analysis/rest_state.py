"""Whether a scene can be at rest at all, so that a refusal says why rather than failing to converge.

:func:`check_held`: something (a support, a prescribed coordinate, a stiffness to the ground) must
hold the scene against the resultant of its loads, or it accelerates whatever its configuration
(a free-flying body under loads, a body falling freely). :func:`check_steady`: in a steady motion the
unknown coordinates must not have to accelerate (a relative equilibrium).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConvergenceError
from ..numerics.linear_solver import linear_solve
from .balance import force_balance
from .matrix_tools import TINY, abs_entries, inf_norm, submatrix
from .start import consistent_start

__all__ = ["check_held", "check_steady"]


def _translation_fields(scene, q):
    """W (dim, n) with rows the generalized rigid translations t_x, t_y (, t_z) of the whole scene, or None.

    For bodies whose linear momentum is p = G v with M t = Gᵀ (every body of the package: a
    rigid translation moves every mass element by the same vector), W = G M⁻¹, and W f is the
    resultant (N) of a generalized force f. None when a body gives no momentum or M is singular.
    """
    g = np.zeros((getattr(scene, "dimension", 2), scene.n))
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


def check_held(scene, q, v, a, t):
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
    cols = [(stiff.T @ w.T).T, (abs_entries(stiff).T @ absw.T).T]
    if scene.n_constraints:
        cq = scene.constraint_jacobian(q, t)
        cols += [(cq @ w.T).T, (abs_entries(cq) @ absw.T).T]
    pres = scene.prescribed_index
    cols += [w[:, pres], absw[:, pres]]
    held = np.hstack(cols[0::2])
    size = np.linalg.norm(np.hstack(cols[1::2]), axis=0)
    norm = np.linalg.norm(held, axis=0)
    keep = norm > 1e-8 * np.maximum(size, TINY)       # forces a support exerts on a rigid translation
    dim = w.shape[0]
    free = np.eye(dim)
    if np.any(keep):
        u, sv, _ = np.linalg.svd(held[:, keep] / norm[keep], full_matrices=True)
        free = np.hstack([u[:, :sv.size][:, sv <= 1e-6 * sv[0]], u[:, sv.size:]])
    size = max(float(np.linalg.norm(absw @ np.abs(force))), TINY)
    free = free[:, [_translates_freely(scene, q, v, a, t, w, force, d, size) for d in free.T]]
    if free.shape[1] == 0:
        return
    resultant = -(w @ force) + 0.0                    # + 0.0: no "-0" in the message
    along = free.T @ resultant
    if np.linalg.norm(along) <= 1e-8 * size:
        return
    what = ("in any direction" if free.shape[1] == dim else
            "along (" + ", ".join(f"{x:.3g}" for x in free[:, 0]) + ")")
    raise ValueError(f"scene {scene.name!r} has no rest state: nothing holds it {what} (no support, prescribed "
                     f"coordinate or stiffness to the ground), and its loads at t = {t:g} s have a resultant "
                     f"force (" + ", ".join(f"{x:.4g}" for x in resultant) + ") N, so it accelerates (a free-flying body "
                     "under loads, or a body falling freely); linearize it about its initial state "
                     "(about='initial') or about a state of a run instead")


def _translates_freely(scene, q, v, a, t, w, force, d, size):
    """True if a finite rigid translation along d changes neither Φ nor the loads' resultant along d.

    The first-order test of :func:`check_held` is local: a pendulum held horizontal has a rod whose
    Jacobian is blind to a vertical translation (Φ changes by ½δ² only), yet the rod holds it. A
    translation by a tenth of the scene's size tells supports that act at some distance from
    ones that never act (joints between bodies, internal forces: translation invariant exactly).
    """
    td = d @ w
    delta = 0.1 * scene.length_scale
    q1 = q + delta * td
    if scene.n_constraints:
        dphi = scene.constraint_value(q1, t) - scene.constraint_value(q, t)
        reach = inf_norm(abs_entries(scene.constraint_jacobian(q, t)) @ np.abs(td)) + inf_norm(td) * scene.length_scale
        if inf_norm(dphi) > 1e-8 * delta * max(reach, TINY):
            return False
    try:
        force1 = force_balance(scene, q1, v, a, t)[0]
    except (ValueError, ConvergenceError):     # a body that cannot be moved there is held somehow
        return False
    return abs(float(d @ (w @ (force1 - force)))) <= 1e-8 * size


def check_steady(scene, state):
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
        acc = consistent_start(scene, state.t, state.q, state.v)[0]
    except ValueError:                      # no inertia in some direction: nothing to check against
        return
    free = scene.free_index
    inertia = submatrix(scene.mass_matrix(state.q), free, free) @ acc[free]
    scale = force_balance(scene, state.q, state.v, state.acc, state.t)[3]
    if inf_norm(inertia) > max(1e-6 * scale, 100.0 * state.residual_tolerance, TINY):
        raise ValueError(f"scene {scene.name!r} has no steady state: with the velocities of its steady motion "
                         f"the unknown coordinates must accelerate (inertia force {inf_norm(inertia):.3g} against "
                         f"forces of {scale:.3g}); a relative equilibrium needs a steady motion along "
                         f"coordinates the equations do not depend on (a prescribed spin)")
