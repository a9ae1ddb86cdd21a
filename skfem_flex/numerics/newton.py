"""The one Newton–Raphson core of the package, compiled (Numba).

Every nonlinear solve of the package — each step of the energy-momentum, trapezoidal and
generalized-α schemes, on the compiled path and on the Python-assembled path alike, and the
load steps of the static solver — runs this core. Its rules exist only here:

* convergence when the caller's scaled error is at most one;
* the exit for an update below round-off of the unknowns;
* the stagnation exit at the round-off floor of the residual's own terms;
* the line search (how far to backtrack, and when not to);
* when to give up (non-finite residual or update, singular Newton matrix, no convergence
  within the iteration cap), reported as a status code; the caller decides what a failure
  means (halve the step, raise :class:`~skfem_flex.errors.ConvergenceError`);
* :func:`roundoff_floor`, the acceptance of a residual that has reached what round-off allows
  the energy scheme's stiff internal forces.

The core is a *reverse-communication* state machine (as ARPACK's solvers): :func:`newton_start`
makes its state, and its driver does what it asks — EVALUATE the residual, tangent and scaled
error at ``x_try`` and hand the error to :func:`newton_evaluated`, or SOLVE J y = r for the last
evaluation and hand y to :func:`newton_solved` — until it answers with a status. The drivers hold
no rule, only that dispatch: the compiled loop (:mod:`skfem_flex.compiled.loop`) drives it from compiled code with their compiled residuals;
:func:`newton_solve` drives it from Python for a :class:`PythonSystem` — the documented slower
path that user-defined elements and the Python-assembled scenes take: same core, same rules,
Python arithmetic. (A core that took the residual as a function argument would be the more
obvious design, but Numba cannot cache a compiled function whose arguments are functions: every
process would compile the loops again.)
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from ..errors import ConvergenceError
from .linear_solver import linear_solve as default_linear_solve

__all__ = ["NewtonSettings", "set_compile_hook", "newton_start", "newton_reset", "newton_evaluated", "newton_solved", "newton_solve", "roundoff_floor",
           "PythonSystem", "max_abs", "all_finite", "EVALUATE", "SOLVE", "CONVERGED", "NONFINITE_RESIDUAL",
           "NONFINITE_UPDATE", "SINGULAR", "NOT_CONVERGED"]

_EPS = np.finfo(float).eps
_TINY = 1e-300
#: a step is converged when the caller's scaled error is at most this
CONVERGED_BELOW = 1.0
#: the line search multiplies the update by this factor per backtrack ...
LINE_SEARCH_FACTOR = 0.5
#: ... at most this many times
LINE_SEARCH_BACKTRACKS = 6
#: scaled errors at or below this count as 'at the round-off floor': no backtracking there
NEAR_FLOOR = 1e4
#: statuses the core finishes with (≥ 0)
CONVERGED, NONFINITE_RESIDUAL, NONFINITE_UPDATE, SINGULAR, NOT_CONVERGED = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class NewtonSettings:
    """Convergence control of the Newton–Raphson core.

    A step is converged when every scaled measure is at most one:
    ‖r‖∞ ≤ ``rtol`` · (largest term of the balance it checks), ‖Φ‖∞ ≤
    ``ctol`` · (scale of Φ), and for the energy-conserving scheme
    abs(v̄ · r) ≤ ``etol`` · (energy scale). The scales come from the terms
    themselves, so the defaults work for a 1 kg oscillator and for a steel
    beam with forces of 10⁷ N alike. An update below round-off of the state
    also ends the iteration (the residual is then as small as floating
    point allows).

    Attributes
    ----------
    rtol, ctol, etol : float
        Relative tolerances (dimensionless).
    max_iterations : int
        Cap on Newton iterations per step.
    line_search : bool
        Backtrack (up to ``LINE_SEARCH_BACKTRACKS`` times by ``LINE_SEARCH_FACTOR``) when the
        residual grows.
    """

    rtol: float = 1e-12
    ctol: float = 1e-12
    etol: float = 1e-14
    max_iterations: int = 25
    line_search: bool = True

    def __post_init__(self):
        for name in ("rtol", "ctol", "etol"):
            val = getattr(self, name)
            if not (np.isfinite(val) and 0 < val < 1):
                raise ValueError(f"NewtonSettings.{name} must be in (0, 1), got {val!r}")
        if int(self.max_iterations) < 1:
            raise ValueError(f"NewtonSettings.max_iterations must be >= 1, got {self.max_iterations!r}")


@numba.njit(cache=True, _nrt=False)
def max_abs(x):
    """‖x‖∞ of a 1D array (0 for an empty one)."""
    m = 0.0
    for i in range(x.size):
        a = abs(x[i])
        if a > m:
            m = a
    return m


@numba.njit(cache=True, _nrt=False)
def all_finite(x):
    """True if every entry of the 1D array x is finite."""
    for i in range(x.size):
        if not np.isfinite(x[i]):
            return False
    return True


# Functions that only read and write arrays they are given are compiled with ``_nrt=False``: Numba
# then emits no reference counting for the arrays they unpack from tuples (an atomic increment and
# decrement per array per call, which was a third of a small scene's residual evaluation: the rigid
# pendulum's 1.4 µs → 0.9 µs). Such a function may not allocate (numba refuses to compile it then).
# ``_nrt`` is a numba compile option without a public name; the test suite exercises every use.
@numba.njit(cache=True, _nrt=False)
def _copy(src, dst):
    for i in range(src.size):
        dst[i] = src[i]


#: the Newton start of a time step continues the last step's mean acceleration only while the step
#: resolves the motion: ½ Δt ‖a0‖∞ ≤ PREDICTOR_LIMIT ‖v0‖∞ (the velocity changes by less than half)
PREDICTOR_LIMIT = 0.25


@numba.njit(cache=True, _nrt=False)
def predicted_increment(v0, a0, h, free, out):
    """The start of a time step's Newton iteration on the free coordinates ``free``, into ``out``:
    Δq⁰ = Δt v0 + ½ Δt² a0 (the quadratic through the last step when a0 is its mean acceleration;
    on smooth motion it saves about one Newton iteration per step), or Δt v0 when the step does not
    resolve the motion (½ Δt ‖a0‖∞ > PREDICTOR_LIMIT ‖v0‖∞ over the free coordinates: a large step
    of a fast pendulum, stiff vibration, a start from rest), where extrapolating overshoots and
    Newton may end on another root or not at all. Used by the Python step and the compiled loops
    alike (one rule)."""
    v_inf, a_inf = 0.0, 0.0
    for i in free:
        v_inf = max(v_inf, abs(v0[i]))
        a_inf = max(a_inf, abs(a0[i]))
    c = 0.5 * h * h if 0.5 * h * a_inf <= PREDICTOR_LIMIT * v_inf else 0.0
    for j in range(free.size):
        out[j] = h * v0[free[j]] + c * a0[free[j]]


#: what the core asks its driver to do next (negative; a status ≥ 0 means it has finished)
EVALUATE, SOLVE = -1, -2


@numba.njit(cache=True)
def newton_start(x0, x_scale, max_iterations, line_search):
    """A Newton iteration from ``x0``: its state, to be driven by :func:`newton_evaluated` and
    :func:`newton_solved` (the first request is EVALUATE at ``x_try(state)``).

    Parameters
    ----------
    x0 : ndarray
        Start.
    x_scale : float
        Size of the state x is an increment of (0 if none): updates of a step that starts at
        rest are judged against it for the stagnation exit.
    max_iterations : int
    line_search : bool

    Returns
    -------
    state : tuple
        (x, dx, x_try, floats [err, err_prev, step, x_scale], ints [iterations, backtracks, phase,
        max_iterations, line_search]). ``x`` is the current iterate and the last point evaluated
        once an evaluation has been accepted.
    """
    x = x0.copy()
    fl = np.array([np.inf, np.inf, 1.0, x_scale])
    ints = np.array([0, 0, 0, max_iterations, 1 if line_search else 0], dtype=np.int64)
    return x, np.zeros(x.size), x0.copy(), fl, ints


@numba.njit(cache=True, _nrt=False)
def newton_reset(state, x_scale, max_iterations, line_search):
    """Start a Newton iteration in the preallocated ``state`` (as :func:`newton_start` makes it) from
    the start already written into ``x_try``: the compiled loop's form, which allocates nothing."""
    x, dx, x_try, fl, ints = state
    for i in range(x.size):
        x[i] = x_try[i]
        dx[i] = 0.0
    fl[0], fl[1], fl[2], fl[3] = np.inf, np.inf, 1.0, x_scale
    ints[0], ints[1], ints[2], ints[3] = 0, 0, 0, max_iterations
    ints[4] = 1 if line_search else 0


