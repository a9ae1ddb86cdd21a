r"""The scalar functions of the rotation-interpolated spatial beam (:mod:`.rotation_kernel`) and the turn of a
vector by the exponential of a rotation vector, with their derivatives: compiled without numba's reference
counting (``_nrt=False``; they write into arrays they are given and return scalars or nothing, see
:mod:`.rotation_kernel`).

* A(y) = arctan(√y)/√y, which gives the rotation vector ψ = 2 p A(σ p²) a, p = 1/(1 + c), of the element's
  invariants;
* exp(ŵ) = γ I + α ŵ + β w wᵀ with τ = w · w,

  .. math::

      γ = \cos t, \qquad α = \frac{\sin t}{t}, \qquad β = \frac{1 - \cos t}{t^2}, \qquad t = \sqrt τ ;

* y = exp(ŵ) x and its first and second derivatives in w and x.

The scalar functions are summed as power series near zero, where their closed forms cancel; a straight
element is the common case.
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["atan_ratio", "rodrigues", "turn"]

# below these arguments the scalar functions are summed as series: their closed forms cancel
_SERIES_BELOW = 0.1


def _series(coefficients):
    """The coefficients of a power series Σ c_n xⁿ and of its first and second derivatives, as a (3, N) table."""
    c = np.asarray(coefficients, dtype=float)
    n = np.arange(c.size, dtype=float)
    out = np.zeros((3, c.size))
    out[0] = c
    out[1, :-1] = (n * c)[1:]
    out[2, :-2] = (n * (n - 1) * c)[2:]
    return out


_FACTORIAL = np.cumprod(np.concatenate([[1.0], np.arange(1.0, 31.0)]))
#: arctan(√y)/√y = Σ (−y)ⁿ/(2n + 1); sin t/t and (1 − cos t)/t² in τ = t²: Σ (−τ)ⁿ/(2n + 1)!, Σ (−τ)ⁿ/(2n + 2)!
_ATAN_SERIES = _series([(-1.0) ** n / (2 * n + 1) for n in range(27)])
_SIN_SERIES = _series([(-1.0) ** n / _FACTORIAL[2 * n + 1] for n in range(15)])
_COS_SERIES = _series([(-1.0) ** n / _FACTORIAL[2 * n + 2] for n in range(15)])


@numba.njit(cache=True, _nrt=False, inline="always")
def _terms(x, most):
    """How many terms of a series in x (0 ≤ x < 1, coefficients at most 1) reach round-off: the first n with
    xⁿ below 1e-17, at most ``most``."""
    n, p = 1, x
    while p > 1e-17 and n < most:
        p *= x
        n += 1
    return n


@numba.njit(cache=True, _nrt=False, inline="always")
def _horner(table, row, x, n):
    """Σ_{k<n} table[row, k] x^k, by Horner's rule."""
    s = 0.0
    for k in range(n - 1, -1, -1):
        s = s * x + table[row, k]
    return s


@numba.njit(cache=True, _nrt=False, inline="always")
def atan_ratio(y):
    """A(y) = arctan(√y)/√y and its first two derivatives in y (y ≥ 0)."""
    if y < _SERIES_BELOW:
        # the terms past n fall below round-off; the derivatives' series, two terms shorter, need two more
        n = min(_terms(y, 25) + 2, 25)
        return (_horner(_ATAN_SERIES, 0, y, n), _horner(_ATAN_SERIES, 1, y, n),
                _horner(_ATAN_SERIES, 2, y, n))
    r = np.sqrt(y)
    a = np.arctan(r) / r
    da = (1.0 / (1.0 + y) - a) / (2.0 * y)
    dda = (-1.0 / (1.0 + y) ** 2 - 3.0 * da) / (2.0 * y)
    return a, da, dda


