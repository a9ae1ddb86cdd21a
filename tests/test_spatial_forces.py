"""Springs, dampers and loads on spatial bodies (skfem_flex/elements/forces/spatial.py).

References: the exact discrete-gradient identity, central differences of every derivative, the
conservation of energy, linear and angular momentum of a free system held by internal springs, the energy
balance with a damper (its work), and impulse–momentum for constant forces and moments.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.numerics.quaternions import rotation_vector_matrix

H = 1e-6


def _bodies():
    a = sf.SpatialRigidBody(2.0, [0.2, 0.3, 0.25], position=[0.0, 0.0, 0.0], name="a",
                            orientation=rotation_vector_matrix([0.1, 0.2, 0.3]))
    b = sf.SpatialRigidBody(1.0, [0.1, 0.12, 0.15], position=[0.6, 0.2, -0.1], name="b",
                            orientation=rotation_vector_matrix([-0.3, 0.1, 0.2]))
    return a, b


def _fd_gradient(fun, q):
    return np.array([(fun(q + H * e) - fun(q - H * e)) / (2 * H) for e in np.eye(q.size)])


def _potentials():
    a, b = _bodies()
    return [sf.SpatialSpring(a.point([0.1, 0.0, 0.05]), b.point([-0.1, 0.02, 0.0]), 50.0, rest_length=0.3),
            sf.SpatialSpring(a.point([0.0, 0.1, 0.0]), [0.3, 0.4, 0.5], 20.0),
            sf.SpatialTorsionalSpring(a, b, axis=(0.2, 0.3, 1.0), stiffness=7.0, angle=0.2),
            sf.SpatialTorsionalSpring(b, None, axis=(1.0, 0.0, 0.0), stiffness=3.0)]


@pytest.mark.parametrize("k", range(4))
def test_potential_derivatives_and_exact_discrete_gradient(k):
    el = _potentials()[k]
    rng = np.random.default_rng(k)
    q = el.layout.initial()
    q0, q1 = q + 0.2 * rng.normal(size=q.size), q + 0.2 * rng.normal(size=q.size)
    assert np.abs(el.potential_gradient(q0) - _fd_gradient(el.potential_energy, q0)).max() < 1e-6
    assert np.abs(el.potential_hessian(q0) - _fd_gradient(el.potential_gradient, q0)).max() < 1e-5
    g, dg = el.potential_discrete_gradient(q0, q1)
    jump = el.potential_energy(q1) - el.potential_energy(q0)
    assert abs(g @ (q1 - q0) - jump) <= 1e-12 * max(1.0, abs(jump))
    if k < 2:       # the springs' ∂g/∂q₁ is exact (the torsional spring's leaves out its correction's part)
        fd = _fd_gradient(lambda x: el.potential_discrete_gradient(q0, x)[0], q1).T
        assert np.abs(dg - fd).max() < 1e-6 * max(1.0, np.abs(fd).max())


def test_torsional_spring_angle_is_the_hinge_angle():
    a, b = _bodies()
    spring = sf.SpatialTorsionalSpring(a, b, axis=(0.0, 0.0, 1.0), stiffness=1.0)
    q = spring.layout.initial()
    turn = rotation_vector_matrix([0.0, 0.0, 0.7])
    qb = q[12:].copy()
    for k in range(3):           # turn body b's directors by 0.7 rad about z
        qb[3 + 3 * k:6 + 3 * k] = turn @ qb[3 + 3 * k:6 + 3 * k]
    assert spring.angle(np.concatenate([q[:12], qb])) == pytest.approx(0.7, abs=1e-12)


def _free_pair(damping=0.0):
    a, b = _bodies()
    a.v0[:3] = (0.3, -0.2, 0.1)
    b.v0[3:] = np.concatenate([np.cross([1.0, -2.0, 3.0], b.q0[3 + 3 * k:6 + 3 * k]) for k in range(3)])
    forces = [sf.SpatialSpring(a.point([0.1, 0.0, 0.05]), b.point([-0.1, 0.02, 0.0]), 200.0, rest_length=0.3),
              sf.SpatialTorsionalSpring(a, b, axis=(0.0, 0.0, 1.0), stiffness=2.0)]
    if damping:
        forces.append(sf.SpatialDamper(a.point([0.1, 0.0, 0.05]), b.point([-0.1, 0.02, 0.0]), damping))
    where = np.array([0.3, 0.1, -0.05])
    joint = sf.Cylindrical(a.point(a.body_coordinates(where)), b.point(b.body_coordinates(where)), axis=(0, 0, 1))
    return sf.Scene([a, b], [joint], forces)


def test_free_pair_on_springs_conserves_energy_and_momenta():
    r = sf.simulate(_free_pair(), 2.0, 0.02, scheme="energy-momentum")
    E, P, L = r.total_energy, r.linear_momentum, r.angular_momentum
    assert np.ptp(r.potential) > 1e-2                          # the springs worked
    assert np.abs(E - E[0]).max() <= 1e-10 * E[0]
    assert np.abs(P - P[0]).max() <= 1e-12 * np.abs(P[0]).max()
    assert np.abs(L - L[0]).max() <= 1e-10 * np.abs(L[0]).max()


def _sprung(dampers=False):
    """Two rigid bodies on two springs (one to a ground point, one with a rest length) and an exact beam whose tip
    node hangs on a third, under gravity: every spring's points are affine in q; ``dampers``: a damper beside
    the first two springs and one from the beam's tip to the ground."""
    a, b = _bodies()
    a.v0[:3] = (0.3, -0.2, 0.1)
    b.v0[3:] = np.concatenate([np.cross([1.0, -2.0, 3.0], b.q0[3 + 3 * k:6 + 3 * k]) for k in range(3)])
    sec = sf.SpatialSection(EA=1e4, GA1=5e3, GA2=5e3, GJ=20.0, EI1=20.0, EI2=20.0, rhoA=1.0, rhoI1=1e-3,
                            rhoI2=1e-3)
    beam = sf.SpatialExactBeam.straight(sec, (1.0, 0.0, 0.0), (2.0, 0.0, 0.0), n_elements=2, normal=(0.0, 1.0, 0.0))
    springs = [sf.SpatialSpring(a.point([0.1, 0.0, 0.05]), b.point([-0.1, 0.02, 0.0]), 200.0, rest_length=0.3),
               sf.SpatialSpring(a.point([0.0, 0.1, 0.0]), [0.3, 0.4, 0.5], 20.0, rest_length=0.0),
               sf.SpatialSpring(beam.point(1.0), [2.0, 0.0, 0.5], 300.0)]
    if dampers:
        springs += [sf.SpatialDamper(a.point([0.1, 0.0, 0.05]), b.point([-0.1, 0.02, 0.0]), 3.0),
                    sf.SpatialDamper(a.point([0.0, 0.1, 0.0]), [0.3, 0.4, 0.5], 2.0),
                    sf.SpatialDamper(beam.point(1.0), [2.0, 0.1, 0.5], 5.0)]
    return sf.Scene([a, b, beam], [sf.Weld3D(beam.point(0.0))], springs + [sf.Gravity((0.0, 0.0, -9.81))])


