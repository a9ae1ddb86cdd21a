r"""Following the load path to the equilibrium: pseudo-arc-length continuation, and settling from a singular start.

:func:`continuation` runs the homotopy

    H(x, s) = R(x) − (1 − s) (R(x₀) + E(x₀) − E(x))

(R the residual of :class:`~skfem_flex.analysis.balance.StaticResidual`, E the scene's non-potential
loads, ``external_force``, from the same evaluation as R) from s = 0, the start, to s = 1, the scene's loads. With R = R_int − E this
is R_int(x) − (1 − s) R_int(x₀) − s E(x): the potential forces (strain, gravity) are blended from the
start's imbalance, and the loads that depend on the configuration (a moment in space axes on a beam's directors, a
following force) are scaled by s where they act now, so every point of the path is an equilibrium under
the share s of those loads (with R(x₀) frozen instead, a moment's director forces of the start would pull
at a turned section, and a beam rolled up by an end moment finds no path). Then: predictor along the tangent, Newton corrector on the hyperplane orthogonal to it, step halved
on failure and doubled after quick convergence, a last Newton solve at s = 1. A start where no
stiffness meets the loads raises :class:`SingularStart`; :func:`settle` then lets the scene come to
rest under its full loads by pseudo-transient continuation first. :func:`load_stepping` instead takes
equal steps of s, each solved by Newton (a path-independence check takes 3, 8 or 30 of them).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sps

from ..errors import ConvergenceError
from ..numerics.linear_solver import linear_solve
from ..numerics.newton import newton_solve
from ..scene import add_matrices
from .balance import StaticResidual, equilibrium_state, initial_multipliers
from .matrix_tools import EPS, TINY, inf_norm, submatrix

__all__ = ["SingularStart", "continuation", "load_stepping", "settle"]


class SingularStart(ValueError):
    """The load path cannot start at the given state: no stiffness meets the loads there."""


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


def settle(scene, q0, t, settings, why, max_steps=400):
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
    sys_ = StaticResidual(scene, q0, v, a, t, settings)
    nf, free = sys_.nf, scene.free_index
    x = np.concatenate([q0[free], initial_multipliers(scene, q0, v, a, t)])
    res, jac, sc = sys_.evaluate(x)
    mass = submatrix(scene.mass_matrix(q0), free, free)
    m_diag = np.abs(mass.diagonal() if sps.issparse(mass) else np.diag(mass))
    # the first pseudo-step moves the most accelerated coordinate by a tenth of the scene's size
    acc = inf_norm(res[:nf] / np.maximum(m_diag, TINY))
    tau2 = 0.1 * max(scene.length_scale, 1.0) / max(acc, TINY)
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
        tau2 *= min(max(norm / max(new_norm, TINY), 0.1), 100.0)
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


def _start(scene, q0, v, a, t, settings, steady):
    """The residual at the start and the function that turns a point x of the path into an equilibrium."""
    sys_ = StaticResidual(scene, q0, v, a, t, settings)
    nf = sys_.nf
    x0 = np.concatenate([q0[scene.free_index], initial_multipliers(scene, q0, v, a, t)])
    r0, jac0, sc0 = sys_.evaluate(x0)
    # the loads that depend on the configuration, at the start (the homotopy scales them where they act);
    # the path's tangent at s = 0 takes their derivative too
    sys_.external_start = sys_.last_external[0]
    if sys_.external_start is not None:
        jac0 = _homotopy(sys_, x0, 0.0, r0)[1]

    def done(x, s, steps, its):
        # the force balance at x, for the prescribed coordinates' forces and the accepted imbalance
        _, _, (scale, floor, _) = sys_.evaluate(x)
        tolerance = settings.rtol * max(scale, inf_norm(r0[:nf])) + 16 * EPS * floor
        q = sys_.full_q(x)
        lam = x[nf:]
        return equilibrium_state(scene, t, q, v, a, lam, s, steps, its, steady, sys_.last_force, tolerance)

    return sys_, x0, r0, jac0, sc0, done


def load_stepping(scene, q0, v, a, t, settings, n_steps, min_step, steady):
    """Equal steps of the load factor s = 1/n, 2/n, …, 1 of the homotopy, each solved by Newton from the
    secant predictor of the two states before (the first from the linear response to the loads; a step that
    fails is halved down to ``min_step``).

    With loads that do not depend on the configuration (dead loads, gravity), s is the load factor and every
    step an equilibrium under that share of the loads: a path-independent formulation gives the same end
    state for any n. Raises ``ConvergenceError`` (with ``exc.state``) when a step cannot be solved."""
    sys_, x0, r0, jac0, _, done = _start(scene, q0, v, a, t, settings, steady)
    name = "static equilibrium"
    x, s, x_before, s_before = x0, 0.0, None, 0.0
    try:                                   # the first predictor: the linear response to the load
        dxds = -linear_solve(jac0, r0)
    except np.linalg.LinAlgError:
        dxds = np.zeros_like(x0)
    if not np.all(np.isfinite(dxds)):
        dxds = np.zeros_like(x0)
    steps = its_total = 0
    target = 1.0 / n_steps
    while s < 1.0 - 1e-14:
        s_new = min(s + target, 1.0)
        pred = x + (s_new - s) * dxds if x_before is None else x + (x - x_before) * ((s_new - s) / (s - s_before))
        try:
            x_new, _, its = newton_solve(_level(sys_, s_new, r0), pred, settings,
                                         name, f"load factor {s_new:.6g}")
        except (ConvergenceError, np.linalg.LinAlgError):
            target *= 0.5
            if target < min_step:
                exc = ConvergenceError(f"{name} of {scene.name!r} failed: no equilibrium found beyond load factor "
                                       f"{s:.9g} of 1 with steps down to {min_step:g}", load_factor=s, steps=steps)
                exc.state = done(x, s, steps, its_total)
                raise exc from None
            continue
        x_before, s_before, x, s = x, s, x_new, s_new
        steps += 1
        its_total += its
        target = max(target, 1.0 / n_steps) if its <= 6 else target
    return done(x, 1.0, steps, its_total)


def continuation(scene, q0, v, a, t, settings, max_steps, min_step, steady):
    """Follow the load path from q0 to the equilibrium under the full loads (the notes of
    :func:`~skfem_flex.analysis.statics.static_equilibrium`).

    Raises :class:`SingularStart` when no stiffness meets the loads at q0, ``ConvergenceError`` (with
    ``exc.state``, the last equilibrium on the path) when the path cannot be followed to the full load."""
    sys_, x0, r0, jac0, sc0, done = _start(scene, q0, v, a, t, settings, steady)
    nf, m = sys_.nf, sys_.m
    name = "static equilibrium"

    if sys_.error(r0, sc0) <= 1.0:
        return done(x0, 1.0, 0, 0)
    try:
        dxds = -linear_solve(jac0, r0)
    except np.linalg.LinAlgError:
        raise SingularStart(f"{name}: the start state of {scene.name!r} is a singular point of the load path (a "
                         f"coordinate without stiffness or a redundant constraint at the load-free start); "
                         f"start nearer the rest state (q=...)") from None
    if not np.all(np.isfinite(dxds)):
        raise ValueError(f"{name}: the tangent of the load path is not finite at the start of {scene.name!r}")
    # the linear response to the full load: a coordinate moving by more than a hundred sizes of
    # the scene (or turns) means no stiffness meets the load at the start
    reach = 100.0 * max(scene.length_scale, 2.0 * np.pi)
    if inf_norm(dxds[:nf]) > reach:
        raise SingularStart(f"{name}: the start state of {scene.name!r} is (nearly) a singular point of the load "
                         f"path: the linear response to the loads moves a coordinate by {inf_norm(dxds[:nf]):.3g} "
                         f"(no stiffness meets the load there, e.g. a pendulum held horizontal); start nearer "
                         f"the rest state (q=...)")
    sigma = max(float(np.linalg.norm(dxds[:nf])), TINY)
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

    while steps < max_steps:
        s = float(y[-1])
        y_pred = y + h * tau
        final = tau[-1] > 0 and y_pred[-1] >= 1.0 - 1e-12
        try:
            if final:                # land on the full load: Newton at s = 1 from the predictor there
                y_pred = y + ((1.0 - s) / tau[-1]) * tau
                x, _, its = newton_solve(_level(sys_, 1.0, r0), y_pred[:-1], settings, name, "load factor 1")
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
        res, jac, _, col = _homotopy(sys_, y_new[:-1], float(y_new[-1]), r0)
        try:
            aug = _bordered_matrix(jac, col, weight[:-1] * tau[:-1], weight[-1] * tau[-1])
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
    """(H, ∂H/∂x, error, ∂H/∂s) at (x, s) (module docstring)."""
    res, jac, (scale, floor, c_scale) = sys_.evaluate(x)
    col = r0
    if sys_.external_start is not None:
        e, de = sys_.last_external
        col = r0 + sys_.external_start - e
        jac = add_matrices(jac, (1.0 - s) * de)
    h = res - (1.0 - s) * col
    # the start's imbalance is a force scale of the path too: an equilibrium without loads
    # (all forces → 0) is then found to rtol of the forces that were out of balance
    return h, jac, sys_.error(h, (max(scale, inf_norm(r0[:sys_.nf])), floor, c_scale)), col


def _level(sys_, s, r0):
    """x ↦ (H, ∂H/∂x, error) at the load factor s: the function Newton solves."""
    return lambda x: _homotopy(sys_, x, s, r0)[:3]


def _corrector(sys_, y_pred, tau, weight, r0, settings, name):
    """Newton on H(x, s) = 0 and (y − y_pred)·W τ = 0."""
    wt = weight * tau

    def fun(y):
        h, jac, err, col = _homotopy(sys_, y[:-1], float(y[-1]), r0)
        row = float(wt @ (y - y_pred))
        return np.concatenate([h, [row]]), _bordered_matrix(jac, col, wt[:-1], wt[-1]), err

    y, _, its = newton_solve(fun, y_pred, settings, name, f"load factor {y_pred[-1]:.4g}")
    return y, its
