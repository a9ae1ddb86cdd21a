"""User-defined elements: a body written by the user (a subclass of ``skfem_flex.bodies.base.Body``)
and a constraint given by callables (``UserConstraint``), run through ``simulate`` with each scheme.

The bodies below implement the body contract themselves (docs/user_elements.md):

* ``MorseParticle``: a planar particle in Cartesian coordinates tied to a ground anchor by a Morse
  spring V(ρ) = D (1 − exp(−a (ρ − l)))², ρ = |x − anchor|, with its own exact discrete gradient
  (a divided difference of V in ρ times the exact discrete gradient (x0 + x1)/(ρ0 + ρ1) of ρ);
  constant mass, positions linear in q (gravity from ``mass_moment``), its own ``BodyPoint``.
* ``PolarParticle``: the same particle in polar coordinates (r, θ): a variable mass matrix
  diag(m, m r²) with its kinetic discrete gradient, momentum Jacobian and quadratic velocity
  forces, the Morse spring in r, and gravity, which is not linear in (r, θ), through its own
  ``gravity_potential`` and exact ``gravity_discrete_gradient``.

References are independent of the user code where possible: the built-in pendulum scene, the
built-in PointMass, the exact period of the Morse oscillator, and the Cartesian body against the
polar one (same motion in other coordinates).
"""
import math

import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.bodies.base import Body, BodyGeometry, BodyPoint
from skfem_flex.bodies.rigid import RigidBody
from skfem_flex.elements.constraints import Pin, Revolute, UserConstraint

from helpers import crossing_times

SCHEMES = ["energy-momentum", "trapezoidal", "generalized-alpha"]
G = 9.81


# ------------------------------------------------------------------ the user's bodies
def morse(rho, depth, width, rest):
    """V, V′, V″ of the Morse potential D (1 − e^{−a(ρ − l)})²."""
    e = np.exp(-width * (rho - rest))
    return depth * (1.0 - e) ** 2, 2.0 * depth * width * e * (1.0 - e), 2.0 * depth * width ** 2 * e * (2.0 * e - 1.0)


def divided_difference(f, x0, x1):
    """s = (F(x1) − F(x0))/(x1 − x0) and ∂s/∂x1 for ``f(x) -> (F, F′, F″)`` (limits when x1 ≈ x0)."""
    dx = x1 - x0
    if abs(dx) > 1e-6 * max(abs(x0), abs(x1), 1.0):
        s = (f(x1)[0] - f(x0)[0]) / dx
        return s, (f(x1)[1] - s) / dx
    _, d1, d2 = f(0.5 * (x0 + x1))           # the error O(dx²) of these is far below round-off here
    return d1, 0.5 * d2


class MorseParticle(Body):
    """Planar particle (x, y) of mass m on a Morse spring to ``anchor`` (no spring when depth = 0)."""

    constant_mass = True

    def __init__(self, mass, position, velocity=(0.0, 0.0), depth=0.0, width=1.0, rest=1.0, anchor=(0.0, 0.0),
                 name="morse particle"):
        self.mass = float(mass)
        self.q0 = np.array(position, dtype=float)
        self.v0 = np.array(velocity, dtype=float)
        self.n_dofs = 2
        self.name = name
        self.depth, self.width, self.rest = float(depth), float(width), float(rest)
        self.anchor = np.array(anchor, dtype=float)
        self.has_potential = self.depth > 0.0

    @property
    def coordinate_names(self):
        return ("x", "y")

    def mass_matrix(self, q):
        return self.mass * np.eye(2)

    def _v(self, rho):
        return morse(rho, self.depth, self.width, self.rest)

    def potential_energy(self, q):
        return float(self._v(np.linalg.norm(q - self.anchor))[0])

    def potential_gradient(self, q):
        d = q - self.anchor
        rho = np.linalg.norm(d)
        return self._v(rho)[1] * d / rho

    def potential_hessian(self, q):
        d = q - self.anchor
        rho = np.linalg.norm(d)
        n = d / rho
        _, d1, d2 = self._v(rho)
        return d2 * np.outer(n, n) + d1 / rho * (np.eye(2) - np.outer(n, n))

    def potential_discrete_gradient(self, q0, q1):
        d0, d1 = q0 - self.anchor, q1 - self.anchor
        r0, r1 = np.linalg.norm(d0), np.linalg.norm(d1)
        w = (d0 + d1) / (r0 + r1)                    # w · (q1 − q0) = ρ1 − ρ0 exactly
        s, ds = divided_difference(self._v, r0, r1)   # s (ρ1 − ρ0) = V(ρ1) − V(ρ0)
        n1 = d1 / r1
        jac = ds * np.outer(w, n1) + s * (np.eye(2) - np.outer(w, n1)) / (r0 + r1)
        return s * w, jac

    def mass_moment(self):
        return self.mass * np.eye(2), np.zeros(2)       # ∫ r dm = m q

    def linear_momentum(self, q, v):
        return self.mass * v

    def angular_momentum(self, q, v):
        return self.mass * float(q[0] * v[1] - q[1] * v[0])

    def point(self, locator=None):
        if locator is not None:
            raise ValueError(f"{self.name!r} has a single point; got locator {locator!r}")
        return ParticlePoint(self)

    def geometry(self, q, v):
        return BodyGeometry(np.array([q]), [("vertex", np.array([[0]]))], {"velocity": np.array([v])})


