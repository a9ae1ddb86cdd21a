"""The rigid body turned by a quaternion: its kernel against differences and closed forms, its compiled
steps against their own residuals and the Python path, and the conservation laws of the Simo–Wong top
(docs/spatial.md)."""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.bodies import quaternion_kernel as qk
from skfem_flex.bodies.quaternion import QuaternionRigidBody
from skfem_flex.numerics.quaternions import quaternion_matrix, rotation_vector_matrix
from skfem_flex.scenes.spatial import BRULS_REFERENCE

from family_checks import fd_mismatch, loaded_stepper

RNG = np.random.default_rng(7)
J = np.array([[2.0, 0.1, -0.2], [0.1, 3.0, 0.3], [-0.2, 0.3, 4.0]])


def _unit(n):
    e = RNG.normal(size=n)
    return e / np.linalg.norm(e)


def _free_body(**kw):
    return QuaternionRigidBody(3.0, J, position=[0.1, -0.2, 0.3], orientation=_unit(4), velocity=[0.5, 0.0, -0.2],
                               body_angular_velocity=[1.0, -2.0, 3.0], **kw)


def test_kernel_mass_inverse_and_angular_velocity():
    b = _free_body()
    e, edot = b.q0[3:], b.v0[3:]
    assert np.allclose(qk.mass(b.J4, e) @ qk.inverse_mass(b.J4i, e), np.eye(4), atol=1e-13)
    assert np.allclose(b.body_angular_velocity(b.q0, b.v0), [1.0, -2.0, 3.0], atol=1e-13)
    # T = ½ ΩᵀJΩ and the rotation's angular momentum about the centre of mass R J Ω
    Om = np.array([1.0, -2.0, 3.0])
    assert np.isclose(0.5 * edot @ qk.mass(b.J4, e) @ edot, 0.5 * Om @ J @ Om, rtol=1e-13)
    R = quaternion_matrix(e)
    L = b.angular_momentum(b.q0, b.v0) - np.cross(b.q0[:3], 3.0 * b.v0[:3])
    assert np.allclose(L, R @ J @ Om, rtol=1e-13)
    # Ṙ = R Ω̂ from ė
    h = 1e-6
    Rdot = (quaternion_matrix(e + h * edot) - quaternion_matrix(e - h * edot)) / (2 * h)
    W = R.T @ Rdot
    assert np.allclose([W[2, 1], W[0, 2], W[1, 0]], Om, atol=1e-8)


def test_kernel_derivatives_against_differences():
    e, v, a = _unit(4), RNG.normal(size=4), RNG.normal(size=4)
    J4 = np.diag([2.0, 2.0, 3.0, 4.0])
    h = 1e-6

    def d(f, x, k):
        u = np.zeros(4)
        u[k] = h
        return (f(x + u) - f(x - u)) / (2 * h)

    B = qk.mass_jacobian(J4, e, a)
    f, fe, fv = qk.quadratic_velocity_force(J4, e, v)
    for k in range(4):
        assert np.allclose(B[:, k], d(lambda x: qk.mass(J4, x) @ a, e, k), atol=1e-7)
        assert np.allclose(fe[:, k], d(lambda x: qk.quadratic_velocity_force(J4, x, v)[0], e, k), atol=1e-7)
        assert np.allclose(fv[:, k], d(lambda x: qk.quadratic_velocity_force(J4, e, x)[0], v, k), atol=1e-7)
    # Q_v = ∂T/∂e − Ṁv
    T = lambda x: 0.5 * v @ qk.mass(J4, x) @ v                                        # noqa: E731
    Mdot_v = sum(v[k] * d(lambda x: qk.mass(J4, x) @ v, e, k) for k in range(4))
    assert np.allclose(f, np.array([d(lambda x: np.array([T(x)] * 4), e, k)[0] for k in range(4)]) - Mdot_v,
                       atol=1e-7)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_compiled_step_matrix_is_the_derivative_of_its_residual(scheme):
    scene = sf.Scene([_free_body()], forces=[sf.Gravity((0.0, -9.81, 1.0))])
    pivot = sf.scenes.heavy_top("bruls", rotation="quaternion")
    for sc in (scene, pivot):
        q, v = sc.initial_state()
        st = loaded_stepper(sc, scheme, q, v, acc=0.1 * RNG.normal(size=sc.n))
        x = np.concatenate([1e-3 * RNG.normal(size=sc.n), 1e-2 * RNG.normal(size=sc.n_constraints)])
        err, _, _ = fd_mismatch(st, 0.0, 1e-3, x)
        assert err < 1e-7


