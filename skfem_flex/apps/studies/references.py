"""Exact references of the studies: periods of the quartic oscillator and the pendulum, the pendulum's
exact motion, zero crossings, and the error functions a study measures a run with."""
from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import ellipj, ellipk, gamma

__all__ = ["oscillator_period", "pendulum_period", "pendulum_position", "upward_crossings", "period_error",
           "history_error"]


def oscillator_period(exponent=2.0, m=1.0, k=1.0, u0=1.0):
    """Exact period of m ü + n k u^(2n−1) = 0 from rest at u0 > 0 (V = ½ k u^(2n), 2n even).

    T = 4 ∫₀^u0 du / sqrt(2 (V(u0) − V(u))/m) = 4 sqrt(m/k) u0^(1−n) ∫₀¹ (1 − s^(2n))^(−1/2) ds,
    and ∫₀¹ (1 − s^p)^(−1/2) ds = Γ(1/p) Γ(1/2) / (p Γ(1/p + 1/2)).
    """
    p = 2.0 * exponent
    if abs(p - round(p)) > 1e-12 or round(p) % 2:
        raise ValueError(f"oscillator_period needs an even power 2n (bounded potential), got exponent {exponent!r}")
    integral = gamma(1.0 / p) * math.sqrt(math.pi) / (p * gamma(1.0 / p + 0.5))
    return 4.0 * math.sqrt(m / k) * u0 ** (1.0 - exponent) * integral


def pendulum_period(length=0.5, v0=1.695, g=9.81):
    """Exact period of a pendulum started at the bottom with speed v0: 4 sqrt(l/g) K(sin²(θ0/2))."""
    k2 = v0 ** 2 / (4.0 * g * length)          # sin²(θ0/2) = (1 − cos θ0)/2
    if k2 >= 1.0:
        raise ValueError(f"v0 = {v0} makes the pendulum go over the top: no period")
    return 4.0 * math.sqrt(length / g) * ellipk(k2)


def pendulum_position(t, length=0.5, v0=1.695, g=9.81):
    """Exact motion of the pendulum started at the bottom with horizontal speed v0, m.

    sin(θ/2) = k sn(√(g/l) t | k²) with k = v0 / (2√(g l)) (k < 1: it swings, never over the top);
    position l (sin θ, −cos θ), shape (len(t), 2).
    """
    k = v0 / (2.0 * math.sqrt(g * length))
    if k >= 1.0:
        raise ValueError(f"v0 = {v0} makes the pendulum go over the top: no swinging motion")
    theta = 2.0 * np.arcsin(k * ellipj(math.sqrt(g / length) * np.asarray(t, dtype=float), k * k)[0])
    return length * np.stack([np.sin(theta), -np.cos(theta)], axis=-1)


def upward_crossings(t, x, xdot):
    """Times at which x crosses zero upwards, by cubic Hermite interpolation within each step."""
    out = []
    for i in np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]:
        h = t[i + 1] - t[i]
        c = [x[i], xdot[i] * h, x[i + 1], xdot[i + 1] * h]
        # Hermite cubic in s ∈ [0, 1] written as a polynomial, roots by numpy
        poly = np.array([2 * c[0] + c[1] - 2 * c[2] + c[3], -3 * c[0] - 2 * c[1] + 3 * c[2] - c[3], c[1], c[0]])
        roots = [r.real for r in np.roots(poly) if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
        if roots:
            out.append(t[i] + min(roots) * h)
    return np.array(out)


def period_error(exact, coordinate=0):
    """An error function: |measured mean period − exact| / exact from upward zero crossings."""
    def err(result):
        tc = upward_crossings(result.t, result.q[:, coordinate], result.v[:, coordinate])
        if tc.size < 2:
            return float("nan")
        return abs((tc[-1] - tc[0]) / (tc.size - 1) - exact) / exact
    return err


def history_error(reference, probe):
    """An error function: max over time of |probe − reference| / max |reference|.

    ``reference`` is a Result (interpolated with cubic splines onto the
    run's times) or a callable t -> value.
    """
    if callable(reference):
        ref_fn = reference
    else:
        ref_fn = CubicSpline(reference.t, reference.probes[probe], axis=0)

    def err(result):
        ref = np.asarray(ref_fn(result.t))
        val = result.probes[probe]
        return float(np.max(np.abs(val - ref)) / max(np.max(np.abs(ref)), 1e-300))
    return err