class ParticlePoint(BodyPoint):
    """The particle itself: r = q (linear, so the discrete gradient is the identity)."""

    def __init__(self, body):
        self.body = body

    def position(self, q):
        return np.array(q, dtype=float)

    def position_jacobian(self, q):
        return np.eye(2)

    def position_hessian_product(self, q, f):
        return np.zeros((2, 2))

    def position_discrete_gradient(self, q0, q1):
        return np.eye(2)

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return np.zeros((2, 2))


class PolarParticle(Body):
    """Particle in polar coordinates (r, θ) about the origin: M = diag(m, m r²), Morse spring in r."""

    constant_mass = False

    def __init__(self, mass, r, theta, rdot=0.0, thetadot=0.0, depth=0.0, width=1.0, rest=1.0,
                 name="polar particle"):
        self.mass = float(mass)
        self.q0 = np.array([r, theta], dtype=float)
        self.v0 = np.array([rdot, thetadot], dtype=float)
        self.n_dofs = 2
        self.name = name
        self.depth, self.width, self.rest = float(depth), float(width), float(rest)
        self.has_potential = self.depth > 0.0

    @property
    def coordinate_names(self):
        return ("r", "theta")

    # kinetic: T = ½ m (ṙ² + r² θ̇²)
    def mass_matrix(self, q):
        return self.mass * np.diag([1.0, q[0] ** 2])

    def kinetic_energy(self, q, v):
        return 0.5 * self.mass * (v[0] ** 2 + q[0] ** 2 * v[1] ** 2)

    def momentum(self, q, v):
        return self.mass * np.array([v[0], q[0] ** 2 * v[1]])

    def momentum_jacobian(self, q, v):
        return self.mass * np.array([[0.0, 0.0], [2.0 * q[0] * v[1], 0.0]])

    def quadratic_velocity_force(self, q, v):
        m, r, vr, vt = self.mass, q[0], v[0], v[1]
        f = m * np.array([r * vt ** 2, -2.0 * r * vr * vt])          # ∂T/∂q − Ṁ v
        fq = m * np.array([[vt ** 2, 0.0], [-2.0 * vr * vt, 0.0]])
        fv = m * np.array([[0.0, 2.0 * r * vt], [-2.0 * r * vt, -2.0 * r * vr]])
        return f, fq, fv

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        # G(q) = ½ v0ᵀ M(q) v1 = ½ m (ṙ0 ṙ1 + r² θ̇0 θ̇1): quadratic in r, so the mean gradient is exact
        m, c = self.mass, 0.5 * self.mass * v0[1] * v1[1]
        g = np.array([c * (q0[0] + q1[0]), 0.0])
        return g, np.array([[c, 0.0], [0.0, 0.0]]), np.array([[0.0, 0.5 * m * v0[1] * (q0[0] + q1[0])], [0.0, 0.0]])

    # strain energy: the Morse spring in r
    def _v(self, r):
        return morse(r, self.depth, self.width, self.rest)

    def potential_energy(self, q):
        return float(self._v(q[0])[0])

    def potential_gradient(self, q):
        return np.array([self._v(q[0])[1], 0.0])

    def potential_hessian(self, q):
        return np.array([[self._v(q[0])[2], 0.0], [0.0, 0.0]])

    def potential_discrete_gradient(self, q0, q1):
        s, ds = divided_difference(self._v, q0[0], q1[0])
        return np.array([s, 0.0]), np.array([[ds, 0.0], [0.0, 0.0]])

    # gravity: V = −m g · r (cos θ, sin θ), not linear in q
    def mass_moment(self):
        raise NotImplementedError("positions are not linear in (r, theta)")

    def gravity_potential(self, q, g):
        m, r, c, s = self.mass, q[0], np.cos(q[1]), np.sin(q[1])
        h, dh = g[0] * c + g[1] * s, -g[0] * s + g[1] * c
        return -m * r * h, -m * np.array([h, r * dh]), -m * np.array([[0.0, dh], [dh, -r * h]])

    def gravity_discrete_gradient(self, q0, q1, g):
        def h(t):                                       # h(θ) = g · (cos θ, sin θ) with h′, h″
            c, s = np.cos(t), np.sin(t)
            return g[0] * c + g[1] * s, -g[0] * s + g[1] * c, -(g[0] * c + g[1] * s)

        rbar = 0.5 * (q0[0] + q1[0])
        hbar = 0.5 * (h(q0[1])[0] + h(q1[1])[0])
        k, dk = divided_difference(h, q0[1], q1[1])     # k Δθ = h(θ1) − h(θ0)
        # Δ(r h) = h̄ Δr + r̄ k Δθ exactly
        grad = -self.mass * np.array([hbar, rbar * k])
        jac = -self.mass * np.array([[0.0, 0.5 * h(q1[1])[1]], [0.5 * k, rbar * dk]])
        return grad, jac

    def linear_momentum(self, q, v):
        c, s = np.cos(q[1]), np.sin(q[1])
        return self.mass * np.array([v[0] * c - q[0] * s * v[1], v[0] * s + q[0] * c * v[1]])

    def angular_momentum(self, q, v):
        return self.mass * q[0] ** 2 * v[1]

    def geometry(self, q, v):
        return BodyGeometry(np.array([[q[0] * np.cos(q[1]), q[0] * np.sin(q[1])]]), [("vertex", np.array([[0]]))])


