"""The spatial floating-frame family of the compiled core (skfem_flex/compiled/families/spatial_floating_frame.py,
its arithmetic in skfem_flex/bodies/floating_spatial/kernel.py): FloatingBeam3D (Green–Lagrange and linear
strain) and FloatingSolid3D (linear strain).

1. The compiled M(q), B(q, a), H(a, b), strain and gravity terms are the numpy specification's
   (bodies/floating_spatial/kinetics.py, the strain objects, FloatingFrame3D.gravity_potential) at round-off.
2. Kernel against the task specification (compiled/tasks.py): at random states and unknowns the Newton matrix is
   the central difference of the residual under energy-momentum, trapezoidal and generalized-α, and the residual
   is the bodies' numpy contract; the recorded momenta and energies are those of M(q) v, of V and of gravity.
3. Scenes run compiled (no element left to Python) and their trajectories equal the Python path's under every
   scheme; the solid's Green–Lagrange energy, which has no compiled form, runs in Python and says so.
"""
import functools

import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating_spatial import kernel, kinetics
from skfem_flex.bodies.floating_spatial.body import FloatingBeam3D
from skfem_flex.bodies.floating_spatial.solid import FloatingSolid3D
from skfem_flex.fem.elasticity3d import ElasticSolid3D
from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D
from skfem_flex.fem.spatial_section import SpatialSection

from family_checks import SCHEMES, dense, em_reference, fd_mismatch, loaded_stepper, rel_dev, run_both, run_new
from helpers import assert_loop_measures_are_the_scenes
from skfem_flex.schemes.stepper import Stepper

#: the Newton matrix against Richardson-extrapolated central differences, relative to each row's largest entry
FD_TOL = 1e-9
#: the compiled terms and residual against the numpy specification: round-off of sums of ~1e3 terms
PARTS_TOL = 1e-12
#: trajectories against the Python path (relative to the largest entry): the same equations, summed in
#: another order
RUN_TOL = 1e-10

SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.3, rhoI1=2.0, rhoI2=1.0)
GRAVITY = (0.3, -1.0, -9.81)


def beam(strain="green-lagrange", reference="clamped"):
    line = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 4)), SECTION, order=2)
    return FloatingBeam3D(line, reference=reference, strain=strain, angular_velocity=(0.4, -0.3, 2.0))


@functools.lru_cache(maxsize=None)
def _mesh_solid():
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 1.0, 5), np.linspace(0, 0.1, 2), np.linspace(0, 0.1, 2))
    return ElasticSolid3D(mesh.to_meshtet(), 2e11, 0.3, 7800.0, order=1)


def _solid(strain, position=(0.0, 0.0, 0.0)):
    """A new reduced bar (a body is not shared between scenes: a scene may change its state)."""
    return FloatingSolid3D(_mesh_solid(), lambda X: np.isclose(X[0], 0.0), 3,
                           interfaces={"tip": lambda X: np.isclose(X[0], 1.0)}, position=position,
                           angular_velocity=(1.0, 0.5, 3.0), strain=strain)


BODIES = {"beam": beam, "linear-strain beam": lambda: beam("linear", "chord"), "solid": lambda: _solid("linear"),
          "green-lagrange solid": lambda: _solid("green-lagrange")}


def random_state(body, rng, scale=1e-3):
    """A turned, moving, deformed state (the directors orthonormal, as the scene's rows keep them)."""
    q = np.array(body.q0, dtype=float)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    for k in range(1, 4):
        q[3 * k:3 * k + 3] = R @ q[3 * k:3 * k + 3]
    q[:3] = (0.3, -0.2, 0.7)
    q[12:] = scale * rng.normal(size=q.size - 12)
    v = rng.normal(size=q.size)
    v[12:] *= 0.05
    return q, v


def gravity_scene(body):
    return sf.Scene([body], forces=[sf.Gravity(GRAVITY)])