def test_compiled_trapezoidal_run_matches_the_python_path():
    """The Newmark terms are the body's Python methods' (one implementation): the two paths agree."""
    a = sf.simulate(sf.scenes.heavy_top("bruls", rotation="quaternion"), 0.02, 1e-3, scheme="trapezoidal")
    b = sf.simulate(sf.scenes.heavy_top("bruls", rotation="quaternion"), 0.02, 1e-3, scheme="trapezoidal",
                    compiled=False)
    assert np.abs(a.q - b.q).max() < 1e-11
    assert np.abs(a.v - b.v).max() < 1e-8


@pytest.mark.parametrize("dt", [0.009, 0.05])
def test_simo_wong_top_conserves_energy_vertical_momentum_and_spin(dt):
    scene = sf.scenes.heavy_top("simo-wong", rotation="quaternion")
    top = scene.bodies[0]
    r = sf.simulate(scene, 10.0, dt, scheme="energy-momentum")
    E, L3 = r.total_energy, r.angular_momentum[:, 2]
    spin = np.array([top.body_angular_velocity(q, v)[2] for q, v in zip(r.q, r.v)])
    assert np.abs(E - E[0]).max() <= 1e-10 * abs(E[0])
    assert np.abs(L3 - L3[0]).max() <= 1e-10 * abs(L3[0])
    assert np.abs(spin - 50.0).max() <= 1e-10 * 50.0
    assert np.abs(np.linalg.norm(r.q, axis=1) - 1.0).max() <= 1e-12
    com = r.probes["com"]
    assert np.allclose(np.linalg.norm(com, axis=1), 1.0, atol=1e-12)
    assert np.ptp(com[:, 0]) > 0.05
    # the same top on directors: the spin drifts (O(Δt²)), which is why the quaternion is offered
    d = sf.scenes.heavy_top("simo-wong")
    rd = sf.simulate(d, 2.0, dt, scheme="energy-momentum")
    spin_d = np.array([d.bodies[0].body_angular_velocity(q, v)[2] for q, v in zip(rd.q, rd.v)])
    assert np.abs(spin_d - 50.0).max() > 1e3 * np.abs(spin[:len(spin_d)] - 50.0).max()


def test_trapezoidal_top_drifts_where_energy_momentum_does_not():
    r = sf.simulate(sf.scenes.heavy_top("simo-wong", rotation="quaternion"), 2.0, 0.009, scheme="trapezoidal")
    E = r.total_energy
    assert 1e-9 < np.abs(E - E[0]).max() / abs(E[0]) < 1e-2


def test_free_symmetric_body_conserves_every_momentum_and_its_spin():
    """No load, inertia with an axis of symmetry: energy, linear momentum, all three components of the angular
    momentum and the spin about the symmetry axis, to round-off at a coarse step; the Euler parameters stay
    unit."""
    body = QuaternionRigidBody(3.0, [2.0, 2.0, 3.0], position=[0.1, -0.2, 0.3], orientation=_unit(4),
                               velocity=[0.5, 0.0, -0.2], body_angular_velocity=[1.0, -2.0, 3.0])
    r = sf.simulate(sf.Scene([body]), 5.0, 0.05, scheme="energy-momentum")
    L, P, E = r.angular_momentum, r.linear_momentum, r.total_energy
    spin = np.array([body.body_angular_velocity(q, v)[2] for q, v in zip(r.q, r.v)])
    assert np.abs(L - L[0]).max() <= 1e-12 * np.abs(L[0]).max()
    assert np.abs(P - P[0]).max() <= 1e-13 * np.abs(P[0]).max()
    assert np.abs(E - E[0]).max() <= 1e-12 * abs(E[0])
    assert np.abs(spin - 3.0).max() <= 1e-12 * 3.0
    assert np.allclose(r.q[:, :3], body.q0[:3] + np.outer(r.t, body.v0[:3]), atol=1e-12)
    assert np.abs(np.linalg.norm(r.q[:, 3:], axis=1) - 1.0).max() <= 1e-12


