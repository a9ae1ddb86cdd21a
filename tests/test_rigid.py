"""Planar rigid body (issue 6): contract, exact point gradients, pendulums against independent references."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import skfem_flex as sf
from skfem_flex.bodies.rigid import RigidBody, rotation
from skfem_flex.numerics.rotations import dsinc, sinc

G = 9.81


def test_rigid_body_contract():
    body = RigidBody(2.0, 0.5, position=(1.0, -2.0), angle=0.3, velocity=(0.4, -0.1), angular_velocity=2.0)
    q, v = body.q0, body.v0
    assert body.coordinate_names == ("x", "y", "theta")
    assert body.constant_mass and not body.has_potential
    np.testing.assert_array_equal(body.mass_matrix(q), np.diag([2.0, 2.0, 0.5]))
    assert body.kinetic_energy(q, v) == pytest.approx(0.5 * 2.0 * (0.4 ** 2 + 0.1 ** 2) + 0.5 * 0.5 * 4.0)
    np.testing.assert_allclose(body.linear_momentum(q, v), [0.8, -0.2])
    # angular momentum about the origin: m R × Ṙ + J ω
    assert body.angular_momentum(q, v) == pytest.approx(2.0 * (1.0 * -0.1 - (-2.0) * 0.4) + 0.5 * 2.0)
    gam, c = body.mass_moment()
    np.testing.assert_allclose(gam @ q + c, 2.0 * q[:2])
    V, grad, _ = body.gravity_potential(q, np.array([0.0, -G]))
    assert V == pytest.approx(2.0 * G * q[1])
    np.testing.assert_allclose(grad, [0.0, 2.0 * G, 0.0])


def test_rigid_body_geometry_outline_and_marker():
    bar = RigidBody.bar(3.0, 2.0, start=(1.0, 1.0), angle=np.pi / 2)
    np.testing.assert_allclose(bar.q0, [1.0, 2.0, np.pi / 2])
    assert bar.inertia == pytest.approx(3.0 * 4.0 / 12.0)
    geo = bar.geometry(bar.q0, np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(geo.points, [[1.0, 1.0], [1.0, 3.0]], atol=1e-15)
    assert geo.cells[0][0] == "line"
    # velocity of the ends: ω E (r − R)
    np.testing.assert_allclose(geo.point_data["velocity"], [[1.0, 0.0], [-1.0, 0.0]], atol=1e-15)
    box = RigidBody(1.0, 1.0, outline=[[-1, -1], [1, -1], [1, 1], [-1, 1]])
    conn = box.geometry(box.q0, box.v0).cells[0][1]
    assert conn.shape == (4, 2) and conn[-1].tolist() == [3, 0]           # closed polygon
    cross = RigidBody(4.0, 1.0).geometry(np.zeros(3), np.zeros(3))
    assert cross.points.shape == (4, 2) and np.max(np.abs(cross.points)) == pytest.approx(0.5)


@pytest.mark.parametrize("kwargs, word", [
    (dict(mass=0.0, inertia=1.0), "mass"), (dict(mass=1.0, inertia=-1.0), "inertia"),
    (dict(mass=float("nan"), inertia=1.0), "mass"), (dict(mass=1.0, inertia=1.0, position=(0, np.inf)), "position"),
    (dict(mass=1.0, inertia=1.0, outline=[[0, 0]]), "outline"),
])
def test_rigid_body_rejects_bad_input(kwargs, word):
    with pytest.raises(ValueError, match=word):
        RigidBody(**kwargs)
    with pytest.raises(ValueError, match="rigid body point"):
        RigidBody(1.0, 1.0).point((0.0, float("nan")))


def test_sinc_helpers():
    for x in [0.0, 1e-9, 1e-3, 0.019, 0.021, 0.5, 3.0, -2.0]:
        ref = 1.0 if x == 0 else math.sin(x) / x
        assert sinc(x) == pytest.approx(ref, rel=1e-15, abs=1e-16)
        h = 1e-6
        fd = (math.sin(x + h) / (x + h) - math.sin(x - h) / (x - h)) / (2 * h) if x != 0 else 0.0
        assert dsinc(x) == pytest.approx(fd, abs=1e-9)


def test_rigid_point_exact_discrete_gradient_and_derivatives():
    rng = np.random.default_rng(3)
    body = RigidBody(1.0, 1.0)
    for _ in range(30):
        pt = body.point(rng.normal(size=2))
        q0 = rng.normal(size=3) * 3
        q1 = q0 + rng.normal(size=3) * rng.choice([1e-7, 1e-2, 1.0, 4.0])
        d = pt.position_discrete_gradient(q0, q1)
        jump = pt.position(q1) - pt.position(q0)
        scale = np.abs(pt.position(q0)).max() + np.abs(pt.position(q1)).max()
        assert np.max(np.abs(d @ (q1 - q0) - jump)) <= 1e-14 * scale
        # rotation identities behind it
        dth = q1[2] - q0[2]
        am = rotation(0.5 * (q0[2] + q1[2]))
        E = np.array([[0, -1], [1, 0]])
        np.testing.assert_allclose(rotation(q1[2]) - rotation(q0[2]), sinc(dth / 2) * dth * am @ E, atol=1e-14)
        np.testing.assert_allclose(0.5 * (rotation(q0[2]) + rotation(q1[2])), math.cos(dth / 2) * am, atol=1e-15)
        h, f = 1e-6, rng.normal(size=2)
        eye = np.eye(3)
        jfd = np.array([(pt.position(q0 + h * e) - pt.position(q0 - h * e)) / (2 * h) for e in eye]).T
        np.testing.assert_allclose(pt.position_jacobian(q0), jfd, atol=1e-9)
        hfd = np.array([(pt.position_jacobian(q0 + h * e).T @ f - pt.position_jacobian(q0 - h * e).T @ f) / (2 * h)
                        for e in eye]).T
        np.testing.assert_allclose(pt.position_hessian_product(q0, f), hfd, atol=1e-8)
        gfd = np.array([(pt.position_discrete_gradient(q0, q1 + h * e).T @ f
                         - pt.position_discrete_gradient(q0, q1 - h * e).T @ f) / (2 * h) for e in eye]).T
        np.testing.assert_allclose(pt.position_discrete_gradient_jacobian(q0, q1, f), gfd, atol=1e-8)
        v = rng.normal(size=3)
        np.testing.assert_allclose(pt.velocity(q0, v), pt.position_jacobian(q0) @ v, atol=1e-14)
        assert pt.angle(q0) == q0[2] and pt.angle_jacobian(q0).tolist() == [0, 0, 1]


def compound_pendulum(length=1.0, mass=2.0, angle=0.0):
    bar = RigidBody.bar(mass, length, start=(0.0, 0.0), angle=angle, name="bar")
    pin = sf.Pin(bar.point((-0.5 * length, 0.0)), (0.0, 0.0), name="pivot")
    return bar, sf.Scene([bar], [pin], [sf.Gravity((0.0, -G))], name="compound pendulum")


def test_compound_pendulum_period_and_energy():
    """Bar pinned at one end released horizontal: T = 4 sqrt(J_O/(m g d)) K(sin²(θ0/2)), J_O = m L²/3, d = L/2."""
    length, mass = 1.0, 2.0
    period = 4.0 * math.sqrt((length / 3.0) / (G / 2.0)) * ellipk(0.5)
    bar, scene = compound_pendulum(length, mass)
    res = sf.simulate(scene, 2.2 * period, period / 400)
    y = res.q[:, 2] + np.pi / 2          # passes the bottom every half period (at full speed, θ'' = 0 there)
    i = np.nonzero(np.sign(y[:-1]) != np.sign(y[1:]))[0]
    tc = res.t[i] - y[i] / (y[i + 1] - y[i]) * (res.t[i + 1] - res.t[i])
    assert tc.size >= 4
    assert tc[0] / period == pytest.approx(0.25, abs=1e-4)
    assert (tc[2] - tc[0]) / period == pytest.approx(1.0, abs=1e-4)
    assert np.max(res.constraint_residual) <= 1e-12
    e_scale = mass * G * length / 2
    assert np.max(np.abs(res.energy_balance_error)) / e_scale <= 1e-12


@pytest.mark.parametrize("integrator", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_reaction_of_pinned_pendulum_at_rest_equals_weight(integrator):
    mass = 2.0
    bar, scene = compound_pendulum(1.0, mass, angle=-np.pi / 2)       # hanging straight down, at rest
    res = sf.simulate(scene, 0.2, 0.01, integrator=integrator)
    reac = res.reactions["pivot"]
    assert reac.shape == (res.t.size, 2)
    np.testing.assert_allclose(reac, np.tile([0.0, mass * G], (res.t.size, 1)), atol=1e-10)
    np.testing.assert_allclose(res.q, np.tile(bar.q0, (res.t.size, 1)), atol=1e-12)


def test_reaction_of_swinging_pendulum_matches_newton():
    """Moving bar: the pin force equals m a_G − m g (Newton's second law for the centre of mass)."""
    mass, length = 2.0, 1.0
    bar, scene = compound_pendulum(length, mass)
    dt = 1e-3
    res = sf.simulate(scene, 0.5, dt)
    # energy-momentum: λ is the step mean, so compare with the mean acceleration Δv/Δt of the step
    acc = np.diff(res.v[:, :2], axis=0) / dt
    expect = mass * acc - mass * np.array([0.0, -G])
    np.testing.assert_allclose(res.reactions["pivot"][1:], expect, atol=1e-8 * mass * G)


def double_pendulum_reference(m1, l1, m2, l2, t_end):
    """Two uniform bars in angle coordinates (from +x), released horizontal at rest; Lagrange's equations."""
    j1, j2 = m1 * l1 ** 2 / 12, m2 * l2 ** 2 / 12
    c = m2 * l1 * l2 / 2

    def rhs(t, y):
        p1, p2, w1, w2 = y
        d = p1 - p2
        m = np.array([[j1 + m1 * l1 ** 2 / 4 + m2 * l1 ** 2, c * math.cos(d)],
                      [c * math.cos(d), j2 + m2 * l2 ** 2 / 4]])
        f = np.array([-c * math.sin(d) * w2 ** 2 - G * (m1 * l1 / 2 + m2 * l1) * math.cos(p1),
                      c * math.sin(d) * w1 ** 2 - G * m2 * l2 / 2 * math.cos(p2)])
        a = np.linalg.solve(m, f)
        return [w1, w2, a[0], a[1]]
    sol = solve_ivp(rhs, (0, t_end), [0, 0, 0, 0], rtol=1e-12, atol=1e-12, method="DOP853")
    p1, p2 = sol.y[0, -1], sol.y[1, -1]
    return l1 * np.array([math.cos(p1), math.sin(p1)]) + l2 * np.array([math.cos(p2), math.sin(p2)])


def test_double_rigid_pendulum_converges_to_reference_and_conserves_energy():
    m1, l1, m2, l2 = 1.0, 1.0, 0.7, 0.6
    a = RigidBody.bar(m1, l1, name="upper")
    b = RigidBody.bar(m2, l2, start=(l1, 0.0), name="lower")
    scene = sf.Scene([a, b], [sf.Pin(a.point((-l1 / 2, 0)), (0, 0), name="pivot"),
                              sf.Revolute(a.point((l1 / 2, 0)), b.point((-l2 / 2, 0)), name="elbow")],
                     [sf.Gravity((0, -G))])
    tip = b.point((l2 / 2, 0))
    t_end = 1.0
    ref = double_pendulum_reference(m1, l1, m2, l2, t_end)
    errors = []
    for dt in (2e-3, 1e-3):
        res = sf.simulate(scene, t_end, dt)
        assert np.max(res.constraint_residual) <= 1e-12
        scale = (m1 * l1 / 2 + m2 * (l1 + l2 / 2)) * G
        assert np.max(np.abs(res.energy_balance_error)) / scale <= 1e-12
        errors.append(np.linalg.norm(tip.position(res.q[-1, 3:]) - ref))
    assert errors[-1] < 2e-3
    assert 3.0 < errors[0] / errors[1] < 5.0, errors                  # second order