@pytest.mark.parametrize("kind", list(BODIES))
def test_compiled_terms_are_the_numpy_specification(kind):
    """M, B, H, the strain energy's discrete gradient and gravity: the compiled twins equal the numpy methods."""
    body = BODIES[kind]()
    data = body.compiled_kernel_data()
    kd = data.frame._replace(g=np.array(GRAVITY))
    rng = np.random.default_rng(0)
    q0, v = random_state(body, rng)
    q1, a = random_state(body, rng)
    inv = body.inertia
    pairs = [(kernel.mass_matrix(kd, q0), kinetics.mass_matrix(inv, q0)),
             (kernel.momentum_jacobian(kd, q0, a), kinetics.momentum_jacobian(inv, q0, a)),
             (kernel.kinetic_hessian(kd, v, a), kinetics.kinetic_hessian(inv, v, a))]
    pairs += list(zip(kernel.quadratic_velocity_terms(kd, q0, v), kinetics.quadratic_velocity_force(inv, q0, v)))
    e1, g, jac = kernel.strain_terms(kd, data.quartic, q0[12:], q1[12:])
    g_ref, jac_ref = body.strain_energy.discrete_gradient(q0[12:], q1[12:])
    pairs += [(np.array([e1]), np.array([body.strain_energy.energy(q1[12:])])), (g, g_ref), (jac, jac_ref)]
    pairs += [(np.concatenate([[a_], b_.ravel(), c_.ravel()]), np.concatenate([[a2], b2.ravel(), c2.ravel()]))
              for (a_, b_, c_), (a2, b2, c2) in [(kernel.gravity_terms(kd, q1), body.gravity_potential(q1, GRAVITY))]]
    for mine, ref in pairs:
        assert np.abs(mine - ref).max() <= PARTS_TOL * max(np.abs(ref).max(), 1e-300)
    # the strain energy really is nonlinear for the Green–Lagrange bodies (the test above can see it)
    if kind in ("beam", "green-lagrange solid"):
        assert np.abs(jac - kd.K / 2).max() > 1e-6 * np.abs(jac).max()


@pytest.mark.parametrize("kind", list(BODIES))
def test_energy_momentum_step_is_the_bodies_contract(kind):
    """Energy-momentum: the residual is the numpy contract's, the Newton matrix its derivative."""
    body = BODIES[kind]()
    scene = gravity_scene(body)
    rng = np.random.default_rng(1)
    q0, v0 = random_state(body, rng)
    h = 0.01
    st = loaded_stepper(scene, "energy-momentum", q0, v0)
    assert not st.packed.python_elements
    dq = h * v0 + 1e-4 * rng.normal(size=q0.size)
    mu = 1e-2 * rng.normal(size=scene.n_constraints)          # the rigidity rows' multipliers
    assert fd_mismatch(st, 0.0, h, np.concatenate([dq, mu]))[0] < FD_TOL
    r = st.evaluate(0.0, h, np.concatenate([dq, np.zeros_like(mu)]))[0]
    ref, scale = em_reference(body, q0, q0 + dq, v0, 2.0 * dq / h - v0, h, GRAVITY)
    assert np.abs(r[:body.n_dofs] - ref).max() <= 1e-10 * scale


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("kind", ["beam", "solid", "green-lagrange solid"])
def test_newmark_tangent_is_the_residuals_derivative(kind, scheme):
    """The Newmark family: the Newton matrix is the derivative of the residual (the quadratic-velocity force's two
    derivatives and DM(q)[v] included); the residual itself is held to the Python path's below."""
    body = BODIES[kind]()
    scene = gravity_scene(body)
    rng = np.random.default_rng(2)
    q0, v0 = random_state(body, rng)
    st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=q0.size))
    x = np.concatenate([0.01 * v0 + 1e-4 * rng.normal(size=q0.size), 1e-2 * rng.normal(size=scene.n_constraints)])
    assert fd_mismatch(st, 0.0, 0.01, x)[0] < FD_TOL