@numba.njit(cache=True, _nrt=False)
def _check(state):
    """The tests at a new iterate: finished (a status) or SOLVE."""
    x, dx, x_try, fl, ints = state
    err = fl[0]
    if not np.isfinite(err):
        return NONFINITE_RESIDUAL
    if err <= CONVERGED_BELOW:
        return CONVERGED
    if ints[0] == ints[3]:
        return NOT_CONVERGED
    ints[2] = 1
    return SOLVE


@numba.njit(cache=True, _nrt=False)
def newton_evaluated(state, err):
    """Take the scaled error of the evaluation at ``x_try`` (NaN: residual not finite); the next request.

    The line search lives here: an evaluation after an update is accepted unless the error grew
    far from convergence, in which case the update is cut by ``LINE_SEARCH_FACTOR`` (at most
    ``LINE_SEARCH_BACKTRACKS`` times; the last try is taken whatever it gives)."""
    x, dx, x_try, fl, ints = state
    if ints[2] == 0:                           # the start
        _copy(x_try, x)
        fl[0] = err
        return _check(state)
    # backtrack only on a real increase far from convergence: near the round-off floor the scaled
    # residual jitters by factors of a few between equally good iterates, and backtracking would
    # only burn residual evaluations
    accept = (ints[4] == 0 or ints[1] == LINE_SEARCH_BACKTRACKS
              or (np.isfinite(err) and (err < max(fl[0], CONVERGED_BELOW) or err <= NEAR_FLOOR)))
    if not accept:
        ints[1] += 1
        fl[2] *= LINE_SEARCH_FACTOR
        for i in range(x.size):
            x_try[i] = x[i] + fl[2] * dx[i]
        return EVALUATE
    _copy(x_try, x)
    fl[0] = err
    ints[0] += 1
    return _check(state)


