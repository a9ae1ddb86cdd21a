"""The floating-frame family of the compiled core (skfem_flex/compiled/families/floating_frame.py): FloatingBeam
and ModalBody (reduced, with its quartic energy) bodies.

1. Kernel against the specification (compiled/tasks.py): at random states and unknowns, the Newton matrix is the
   central difference of the residual under energy-momentum and trapezoidal, with dense storage, with prescribed
   coordinates and with CSR storage (a 64-element beam); the residual is the bodies' numpy contract
   (mass_matrix, kinetic_discrete_gradient, potential_discrete_gradient; Newmark: M q̈ + ∇V − Q_v), the consistent
   start solves the numpy M q̈ = Q_v − ∇V, and the recorded momenta and energies are those of M(q) v and of V.
2. Trajectories of the catalogue's floating-frame scenes equal the old Python path under every scheme.
3. Energy balance of the energy-momentum scheme: E₁ − E₀ = work of the prescribed motion, to the Newton tolerance.
"""
import functools

import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.scenes.rotating import hub_beam

from family_checks import dense, em_reference, fd_mismatch, loaded_stepper, rel_dev, run_both, run_new

#: the Newton matrix against central differences, relative to each row's largest entry: they reach 4e-12–3e-11
#: here (family_checks.fd_mismatch)
FD_TOL = 1e-10
#: the residual against the numpy contract: round-off of sums of ~1e3 terms
PARTS_TOL = 1e-10
#: trajectories against the old Python path (relative to the largest |q|): the same equations, the Newton
#: tolerance and the order of summation apart
RUN_TOL = 1e-10

SEC = dict(EA=1e5, EI=50.0, kGA=3e4, rhoA=1.0, rhoI=1e-3)


def beam(strain="green-lagrange", n_elements=3):
    return hub_beam(length=1.5, n_elements=n_elements, strain=strain, **SEC)


def modal():
    """A Craig–Bampton reduced beam with its modal derivatives: a quartic strain energy."""
    return beam(n_elements=6).reduced(2, interfaces=("root",), centrifugal=True)


def random_state(body, rng):
    q = np.array(body.q0, dtype=float)
    q[:3] = (0.3, -0.2, 0.7)
    q[3:] += 1e-3 * rng.normal(size=q.size - 3)
    v = np.concatenate([rng.normal(size=3), 0.05 * rng.normal(size=q.size - 3)])
    return q, v


def scene_of(body, prescribed=None):
    """The body alone; ``prescribed``: (R_x(0), θ(0)) of laws R_x, θ = value + 0.1 t."""
    if prescribed is None:
        return sf.Scene([body])
    laws = [sf.MotionLaw(lambda t, c=c: c + 0.1 * t, lambda t: 0.1, lambda t: 0.0) for c in prescribed]
    return sf.Scene([body], prescribed=[sf.Prescribed(body, "Rx", laws[0]), sf.Prescribed(body, "theta", laws[1])])


BODIES = {"beam": beam, "linear-strain beam": lambda: beam("linear"), "modal": modal}


@pytest.mark.parametrize("kind", list(BODIES))
def test_energy_momentum_step_is_the_bodies_contract(kind):
    """Energy-momentum: residual p₁ − p₀ + Δt (g_V − g_G) of the numpy methods, Newton matrix its derivative."""
    body = BODIES[kind]()
    scene = scene_of(body)
    rng = np.random.default_rng(1)
    q0, v0 = random_state(body, rng)
    h = 0.01
    st = loaded_stepper(scene, "energy-momentum", q0, v0)
    x = h * v0 + 1e-3 * rng.normal(size=q0.size)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL
    q1 = q0 + x
    ref, scale = em_reference(body, q0, q1, v0, 2.0 * x / h - v0, h)
    assert np.abs(r - ref).max() <= PARTS_TOL * scale


def newmark_reference(body, q0, v0, a0, x, h):
    """Trapezoidal: r = Δt (M(q₁) q̈₁ + ∇V(q₁) − Q_v(q₁, v₁)) with q̈₁ = (Δq − Δt v₀ − Δt² a₀/4)/(Δt²/4)."""
    q1 = q0 + x
    a1 = (x - h * v0 - 0.25 * h * h * a0) / (0.25 * h * h)
    v1 = v0 + 0.5 * h * (a0 + a1)
    m = dense(body.mass_matrix(q1)) @ a1
    grad = body.potential_gradient(q1)
    qv = body.quadratic_velocity_force(q1, v1)[0]
    scale = h * max(np.abs(m).max(), np.abs(grad).max(), np.abs(qv).max())
    return h * (m + grad - qv), scale


