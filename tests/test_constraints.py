"""Joints, drivers, force elements and consistent initial conditions (issue 6)."""
import math

import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating.body import FloatingBeam
from skfem_flex.bodies.rigid import RigidBody
from skfem_flex.elements.constraints import Driver, Pin, Prismatic, Revolute, Slider, UserConstraint, Weld
from skfem_flex.elements.forces import (LinearDamper, LinearSpring, PointForce, PointMoment, RotationalDamper,
                               RotationalSpring, half_sine_pulse)
from skfem_flex.scene_initial import (InconsistentInitialConditionsError, RedundantConstraintsError,
                                           consistent_initial_state, find_redundant)
from skfem_flex.elements.motion import MotionLaw

G = 9.81


def bodies():
    a = RigidBody(2.0, 0.3, (0.1, 0.2), 0.3, name="a")
    b = RigidBody(1.0, 0.1, (0.5, -0.2), -0.7, name="b")
    m = sf.PointMass(1.0, [0.3, 0.4], name="m")
    beam = FloatingBeam(sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0, 1, 4)),
                                          sf.Section(EA=1e6, EI=1e2, kGA=3e5, rhoA=1.0, rhoI=1e-4)),
                        reference="pinned", name="beam")
    return a, b, m, beam


def all_constraints():
    a, b, m, beam = bodies()
    law = MotionLaw(math.sin, math.cos, lambda t: -math.sin(t))
    return [
        Pin(a.point((0.2, 0.1))), Pin(beam.point(0.6)),
        Revolute(a.point((0.3, 0.0)), b.point((-0.2, 0.1))), Revolute(m.point(), beam.point(0.4)),
        Weld(a.point((0.1, 0.1)), b.point((0.0, 0.2))), Weld(a.point((0.1, 0.1))), Weld(beam.point(0.7), b.point()),
        Slider(m.point(), (1.0, 2.0)), Slider(m.point(), (1.0, 0.5), on=b.point((0.1, 0.3))),
        Slider(a.point((0.2, 0.0)), (1.0, 1.0), on=beam.point(0.3)),
        Prismatic(a.point((0.1, -0.2)), (0.3, 1.0)),
        Prismatic(a.point((0.1, -0.2)), (0.3, 1.0), on=b.point((0.2, 0.1))),
        Prismatic(beam.point(1.0), (1.0, 0.2), on=a.point((0.3, 0.1))),
        Driver(a, law, coordinate="theta"), Driver(a.point(), law, relative_to=b.point()), Driver(beam, law, "w1"),
        sf.Distance(m, (0.1, 0.2), 0.5),
    ] + exact_beam_constraints(a, m)


def exact_beam_constraints(a, m):
    """Joints on points of a geometrically exact beam (its own BodyPoint implementation)."""
    eb = sf.ExactBeam(sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0, 1, 4)),
                                        sf.Section(EA=1e6, EI=1e2, kGA=3e5, rhoA=1.0, rhoI=1e-4)), name="exact")
    return [Pin(eb.point(0.5)), Weld(eb.point(1.0), a.point()), Slider(m.point(), (1.0, 1.0), on=eb.point(0.6)),
            Prismatic(a.point(), (1.0, 0.3), on=eb.point(0.2))]


def ids(c):
    return f"{type(c).__name__}-{'-'.join(b.name for b in c.bodies)}"


@pytest.mark.parametrize("con", all_constraints(), ids=ids)
def test_discrete_gradient_is_exact(con):
    """D (q1 − q0) = Φ(q1) − Φ(q0) to round-off, for small and very large steps."""
    rng = np.random.default_rng(7)
    n = sum(b.n_dofs for b in con.bodies)
    for _ in range(20):
        q0 = rng.normal(size=n) * 2.0
        q1 = q0 + rng.normal(size=n) * rng.choice([1e-7, 1e-3, 0.3, 3.0])
        t = rng.uniform(0, 2)
        d = con.discrete_gradient(q0, q1, t)
        jump = con.value(q1, t) - con.value(q0, t)
        scale = np.maximum(np.abs(d) @ np.abs(q1 - q0), np.abs(con.value(q0, t)) + np.abs(con.value(q1, t))
                           + np.abs(con.jacobian(q0, t)) @ np.abs(q0))
        assert np.max(np.abs(d @ (q1 - q0) - jump) / scale) <= 1e-13