def test_a_compiled_damper_whose_points_coincide_raises_its_own_error():
    """A damper between two points that coincide at the start has no direction: the compiled run stops with the
    damper's own message, as the Python path does."""
    a = sf.SpatialRigidBody(1.0, [0.01, 0.01, 0.01], position=[0.0, 0.0, 0.0], velocity=[1.0, 0.0, 0.0])
    b = sf.SpatialRigidBody(1.0, [0.01, 0.01, 0.01], position=[0.0, 0.0, 0.0])
    scene = sf.Scene([a, b], [], [sf.SpatialDamper(a.point([0.0, 0.0, 0.0]), b.point([0.0, 0.0, 0.0]), 0.0)])
    for compiled in (True, False):
        with pytest.raises(ValueError, match="its two points coincide"):
            sf.simulate(scene, 0.2, 0.1, scheme="generalized-alpha", compiled=compiled)


def _twisted(damped=True):
    """Two bodies on a hinge (a cylindrical joint about z), a torsional spring and damper about it, and body b on a
    torsional spring and damper about x against the ground (its direction turning off the axis), under gravity."""
    a, b = _bodies()
    a.v0[:3] = (0.3, -0.2, 0.1)
    b.v0[3:] = np.concatenate([np.cross([1.0, -2.0, 3.0], b.q0[3 + 3 * k:6 + 3 * k]) for k in range(3)])
    where = np.array([0.3, 0.1, -0.05])
    joint = sf.Cylindrical(a.point(a.body_coordinates(where)), b.point(b.body_coordinates(where)), axis=(0, 0, 1))
    forces = [sf.SpatialTorsionalSpring(a, b, axis=(0.0, 0.0, 1.0), stiffness=5.0, angle=0.3),
              sf.SpatialTorsionalSpring(b, None, axis=(1.0, 0.0, 0.0), stiffness=3.0)]
    if damped:
        forces += [sf.SpatialTorsionalDamper(a, b, axis=(0.0, 0.0, 1.0), damping=0.4),
                   sf.SpatialTorsionalDamper(b, None, axis=(1.0, 0.0, 0.0), damping=0.2)]
    return sf.Scene([a, b], [joint], forces + [sf.Gravity((0.0, 0.0, -9.81))])