@pytest.mark.parametrize("kind", list(BODIES))
def test_newmark_step_is_the_bodies_contract(kind):
    """Trapezoidal: residual Δt (M q̈₁ + ∇V − Q_v) of the numpy methods, Newton matrix its derivative."""
    body = BODIES[kind]()
    scene = scene_of(body)
    rng = np.random.default_rng(2)
    q0, v0 = random_state(body, rng)
    a0 = rng.normal(size=q0.size)
    h = 0.01
    st = loaded_stepper(scene, "trapezoidal", q0, v0, acc=a0)
    x = h * v0 + 1e-3 * rng.normal(size=q0.size)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL
    ref, scale = newmark_reference(body, q0, v0, a0, x, h)
    assert np.abs(r - ref).max() <= PARTS_TOL * scale


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_prescribed_coordinates_leave_the_matrix(scheme):
    """With R_x and θ prescribed the body's tangent enters only the free rows and columns, still the residual's
    derivative, and the free rows of the residual are the numpy contract's."""
    body = beam()
    rng = np.random.default_rng(3)
    q0, v0 = random_state(body, rng)
    scene = scene_of(body, prescribed=q0[[0, 2]])
    h = 0.02
    st = loaded_stepper(scene, scheme, q0, v0)
    free = scene.free_index
    x = h * v0[free] + 1e-3 * rng.normal(size=free.size)
    mismatch, r, jac = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL and jac.shape == (free.size, free.size)
    dq = np.zeros(scene.n)
    dq[free] = x
    dq[[0, 2]] = 0.1 * h                       # the laws: R_x, θ = value + 0.1 t
    if scheme == "energy-momentum":
        ref, scale = em_reference(body, q0, q0 + dq, v0, 2.0 * dq / h - v0, h)
    else:
        ref, scale = newmark_reference(body, q0, v0, np.zeros(scene.n), dq, h)
        # the prescribed coordinates' velocity and acceleration are their laws', not Newmark's
        v1 = v0 + 0.5 * h * (dq - h * v0) / (0.25 * h * h)
        v1[[0, 2]] = 0.1
        a1 = (dq - h * v0) / (0.25 * h * h)
        a1[[0, 2]] = 0.0
        q1 = q0 + dq
        ref = h * (dense(body.mass_matrix(q1)) @ a1 + body.potential_gradient(q1)
                   - body.quadratic_velocity_force(q1, v1)[0])
    assert np.abs(r - ref[free]).max() <= PARTS_TOL * scale


def test_large_beam_in_csr_storage():
    """A pinned 64-element beam (197 unknowns: the Newton matrix stored as the values of its pattern): the tangent
    lands in the pattern's slots (the residual's derivative) under both schemes."""
    scene = sf.scenes.flexible_pendulum(n_elements=64)
    rng = np.random.default_rng(4)
    q0, v0 = scene.initial_state()
    v0 = v0 + 0.1 * rng.normal(size=v0.size)
    for scheme in ("energy-momentum", "trapezoidal"):
        st = loaded_stepper(scene, scheme, q0, v0, lam=rng.normal(size=scene.n_constraints))
        assert st.packed.storage == 1
        x = np.concatenate([1e-3 * v0 + 1e-6 * rng.normal(size=scene.n), 1e-3 * rng.normal(size=2)])
        mismatch = fd_mismatch(st, 0.0, 1e-3, x)[0]
        assert mismatch < FD_TOL