@pytest.mark.parametrize("con", all_constraints(), ids=ids)
def test_jacobian_hessian_and_discrete_gradient_jacobian_match_finite_differences(con):
    rng = np.random.default_rng(11)
    n = sum(b.n_dofs for b in con.bodies)
    h, eye = 1e-6, np.eye(n)
    for _ in range(3):
        q0 = rng.normal(size=n)
        q1 = q0 + rng.normal(size=n) * 0.5
        t = 0.4
        mu = rng.normal(size=con.n_equations)
        jfd = np.array([(con.value(q0 + h * e, t) - con.value(q0 - h * e, t)) / (2 * h) for e in eye]).T
        np.testing.assert_allclose(con.jacobian(q0, t), jfd, atol=1e-8)
        hfd = np.array([(con.jacobian(q0 + h * e, t).T @ mu - con.jacobian(q0 - h * e, t).T @ mu) / (2 * h)
                        for e in eye]).T
        np.testing.assert_allclose(con.hessian_product(q0, mu, t), hfd, atol=1e-7)
        gfd = np.array([(con.discrete_gradient(q0, q1 + h * e, t).T @ mu
                         - con.discrete_gradient(q0, q1 - h * e, t).T @ mu) / (2 * h) for e in eye]).T
        np.testing.assert_allclose(con.discrete_gradient_jacobian(q0, q1, mu, t), gfd, atol=1e-7)


@pytest.mark.parametrize("con", all_constraints() + [UserConstraint([sf.PointMass(1.0, [1.0, 0.0])],
                                                                   lambda q, t: np.array([0.5 * (q @ q - 1.0)]),
                                                                   lambda q, t: q[None, :])], ids=ids)
def test_reaction_history_is_the_reaction_row_by_row(con):
    """The batch form the recorder uses for compiled chunks equals :meth:`reaction` at each state."""
    rng = np.random.default_rng(3)
    q0 = con.layout.initial() if hasattr(con, "layout") else np.concatenate([b.q0 for b in con.bodies])
    q = q0[None, :] + 0.3 * rng.normal(size=(5, q0.size))
    lam = rng.normal(size=(5, con.n_equations))
    hist = con.reaction_history(q, lam)
    rows = np.array([np.atleast_1d(con.reaction(qi, li)) for qi, li in zip(q, lam)])
    np.testing.assert_allclose(hist, rows, rtol=1e-15, atol=1e-15)


def test_driver_time_derivatives():
    a = RigidBody(1.0, 1.0)
    law = MotionLaw(lambda t: t ** 3, lambda t: 3 * t ** 2, lambda t: 6 * t)
    drv = Driver(a, law, coordinate="theta")
    q, v = np.array([0.0, 0.0, 8.0]), np.array([0.0, 0.0, 1.0])
    assert drv.value(q, 2.0)[0] == pytest.approx(0.0)
    assert drv.time_derivative(q, 2.0)[0] == pytest.approx(-12.0)
    assert drv.acceleration_rhs(q, v, 2.0)[0] == pytest.approx(12.0)
    assert drv.rheonomic and drv.reaction(q, np.array([2.5]))[0] == -2.5
    with pytest.raises(ValueError, match="coordinate"):
        Driver(a, law)
    with pytest.raises(ValueError, match="MotionLaw"):
        Driver(a, lambda t: t, coordinate="theta")
    with pytest.raises(ValueError, match="no angle"):
        Driver(sf.PointMass(1.0, [0.0, 0.0]).point(), law)


def test_joint_input_errors():
    a, b, m, beam = bodies()
    with pytest.raises(ValueError, match="Pin"):
        Revolute(a.point(), None)
    with pytest.raises(ValueError, match="no angle"):
        Weld(m.point())
    with pytest.raises(ValueError, match="direction"):
        Slider(m.point(), (0.0, 0.0))
    with pytest.raises(ValueError, match="outside"):
        Pin(beam.point(1.5))
    with pytest.raises(ValueError, match="body point"):
        Pin((0.0, 0.0))


