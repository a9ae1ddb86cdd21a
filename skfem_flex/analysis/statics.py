r"""The static (or steady) equilibrium of a scene: :func:`static_equilibrium`.

The start state is brought onto the constraints, the load path is followed from it
(:mod:`skfem_flex.analysis.load_path`), a singular start is settled first, and a scene that cannot be
at rest is refused with the reason (:mod:`skfem_flex.analysis.rest_state`).
"""
from __future__ import annotations

import math

import numpy as np

from ..numerics.newton import NewtonSettings
from ..scene_initial import consistent_initial_state
from .load_path import SingularStart, continuation, load_stepping, settle
from .matrix_tools import TINY, as_dense, inf_norm
from .rest_state import check_held, check_steady

__all__ = ["static_equilibrium"]


def static_equilibrium(scene, t=0.0, q=None, steady=False, newton=None, max_steps=500, min_step=1e-8,
                       load_steps=None):
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
    load_steps : int, optional
        Instead of the adaptive path following, n equal steps of the load factor, each solved by
        Newton (halved where one fails). With loads that do not depend on the configuration the
        steps are equilibria under 1/n, 2/n, … of the loads, so a path-independent model ends in
        the same state for any n. Not with ``steady``.

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
    (see ``settle``), which descends to a stable rest state, and the path is finished from
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
    if load_steps is not None:
        if isinstance(load_steps, bool) or int(load_steps) != load_steps or load_steps < 1 or steady:
            raise ValueError(f"load_steps must be a positive integer (and not with steady=True), got {load_steps!r}")
        return load_stepping(scene, q0, v, a, t, settings, int(load_steps), float(min_step), steady)
    if not steady:
        try:
            return continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
        except SingularStart as exc:
            # no stiffness meets the loads at the start: either nothing ever will (a free-flying
            # body under loads: say so), or the scene has a rest state elsewhere (a pendulum held
            # horizontal): let it settle to rest under its loads first, then finish from there
            check_held(scene, q0, v, a, t)
            q0 = settle(scene, q0, t, settings, exc)
            return continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
    for _ in range(4):                     # steady: the constraint velocities follow the solution
        try:
            state = continuation(scene, q0, v, a, t, settings, int(max_steps), float(min_step), steady)
        except SingularStart:
            check_held(scene, q0, v, a, t)
            raise
        if not steady or not scene.n_constraints:
            break
        v_new = _steady_velocity(scene, state.q, t)
        if inf_norm(v_new - v) <= 1e-12 * max(inf_norm(v), TINY):
            break
        v, q0 = v_new, state.q
    if steady:
        check_steady(scene, state)
    return state


def _steady_velocity(scene, q, t):
    """Prescribed rates, and the smallest free velocities with Φ_q v + Φ_t = 0."""
    v = np.zeros(scene.n)
    _, vp, _ = scene.prescribed_state(t)
    v[scene.prescribed_index] = vp
    if scene.n_constraints:
        cq = as_dense(scene.constraint_jacobian(q, t))
        rhs = -scene.constraint_time_derivative(q, t) - cq @ v
        if np.any(rhs):
            v[scene.free_index] = np.linalg.lstsq(cq[:, scene.free_index], rhs, rcond=None)[0]
    return v