@numba.njit(cache=True, _nrt=False, inline="always")
def rodrigues(tau):
    """exp(ŵ) = γ I + α ŵ + β w wᵀ with τ = w·w: (γ, α, β) and their first and second derivatives in τ."""
    if tau < _SERIES_BELOW:
        n = min(_terms(tau, 13) + 2, 13)
        al, dal, ddal = (_horner(_SIN_SERIES, 0, tau, n), _horner(_SIN_SERIES, 1, tau, n),
                         _horner(_SIN_SERIES, 2, tau, n))
        be, dbe, ddbe = (_horner(_COS_SERIES, 0, tau, n), _horner(_COS_SERIES, 1, tau, n),
                         _horner(_COS_SERIES, 2, tau, n))
        ga = 1.0 - be * tau
        return ga, al, be, -0.5 * al, dal, dbe, -0.5 * dal, ddal, ddbe
    t = np.sqrt(tau)
    ga, al = np.cos(t), np.sin(t) / t
    be = (1.0 - ga) / tau
    dga = -0.5 * al
    dal = (ga - al) / (2.0 * tau)
    dbe = (0.5 * al - be) / tau
    ddga = -0.5 * dal
    ddal = (dga - 3.0 * dal) / (2.0 * tau)
    ddbe = (0.5 * dal - 2.0 * dbe) / tau
    return ga, al, be, dga, dal, dbe, ddga, ddal, ddbe


#: the permutation symbol ε_ijk
_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0


@numba.njit(cache=True, _nrt=False, inline="always")
def _skew(x, out):
    """out = x̂, the matrix of x × ·."""
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -x[2], x[1]
    out[1, 0], out[1, 1], out[1, 2] = x[2], 0.0, -x[0]
    out[2, 0], out[2, 1], out[2, 2] = -x[1], x[0], 0.0


@numba.njit(cache=True, _nrt=False, inline="always")
def turn(w, x, level, y, yw, yx, yww, ywx, W, X, cr):
    """y = exp(ŵ) x = γ x + α w × x + β (w·x) w and (``level`` ≥ 1) its derivatives ∂y/∂w, ∂y/∂x and
    (``level`` 2) ∂²y/∂w², ∂²y/∂w∂x (y_i, [i, l], [i, m], [i, l, m], [i, l, m]), written into the given
    arrays (W, X, cr: work arrays)."""
    tau = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    ga, al, be, dga, dal, dbe, ddga, ddal, ddbe = rodrigues(tau)
    wx = w[0] * x[0] + w[1] * x[1] + w[2] * x[2]
    _skew(w, W)
    _skew(x, X)
    cr[0] = w[1] * x[2] - w[2] * x[1]
    cr[1] = w[2] * x[0] - w[0] * x[2]
    cr[2] = w[0] * x[1] - w[1] * x[0]
    for i in range(3):
        y[i] = ga * x[i] + al * cr[i] + be * wx * w[i]
    if level == 0:
        return
    for i in range(3):
        for m in range(3):
            dim = 1.0 if i == m else 0.0
            yx[i, m] = ga * dim + al * W[i, m] + be * w[i] * w[m]
            # ∂(w × x)/∂w = −x̂
            yw[i, m] = (2.0 * dga * w[m] * x[i] + 2.0 * dal * w[m] * cr[i] - al * X[i, m]
                        + 2.0 * dbe * wx * w[i] * w[m] + be * w[i] * x[m] + be * wx * dim)
    if level < 2:
        return
    for i in range(3):
        for l in range(3):
            dil = 1.0 if i == l else 0.0
            for m in range(3):
                dim = 1.0 if i == m else 0.0
                dlm = 1.0 if l == m else 0.0
                yww[i, l, m] = (2.0 * dga * dlm * x[i] + 4.0 * ddga * w[l] * w[m] * x[i]
                                + 2.0 * dal * dlm * cr[i] + 4.0 * ddal * w[l] * w[m] * cr[i]
                                - 2.0 * dal * (w[l] * X[i, m] + w[m] * X[i, l])
                                + 2.0 * dbe * (x[m] * w[i] * w[l] + w[m] * w[i] * x[l])
                                + 2.0 * dbe * wx * (dim * w[l] + dil * w[m] + w[i] * dlm)
                                + 4.0 * ddbe * wx * w[i] * w[l] * w[m]
                                + be * (dim * x[l] + dil * x[m]))
                # ∂(−α x̂_il)/∂x_m = −α ε_iml = α ε_ilm, and ε_ilm = −(ê_m)_il
                ywx[i, l, m] = (2.0 * dga * w[l] * dim + 2.0 * dal * w[l] * W[i, m] + al * _EPS[i, l, m]
                                + 2.0 * dbe * w[m] * w[i] * w[l] + be * w[i] * dlm + be * w[m] * dil)