@pytest.mark.parametrize("kind", ["beam", "solid", "green-lagrange solid"])
def test_start_momenta_and_energy(kind):
    """The recorded linear and angular momenta are those of p = M(q) v (numpy), and the momenta and energies of a
    compiled run equal the Python path's (T = ½ vᵀp, V the strain energy plus gravity's potential)."""
    body = BODIES[kind]()
    scene = gravity_scene(body)
    rec, _ = run_new(scene, "energy-momentum", 0.01, 3)
    ref = sf.simulate(gravity_scene(BODIES[kind]()), 0.03, 0.01, compiled=False)
    for i in range(3):
        q, v = rec.q[i], rec.v[i]
        p = body.mass_matrix(q) @ v
        L = sum(np.cross(q[3 * k:3 * k + 3], p[3 * k:3 * k + 3]) for k in range(4))
        np.testing.assert_allclose(ref.linear_momentum[i + 1], p[:3], rtol=0, atol=1e-11 * np.abs(p).max())
        np.testing.assert_allclose(ref.angular_momentum[i + 1], L, rtol=0, atol=1e-11 * np.abs(L).max())
    res = sf.simulate(gravity_scene(BODIES[kind]()), 0.03, 0.01)
    assert not res.run_path["python_elements"]
    np.testing.assert_allclose(res.linear_momentum, ref.linear_momentum, rtol=0,
                               atol=1e-10 * np.abs(ref.linear_momentum).max())
    np.testing.assert_allclose(res.angular_momentum, ref.angular_momentum, rtol=0,
                               atol=1e-10 * np.abs(ref.angular_momentum).max())
    for key in ("kinetic", "potential"):
        mine, theirs = getattr(res, key), getattr(ref, key)
        assert np.abs(mine - theirs).max() <= 1e-10 * np.abs(theirs).max()
    # gravity's work shows in the potential: the body falls
    assert np.ptp(ref.potential) > 0


RUNS = {  # name: (scene factory, dt, steps, schemes)
    "rotating beam 3D": (lambda: sf.scenes.rotating_beam_3d(n_elements=3), 0.01, 20,
                         ("energy-momentum", "trapezoidal", "generalized-alpha")),
    "rotor 3D": (lambda: sf.scenes.rotor_3d(n_modes=4), 1e-3, 20, ("energy-momentum", "generalized-alpha")),
}


@pytest.mark.parametrize("name, scheme", [(name, s) for name, run in RUNS.items() for s in run[3]])
def test_trajectories_equal_the_python_path(name, scheme):
    """A rotating Green–Lagrange beam on a driven hub and the meshed rotor on two ball joints: q, v and λ of the
    compiled core are the Python path's."""
    factory, dt, steps, _ = RUNS[name]
    rec, ref = run_both(factory, scheme, dt, steps)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL
    assert rel_dev(rec.lam, ref.lam[1:]) < 1e3 * RUN_TOL


def python_stepper(scene, scheme, q, v, acc):
    """The Python path's Stepper (every element through its numpy methods) loaded like ``loaded_stepper``."""
    sch = SCHEMES[scheme]()
    st = Stepper(scene, sch, python_only=True)
    lam = np.zeros(scene.n_constraints)
    st.load(sch.make_state(0.0, np.array(q, dtype=float), np.array(v, dtype=float), acc=np.array(acc, dtype=float),
                           pseudo=np.array(acc, dtype=float), lam=lam))
    return st


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_residual_matrix_and_start_are_the_python_paths(scheme):
    """At one random state and step, the compiled residual and Newton matrix equal the Python path's (every term
    from the numpy methods: M q̈ + ∇V + ∇V_g − Q_v for the Newmark family), and the consistent start's
    accelerations and multipliers are its (the numpy M q̈ = Q_v − ∇V − ∇V_g on the rigidity rows)."""
    body = beam()
    scene = gravity_scene(body)
    rng = np.random.default_rng(4)
    q0, v0 = random_state(body, rng)
    acc = rng.normal(size=q0.size)
    x = np.concatenate([0.01 * v0 + 1e-4 * rng.normal(size=q0.size), 1e-2 * rng.normal(size=scene.n_constraints)])
    fast, slow = loaded_stepper(scene, scheme, q0, v0, acc=acc), python_stepper(scene, scheme, q0, v0, acc)
    r_fast, j_fast, _ = fast.evaluate(0.0, 0.01, x)
    r_slow, j_slow, _ = slow.evaluate(0.0, 0.01, x)
    assert np.abs(r_fast - r_slow).max() <= 1e-11 * np.abs(r_slow).max()
    assert np.abs(dense(j_fast) - dense(j_slow)).max() <= 1e-11 * np.abs(dense(j_slow)).max()
    a_fast, l_fast = fast.start(0.0, q0, v0)[:2]
    a_slow, l_slow = slow.start(0.0, q0, v0)[:2]
    assert rel_dev(a_fast, a_slow) < 1e-10 and rel_dev(l_fast, l_slow) < 1e-10
    assert np.abs(a_fast).max() > 1.0                   # gravity and the spin accelerate it