def cartesian(q_polar):
    return np.c_[q_polar[:, 0] * np.cos(q_polar[:, 1]), q_polar[:, 0] * np.sin(q_polar[:, 1])]


def balance_error(res):
    """max |E(t) − E(0) − W(t)| relative to the energy scale max(|T|, |V|) of the run."""
    e = res.total_energy - res.total_energy[0] - res.external_work
    scale = max(np.max(np.abs(res.kinetic)), np.max(np.abs(res.potential)))
    return np.max(np.abs(e)) / scale


MORSE = dict(depth=1.0, width=4.0, rest=1.0)


# ------------------------------------------------------------------ the contract, checked directly
def test_user_bodies_satisfy_the_contract():
    """Discrete gradients exact (g·Δq = ΔV), derivatives equal to finite differences."""
    rng = np.random.default_rng(1)
    g = np.array([0.3, -9.81])
    cart = MorseParticle(1.3, [1.1, 0.2], **MORSE)
    polar = PolarParticle(1.3, 1.1, 0.4, **MORSE)
    for _ in range(5):
        q0 = np.array([1.0, 0.3]) + 0.3 * rng.random(2)
        q1 = q0 + 0.2 * rng.standard_normal(2)
        v0, v1 = rng.standard_normal(2), rng.standard_normal(2)
        for body in (cart, polar):
            gp, _ = body.potential_discrete_gradient(q0, q1)
            assert abs(gp @ (q1 - q0) - (body.potential_energy(q1) - body.potential_energy(q0))) <= 1e-14
            gg, _ = body.gravity_discrete_gradient(q0, q1, g)
            dv = body.gravity_potential(q1, g)[0] - body.gravity_potential(q0, g)[0]
            assert abs(gg @ (q1 - q0) - dv) <= 1e-13
            # derivatives against central differences
            h = 1e-6
            for k in range(2):
                e = np.zeros(2)
                e[k] = h
                fd = (body.potential_energy(q0 + e) - body.potential_energy(q0 - e)) / (2 * h)
                assert body.potential_gradient(q0)[k] == pytest.approx(fd, abs=1e-8)
                fd = (body.potential_gradient(q0 + e) - body.potential_gradient(q0 - e)) / (2 * h)
                np.testing.assert_allclose(body.potential_hessian(q0)[:, k], fd, atol=1e-6)
                fd = (body.potential_discrete_gradient(q0, q1 + e)[0]
                      - body.potential_discrete_gradient(q0, q1 - e)[0]) / (2 * h)
                np.testing.assert_allclose(body.potential_discrete_gradient(q0, q1)[1][:, k], fd, atol=1e-6)
                fd = (body.gravity_discrete_gradient(q0, q1 + e, g)[0]
                      - body.gravity_discrete_gradient(q0, q1 - e, g)[0]) / (2 * h)
                np.testing.assert_allclose(body.gravity_discrete_gradient(q0, q1, g)[1][:, k], fd, atol=1e-6)
        # the variable-mass terms of the polar body
        gk, gq, gv = polar.kinetic_discrete_gradient(q0, q1, v0, v1)

        def big_g(q):
            return 0.5 * v0 @ polar.mass_matrix(q) @ v1

        assert abs(gk @ (q1 - q0) - (big_g(q1) - big_g(q0))) <= 1e-14
        h = 1e-6
        for k in range(2):
            e = np.zeros(2)
            e[k] = h
            fd = (polar.momentum(q0 + e, v0) - polar.momentum(q0 - e, v0)) / (2 * h)
            np.testing.assert_allclose(polar.momentum_jacobian(q0, v0)[:, k], fd, atol=1e-7)
            fd = (polar.kinetic_discrete_gradient(q0, q1 + e, v0, v1)[0]
                  - polar.kinetic_discrete_gradient(q0, q1 - e, v0, v1)[0]) / (2 * h)
            np.testing.assert_allclose(gq[:, k], fd, atol=1e-7)
            fd = (polar.kinetic_discrete_gradient(q0, q1, v0, v1 + e)[0]
                  - polar.kinetic_discrete_gradient(q0, q1, v0, v1 - e)[0]) / (2 * h)
            np.testing.assert_allclose(gv[:, k], fd, atol=1e-7)
        # Q_v = ∂T/∂q − Ṁ v, with Ṁ v = B(q, v) v
        e = np.eye(2) * h
        dtdq = [(polar.kinetic_energy(q0 + e[k], v0) - polar.kinetic_energy(q0 - e[k], v0)) / (2 * h) for k in range(2)]
        np.testing.assert_allclose(polar.quadratic_velocity_force(q0, v0)[0],
                                   np.array(dtdq) - polar.momentum_jacobian(q0, v0) @ v0, atol=1e-7)