#: scenes of each compiled spatial force family: (its label, the scene, the element class the Python path names)
COMPILED_FORCES = [("springs", _sprung, "SpatialSpring"), ("dampers", lambda: _sprung(dampers=True), "SpatialDamper"),
                   ("torsional", _twisted, "SpatialTorsional")]


@pytest.mark.parametrize("label, factory, element", COMPILED_FORCES, ids=[c[0] for c in COMPILED_FORCES])
@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_compiled_forces_run_as_the_python_path(scheme, label, factory, element):
    """The spatial spring, damper and torsional families against the elements' numpy methods: trajectories,
    potential and work to 1e-10 under the three schemes; the elements act (the springs store energy, the
    dampers dissipate); under energy-momentum the energy balance E − E₀ = W holds."""
    fast = sf.simulate(factory(), 0.3, 0.01, scheme=scheme, compiled=True)
    slow = sf.simulate(factory(), 0.3, 0.01, scheme=scheme, compiled=False)
    assert not fast.run_path["python_elements"]
    assert any(element in why for why in slow.run_path["python_elements"])
    assert np.abs(fast.q - slow.q).max() <= 1e-10 * np.abs(slow.q).max()
    assert np.abs(fast.v - slow.v).max() <= 1e-8 * np.abs(slow.v).max()
    assert np.abs(fast.potential - slow.potential).max() <= 1e-10 * np.abs(slow.potential).max()
    assert np.abs(fast.external_work - slow.external_work).max() <= 1e-9 * max(np.abs(slow.external_work).max(), 1.0)
    assert np.ptp(slow.potential) > 1e-2 and (label == "springs" or fast.external_work[-1] < -1e-4)
    if scheme == "energy-momentum":
        E, W = fast.total_energy, fast.external_work
        assert np.abs(E - E[0] - W).max() <= 1e-10 * np.abs(E).max()


@pytest.mark.parametrize("label, factory, element", COMPILED_FORCES, ids=[c[0] for c in COMPILED_FORCES])
@pytest.mark.parametrize("scheme", ["energy-momentum", "generalized-alpha"])
def test_compiled_force_tangents_are_the_residuals_derivative(scheme, label, factory, element):
    """Each family's part of the Newton matrix (a spring's discrete-gradient derivative, a damper's ∂Q/∂q and
    ∂Q/∂v through the scheme's q_e, v_e) against central differences of the residual."""
    from family_checks import fd_mismatch, loaded_stepper
    scene = factory()
    q0 = np.concatenate([b.q0 for b in scene.bodies])
    v0 = np.concatenate([b.v0 for b in scene.bodies])
    rng = np.random.default_rng(5)
    st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=q0.size))
    assert not st.packed.python_elements
    x = np.concatenate([0.05 * v0 + 1e-2 * rng.normal(size=q0.size), 1e-2 * rng.normal(size=scene.n_constraints)])
    assert fd_mismatch(st, 0.0, 0.05, x)[0] < 1e-8


def test_damper_work_closes_the_energy_balance():
    r = sf.simulate(_free_pair(damping=5.0), 2.0, 0.02, scheme="energy-momentum")
    E, W = r.total_energy, r.external_work
    assert W[-1] < -1e-3                                        # it dissipated
    assert np.abs(E - E[0] - W).max() <= 1e-10 * E[0]
    P = r.linear_momentum
    assert np.abs(P - P[0]).max() <= 1e-12 * np.abs(P[0]).max()     # internal forces