@numba.njit(cache=True, _nrt=False)
def newton_solved(state, y, regular):
    """Take y = J⁻¹ r at the current iterate (``regular`` False: J singular); the next request.

    Ends the iteration when the update is below round-off of x, or when the residual stagnates
    at its round-off floor; otherwise asks to evaluate x + Δx, Δx = −y."""
    x, dx, x_try, fl, ints = state
    if not regular:
        return SINGULAR
    if not all_finite(y):
        return NONFINITE_UPDATE
    for i in range(x.size):
        dx[i] = -y[i]
    err, err_prev = fl[0], fl[1]
    dx_inf, x_inf = max_abs(dx), max_abs(x)
    if dx_inf <= 8 * _EPS * max(x_inf, _TINY) and err < 1e6:
        ints[0] += 1
        return CONVERGED                       # update below round-off: as converged as floating point allows
    if ints[0] >= 2 and err >= 0.25 * err_prev and dx_inf <= 1.5e-8 * max(x_inf, fl[3]) and err < 1e4:
        ints[0] += 1
        return CONVERGED                       # stagnated at the round-off floor of the residual's own terms
    fl[1] = err
    fl[2] = 1.0
    ints[1] = 0
    ints[2] = 2
    for i in range(x.size):
        x_try[i] = x[i] + dx[i]
    return EVALUATE


@numba.njit(cache=True)
def roundoff_floor(err, err_c, r_inf, floor_inf, vr, v_floor):
    """The energy scheme's scaled error, capped where round-off is all that keeps it above one.

    The internal forces of a stiff body are differences of terms far larger than their sum
    (K q cancels: |K||q| ≫ |K q|), so r and v̄·r cannot fall below about ε times those terms.
    Measured: |r| ≈ 0.5 ε |floor|, |v̄·r| ≤ 0.3 ε |v̄|·|floor|. Within 16 ε and 2 ε of them (and
    with the constraints converged) the error is capped at 10³, which lets the core's
    stagnation exit accept the step once Newton stops improving (start from rest, very stiff beams).

    Parameters
    ----------
    err, err_c : float
        Scaled error of the step and of its constraint rows.
    r_inf, floor_inf : float
        ‖r_F‖∞ and ‖floor_F‖∞ over the free coordinates.
    vr, v_floor : float
        |v̄_F · r_F| and |v̄_F| · floor_F.
    """
    if err > 1.0 and err_c <= 1.0 and r_inf <= 16 * _EPS * floor_inf and vr <= 2 * _EPS * v_floor:
        return min(err, 1e3)
    return err