# ------------------------------------------------------------------ (a) a user body alone, nonlinear potential
@pytest.mark.parametrize("scheme", SCHEMES)
def test_user_body_alone_on_a_morse_spring(scheme):
    """An orbit on the Morse spring, in Cartesian and in polar coordinates (variable mass)."""
    r0, vr, vt = 1.1, 0.3, 0.9
    cart = sf.simulate(sf.Scene([MorseParticle(1.0, [r0, 0.0], [vr, vt], **MORSE)]), 3.0, 0.01, integrator=scheme)
    polar = sf.simulate(sf.Scene([PolarParticle(1.0, r0, 0.0, vr, vt / r0, **MORSE)]), 3.0, 0.01, integrator=scheme)
    for res in (cart, polar):
        assert res.completed and res.steps == 300
        # the two coordinate choices integrate the same motion: they agree to the O(Δt²) error
        # (measured 3e-5 for every scheme at Δt = 0.01 s)
    np.testing.assert_allclose(cartesian(polar.q), cart.q, atol=2e-4)
    # the orbit really is nonlinear: the spring stretches and compresses over much of its well
    assert np.ptp(np.hypot(*cart.q.T)) > 0.1
    if scheme == "energy-momentum":
        for res in (cart, polar):
            assert balance_error(res) <= 1e-10        # measured 5e-15 (Cartesian), 2e-14 (polar)
            # a central force: the discrete gradients are central too, so L is kept to round-off
            assert np.max(np.abs(res.angular_momentum - res.angular_momentum[0])) <= 1e-12
    else:
        for res in (cart, polar):
            assert balance_error(res) <= 1e-3         # measured 7e-5 – 9e-5: not exact, but close


def test_morse_oscillator_period_is_the_exact_one():
    """Radial oscillation at half the well depth: T = 2π/(ω0 √(1 − E/D)), ω0 = a √(2D/m) (exact, any E)."""
    m, energy = 1.0, 0.5
    d, a, l = MORSE["depth"], MORSE["width"], MORSE["rest"]
    period = 2.0 * math.pi / (a * math.sqrt(2.0 * d / m) * math.sqrt(1.0 - energy / d))
    errors = []
    for fraction in (100, 200):
        body = MorseParticle(m, [l, 0.0], [math.sqrt(2.0 * energy / m), 0.0], **MORSE)
        res = sf.simulate(sf.Scene([body]), 3.2 * period, period / fraction)
        assert balance_error(res) <= 1e-10
        assert np.max(np.abs(res.q[:, 1])) == 0.0                     # stays on its line
        tc = crossing_times(res.t, res.q[:, 0] - l, res.v[:, 0])
        errors.append(abs((tc[-1] - tc[0]) / (len(tc) - 1) - period) / period)
    # measured 4.6e-4 and 1.2e-4: second order, to the exact anharmonic period
    assert errors[0] < 1e-3
    assert 3.6 < errors[0] / errors[1] < 4.4


