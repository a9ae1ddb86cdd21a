r"""The Cayley parameter of a planar incremental rotation and its divided differences.

In the plane an incremental rotation is one angle Δφ; its Rodrigues/Cayley
parameter is

.. math::

    w = W(Δφ) = 2 \tan(Δφ/2),

and for the rotation matrices Λ_0, Λ_1 = Λ(Δφ) Λ_0 and their mean
\bar Λ = (Λ_0 + Λ_1)/2 it satisfies Λ_1 − Λ_0 = w E \bar Λ exactly
(E the 90° rotation). The energy-momentum integrator therefore takes
w/Δt, not Δφ/Δt, as the mean angular velocity of coordinates that a body
declares as Cayley coordinates (Simo, Tarnow & Doblaré 1995): with it the
mid-point rule is equivariant under rotations, and exact energy and exact
angular momentum no longer exclude each other (see
:mod:`skfem_flex.bodies.exact.strain`).

Shared by the bodies that write their discrete gradients in Cayley rates
and by the integrator that uses them; it knows neither.

The Cayley functions accept complex arguments (the exact beam differentiates
its discrete gradient by complex steps) and are defined for |Δφ| < π; ``sinc`` is
a compiled ufunc, ``dsinc`` compiled for real scalars.
"""
from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["sinc_half", "cayley_terms", "MAX_INCREMENT", "unresolved_turn", "cayley", "cayley_derivative", "cayley_ratio", "cayley_ratio_derivative", "cayley_divided_difference",
           "sinc", "dsinc"]

#: largest incremental rotation per step the Cayley update accepts, rad (W has a pole at π)
MAX_INCREMENT = 0.9 * np.pi


@numba.njit(cache=True, _nrt=False)
def unresolved_turn(dq, angles):
    """True when an angle coordinate (indices ``angles`` into the increment ``dq``, rad) turned by
    :data:`MAX_INCREMENT` or more (or by a non-finite amount) in one step: fewer than ~2 steps per
    revolution resolve no rotation, and a converged Newton root there is spurious (a joint flipped). Every
    scheme refuses such a step (it is halved)."""
    for c in angles:
        if not abs(dq[c]) < MAX_INCREMENT:
            return True
    return False


#: below this |Δφ| the closed forms of the ratio's derivative cancel; its Taylor series is exact there
SERIES_BELOW = 1e-2


@numba.vectorize(cache=True)         # compiled per argument type on first use, not at import
def sinc(x):
    """sin(x)/x, 1 at 0 (unnormalised; a ufunc: arrays and complex arguments allowed). The package's one
    sinc: the rotation identity A(θ₁) − A(θ₀) = sinc(Δθ/2) Δθ A(θ_m) E of every exact discrete
    gradient uses it, from numpy code and from the compiled kernels alike, and so do the Cayley
    divided differences."""
    if x == 0:
        return 1.0
    return np.sin(x) / x


@numba.njit(cache=True)
def dsinc(x):
    """d sinc(x)/dx = (x cos x − sin x)/x², by its Taylor series near 0 (no cancellation)."""
    if abs(x) < 2e-2:
        x2 = x * x
        return x * (-1.0 / 3.0 + x2 * (1.0 / 30.0 - x2 / 840.0))
    return (x * math.cos(x) - math.sin(x)) / (x * x)


@numba.njit(cache=True)
def sinc_half(d):
    """σ = sinc(d/2) and dσ/dd = ½ dsinc(d/2) of an angle increment d (rad)."""
    h = 0.5 * d
    return sinc(h), 0.5 * dsinc(h)


@numba.njit(cache=True)
def cayley_terms(dpsi):
    """(z, Δψ/w, d(Δψ/w)/dΔψ, dz/dΔψ) of an increment Δψ (rad), z = w = 2 tan(Δψ/2): :func:`cayley`,
    :func:`cayley_ratio`, :func:`cayley_ratio_derivative` and :func:`cayley_derivative` in one compiled call
    for the energy-momentum step."""
    h = 0.5 * dpsi
    c = np.cos(h)
    if abs(dpsi) < SERIES_BELOW:
        dratio = -dpsi / 6.0 - dpsi ** 3 / 180.0
    else:
        sh = np.sin(h)
        dratio = (np.sin(dpsi) - dpsi) / (4.0 * sh * sh)
    return 2.0 * np.tan(h), c / sinc(h), dratio, 1.0 / (c * c)


def _sinc_any(x):
    """``sinc`` for numpy callers that may pass complex arrays (complex-step tangents).

    The ufunc adds a loop per argument type on first use, and numpy resolves real input to the
    first loop it can cast to: were the complex loop compiled first, every later real call would
    come back complex. The real loop is therefore made first (eager signatures would instead cost
    0.2 s at every import)."""
    if np.iscomplexobj(x):
        sinc(0.0)
    return sinc(x)


def cayley(dphi):
    """w = 2 tan(Δφ/2), dimensionless (Δφ in rad)."""
    return 2.0 * np.tan(0.5 * np.asarray(dphi))


def cayley_derivative(dphi):
    """dw/dΔφ = 1/cos²(Δφ/2) = 1 + w²/4."""
    c = np.cos(0.5 * np.asarray(dphi))
    return 1.0 / (c * c)


def cayley_ratio(dphi):
    """Δφ / w = cos(Δφ/2) / sinc(Δφ/2), 1 at 0 (no cancellation anywhere on |Δφ| < π)."""
    h = 0.5 * np.asarray(dphi)
    return np.cos(h) / _sinc_any(h)


def cayley_ratio_derivative(dphi):
    """d(Δφ/w)/dΔφ = (sin Δφ − Δφ)/(4 sin²(Δφ/2)), by its Taylor series −Δφ/6 − Δφ³/180 near 0."""
    x = np.asarray(dphi, dtype=float)
    small = np.abs(x) < SERIES_BELOW
    safe = np.where(small, 1.0, x)
    s = np.sin(0.5 * safe)
    exact = (np.sin(safe) - safe) / (4.0 * s * s)
    series = -x / 6.0 - x ** 3 / 180.0
    return np.where(small, series, exact)


def cayley_divided_difference(x, y):
    """(W(x) − W(y))/(x − y) = sinc((x − y)/2) / (cos(x/2) cos(y/2)), W = 2 tan(·/2).

    Smooth, and equal to W'(x) at x = y: no cancellation as x → y.
    """
    x, y = np.asarray(x), np.asarray(y)
    return _sinc_any(0.5 * (x - y)) / (np.cos(0.5 * x) * np.cos(0.5 * y))
