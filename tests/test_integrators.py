"""Time integration (issue 3): oscillators and the pendulum against exact periods and conservation laws."""
import math

import numpy as np
import pytest
from scipy.special import ellipj, ellipk, gamma

import skfem_flex as sf

from helpers import crossing_times


def quartic_period(m=1.0, k=1.0, u0=1.0):
    """Exact period of m ü + 2 k u³ = 0 from rest at u0: T = 4 ∫ du / sqrt(2(E − V)/m), V = ½ k u⁴.

    With s = u/u0: T = 4 sqrt(m/k)/u0 · ∫₀¹ (1 − s⁴)^(−1/2) ds = sqrt(m/k)/u0 · Γ(1/4) √π / Γ(3/4).
    """
    return math.sqrt(m / k) / u0 * gamma(0.25) * math.sqrt(math.pi) / gamma(0.75)


def pendulum_period(length, v0, g):
    """Exact large-amplitude period 4 sqrt(l/g) K(sin²(θ0/2)) with 1 − cos θ0 = v0²/(2 g l)."""
    cos0 = 1.0 - v0 ** 2 / (2.0 * g * length)
    k2 = (1.0 - cos0) / 2.0          # sin²(θ0/2)
    return 4.0 * math.sqrt(length / g) * ellipk(k2)


def measured_period(res, coordinate=0):
    tc = crossing_times(res.t, res.q[:, coordinate], res.v[:, coordinate])
    return (tc[-1] - tc[0]) / (len(tc) - 1)


@pytest.mark.parametrize("fraction", [20, 4])
def test_quartic_energy_conserved_over_10000_steps(fraction):
    period = quartic_period()
    dt = period / fraction
    res = sf.simulate(sf.scenes.spring_mass(exponent=2), t_end=10000 * dt, dt=dt)
    assert res.steps == 10000
    e0 = res.total_energy[0]
    assert e0 == pytest.approx(0.5)
    assert np.max(np.abs(res.total_energy - e0)) / e0 < 1e-10


def test_quartic_period_converges_at_order_two():
    period = quartic_period()
    errors = []
    fractions = [20, 40, 80, 160]
    for f in fractions:
        dt = period / f
        res = sf.simulate(sf.scenes.spring_mass(exponent=2), t_end=6 * period, dt=dt)
        errors.append(abs(measured_period(res) - period))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 2.0) < 0.1), rates


def test_linear_oscillator_trapezoidal_equals_energy_scheme():
    scene = sf.scenes.spring_mass(exponent=1)
    dt = 0.3
    em = sf.simulate(scene, t_end=60, dt=dt, integrator="energy-momentum")
    tr = sf.simulate(scene, t_end=60, dt=dt, integrator="trapezoidal")
    np.testing.assert_allclose(em.q, tr.q, atol=1e-12)
    np.testing.assert_allclose(em.v, tr.v, atol=1e-12)
    for res in (em, tr):
        assert np.max(np.abs(res.total_energy - 0.5)) < 1e-12


def test_generalized_alpha_dissipates_linear_oscillator():
    scene = sf.scenes.spring_mass(exponent=1)
    # a coarse step (ω Δt = 2) sits where ρ∞ < 1 damps noticeably
    res = sf.simulate(scene, t_end=200, dt=2.0, integrator="generalized-alpha", rho_inf=0.5)
    e = res.total_energy
    assert e[-1] < 0.5 * e[0]
    # the algorithmic energy of the linear scheme never grows (stable, dissipative)
    assert np.all(np.diff(e[::2]) <= 1e-12)
    undamped = sf.simulate(scene, t_end=200, dt=2.0, integrator="generalized-alpha", rho_inf=1.0)
    assert undamped.total_energy[-1] > e[-1]