# ------------------------------------------------------------------ (b) a user constraint
def rod(body, length):
    """The Cartesian rod ½(|x|² − l²) = 0 as a UserConstraint (no hessian_product: central differences)."""
    return UserConstraint([body], lambda q, t: [0.5 * (q @ q - length ** 2)], lambda q, t: q[None, :], name="rod")


def polar_rod(body, length):
    """½(r² − l²) = 0 on the polar body, with its exact hessian_product."""
    return UserConstraint([body], lambda q, t: [0.5 * (q[0] ** 2 - length ** 2)], lambda q, t: np.array([[q[0], 0.0]]),
                          hessian_product=lambda q, mu, t: mu[0] * np.diag([1.0, 0.0]), name="rod")


@pytest.mark.parametrize("scheme", SCHEMES)
def test_user_constraint_holds_a_user_body_like_the_builtin_pendulum(scheme):
    length, v0 = 0.5, 1.695
    ref = sf.simulate(sf.scenes.pendulum(length, 1.0, v0, G), 3.0, 0.01, integrator=scheme)
    body = MorseParticle(1.0, [0.0, -length], [v0, 0.0])
    res = sf.simulate(sf.Scene([body], [rod(body, length)], [sf.Gravity((0.0, -G))]), 3.0, 0.01, integrator=scheme)
    assert res.steps == 300
    # the same equations as PointMass + Distance: the same trajectory (measured ≤ 7e-15)
    np.testing.assert_allclose(res.q, ref.q, atol=1e-9)
    np.testing.assert_allclose(res.v, ref.v, atol=1e-9)
    np.testing.assert_allclose(res.lam, ref.lam, rtol=1e-6)     # λ = μ/Δt: to the Newton tolerance
    if scheme == "trapezoidal":                                 # index 2: positions drift by O(Δt²)
        assert np.max(res.constraint_residual) <= 1e-4           # measured 3.6e-5
    else:
        assert np.max(res.constraint_residual) <= 1e-10
    if scheme == "energy-momentum":
        assert balance_error(res) <= 1e-10                      # measured 4e-14


@pytest.mark.parametrize("scheme", SCHEMES)
def test_user_constraint_holds_a_polar_user_body_under_its_own_gravity(scheme):
    """The pendulum in polar coordinates (variable mass, nonlinear gravity) converges at O(Δt²)
    to the built-in Cartesian pendulum."""
    length, v0 = 0.5, 1.695
    diffs = []
    for dt in ((0.01, 0.005) if scheme == "energy-momentum" else (0.01,)):
        body = PolarParticle(1.0, length, -math.pi / 2, 0.0, v0 / length)
        res = sf.simulate(sf.Scene([body], [polar_rod(body, length)], [sf.Gravity((0.0, -G))]), 3.0, dt,
                          integrator=scheme)
        ref = sf.simulate(sf.scenes.pendulum(length, 1.0, v0, G), 3.0, dt, integrator=scheme)
        diffs.append(np.max(np.abs(cartesian(res.q) - ref.q)))
        assert np.max(res.constraint_residual) <= 1e-10
        if scheme == "energy-momentum":
            assert balance_error(res) <= 1e-10                  # measured 1e-15, 5e-15
    # against the same scheme's built-in run, Δt = 0.01 s: measured 2.4e-4 (energy-momentum),
    # 6.6e-4 (trapezoidal: the Cartesian index-2 run drifts off the circle, the polar one cannot),
    # 7.9e-4 (generalized-α, its phase error differs between the two coordinate choices)
    assert diffs[0] < (5e-4 if scheme == "energy-momentum" else 2e-3)
    if len(diffs) == 2:
        assert 3.6 < diffs[0] / diffs[1] < 4.4                  # measured 4.0