def test_constant_force_and_moment_give_their_impulse():
    """A free body at rest under a constant force F at its centre of mass and a constant moment M (space
    axes): p(t) = F t and L(t) = M t (about the origin, where the body starts)."""
    body = sf.SpatialRigidBody(2.0, [0.2, 0.3, 0.4], orientation=rotation_vector_matrix([0.3, -0.2, 0.1]))
    F, M = np.array([1.0, -2.0, 0.5]), np.array([0.2, 0.1, -0.3])
    scene = sf.Scene([body], forces=[sf.SpatialPointForce(body.point(), F), sf.SpatialMoment(body, M)])
    r = sf.simulate(scene, 1.0, 0.05, scheme="energy-momentum")
    assert np.allclose(r.linear_momentum, np.outer(r.t, F), atol=1e-12)
    # L about the origin = x × p + spin; x × p = (F t²/2m) × F t = 0
    assert np.allclose(r.angular_momentum, np.outer(r.t, M), atol=1e-10)
    assert np.abs(r.total_energy - r.total_energy[0] - r.external_work).max() < 1e-10


@pytest.mark.parametrize("following", [False, True])
def test_load_derivatives(following):
    body = sf.SpatialRigidBody(2.0, [0.2, 0.3, 0.4], orientation=rotation_vector_matrix([0.3, -0.2, 0.1]))
    rng = np.random.default_rng(5)
    q, v = body.q0 + 0.1 * rng.normal(size=12), rng.normal(size=12)
    for el in (sf.SpatialPointForce(body.point([0.1, 0.2, 0.3]), [1.0, 2.0, 3.0], following=following),
               sf.SpatialMoment(body, [0.5, -1.0, 2.0], following=following)):
        f, fq, fv = el.generalized_force(q, v, 0.0)
        fd = _fd_gradient(lambda x: el.generalized_force(x, v, 0.0)[0], q).T
        assert np.abs(fq - fd).max() < 1e-8
    a, b = _bodies()
    for el in (sf.SpatialDamper(a.point([0.1, 0.0, 0.0]), b.point(), 3.0),
               sf.SpatialTorsionalDamper(a, b, axis=(0.0, 0.0, 1.0), damping=2.0)):
        q = el.layout.initial() + 0.05 * rng.normal(size=24)
        v = rng.normal(size=24)
        f, fq, fv = el.generalized_force(q, v, 0.0)
        assert np.abs(fq - _fd_gradient(lambda x: el.generalized_force(x, v, 0.0)[0], q).T).max() < 1e-7
        assert np.abs(fv - _fd_gradient(lambda x: el.generalized_force(q, x, 0.0)[0], v).T).max() < 1e-7


def test_moment_on_directors_is_the_moment():
    """Σ f_{d_i}·(δφ × d_i) = M·δφ (the generalized forces of SpatialMoment do the work of M), and their
    moment Σ d_i × f_{d_i} is M also where the directors are not orthonormal."""
    body = sf.SpatialRigidBody(1.0, [1, 1, 1], orientation=rotation_vector_matrix([0.4, 0.5, -0.6]))
    M = np.array([0.3, -0.7, 1.1])
    f, _, _ = sf.SpatialMoment(body, M).generalized_force(body.q0, body.v0, 0.0)
    dphi = np.array([0.2, 0.1, -0.4])
    work = sum(f[3 + 3 * k:6 + 3 * k] @ np.cross(dphi, body.q0[3 + 3 * k:6 + 3 * k]) for k in range(3))
    assert work == pytest.approx(M @ dphi, rel=1e-13)
    q = body.q0 + 0.05 * np.random.default_rng(0).normal(size=12)
    f, _, _ = sf.SpatialMoment(body, M).generalized_force(q, body.v0, 0.0)
    moment = sum(np.cross(q[3 + 3 * k:6 + 3 * k], f[3 + 3 * k:6 + 3 * k]) for k in range(3))
    assert np.allclose(moment, M, rtol=1e-13)


def test_bad_input():
    a, b = _bodies()
    with pytest.raises(ValueError, match="stiffness"):
        sf.SpatialSpring(a.point(), b.point(), -1.0)
    with pytest.raises(ValueError, match="spatial body"):
        sf.SpatialSpring(sf.PointMass(1.0, [0.0, 0.0]).point(), b.point(), 1.0)
    with pytest.raises(ValueError, match="zero length"):
        sf.SpatialTorsionalSpring(a, b, axis=(0, 0, 0), stiffness=1.0)
    with pytest.raises(ValueError, match="3 value"):
        sf.SpatialPointForce(a.point(), lambda t: [1.0, 2.0])