def test_asymmetric_body_conserves_every_momentum():
    """Three different principal values and a full inertia tensor in body axes: energy, linear momentum and
    all three components of the angular momentum at a coarse step."""
    body = _free_body()
    r = sf.simulate(sf.Scene([body]), 5.0, 0.05, scheme="energy-momentum")
    L, P, E = r.angular_momentum, r.linear_momentum, r.total_energy
    assert np.abs(L - L[0]).max() <= 1e-12 * np.abs(L[0]).max()
    assert np.abs(P - P[0]).max() <= 1e-13 * np.abs(P[0]).max()
    assert np.abs(E - E[0]).max() <= 1e-12 * abs(E[0])


def test_bruls_top_conserves_energy_vertical_momentum_and_its_axis_spin():
    """The Brüls top's inertia about the pivot is symmetric about its second axis (the one through the
    centre of mass): that spin is conserved with the energy and the vertical angular momentum."""
    scene = sf.scenes.heavy_top("bruls", rotation="quaternion")
    top = scene.bodies[0]
    r = sf.simulate(scene, 0.2, 1e-3, scheme="energy-momentum")
    E, L3 = r.total_energy, r.angular_momentum[:, 2]
    spin = np.array([top.body_angular_velocity(q, v)[1] for q, v in zip(r.q, r.v)])
    assert np.abs(E - E[0]).max() <= 1e-11 * abs(E[0])
    assert np.abs(L3 - L3[0]).max() <= 1e-11 * np.abs(r.angular_momentum[0]).max()
    assert np.abs(spin - 150.0).max() <= 1e-11 * 150.0


@pytest.mark.parametrize("scheme,dt,bound", [("energy-momentum", 5e-5, 1e-4), ("trapezoidal", 5e-5, 1e-4),
                                             ("generalized-alpha", 1e-4, 5e-4)])
def test_bruls_top_with_quaternions_against_the_published_reference(scheme, dt, bound):
    scene = sf.scenes.heavy_top("bruls", rotation="quaternion")
    r = sf.simulate(scene, 0.2, dt, scheme=scheme)
    e = scene.bodies[0].euler_parameters(r.q[-1], BRULS_REFERENCE)
    assert np.abs(e - BRULS_REFERENCE).max() <= bound


def test_bad_input_and_joints_get_clear_errors():
    with pytest.raises(ValueError, match="must not be zero"):
        QuaternionRigidBody(1.0, [1.0, 1.0, 1.0], orientation=[0.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="positive definite"):
        QuaternionRigidBody(1.0, [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="rotation must be one of"):
        sf.scenes.heavy_top("simo-wong", rotation="euler angles")
    body = QuaternionRigidBody(1.0, [1.0, 1.0, 1.0], orientation=rotation_vector_matrix([0.1, 0.2, 0.3]))
    with pytest.raises(ValueError, match="cannot take joints"):
        sf.Spherical(body.point([1.0, 0.0, 0.0]), None)


def test_hanging_top_statics_and_modes():
    """Started 3 rad off, the top rests with its centre of mass under the pivot; about that rest its two
    swinging modes are the compound pendulum's √(m g l / J) = √(20·1·1/5) = 2 rad/s, and the spin about the
    axis is a zero mode (the unit-norm constraint taken out in the null space)."""
    from skfem_flex.bodies.probes import PointProbe
    top = QuaternionRigidBody(20.0, [5.0, 5.0, 1.0], orientation=rotation_vector_matrix([3.0, 0.2, 0.0]),
                              pivot=[0.0, 0.0, 0.0], center_of_mass=[0.0, 0.0, 1.0])
    scene = sf.Scene([top], forces=[sf.Gravity((0.0, 0.0, -1.0))], probes={"com": PointProbe(top.point(top.center))})
    rest = sf.static_equilibrium(scene)
    assert np.allclose(top.point(top.center).position(rest.q), [0.0, 0.0, -1.0], atol=1e-10)
    m = sf.modes(scene, about="static", n_modes=3)
    assert np.allclose(np.sort(m.omega), [0.0, 2.0, 2.0], atol=1e-8)
