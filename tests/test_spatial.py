"""Spatial rigid bodies (directors), spatial joints and the heavy tops of the catalogue.

References: conservation laws (energy, angular momentum about the axis of gravity), the rigidity of the
directors, the published Euler parameters of the Brüls top at t = 0.2 s, second-order convergence, the
exact discrete gradient identity D (q₁ − q₀) = Φ(q₁) − Φ(q₀) of every joint, Rodrigues' formula and the
quaternion–matrix algebra.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.numerics.quaternions import matrix_quaternion, quaternion_matrix, rotation_vector_matrix, skew
from skfem_flex.scenes.spatial import BRULS_REFERENCE

from spatial_scenes import spatial_mechanism


def _orthonormality(body, q):
    return max(np.abs(body.rotation_matrix(qi).T @ body.rotation_matrix(qi) - np.eye(3)).max() for qi in q)


# ---------------------------------------------------------------- rotations
def test_quaternion_algebra():
    rng = np.random.default_rng(0)
    for _ in range(20):
        phi = rng.normal(size=3)
        R = rotation_vector_matrix(phi)
        assert np.abs(R.T @ R - np.eye(3)).max() < 1e-14 and np.linalg.det(R) > 0
        e = matrix_quaternion(R)
        ang = np.linalg.norm(phi)
        expected = np.concatenate([[np.cos(ang / 2)], np.sin(ang / 2) * phi / ang])
        expected *= np.sign(expected[0])
        assert np.abs(e - expected).max() < 1e-13
        assert np.abs(quaternion_matrix(e) - R).max() < 1e-14
        assert np.abs(R @ phi - phi).max() < 1e-14          # the axis stays
    a, b = rng.normal(size=3), rng.normal(size=3)
    assert np.allclose(skew(a) @ b, np.cross(a, b))


# ----------------------------------------------------------------- the body
def test_rigid_body_kinetic_energy_and_momenta_are_those_of_a_rigid_body():
    """T = ½ m |ẋ|² + ½ Ωᵀ J Ω and L = x × m ẋ + R J Ω from the director coordinates."""
    rng = np.random.default_rng(1)
    J = np.array([[0.3, 0.02, 0.0], [0.02, 0.5, 0.01], [0.0, 0.01, 0.6]])
    R = rotation_vector_matrix(rng.normal(size=3))
    x, xd, Om = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    b = sf.SpatialRigidBody(2.0, J, position=x, orientation=R, velocity=xd, body_angular_velocity=Om)
    q, v = b.q0, b.v0
    assert b.kinetic_energy(q, v) == pytest.approx(0.5 * 2.0 * xd @ xd + 0.5 * Om @ J @ Om, rel=1e-13)
    assert np.allclose(b.angular_momentum(q, v), np.cross(x, 2.0 * xd) + R @ J @ Om, rtol=1e-13, atol=1e-13)
    assert np.allclose(b.body_angular_velocity(q, v), Om, rtol=1e-13)
    assert np.allclose(b.euler_parameters(q), matrix_quaternion(R))
    # a body point moves rigidly: r = x + R s
    s = rng.normal(size=3)
    assert np.allclose(b.point(s).position(q), x + R @ s)
    assert np.allclose(b.point(s).velocity(q, v), xd + np.cross(R @ Om, R @ s))


def test_pivot_body_is_the_body_about_its_pivot():
    """A top given by its inertia about the pivot has the kinetic energy ½ Ωᵀ J_O Ω and L = R J_O Ω."""
    JO = np.diag([5.0, 5.0, 1.0])
    R = rotation_vector_matrix([0.3, -0.2, 0.1])
    Om = np.array([0.5, -1.0, 20.0])
    b = sf.SpatialRigidBody(20.0, JO, orientation=R, body_angular_velocity=Om, pivot=[0, 0, 0],
                            center_of_mass=[0, 0, 1])
    assert b.n_dofs == 9
    assert b.kinetic_energy(b.q0, b.v0) == pytest.approx(0.5 * Om @ JO @ Om, rel=1e-13)
    assert np.allclose(b.angular_momentum(b.q0, b.v0), R @ JO @ Om, rtol=1e-13)
    assert np.allclose(b.linear_momentum(b.q0, b.v0), 20.0 * np.cross(R @ Om, R @ [0, 0, 1.0]))


def test_free_tumbling_body_conserves_momenta_and_rigidity():
    """A free asymmetric body (no gravity) under energy-momentum at a large step: energy, linear and angular
    momentum exactly, the centre of mass moving uniformly, the directors orthonormal."""
    b = sf.SpatialRigidBody(3.0, [0.2, 0.5, 0.6], position=[0.1, 0.2, 0.3], velocity=[1.0, -0.5, 0.2],
                            body_angular_velocity=[0.1, 8.0, 0.3], orientation=rotation_vector_matrix([0.4, 0.1, 0]))
    r = sf.simulate(sf.Scene([b]), 5.0, 0.05, scheme="energy-momentum")
    E, L, P = r.total_energy, r.angular_momentum, r.linear_momentum
    assert np.abs(E - E[0]).max() <= 1e-12 * E[0]
    assert np.abs(L - L[0]).max() <= 1e-12 * np.abs(L[0]).max()
    assert np.abs(P - P[0]).max() <= 1e-13 * np.abs(P[0]).max()
    assert np.allclose(r.q[:, :3], b.q0[:3] + np.outer(r.t, b.v0[:3]), atol=1e-12)
    assert _orthonormality(b, r.q) < 1e-12
    assert r.linear_momentum.shape == (len(r.t), 3) and r.angular_momentum.shape == (len(r.t), 3)


# ---------------------------------------------------------------- heavy tops
@pytest.mark.parametrize("dt", [0.009, 0.05])
def test_simo_wong_top_conserves_energy_and_vertical_momentum(dt):
    scene = sf.scenes.heavy_top("simo-wong")
    top = scene.bodies[0]
    r = sf.simulate(scene, 10.0, dt, scheme="energy-momentum")
    E, L3 = r.total_energy, r.angular_momentum[:, 2]
    assert np.abs(E - E[0]).max() <= 1e-10 * abs(E[0])
    assert np.abs(L3 - L3[0]).max() <= 1e-10 * abs(L3[0])
    assert _orthonormality(top, r.q) <= 1e-12
    # the body's spin about its symmetry axis: conserved to O(Δt²) only by the director constraints
    # (docs/spatial.md): measured 1.0e-8 at Δt = 0.009 s and 7.6e-7 at 0.05 s
    spin = np.array([top.body_angular_velocity(q, v)[2] for q, v in zip(r.q, r.v)])
    assert np.abs(spin - 50.0).max() <= 5e-7 * (dt / 0.009) ** 2 * 50.0
    # the centre of mass precesses: it leaves its start but stays at 1 m from the pivot
    com = r.probes["com"]
    assert np.allclose(np.linalg.norm(com, axis=1), 1.0, atol=1e-12)
    assert np.ptp(com[:, 0]) > 0.05


def test_newmark_schemes_drift_on_the_simo_wong_top():
    """The trapezoidal rule and generalized-α run the top; neither conserves its energy exactly, which is the
    point of the comparison: the trapezoidal rule's energy wanders, generalized-α at velocity level only
    dissipates (in director coordinates the spin is an oscillation of d₁ and d₂ at 50 rad/s, which its
    numerical damping takes away); at position level its velocities oscillate (docs/spatial.md)."""
    r = sf.simulate(sf.scenes.heavy_top("simo-wong"), 2.0, 0.009, scheme="trapezoidal")
    E = r.total_energy
    assert 1e-9 < np.abs(E - E[0]).max() / abs(E[0]) < 1e-2
    r = sf.simulate(sf.scenes.heavy_top("simo-wong"), 2.0, 0.009,
                    scheme=sf.GeneralizedAlpha(constraint_level="velocity"))
    E = r.total_energy
    assert (E - E[0]).max() <= 1e-9 * abs(E[0])
    assert 0.9 * E[0] < E[-1] < 0.999 * E[0]


@pytest.mark.parametrize("scheme,dt,bound", [("energy-momentum", 5e-5, 1e-4), ("trapezoidal", 5e-5, 1e-4),
                                             ("generalized-alpha", 1e-4, 5e-4)])
def test_bruls_top_against_the_published_reference(scheme, dt, bound):
    scene = sf.scenes.heavy_top("bruls")
    r = sf.simulate(scene, 0.2, dt, scheme=scheme)
    e = scene.bodies[0].euler_parameters(r.q[-1], BRULS_REFERENCE)
    assert np.abs(e - BRULS_REFERENCE).max() <= bound


def test_bruls_top_converges_at_second_order():
    errors = []
    for dt in (4e-4, 2e-4):
        scene = sf.scenes.heavy_top("bruls")
        r = sf.simulate(scene, 0.2, dt, scheme="energy-momentum")
        errors.append(np.abs(scene.bodies[0].euler_parameters(r.q[-1], BRULS_REFERENCE) - BRULS_REFERENCE).max())
    order = np.log2(errors[0] / errors[1])
    assert 1.8 < order < 2.2


# -------------------------------------------------------------------- joints
@pytest.mark.parametrize("k", [0] + list(range(6, 14)))      # a body's rigidity, then each joint
def test_each_joint_has_an_exact_discrete_gradient(k):
    """D (q₁ − q₀) = Φ(q₁) − Φ(q₀) at random far-apart states, Φ_q and ∂(Φ_qᵀμ)/∂q by central differences."""
    c = spatial_mechanism().constraints[k]
    rng = np.random.default_rng(k)
    n = c.layout.n
    q0, q1, mu = rng.normal(size=n), rng.normal(size=n), rng.normal(size=c.n_equations)
    t = 0.3
    jump = c.value(q1, t) - c.value(q0, t)
    assert np.abs(c.discrete_gradient(q0, q1, t) @ (q1 - q0) - jump).max() <= 1e-13 * max(1.0, np.abs(jump).max())
    h = 1e-6
    fd = np.column_stack([(c.value(q0 + h * e, t) - c.value(q0 - h * e, t)) / (2 * h) for e in np.eye(n)])
    assert np.abs(c.jacobian(q0, t) - fd).max() <= 1e-8
    fdh = np.column_stack([(c.jacobian(q0 + h * e, t).T @ mu - c.jacobian(q0 - h * e, t).T @ mu) / (2 * h)
                           for e in np.eye(n)])
    assert np.abs(c.hessian_product(q0, mu, t) - fdh).max() <= 1e-8


def test_joint_reactions_balance_gravity_at_rest():
    """A body hanging from a ball joint at rest: the joint's force on it is m g upwards, no moment."""
    b = sf.SpatialRigidBody(2.0, [0.1, 0.1, 0.05], position=[0, 0, -0.5])
    ball = sf.Spherical(b.point([0, 0, 0.5]), None, name="ball")
    r = sf.simulate(sf.Scene([b], [ball], [sf.Gravity((0, 0, -9.81))]), 0.1, 0.01)
    reaction = r.reactions["ball"]
    assert np.allclose(reaction[-1], [0, 0, 2.0 * 9.81, 0, 0, 0], atol=1e-9)