# ------------------------------------------------------------------ forces
def all_forces():
    a, b, m, beam = bodies()
    return [LinearSpring(a.point((0.2, 0.1)), b.point((0.1, -0.3)), 10.0, 0.2),
            LinearSpring(m.point(), None, 3.0, 0.5), LinearSpring(m.point(), (1.0, 1.0), 3.0, 0.0),
            LinearSpring(beam.point(0.5), a.point(), 5.0),
            RotationalSpring(a.point(), b.point((1.0, 1.0)), 4.0, 0.3), RotationalSpring(beam.point(0.2), None, 2.0),
            LinearDamper(a.point((0.2, 0.1)), b.point((0.1, -0.3)), 3.0), LinearDamper(m.point(), (0.0, 0.0), 3.0),
            LinearDamper(beam.point(1.0), m.point(), 2.0),
            RotationalDamper(a.point(), b.point(), 2.0),
            PointForce(a.point((0.3, 0.2)), lambda t: [math.sin(t), 2.0]),
            PointForce(beam.point(0.8), lambda t: [math.sin(t), 2.0], follower=True),
            PointMoment(b.point(), math.cos)]


@pytest.mark.parametrize("el", all_forces(), ids=lambda e: type(e).__name__)
def test_force_elements_derivatives_and_exact_discrete_gradient(el):
    rng = np.random.default_rng(5)
    n = sum(b.n_dofs for b in el.bodies)
    h, eye = 1e-6, np.eye(n)
    for _ in range(4):
        q0 = rng.normal(size=n)
        q1 = q0 + rng.normal(size=n) * rng.choice([1e-4, 0.5, 3.0])
        v = rng.normal(size=n)
        if el.conservative:
            gfd = np.array([(el.potential_energy(q0 + h * e) - el.potential_energy(q0 - h * e)) / (2 * h) for e in eye])
            np.testing.assert_allclose(el.potential_gradient(q0), gfd, atol=1e-7)
            hfd = np.array([(el.potential_gradient(q0 + h * e) - el.potential_gradient(q0 - h * e)) / (2 * h)
                            for e in eye]).T
            np.testing.assert_allclose(el.potential_hessian(q0), hfd, atol=1e-6)
            g, gq = el.potential_discrete_gradient(q0, q1)
            jump = el.potential_energy(q1) - el.potential_energy(q0)
            scale = abs(el.potential_energy(q0)) + abs(el.potential_energy(q1))
            assert abs(g @ (q1 - q0) - jump) <= 1e-13 * scale
            dfd = np.array([(el.potential_discrete_gradient(q0, q1 + h * e)[0]
                             - el.potential_discrete_gradient(q0, q1 - h * e)[0]) / (2 * h) for e in eye]).T
            np.testing.assert_allclose(gq, dfd, atol=1e-6)
        else:
            f, fq, fv = el.generalized_force(q0, v, 0.7)
            fq = np.zeros((n, n)) if fq is None else fq
            fv = np.zeros((n, n)) if fv is None else fv
            qfd = np.array([(el.generalized_force(q0 + h * e, v, 0.7)[0] - el.generalized_force(q0 - h * e, v, 0.7)[0])
                            / (2 * h) for e in eye]).T
            vfd = np.array([(el.generalized_force(q0, v + h * e, 0.7)[0] - el.generalized_force(q0, v - h * e, 0.7)[0])
                            / (2 * h) for e in eye]).T
            np.testing.assert_allclose(fq, qfd, atol=1e-7)
            np.testing.assert_allclose(fv, vfd, atol=1e-7)


def measured_period(t, x):
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    tc = t[i] - x[i] / (x[i + 1] - x[i]) * (t[i + 1] - t[i])
    return (tc[-1] - tc[0]) / (len(tc) - 1)