def several_bodies():
    """Three bodies in one family (a Green–Lagrange beam, a linear-strain beam, a solid), two gravity fields (one
    on two of them), one coordinate of the first beam prescribed by a law in time."""
    a, b, c = beam(), beam("linear", "chord"), _solid("linear", position=(0.0, 3.0, 0.0))
    b.q0[:3] += (3.0, 0.0, 0.0)
    law = sf.MotionLaw(lambda t: 0.2 * t, lambda t: 0.2, lambda t: 0.0)
    return sf.Scene([a, b, c], forces=[sf.Gravity(GRAVITY), sf.Gravity((0.5, 0.2, 0.0), bodies=[a, c])],
                    prescribed=[sf.Prescribed(a, 0, law)])


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_several_bodies_two_gravity_fields_and_a_prescribed_coordinate(scheme):
    """The family packs several bodies and sums the gravity fields on each; with a prescribed coordinate the
    trajectory, the energies and the momenta equal the Python path's."""
    rec, ref = run_both(several_bodies, scheme, 0.01, 10)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL
    res = sf.simulate(several_bodies(), 0.1, 0.01, integrator=scheme)
    assert not res.run_path["python_elements"]
    for key in ("kinetic", "potential", "linear_momentum", "angular_momentum"):
        mine, theirs = np.asarray(getattr(res, key)), np.asarray(getattr(ref, key))
        assert np.abs(mine - theirs).max() <= 1e-10 * np.abs(theirs).max(), key


def test_energy_of_a_free_tumbling_beam_under_energy_momentum():
    """A free Green–Lagrange beam tumbling under gravity, compiled: T + V + V_g stays to 1e-10 relative and the
    momenta are gravity's impulse, over 100 large steps."""
    body = beam()
    res = sf.simulate(gravity_scene(body), 1.0, 0.01)
    assert not res.run_path["python_elements"]
    e = res.total_energy
    assert np.abs(e - e[0]).max() <= 1e-10 * res.kinetic.max()
    mass = body.inertia.mass
    expected = res.linear_momentum[0] + mass * np.outer(res.t, GRAVITY)
    assert np.abs(res.linear_momentum - expected).max() <= 1e-9 * np.abs(expected).max()


def spinning_green_lagrange_solid():
    """The reduced bar with the Green–Lagrange strain, hanging by its tip from a ball joint, spinning, under gravity."""
    body = _solid("green-lagrange")
    return sf.Scene([body], constraints=[sf.Spherical(body.point("tip"))], forces=[sf.Gravity(GRAVITY)])


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_green_lagrange_solid_runs_compiled_as_the_python_path(scheme):
    """The solid's Green–Lagrange energy (its cubic and quartic modal tensors) runs on the compiled core, in a
    joint, under every scheme: trajectory, energies and momenta equal the Python path's (numpy on the same
    tensors; test_spatial_solid.py holds the tensors to the sums at the quadrature points)."""
    res = sf.simulate(spinning_green_lagrange_solid(), 0.02, 0.002, integrator=scheme, compiled=True)
    ref = sf.simulate(spinning_green_lagrange_solid(), 0.02, 0.002, integrator=scheme, compiled=False)
    assert not res.run_path["python_elements"] and ref.run_path["python_elements"]
    assert rel_dev(res.q, ref.q) < RUN_TOL
    assert rel_dev(res.v, ref.v) < 1e3 * RUN_TOL
    assert rel_dev(res.lam, ref.lam) < 1e3 * RUN_TOL
    for key in ("kinetic", "potential"):
        mine, theirs = getattr(res, key), getattr(ref, key)
        assert np.abs(mine - theirs).max() <= 1e-10 * np.abs(theirs).max(), key