def test_revolute_hinge_keeps_its_axis():
    """A bar on a hinge about y under gravity swings in the x–z plane and keeps y = 0 and its axis."""
    bar = sf.SpatialRigidBody(1.0, [0.001, 0.08, 0.08], position=[0.5, 0, 0])
    hinge = sf.Revolute3D(bar.point([-0.5, 0, 0]), None, axis=(0, 1, 0))
    r = sf.simulate(sf.Scene([bar], [hinge], [sf.Gravity((0, 0, -9.81))]), 1.0, 0.01)
    assert np.abs(r.q[:, 1]).max() < 1e-12
    assert np.abs(r.q[:, 6:9] - [0, 1, 0]).max() < 1e-12          # d₂ stays the hinge axis
    assert r.q[:, 2].min() < -0.3


# ---------------------------------------------------------------- bad input
def test_bad_input_is_named():
    with pytest.raises(ValueError, match="zero"):
        sf.SpatialRigidBody(1.0, [1, 1, 1], orientation=[0, 0, 0, 0])
    with pytest.raises(ValueError, match="finite"):
        sf.SpatialRigidBody(1.0, [1, 1, 1], orientation=[np.nan, 0, 0, 1])
    with pytest.raises(ValueError, match="positive definite"):
        sf.SpatialRigidBody(1.0, [[1, 0, 0], [0, -1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="symmetric"):
        sf.SpatialRigidBody(1.0, [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="triangle"):
        sf.SpatialRigidBody(1.0, [1.0, 1.0, 3.0])
    b = sf.SpatialRigidBody(1.0, [1, 1, 1])
    c = sf.SpatialRigidBody(1.0, [1, 1, 1])
    with pytest.raises(ValueError, match="zero length"):
        sf.Revolute3D(b.point(), c.point(), axis=(0, 0, 0))
    with pytest.raises(ValueError, match="zero length"):
        b.axis([0, 0, 0])
    with pytest.raises(ValueError, match="must not coincide|positive"):
        sf.Distance3D(b.point(), c.point())
    with pytest.raises(ValueError, match="does not hold"):
        sf.Spherical(b.point(), c.point([1.0, 0, 0]))
    with pytest.raises(ValueError, match="3 entries"):
        sf.Scene([b], forces=[sf.Gravity((0, -9.81))])
    with pytest.raises(ValueError, match="all be planar or all spatial"):
        sf.Scene([b, sf.RigidBody(1.0, 1.0)])


# ------------------------------------------------------------- mechanisms
def test_bricard_runs_with_its_redundant_hinge_dropped():
    """The redundant equation is dropped and said once; P3 follows the reference (1e-4 m: the library's
    'high precision' is 1e-3) and energy-momentum conserves the energy."""
    from skfem_flex.scenes.spatial import BRICARD_REFERENCE

    with pytest.warns(UserWarning, match="1 redundant constraint equation"):
        scene = sf.scenes.bricard()
    assert scene.n_constraints == 59
    for scheme, t_end in (("energy-momentum", 2.0), ("trapezoidal", 1.0), ("generalized-alpha", 1.0)):
        r = sf.simulate(scene, t_end, 1e-3, scheme=scheme)
        for t, p in BRICARD_REFERENCE.items():
            if t <= t_end:
                assert np.abs(r.probes["P3"][np.argmin(np.abs(r.t - t))] - p).max() < 1e-4
        if scheme == "energy-momentum":
            assert np.abs(r.total_energy - r.total_energy[0]).max() <= 1e-9 * r.kinetic.max()


def test_spatial_slider_crank_against_its_reference():
    from skfem_flex.scenes.spatial import SLIDER_CRANK_REFERENCE

    r = sf.simulate(sf.scenes.spatial_slider_crank(), 1.0, 1e-3, scheme="energy-momentum")
    theta = np.unwrap(r.probes["crank angle"])
    for t, (x, th) in SLIDER_CRANK_REFERENCE.items():
        if t <= 1.0:
            i = np.argmin(np.abs(r.t - t))
            assert abs(r.probes["slider"][i] - x) < 1e-4 and abs(theta[i] - th) < 1e-3
    assert np.abs(r.total_energy - r.total_energy[0]).max() <= 1e-10 * r.total_energy[0]


def test_redundant_planar_constraints_still_raise():
    """Only spatial joints may drop equations: a planar duplicate is still named as an error."""
    from skfem_flex.scene_initial import RedundantConstraintsError, drop_redundant_constraints

    m = sf.PointMass(1.0, [1.0, 0.0])
    scene = sf.Scene([m], [sf.Pin(m.point(), (1.0, 0.0)), sf.Pin(m.point(), (1.0, 0.0), name="again")])
    with pytest.raises(RedundantConstraintsError, match="again"):
        drop_redundant_constraints(scene)


def _driven_bar(law, omega=0.0):
    bar = sf.SpatialRigidBody(1.0, [0.001, 0.08, 0.08], position=[0.5, 0, 0], velocity=[0, 0.5 * omega, 0],
                              angular_velocity=[0, 0, omega])
    hinge = sf.Revolute3D(bar.point([-0.5, 0, 0]), None, axis=(0, 0, 1))
    driver = sf.RotationDriver(bar, None, axis=(0, 0, 1), law=law)
    return bar, sf.Scene([bar], [hinge, driver], [sf.Gravity((0, -9.81, 0))])


def test_rotation_driver_time_derivatives():
    """Φ_t and 2 Φ_qt v + Φ_tt against central differences of Φ(q₀ + v t, t) in t."""
    law = sf.spin_up_law(2.0, 1.5)
    bar, scene = _driven_bar(law)
    c = scene.constraints[-1]
    rng = np.random.default_rng(2)
    q0, v = c.layout.initial() + 0.05 * rng.normal(size=12), rng.normal(size=12)
    t, h = 0.7, 1e-4

    def phi(s):
        return c.value(q0 + v * s, t + s)[0]
    assert c.time_derivative(q0, t)[0] == pytest.approx((c.value(q0, t + h)[0] - c.value(q0, t - h)[0]) / (2 * h),
                                                        abs=1e-7)
    second = (phi(h) - 2 * phi(0.0) + phi(-h)) / h ** 2
    assert c.time_terms(q0, v, t)[0] + v @ c.hessian_product(q0, [1.0], t) @ v == pytest.approx(second, abs=1e-5)
    # Φ_qt, the velocity rows' extra Newton term, against central differences of Φ_t in q
    fd = [(c.time_derivative(q0 + e, t)[0] - c.time_derivative(q0 - e, t)[0]) / (2 * h) for e in h * np.eye(12)]
    assert np.abs(c.time_derivative_jacobian(q0, t)[0] - fd).max() <= 1e-7


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_rotation_driver_turns_the_bar_by_its_law(scheme):
    law = sf.spin_up_law(3.0, 1.0)
    bar, scene = _driven_bar(law)
    r = sf.simulate(scene, 1.5, 1e-3, scheme=scheme)
    d1 = r.q[:, 3:6]
    angle = np.unwrap(np.arctan2(d1[:, 1], d1[:, 0]))
    expected = np.array([law(t)[0] for t in r.t])
    tol = 1e-9 if scheme != "trapezoidal" else 1e-5          # the trapezoidal rule holds it at velocity level
    assert np.abs(angle - expected).max() < tol
    if scheme == "energy-momentum":
        E, W = r.total_energy, r.external_work
        assert np.abs(E - E[0] - W).max() < 1e-9 * np.abs(E).max()
        assert r.reactions["rotation driver"].shape == (len(r.t), 1)


@pytest.mark.parametrize("spinning", [False, True], ids=["spin-up", "spinning"])
@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_rotation_driver_runs_compiled_as_the_python_path(scheme, spinning):
    """The rotation-driver family against the driver's own methods: the bar spun up by its law from rest, or
    turning at a constant rate from the start (the consistent start then needs 2 Φ_qt v + Φ_tt), under gravity:
    states and the driving moment to the Newton tolerance (the trapezoidal rule's velocity-level multipliers
    to 1e-7), and the family's Newton matrix against central differences of its residual."""
    from family_checks import fd_mismatch, loaded_stepper
    law, omega = (sf.MotionLaw.constant_rate(2.0), 2.0) if spinning else (sf.spin_up_law(3.0, 1.0), 0.0)
    fast = sf.simulate(_driven_bar(law, omega)[1], 1.5, 1e-2, scheme=scheme, compiled=True)
    slow = sf.simulate(_driven_bar(law, omega)[1], 1.5, 1e-2, scheme=scheme, compiled=False)
    assert not fast.run_path["python_elements"]
    assert any("RotationDriver" in why for why in slow.run_path["python_elements"])
    assert np.abs(fast.q - slow.q).max() <= 1e-9
    assert np.abs(fast.v - slow.v).max() <= 1e-8 * np.abs(slow.v).max()
    moment = slow.reactions["rotation driver"]
    assert np.abs(fast.reactions["rotation driver"] - moment).max() <= 1e-7 * np.abs(moment).max()
    scene = _driven_bar(law, omega)[1]
    rng = np.random.default_rng(5)
    q0, v0 = (np.concatenate([getattr(b, k) for b in scene.bodies]) for k in ("q0", "v0"))
    st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=q0.size))
    x = np.concatenate([1e-3 * rng.normal(size=q0.size), 1e-2 * rng.normal(size=scene.n_constraints)])
    assert fd_mismatch(st, 0.3, 0.01, x)[0] < 1e-8


def test_rotation_driver_acceleration_row_is_the_drivers_own():
    """The family's acceleration row (Φ_q q̈ + vᵀ(c H_Y − s H_X)v + 2 Φ_qt v + Φ_tt) in mid-turn, with
    velocities off the constraints (on them Φ_qt v vanishes: the row's terms are seen one by one only off
    them): the start's (q̈, λ), the solution of those rows with the balance of forces, equals the one through
    the driver's numpy methods (a subclass the family does not take) to 1e-10."""
    from family_checks import loaded_stepper
    from skfem_flex.numerics.quaternions import rotation_vector_matrix

    class OwnDriver(sf.RotationDriver):
        def value(self, q, t):
            return super().value(q, t)

    law = sf.spin_up_law(3.0, 1.0)
    t = 0.6
    R = rotation_vector_matrix([0.0, 0.0, law(t)[0]])
    starts = []
    for cls in (sf.RotationDriver, OwnDriver):
        bar = sf.SpatialRigidBody(1.0, [0.001, 0.08, 0.08], position=[0.5, 0, 0])
        scene = sf.Scene([bar], [sf.Revolute3D(bar.point([-0.5, 0, 0]), None, axis=(0, 0, 1)),
                                 cls(bar, None, axis=(0, 0, 1), law=law)], [sf.Gravity((0, -9.81, 0))])
        q = np.concatenate([R @ [0.5, 0.0, 0.0], (R @ np.eye(3)).T.ravel()])
        v = np.random.default_rng(7).normal(size=12)
        st = loaded_stepper(scene, "generalized-alpha", q, v)
        assert bool(st.packed.python_elements) == (cls is OwnDriver)
        starts.append(st.start(t, q, v)[:2])
    (a1, l1), (a2, l2) = starts
    assert np.abs(a1 - a2).max() <= 1e-10 * np.abs(a2).max() and np.abs(a2).max() > 1.0
    assert np.abs(l1 - l2).max() <= 1e-10 * np.abs(l2).max()


def test_statics_and_modes_of_a_spatial_pendulum():
    """A bar on a hinge about y, started 1.2 rad below horizontal: it rests hanging straight down, and its one
    mode is the compound pendulum's, ω = √(m g l / J_O)."""
    R = rotation_vector_matrix([0.0, 1.2, 0.0])
    bar = sf.SpatialRigidBody(1.0, [0.001, 0.08, 0.08], position=R @ [0.5, 0, 0], orientation=R)
    hinge = sf.Revolute3D(bar.point([-0.5, 0, 0]), None, axis=(0, 1, 0))
    scene = sf.Scene([bar], [hinge], [sf.Gravity((0, 0, -9.81))])
    eq = sf.static_equilibrium(scene)
    assert np.allclose(eq.q[:3], [0.0, 0.0, -0.5], atol=1e-10)
    omega = np.abs(sf.modes(scene).eigenvalues)
    assert omega.size == 1 and omega[0] == pytest.approx(np.sqrt(9.81 * 0.5 / (0.08 + 0.25)), rel=1e-8)
    with pytest.raises(ValueError, match="no rest state"):
        sf.static_equilibrium(sf.Scene([sf.SpatialRigidBody(1.0, [1, 1, 1])], forces=[sf.Gravity((0, 0, -9.81))]))


def test_a_sweep_of_spatial_scenes():
    """Sweeps take spatial scenes: a vector probe keeps its three components, and each case's energy holds."""
    ds = sf.sweep("heavy_top", vary={"variant": ["bruls", "simo-wong"]}, t_end=0.01, dt=1e-3, n_workers=1)
    assert ds["probe_com"].shape == (2, 11, 3)
    assert float(ds["relative_energy_error"].max()) < 1e-12
    assert np.allclose(ds["probe_com"].values[1, 0], [0.0, -np.sin(0.05), np.cos(0.05)], atol=1e-12)