def test_linear_spring_oscillator_has_the_trapezoidal_frequency():
    """Mass on a spring along x (rest length 1): linear, so the energy scheme's discrete frequency is
    ω_d = (2/Δt) arctan(ω Δt/2) exactly (the trapezoidal rule's)."""
    m, k, dt = 2.0, 50.0, 0.05
    body = sf.PointMass(m, [1.3, 0.0])
    scene = sf.Scene([body], [Slider(body.point(), (1.0, 0.0), name="rail")],
                     [LinearSpring(body.point(), (0.0, 0.0), k, 1.0)])
    res = sf.simulate(scene, 20.0, dt)
    omega = math.sqrt(k / m)
    omega_d = 2.0 / dt * math.atan(omega * dt / 2.0)
    # |x − 1| stays below the amplitude; crossings of x = 1 are sampled linearly (error O(dt²) ≪ test)
    period = measured_period(res.t, res.q[:, 0] - 1.0)
    assert period == pytest.approx(2 * math.pi / omega_d, rel=2e-3)
    assert np.max(np.abs(res.total_energy - res.total_energy[0])) <= 1e-12 * res.total_energy[0]


def test_elastic_pendulum_energy_exact():
    """Nonlinear spring pendulum (spring to a ground point, gravity): the closed-form discrete gradient
    ½k(1 − 2l₀/(l_0 + l_1)) Δ(l²) keeps the energy to round-off at a large step."""
    body = sf.PointMass(1.0, [0.6, -0.3], [0.0, 1.0])
    scene = sf.Scene([body], forces=[LinearSpring(body.point(), (0.0, 0.0), 40.0, 0.5), sf.Gravity((0.0, -G))])
    res = sf.simulate(scene, 10.0, 0.05)
    e = res.total_energy
    assert np.max(np.abs(e - e[0])) <= 1e-12 * np.max(np.abs(res.kinetic) + np.abs(res.potential))


def test_damped_oscillator_decay_and_energy_balance():
    m, k, c = 1.0, 100.0, 2.0
    body = sf.PointMass(m, [1.1, 0.0])
    scene = sf.Scene([body], [Slider(body.point(), (1.0, 0.0))],
                     [LinearSpring(body.point(), (0.0, 0.0), k, 1.0), LinearDamper(body.point(), (0.0, 0.0), c)])
    res = sf.simulate(scene, 2.0, 1e-3)
    zeta, wn = c / (2 * math.sqrt(k * m)), math.sqrt(k / m)
    wd = wn * math.sqrt(1 - zeta ** 2)
    exact = 1.0 + 0.1 * np.exp(-zeta * wn * res.t) * (np.cos(wd * res.t) + zeta / math.sqrt(1 - zeta ** 2)
                                                      * np.sin(wd * res.t))
    assert np.max(np.abs(res.q[:, 0] - exact)) < 2e-5
    assert res.external_work[-1] < -0.8 * res.total_energy[0]           # the damper took the energy
    assert np.max(np.abs(res.energy_balance_error)) <= 1e-12 * res.total_energy[0]


def test_torsion_spring_and_moment_on_rigid_body():
    j, k = 0.5, 8.0
    body = RigidBody(1.0, j, angle=0.2)
    scene = sf.Scene([body], [Pin(body.point())], [RotationalSpring(body.point(), None, k, 0.0)])
    dt = 0.02
    res = sf.simulate(scene, 10.0, dt)
    omega_d = 2.0 / dt * math.atan(math.sqrt(k / j) * dt / 2.0)
    assert measured_period(res.t, res.q[:, 2]) == pytest.approx(2 * math.pi / omega_d, rel=2e-3)
    # constant moment on a free body: θ = M t²/(2J), and the moment's work is the kinetic energy
    free = RigidBody(1.0, j)
    res = sf.simulate(sf.Scene([free], forces=[PointMoment(free.point(), 3.0)]), 1.0, 0.1)
    np.testing.assert_allclose(res.q[:, 2], 3.0 * res.t ** 2 / (2 * j), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.external_work, res.kinetic, rtol=1e-12, atol=1e-14)