@pytest.mark.parametrize("dt", [0.01, 0.05])
def test_pendulum_constraint_and_energy(dt):
    res = sf.simulate(sf.scenes.pendulum(), t_end=10.0, dt=dt)
    assert np.max(res.constraint_residual) <= 1e-10
    e0 = res.total_energy[0]
    scale = res.kinetic[0]               # m v0²/2, the energy that moves
    assert np.max(np.abs(res.total_energy - e0)) / scale <= 1e-10
    # the rod is always in tension: λ never vanishes
    assert np.min(np.abs(res.lam[:, 0])) > 1.0


def test_pendulum_period_converges_to_elliptic_integral():
    length, v0, g = 0.5, 1.695, 9.81
    period = pendulum_period(length, v0, g)
    errors = []
    for dt in [0.02, 0.01, 0.005]:
        res = sf.simulate(sf.scenes.pendulum(length, 1.0, v0, g), t_end=5 * period, dt=dt)
        errors.append(abs(measured_period(res) - period))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 2.0) < 0.15), (errors, rates)
    assert errors[-1] / period < 1e-3


def pendulum_position(t, length, v0, g):
    """Exact motion of the pendulum started at the bottom with horizontal speed v0:
    sin(θ/2) = k sn(√(g/l) t | k²), k = v0 / (2√(g l)); position l (sin θ, −cos θ)."""
    k = v0 / (2.0 * math.sqrt(g * length))
    sn = ellipj(math.sqrt(g / length) * np.asarray(t), k * k)[0]
    theta = 2.0 * np.arcsin(k * sn)
    return length * np.stack([np.sin(theta), -np.cos(theta)], axis=-1)


def test_trapezoidal_keeps_the_pendulum_at_velocity_level():
    """Index-2 trapezoidal rule (velocity-level constraints) on the pendulum over 10 s (≈ 7 periods).

    The established C++ code's index-2 trapezoidal rule, run on the same problem, gives 4.623e-3 m
    (largest error over the run) and 6.6e-4 m (at t = 10 s) at Δt = 0.01 s: the O(Δt²) phase error
    any second-order scheme has (the energy scheme: 3.0e-3). Positions drift off the constraint by a
    bounded O(Δt²) amount; the index-3 form of the same rule loses the pendulum (error 0.9 m).
    """
    length, v0, g = 0.5, 1.695, 9.81
    errors, drifts = [], []
    for dt in (0.01, 0.005):
        res = sf.simulate(sf.scenes.pendulum(length, 1.0, v0, g), t_end=10.0, dt=dt, integrator="trapezoidal")
        assert res.completed and res.halvings == 0
        err = np.linalg.norm(res.probes["position"] - pendulum_position(res.t, length, v0, g), axis=1)
        errors.append(err.max())
        if dt == 0.01:
            assert err[-1] <= 2e-3
            assert err.max() <= 5e-3
        assert np.max(res.velocity_constraint_residual) <= 1e-12 * v0 * length
        half = res.t.size // 2
        drift = res.constraint_residual
        assert drift[half:].max() <= 1.01 * drift[:half].max()      # bounded, not growing
        drifts.append(drift.max())
    assert abs(math.log2(errors[0] / errors[1]) - 2.0) < 0.1        # second order
    assert abs(math.log2(drifts[0] / drifts[1]) - 2.0) < 0.1


def test_pendulum_generalized_alpha_reports_velocity_residual():
    res = sf.simulate(sf.scenes.pendulum(), t_end=1.0, dt=0.01, integrator="generalized-alpha")
    assert np.max(res.constraint_residual) <= 1e-10
    # position-level constraints leave a small, nonzero velocity-level residual
    assert 0.0 < np.max(res.velocity_constraint_residual[1:]) < 1e-2