class PythonSystem:
    """A system assembled in Python, driven by the compiled core from :func:`newton_solve`.

    Parameters
    ----------
    fun : callable x -> (r, J, err)
        Residual, Jacobian (dense or scipy.sparse) and scaled error.
    linear_solve : callable (J, r) -> y
        The linear solver; raises ``numpy.linalg.LinAlgError`` when J is singular.
    """

    def __init__(self, fun, linear_solve):
        self.fun, self.linear_solve = fun, linear_solve
        self.r = self.jac = None

    def evaluate(self, x):
        """Scaled error at x (NaN if the residual is not finite); keeps r and J."""
        r, jac, err = self.fun(x.copy())
        self.r, self.jac = r, jac
        err = float(err)
        return err if np.all(np.isfinite(r)) else np.nan

    def solve(self):
        """(J⁻¹ r, True) for the last evaluation, or (zeros, False) if J is singular."""
        try:
            return np.asarray(self.linear_solve(self.jac, self.r), dtype=float), True
        except np.linalg.LinAlgError:
            return np.zeros(np.size(self.r)), False


_COMPILE_HOOK = [None]
_READY = set()


def set_compile_hook(hook):
    """``hook(dispatcher, argtypes, what)`` compiles a core function before :func:`newton_solve` first
    calls it from Python, so that the compile is announced and timed like every other
    (:func:`skfem_flex.compiled.registry.compiled_function` installs itself here; without a hook numba
    compiles on the first call, silently)."""
    _COMPILE_HOOK[0] = hook


def _core(fn, *args):
    """``fn(*args)``, compiled through the hook on its first call from Python."""
    if fn not in _READY and _COMPILE_HOOK[0] is not None:
        _COMPILE_HOOK[0](fn, tuple(numba.typeof(a) for a in args),
                         f"the Newton core's {fn.__name__} for Python-assembled systems")
        _READY.add(fn)
    return fn(*args)


def newton_solve(fun, x0, settings, name, where, x_scale=0.0, linear_solve=None):
    """Solve fun(x) = 0 on a Python-assembled system, driving the compiled core.

    Parameters
    ----------
    fun : callable x -> (r, J, err)
        Residual r, its Jacobian J (dense or sparse) and the scaled error
        err (≤ 1 means converged; the caller scales its own measures).
    x0 : ndarray
        Start.
    settings : NewtonSettings
        ``max_iterations`` and ``line_search`` are used here.
    name, where : str
        Solver name and where the solve happens (time and step, load factor), for messages.
    x_scale : float
        Size of the state x belongs to when x is an increment of it (the time steppers'
        Δq); a step that starts at rest has x ≈ 0, and its updates are then judged
        against this size for the stagnation exit.
    linear_solve : callable (J, r) -> y, optional
        The linear solver; default :func:`skfem_flex.numerics.linear_solver.linear_solve`.

    Returns
    -------
    x, r, iterations

    Raises
    ------
    ConvergenceError
        On a non-finite residual or update, a singular Jacobian or no convergence
        within ``settings.max_iterations``. Exceptions raised by ``fun`` pass through.
    """
    system = PythonSystem(fun, default_linear_solve if linear_solve is None else linear_solve)
    state = _core(newton_start, np.ascontiguousarray(x0, dtype=float), float(x_scale), int(settings.max_iterations),
                  bool(settings.line_search))
    action = EVALUATE
    while action < 0:                          # do what the core asks; the rules are all in the core
        if action == EVALUATE:
            action = _core(newton_evaluated, state, float(system.evaluate(state[2])))
        else:
            y, regular = system.solve()
            action = _core(newton_solved, state, np.ascontiguousarray(y, dtype=float), bool(regular))
    status, x, it, err = action, state[0], int(state[4][0]), float(state[3][0])
    if status == CONVERGED:
        return x, system.r, it
    if status == NONFINITE_RESIDUAL:
        msg = (f"{name}: residual is not finite at {where} after {it} iterations "
               f"(the solution escaped or the step is far too large)")
        err = float("nan")
    elif status == SINGULAR:
        msg = (f"{name}: singular Newton matrix at {where}, iteration {it} "
               f"(redundant constraints or a coordinate without inertia or stiffness)")
    elif status == NONFINITE_UPDATE:
        msg = f"{name}: Newton update is not finite at {where}, iteration {it}"
    else:
        msg = f"{name}: Newton did not converge at {where}: scaled residual {err:.3g} after {it} iterations"
    raise ConvergenceError(msg, iterations=it, residual=float(err))