def test_follower_and_global_point_force():
    body = RigidBody(2.0, 0.5)
    res = sf.simulate(sf.Scene([body], forces=[PointForce(body.point(), [4.0, 0.0])]), 1.0, 0.1)
    np.testing.assert_allclose(res.q[:, 0], res.t ** 2, rtol=1e-12)
    # a follower force at an arm turns with the body; its work goes into kinetic energy exactly
    body = RigidBody(2.0, 0.5)
    scene = sf.Scene([body], forces=[PointForce(body.point((0.5, 0.0)), half_sine_pulse([0.0, 3.0], 0.4),
                                                follower=True)])
    res = sf.simulate(scene, 1.0, 0.01)
    assert res.q[-1, 2] > 0.1
    np.testing.assert_allclose(res.total_energy, res.external_work, atol=1e-13)
    np.testing.assert_allclose(res.linear_momentum[-1], res.linear_momentum[-2], atol=1e-13)  # after the pulse


def test_block_sliding_down_an_incline():
    """Prismatic joint on a 30° rail: x'' = g sin α exactly (constant acceleration), normal force m g cos α."""
    alpha, m = math.radians(30.0), 3.0
    block = RigidBody(m, 0.2, (0.0, 0.0), 0.4)
    d = np.array([math.cos(alpha), -math.sin(alpha)])
    scene = sf.Scene([block], [Prismatic(block.point(), d, name="rail")], [sf.Gravity((0.0, -G))])
    for integrator in ("energy-momentum", "trapezoidal", "generalized-alpha"):
        res = sf.simulate(scene, 1.0, 0.1, integrator=integrator)
        s = res.q[:, :2] @ d
        np.testing.assert_allclose(s, 0.5 * G * math.sin(alpha) * res.t ** 2, rtol=1e-10, atol=1e-13)
        np.testing.assert_allclose(res.q[:, 2], 0.4, atol=1e-13)
        normal = np.array([math.sin(alpha), math.cos(alpha)])
        reac = res.reactions["rail"]
        assert reac.shape == (res.t.size, 3)
        np.testing.assert_allclose(reac[:, :2], np.tile(m * G * math.cos(alpha) * normal, (res.t.size, 1)),
                                   atol=1e-9)
        np.testing.assert_allclose(reac[:, 2], 0.0, atol=1e-9)


def test_user_constraint_pendulum_and_reactions_saved(tmp_path):
    body = sf.PointMass(1.0, [0.0, -0.5], [1.695, 0.0])
    con = UserConstraint([body], lambda q, t: [0.5 * (q @ q - 0.25)], lambda q, t: q[None, :], name="rod")
    res = sf.simulate(sf.Scene([body], [con], [sf.Gravity()]), 2.0, 0.01)
    assert np.max(res.constraint_residual) <= 1e-10
    assert np.max(np.abs(res.total_energy - res.total_energy[0])) <= 1e-10
    ref = sf.simulate(sf.scenes.pendulum(), 2.0, 0.01)
    np.testing.assert_allclose(res.q, ref.q, atol=1e-10)
    np.testing.assert_allclose(res.reactions["rod"][:, 0], -res.lam[:, 0])
    np.testing.assert_allclose(ref.reactions["rod"], -ref.lam[:, :1] * ref.q, atol=1e-12)   # tension along the rod
    back = sf.Result.load(res.save(tmp_path / "r.npz"))
    np.testing.assert_array_equal(back.reactions["rod"], res.reactions["rod"])


# ------------------------------------------------------- initial conditions
def test_redundant_constraints_are_named():
    bar = RigidBody.bar(2.0, 1.0, angle=-np.pi / 2, name="bar")
    scene = sf.Scene([bar], [Pin(bar.point((-0.5, 0)), name="pin A"), Pin(bar.point((-0.5, 0)), name="pin B"),
                             Weld(bar.point((0.5, 0)), name="clamp")])
    rank, names = find_redundant(scene, scene.initial_state()[0])
    assert rank == 3 and names == ["pin A", "pin B", "clamp"]
    with pytest.raises(RedundantConstraintsError, match="redundant") as info:
        sf.simulate(scene, 0.1, 0.01)
    msg = str(info.value)
    assert "'pin A'" in msg and "'pin B'" in msg and "'clamp'" in msg and "rank 3" in msg
    # a well-posed mechanism next to a redundant pair: only the pair is named
    m = sf.PointMass(1.0, [1.0, 0.0])
    scene = sf.Scene([bar, m], [Pin(bar.point((-0.5, 0)), name="pivot"), sf.Distance(m, (0, 0), 1.0, name="rod"),
                                Slider(m.point(), (1.0, 0.0), name="rail"),
                                Slider(m.point(), (2.0, 0.0), name="rail 2")])
    assert find_redundant(scene, scene.initial_state()[0])[1] == ["rail", "rail 2"]