def test_escaping_motion_is_reported_not_nan():
    """Exponent 1.5: V = ½ k u³ is unbounded below; the motion escapes to −∞ in finite time."""
    with pytest.raises(sf.ConvergenceError) as info:
        sf.simulate(sf.scenes.spring_mass(exponent=1.5), t_end=20.0, dt=0.05)
    msg = str(info.value)
    assert "energy-momentum" in msg and "t = " in msg and "step" in msg and "iterations" in msg
    res = info.value.result
    assert res is not None and not res.completed
    assert np.all(np.isfinite(res.q)) and np.all(np.isfinite(res.total_energy))
    assert res.q[-1, 0] < -100.0                      # it did escape
    # energy held while escaping (relative to the kinetic energy reached)
    assert abs(res.total_energy[-1] - 0.5) / res.kinetic[-1] < 1e-10


@pytest.mark.parametrize("kwargs, word", [
    (dict(dt=0.0), "dt"), (dict(dt=-1.0), "dt"), (dict(dt=float("nan")), "dt"),
    (dict(t_end=-1.0), "t_end"), (dict(integrator="euler"), "euler"),
    (dict(integrator="generalized-alpha", rho_inf=1.5), "rho_inf"),
    (dict(integrator="generalized-alpha", rho_inf=-0.1), "rho_inf"),
])
def test_bad_simulation_arguments(kwargs, word):
    args = dict(t_end=1.0, dt=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=word):
        sf.simulate(sf.scenes.spring_mass(), **args)


def test_nan_initial_state_rejected():
    with pytest.raises(ValueError, match="finite"):
        sf.scenes.spring_mass(u0=float("nan"))
    with pytest.raises(ValueError, match="finite"):
        sf.scenes.pendulum(v0=float("nan"))


def test_inconsistent_initial_state_rejected():
    body = sf.PointMass(1.0, [0.0, -0.6], [1.0, 0.0])
    scene = sf.Scene([body], constraints=[sf.Distance(body, (0, 0), 0.5)])
    with pytest.raises(ValueError, match="inconsistent"):
        sf.simulate(scene, 1.0, 0.01)


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
def test_newmark_converges_where_the_acceleration_nearly_cancels(scheme):
    """Regression: near u = 0 the net inertia force of the quartic oscillator is tiny while the
    terms forming the Newmark acceleration are O(1); the residual scale must come from those
    terms, or Newton stalls at round-off and the run fails (it did at t ≈ 77 s)."""
    period = quartic_period()
    res = sf.simulate(sf.scenes.spring_mass(exponent=2), t_end=1000 * period / 50, dt=period / 50, integrator=scheme)
    assert res.completed and res.halvings == 0
    assert np.max(res.newton_iterations) <= 4


def test_scheme_objects_carry_their_parameters():
    """A scheme object is used as given; a second copy of its parameters beside it is refused, not ignored."""
    scene = sf.scenes.get("pendulum")()
    by_object = sf.simulate(scene, 0.2, 1e-2, integrator=sf.GeneralizedAlpha(rho_inf=0.6))
    by_name = sf.simulate(scene, 0.2, 1e-2, integrator="generalized-alpha", rho_inf=0.6)
    np.testing.assert_array_equal(by_object.q, by_name.q)
    with pytest.raises(ValueError, match="rho_inf=0.5 given with the scheme object GeneralizedAlpha"):
        sf.simulate(scene, 0.2, 1e-2, integrator=sf.GeneralizedAlpha(rho_inf=0.8), rho_inf=0.5)