def loaded_bodies():
    """A spinning bar and a beam, each pushed at a material point (quadratic in q) by a force fixed in space,
    one constant and one a function of time."""
    bar, rod = _solid("green-lagrange"), beam()
    rod.q0[:3] += (0.0, 3.0, 0.0)
    loads = [sf.SpatialPointForce(bar.point("tip"), lambda t: np.array([2e4 * np.sin(40.0 * t), 1e4, -3e4])),
             sf.SpatialPointForce(rod.point(1.5), (0.0, 50.0, 20.0))]
    return sf.Scene([bar, rod], forces=loads)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_point_forces_at_material_points_run_compiled_as_the_python_path(scheme):
    """A force fixed in space at a floating-frame body's material point (r quadratic in q: Q = Jᵀ(q) F(t),
    ∂Q/∂q = Σ F_c H_c) runs on the compiled point-load family: trajectory and energies as the Python path's."""
    res = sf.simulate(loaded_bodies(), 0.02, 0.002, integrator=scheme, compiled=True)
    ref = sf.simulate(loaded_bodies(), 0.02, 0.002, integrator=scheme, compiled=False)
    assert not res.run_path["python_elements"] and ref.run_path["python_elements"]
    assert rel_dev(res.q, ref.q) < RUN_TOL
    assert rel_dev(res.v, ref.v) < 1e3 * RUN_TOL
    assert np.abs(ref.external_work).max() > 1e-3 * np.abs(ref.kinetic).max()          # the loads do work
    for key in ("kinetic", "external_work"):
        mine, theirs = np.asarray(getattr(res, key)), np.asarray(getattr(ref, key))
        assert np.abs(mine - theirs).max() <= 1e-9 * np.abs(theirs).max(), key


def test_a_users_strain_object_runs_in_python():
    """A strain energy without a compiled form (any object with energy, gradient, hessian and
    discrete_gradient): the body runs through its numpy methods, named with why, and moves as the compiled one."""
    class Wrapped:
        def __init__(self, inner):
            self.inner = inner

        def energy(self, y):
            return self.inner.energy(y)

        def gradient(self, y):
            return self.inner.gradient(y)

        def hessian(self, y):
            return self.inner.hessian(y)

        def discrete_gradient(self, y0, y1):
            return self.inner.discrete_gradient(y0, y1)

    users = beam()
    users.strain_energy = Wrapped(users.strain_energy)
    assert users.compiled_kernel_data() is None and "Wrapped" in users.compiled_refusal
    res = sf.simulate(gravity_scene(users), 0.05, 0.01)
    assert any("Wrapped" in why for why in res.run_path["python_elements"])
    ref = sf.simulate(gravity_scene(beam()), 0.05, 0.01)
    assert not ref.run_path["python_elements"]
    assert rel_dev(res.q, ref.q) < RUN_TOL


def _kernel_case(seed):
    """(beam, its kernel data, the frame data with gravity, (q0, v0, q1, v1, a1) at random states, the rng)."""
    body = beam()
    data = body.compiled_kernel_data()
    rng = np.random.default_rng(seed)
    (q0, v0), (q1, v1) = random_state(body, rng), random_state(body, rng)
    return body, data, data.frame._replace(g=np.array(GRAVITY)), (q0, v0, q1, v1, rng.normal(size=q0.size)), rng


@pytest.mark.parametrize("mode", [kernel.EM, kernel.NEWMARK])
def test_kinetic_block_is_the_weighted_numpy_terms(mode):
    """``body_terms`` forms the momentum, the kinetic force and the Newton block with the task's weights folded
    in (the elastic blocks gathered, B's passes shared): each equals the weighted sum of the numpy terms
    (``kinetics``: M, B, H, DM(q)[v], the discrete gradient) at random weights and states."""
    body, data, kd, (q0, v0, q1, v1, a1), rng = _kernel_case(5)
    weights = rng.normal(size=5)
    w_p, w_gk, dq1, dv1, da1 = weights
    inv = body.inertia
    M = kinetics.mass_matrix(inv, q1)
    p, gk, _, M1, K, _, _ = kernel.body_terms(kd, data.quartic, mode, q0, q1, v0, v1, a1, q0, q1, weights, False)
    if mode == kernel.EM:
        g_ref, g_q, g_v = kinetics.kinetic_discrete_gradient(inv, q0, q1, v0, v1)
        p_ref, B = M @ v1, kinetics.momentum_jacobian(inv, q1, v1)
        K_ref = w_p * (dq1 * B + dv1 * M) + w_gk * (dq1 * g_q + dv1 * g_v)
        assert M1.size == 0
    else:
        g_ref, g_q, g_v = kinetics.quadratic_velocity_force(inv, q1, v1)
        p_ref, B = M @ a1, kinetics.momentum_jacobian(inv, q1, a1)
        K_ref = w_p * (dq1 * B + da1 * M) + w_gk * (dq1 * g_q + dv1 * g_v)
        assert np.abs(M1 - M).max() <= PARTS_TOL * np.abs(M).max()
    for mine, ref in ((p, p_ref), (gk, g_ref), (K, K_ref)):
        assert np.abs(mine - ref).max() <= PARTS_TOL * np.abs(ref).max()