@pytest.mark.parametrize("kind", list(BODIES))
def test_start_momenta_and_energy(kind):
    """The consistent start solves the numpy M q̈ = Q_v − ∇V; the recorded p_x, p_y, L and T are those of
    p = M(q) v (numpy), V the strain energy (the integral of the numpy gradient)."""
    body = BODIES[kind]()
    scene = scene_of(body)
    rng = np.random.default_rng(5)
    q0, v0 = random_state(body, rng)
    body.q0[:], body.v0[:] = q0, v0
    st = loaded_stepper(scene, "trapezoidal", q0, v0)
    acc = st.start(0.0, q0, v0)[0]
    mass = dense(body.mass_matrix(q0))
    rhs = body.quadratic_velocity_force(q0, v0)[0] - body.potential_gradient(q0)
    assert rel_dev(acc, np.linalg.solve(mass, rhs)) < 1e-10
    rec, _ = run_new(scene, "energy-momentum", 0.01, 3)
    for i in range(3):
        q, v = rec.q[i], rec.v[i]
        p = dense(body.mass_matrix(q)) @ v
        px, py, lz = rec.derived[i, 2], rec.derived[i, 3], rec.derived[i, 7]
        scale = np.abs(p).max() * max(np.abs(q[:2]).max(), 1.0)
        assert abs(px - p[0]) + abs(py - p[1]) <= 1e-12 * scale
        assert abs(lz - (q[0] * p[1] - q[1] * p[0] + p[2])) <= 1e-12 * scale
        assert abs(rec.derived[i, 0] - 0.5 * v @ p) <= 1e-12 * abs(v) @ np.abs(p)
        assert abs(rec.derived[i, 1] - strain_energy(body, q)) <= 1e-12 * abs(strain_energy(body, q))


def strain_energy(body, q):
    """V(q) = ∫₀¹ ∇V(q_R, s q_f) · q ds by 3-point Gauss on the numpy gradient (exact: V is at most quartic in
    q_f, and V = 0 at q_f = 0)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    total = 0.0
    for s, w in zip(0.5 * (nodes + 1.0), 0.5 * weights):
        qs = np.array(q, dtype=float)
        qs[3:] *= s
        total += w * (body.potential_gradient(qs) @ np.concatenate([np.zeros(3), q[3:]]))
    return total


@functools.lru_cache(maxsize=None)
def _modal_slider_crank():
    return sf.scenes.slider_crank(body="plane-stress-modal")


RUNS = {  # name: (scene factory, dt, steps, schemes)
    "flexible pendulum": (sf.scenes.flexible_pendulum, 0.01, 40,
                          ("energy-momentum", "trapezoidal", "generalized-alpha")),
    "spin-up": (lambda: sf.scenes.spin_up_beam(n_elements=4), 0.02, 40,
                ("energy-momentum", "trapezoidal", "generalized-alpha")),
    "modal spin-up": (lambda: sf.scenes.spin_up_beam(body="beam-modal"), 0.02, 40,
                      ("energy-momentum", "generalized-alpha")),
    "double pendulum": (sf.scenes.double_pendulum, 0.01, 30, ("energy-momentum", "trapezoidal")),
    "rotating beam": (sf.scenes.rotating_beam, 0.01, 30, ("trapezoidal",)),
    # the plane-stress reduction takes a while: built once (neither run changes a scene)
    "modal slider-crank": (_modal_slider_crank, 2e-4, 20, ("energy-momentum", "generalized-alpha")),
}


@pytest.mark.parametrize("name, scheme", [(name, s) for name, run in RUNS.items() for s in run[3]])
def test_trajectories_equal_the_python_path(name, scheme):
    """The catalogue's floating-frame scenes (a pinned beam under gravity, the spin-up with its prescribed hub,
    reduced modal bodies, a rigid bar and a beam, a slider-crank with a plane-stress modal rod): q, v and λ of the
    new core are the old Python path's."""
    factory, dt, steps, _ = RUNS[name]
    rec, ref = run_both(factory, scheme, dt, steps)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL            # v = 2Δq/Δt − v₀ (or the Newmark update)
    if rec.lam.size:
        assert rel_dev(rec.lam, ref.lam[1:]) < 1e3 * RUN_TOL


def test_energy_balance_of_the_spin_up():
    """Energy-momentum: T + V − E₀ equals the work the prescribed hub does, step by step, to the Newton tolerance."""
    scene = sf.scenes.spin_up_beam(n_elements=4)
    rec, _ = run_new(scene, "energy-momentum", 0.05, 60)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    assert np.abs(energy - rec.work).max() <= 1e-8 * np.abs(energy).max()
    assert np.abs(energy).max() > 1.0                             # the hub did work