def test_unreachable_configuration_is_reported():
    m = sf.PointMass(1.0, [0.3, -0.4])           # on the circle, but the rail y = −1 misses it
    scene = sf.Scene([m], [sf.Distance(m, (0, 0), 0.5, name="rod"), Slider(m.point(), (1, 0), (0, -1.0), name="rail")])
    with pytest.raises(InconsistentInitialConditionsError, match="cannot be satisfied") as info:
        sf.simulate(scene, 0.1, 0.01)
    assert set(info.value.names) == {"rod", "rail"}
    assert isinstance(info.value, ValueError)


def test_projection_of_initial_state():
    # slightly off the circle and with a radial velocity component: projected, prescribed-free
    m = sf.PointMass(1.0, [0.0, -0.5002], [1.0, 0.05])
    scene = sf.Scene([m], [sf.Distance(m, (0, 0), 0.5)], [sf.Gravity()])
    q, v = consistent_initial_state(scene, *scene.initial_state())
    np.testing.assert_allclose(q, [0.0, -0.5], atol=1e-15)
    np.testing.assert_allclose(v, [1.0, 0.0], atol=1e-15)              # minimum-norm: only the radial part removed
    res = sf.simulate(scene, 0.05, 0.01)
    np.testing.assert_allclose(res.q[0], q)
    with pytest.raises(InconsistentInitialConditionsError, match="project=True"):
        sf.simulate(scene, 0.05, 0.01, project=False)
    # a large inconsistency is a user error, not something to project silently
    far = sf.PointMass(1.0, [0.0, -0.8])
    with pytest.raises(InconsistentInitialConditionsError, match="max_correction"):
        sf.simulate(sf.Scene([far], [sf.Distance(far, (0, 0), 0.5, name="rod")]), 0.1, 0.01)
    q, v = consistent_initial_state(sf.Scene([far], [sf.Distance(far, (0, 0), 0.5)]), [0.0, -0.8], [0.0, 0.0],
                                    max_correction=None)
    np.testing.assert_allclose(q, [0.0, -0.5], atol=1e-15)


def test_projection_keeps_prescribed_coordinates_and_uses_driver_rates():
    # a crank whose angle is prescribed by a Driver: the projection sets θ and θ̇ from the law
    crank = RigidBody.bar(1.0, 0.2, angle=0.001, name="crank")
    law = MotionLaw.constant_rate(5.0)
    scene = sf.Scene([crank], [Pin(crank.point((-0.1, 0)), (0, 0), name="pivot"),
                               Driver(crank, law, coordinate="theta", name="drive")])
    q, v = consistent_initial_state(scene, *scene.initial_state())
    assert q[2] == pytest.approx(0.0, abs=1e-15) and v[2] == pytest.approx(5.0)
    np.testing.assert_allclose(v[:2], [0.0, 0.5], atol=1e-14)          # centre speed ω L/2
    # a Prescribed coordinate is not moved by the projection
    bar = RigidBody.bar(1.0, 1.0, angle=0.01, name="bar")
    scene = sf.Scene([bar], [Pin(bar.point((-0.5, 0)), (0.0, 0.0))],
                     prescribed=[sf.Prescribed(bar, "theta", MotionLaw.constant_rate(1.0, start=0.02))])
    q, v = consistent_initial_state(scene, *scene.initial_state())
    assert q[2] == 0.02 and v[2] == 1.0
    np.testing.assert_allclose(bar.point((-0.5, 0)).position(q), [0, 0], atol=1e-15)