# ------------------------------------------------------------------ (c) a user body on a built-in joint
def bar_and_bob(user=True, depth=2.0):
    """A bar pinned at one end; at the other, a Revolute to a bob (the user's particle on a Morse
    spring to the ground point (0.8, 0), or a built-in PointMass); gravity on both."""
    bar = RigidBody.bar(1.0, 0.6, angle=-0.3, angular_velocity=2.0, name="bar")
    tip = bar.point((0.3, 0.0))
    start = tip.position(bar.q0)
    if user:
        bob = MorseParticle(0.5, start, depth=depth, width=3.0, rest=0.5, anchor=(0.8, 0.0), name="bob")
    else:
        bob = sf.PointMass(0.5, start, name="bob")
    return sf.Scene([bar, bob], [Pin(bar.point((-0.3, 0.0)), name="pivot"), Revolute(tip, bob.point(), name="hinge")],
                    [sf.Gravity((0.0, -G))])


@pytest.mark.parametrize("scheme", SCHEMES)
def test_user_body_joined_to_a_builtin_body(scheme):
    res = sf.simulate(bar_and_bob(), 3.0, 0.01, integrator=scheme)
    assert res.steps == 300
    assert np.ptp(res.potential) > 1.0                       # the spring and gravity both work hard
    if scheme == "trapezoidal":
        assert np.max(res.constraint_residual) <= 1e-3       # measured 1e-4 (index 2)
    else:
        assert np.max(res.constraint_residual) <= 1e-10
    if scheme == "energy-momentum":
        assert balance_error(res) <= 1e-10                   # measured 8e-14
    else:
        assert balance_error(res) <= 1e-2                    # measured 1.1e-3, 1.3e-3
    # without the spring, the user's particle is a point mass: the same run as the built-in one
    # (measured: identical to the last bit)
    mine = sf.simulate(bar_and_bob(depth=0.0), 1.0, 0.01, integrator=scheme)
    builtin = sf.simulate(bar_and_bob(user=False), 1.0, 0.01, integrator=scheme)
    np.testing.assert_allclose(mine.q, builtin.q, atol=1e-12)
    np.testing.assert_allclose(mine.lam, builtin.lam, atol=1e-9)
    np.testing.assert_allclose(mine.total_energy, builtin.total_energy, atol=1e-12)


# ------------------------------------------------------------------ missing methods
class NoMass(Body):
    n_dofs = 2
    name = "no mass"

    def __init__(self):
        self.q0, self.v0 = np.zeros(2), np.ones(2)


def without(base, method):
    """A subclass of ``base`` that leaves ``method`` at the Body default (which raises, naming it)."""
    return type("No" + "".join(w.title() for w in method.split("_")), (base,), {method: getattr(Body, method)})


def polar(cls):
    return cls(1.0, 0.5, -1.0, 0.1, 1.0)


MISSING = {
    "mass_matrix": (lambda: NoMass(), "energy-momentum", (), r"mass_matrix\(q\)"),
    "kinetic_discrete_gradient": (lambda: polar(without(PolarParticle, "kinetic_discrete_gradient")), "energy-momentum", (), "kinetic_discrete_gradient"),
    "quadratic_velocity_force": (lambda: polar(without(PolarParticle, "quadratic_velocity_force")), "energy-momentum", (),
                                 "quadratic_velocity_force"),
    "momentum_jacobian": (lambda: polar(without(PolarParticle, "momentum_jacobian")), "trapezoidal", (), "momentum_jacobian"),
    # these two used to run on silently: zero internal force, and gravity frozen at the step's start
    "potential_discrete_gradient": (lambda: without(MorseParticle, "potential_discrete_gradient")(1.0, [1.1, 0.0], **MORSE), "energy-momentum", (),
                                    "potential_discrete_gradient.*has_potential = True"),
    "gravity_discrete_gradient": (lambda: polar(without(PolarParticle, "gravity_discrete_gradient")), "energy-momentum", "gravity",
                                  "mass_moment.*gravity_discrete_gradient"),
    "mass_moment": (lambda: without(MorseParticle, "mass_moment")(1.0, [1.1, 0.0]), "energy-momentum", "gravity", "mass_moment.*gravity_potential"),
}


@pytest.mark.parametrize("method", list(MISSING))
def test_a_missing_contract_method_is_named(method):
    make, scheme, forces, pattern = MISSING[method]
    body = make()
    with pytest.raises(NotImplementedError, match=pattern) as info:
        scene = sf.Scene([body], forces=[sf.Gravity()] if forces else [])
        sf.simulate(scene, 0.05, 0.01, integrator=scheme)
    assert repr(body.name) in str(info.value) and type(body).__name__ in str(info.value)
    with pytest.raises(NotImplementedError, match=r"point\(locator\).*joints"):
        without(MorseParticle, "point")(1.0, [1.0, 0.0]).point()