# ------------------------------------------------------------------ the energy-momentum step's Newton start
def test_predicted_increment_is_third_order_and_falls_back_on_unresolved_steps():
    """Δq⁰ = Δt v0 + ½ Δt² a0 with a0 the last step's mean acceleration misses the exact increment of a
    smooth motion by O(Δt³) (Δt v0 alone: O(Δt²)); a step with ½ Δt ‖a0‖ > PREDICTOR_LIMIT ‖v0‖ starts
    from Δt v0."""
    from skfem_flex.numerics.newton import PREDICTOR_LIMIT, predicted_increment

    def q(t):
        return np.array([np.sin(t), 2.0 * np.cos(0.5 * t), 0.3 * t])

    def v(t):
        return np.array([np.cos(t), -np.sin(0.5 * t), 0.3])

    free = np.array([0, 1], dtype=np.int64)
    errors, plain = [], []
    for h in (0.1, 0.05, 0.025):
        a0 = (v(1.0) - v(1.0 - h)) / h
        out = np.empty(2)
        predicted_increment(v(1.0), a0, h, free, out)
        exact = (q(1.0 + h) - q(1.0))[free]
        errors.append(np.abs(out - exact).max())
        plain.append(np.abs(h * v(1.0)[free] - exact).max())
    assert np.allclose(np.log2(np.array(errors[:-1]) / errors[1:]), 3.0, atol=0.15), errors
    assert np.allclose(np.log2(np.array(plain[:-1]) / plain[1:]), 2.0, atol=0.15), plain
    v0, h = np.array([1.0, -2.0, 0.0]), 0.1
    out = np.empty(2)
    for scale, expected_c in ((0.99, 0.5 * h * h), (1.01, 0.0)):      # ½ h ‖a0‖∞ just below / above the limit
        a0 = np.array([0.0, -scale * PREDICTOR_LIMIT * 2.0 / (0.5 * h), 1e9])   # coordinate 2 is not free
        predicted_increment(v0, a0, h, free, out)
        np.testing.assert_allclose(out, h * v0[free] + expected_c * a0[free], rtol=1e-15)


@pytest.mark.parametrize("compiled", [True, False])
def test_predictor_saves_a_newton_iteration_on_the_pendulum(compiled):
    """The rigid pendulum at Δt = 0.01 s takes two Newton iterations per step with the predicted start, on
    both paths (from Δt v0 it took 2.9); the run still keeps the energy to the Newton tolerance."""
    res = sf.simulate(sf.scenes.pendulum(), t_end=2.0, dt=1e-2, compiled=compiled)
    assert res.newton_iterations[1:].mean() <= 2.1
    e = res.total_energy - res.external_work
    assert np.abs(e - e[0]).max() <= 1e-10 * abs(res.kinetic).max()


def test_each_scheme_carries_its_own_state():
    """Energy-momentum carries State (no algorithmic acceleration), the Newmark family NewmarkState with
    generalized-α's a (equal to q̈ at the start); a Newmark step refuses a state without it."""
    import skfem_flex as sf
    from skfem_flex.schemes.base import NewmarkState, State
    from skfem_flex.schemes.stepper import Stepper
    scene = sf.scenes.get("pendulum")()
    q, v = scene.initial_state()
    em = Stepper(scene, sf.EnergyMomentum()).starting_state(State(0.0, q, v))
    assert type(em) is State and not hasattr(em, "pseudo")
    for scheme in (sf.GeneralizedAlpha(rho_inf=0.8), sf.Trapezoidal()):
        stepper = Stepper(scene, scheme)
        s0 = stepper.starting_state(State(0.0, q, v))
        assert type(s0) is NewmarkState and np.array_equal(s0.pseudo, s0.acc)
        s1, _ = stepper.step(s0, 1e-3)
        assert type(s1) is NewmarkState
        with pytest.raises(ValueError, match="NewmarkState"):
            stepper.step(em, 1e-3)
    assert np.array_equal(em.acc, s0.acc)             # the same consistent start


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_every_scheme_refuses_a_turn_it_cannot_resolve(scheme):
    """A free body spinning at 100 rad/s, stepped at 0.05 s (5 rad per step, beyond 0.9π): every scheme refuses
    the step (a Newton root there is no resolved rotation; under generalized-α a converged spurious root
    once flipped a joint) and halves it once; the spin is then exact (θ = ω t: free rotation)."""
    import skfem_flex as sf
    body = sf.RigidBody(mass=1.0, inertia=0.1, angular_velocity=100.0, name="spinner")
    res = sf.simulate(sf.Scene([body]), t_end=0.2, dt=0.05, scheme=scheme)
    assert res.halvings == 4 and res.completed
    np.testing.assert_allclose(res.q[:, 2], 100.0 * res.t, rtol=1e-12, atol=1e-9)