@pytest.mark.parametrize("mode", [kernel.EM, kernel.NEWMARK])
def test_residual_only_terms_are_the_full_terms(mode):
    """``body_terms(..., residual=True)`` (an evaluation whose matrix the loop does not use) gives the same
    momentum, discrete gradients, M(q₁) and energy as the full evaluation, and neither the Newton block nor
    ∂g_p/∂q (which only the matrix and the round-off floor use)."""
    _, data, kd, (q0, v0, q1, v1, a1), _ = _kernel_case(4)
    weights = np.array([0.01, -0.01, 1.0, 200.0, 4e4])
    full = kernel.body_terms(kd, data.quartic, mode, q0, q1, v0, v1, a1, q0, q1, weights, False)
    part = kernel.body_terms(kd, data.quartic, mode, q0, q1, v0, v1, a1, q0, q1, weights, True)
    for k in (0, 1, 2, 3, 6):                           # p, g_k, g_p, M(q₁), V
        assert np.array_equal(np.asarray(full[k]), np.asarray(part[k]))
    for k in (4, 5):                                    # the Newton block and ∂g_p/∂q are not formed
        assert part[k].size == 0 and np.any(full[k])


@pytest.mark.parametrize("scheme, its", [("trapezoidal", 1), ("energy-momentum", 2)])
def test_residual_only_checks_change_no_iterate(monkeypatch, scheme, its):
    """A reduced beam whose steps converge in a steady number of iterations (one under the trapezoidal rule,
    two under energy–momentum here): the loop checks the last update of a step with a residual-only
    evaluation (``RESIDUAL_ONLY``); the trajectory and the iterations are those of full evaluations."""
    from skfem_flex.apps import peer_ffrf_beam
    from skfem_flex.compiled.families import spatial_floating_frame as family

    data = peer_ffrf_beam.beam_data()
    make = {"trapezoidal": sf.Trapezoidal, "energy-momentum": sf.EnergyMomentum}[scheme]
    settings = sf.NewtonSettings(rtol=1e-8, ctol=1e-8, etol=1e-10)
    runs = []
    for lazy in (True, False):
        monkeypatch.setattr(family, "RESIDUAL_ONLY", lazy)
        runs.append(sf.simulate(peer_ffrf_beam.scene(data, probe=False), 0.3, 0.01, scheme=make(newton=settings)))
    assert np.mean(runs[0].newton_iterations[1:] == its) > 0.8    # steady: the residual-only checks did run
    assert np.array_equal(runs[0].newton_iterations, runs[1].newton_iterations)
    assert np.abs(runs[0].q - runs[1].q).max() <= 1e-14 * np.abs(runs[1].q).max()


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
def test_recorded_energies_and_momenta_under_the_newmark_schemes_are_the_scenes(scheme):
    """Under the Newmark schemes a step's record takes T, V and the momenta from its acceptance (its energy
    guard computed them at the same state): at every recorded state they are the scene's at (q, v), for a
    spinning, deforming beam under gravity, whose M(q) and V(q) change from step to step."""
    assert_loop_measures_are_the_scenes(gravity_scene(beam()), rel=1e-12, scheme=scheme)


def test_recording_halves_are_the_state_terms():
    """The recording tasks' halves of ``body_terms``: MOMENTUM gives the STATE's p = M(q₁)v₁ and ENERGY its V,
    bit for bit."""
    body = beam()
    data = body.compiled_kernel_data()
    kd = data.frame._replace(g=np.array(GRAVITY))
    q, v = random_state(body, np.random.default_rng(6))
    weights = np.zeros(5)
    state = kernel.body_terms(kd, data.quartic, kernel.STATE, q, q, v, v, v, q, q, weights, False)
    momentum = kernel.body_terms(kd, data.quartic, kernel.MOMENTUM, q, q, v, v, v, q, q, weights, False)
    energy = kernel.body_terms(kd, data.quartic, kernel.ENERGY, q, q, v, v, v, q, q, weights, False)
    assert np.array_equal(momentum[0], state[0])
    assert np.abs(state[0] - kinetics.mass_matrix(body.inertia, q) @ v).max() <= PARTS_TOL * np.abs(state[0]).max()
    assert energy[6] == state[6] and state[6] != 0.0
