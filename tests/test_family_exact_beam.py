"""The exact-beam family of the compiled core (skfem_flex/compiled/families/exact_beam.py): the strain energy of
geometrically exact beams (ExactBeam, linear and quadratic elements, Cayley and mid-point rotation rates).

1. Kernel against the specification (compiled/tasks.py): at random states with large section turns, the Newton
   matrix is the central difference of the residual under energy-momentum and trapezoidal (dense and CSR
   storage); the residual is the beam's numpy contract (energy-momentum: M (v₁ − v₀) + Δt S g_V with the
   numpy potential_discrete_gradient and S = Δψ/w on the Cayley rows; Newmark: Δt (M q̈₁ + ∇V)); a folded
   element or a section turn of π in a step is refused; the recorded V is the numpy potential_energy.
2. Trajectories (the very flexible pendulum, the exact spin-up, a free beam) equal the old Python path under
   every scheme.
3. Energy balance of the energy-momentum scheme on the very flexible pendulum (conservative: E₁ = E₀).
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.compiled.tasks import STATUS_OK, STATUS_REFUSED
from skfem_flex.numerics.rotations import cayley, cayley_ratio

from family_checks import dense, fd_mismatch, loaded_stepper, rel_dev, run_both, run_new

#: the Newton matrix against central differences, relative to each row's largest entry (family_checks)
FD_TOL = 1e-10
#: the residual against the numpy contract
PARTS_TOL = 1e-10
#: trajectories against the old Python path, relative to the largest |q|
RUN_TOL = 1e-10

SEC = dict(EA=1e4, EI=100.0, kGA=1e4, rhoA=1.0, rhoI=10.0)


def beam(order=1, n_elements=3, rotation_rate="cayley"):
    return sf.ExactBeam.from_points(sf.Section(**SEC), (0.0, 0.0), (1.6, 1.2), n_elements=n_elements, order=order,
                                    name="beam", rotation_rate=rotation_rate)


def random_state(body, rng, size=1.0):
    """Displacements of 1 % of ``size`` (an element's length) and section angles of 0.5 rad."""
    q = np.array(body.q0, dtype=float)
    psi = body.node_dofs[:, 2]
    q += 1e-2 * size * rng.normal(size=q.size)
    q[psi] += 0.5 * rng.normal(size=psi.size)
    return q, rng.normal(size=q.size)


def increment(body, rng, h, v0):
    """Unknowns Δq: the velocity's step, and section turns up to about 1 rad."""
    x = h * v0 + 1e-3 * rng.normal(size=v0.size)
    x[body.node_dofs[:, 2]] += 0.6 * rng.normal(size=body.node_dofs.shape[0])
    return x


CASES = {"linear": dict(order=1), "quadratic": dict(order=2), "mid-point rates": dict(rotation_rate="mid-point")}


@pytest.mark.parametrize("case", list(CASES))
def test_energy_momentum_step_is_the_beams_contract(case):
    body = beam(**CASES[case])
    scene = sf.Scene([body])
    rng = np.random.default_rng(1)
    q0, v0 = random_state(body, rng)
    h = 0.05
    st = loaded_stepper(scene, "energy-momentum", q0, v0)
    x = increment(body, rng, h, v0)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL
    # z = Δq, or the Cayley rate 2 tan(Δψ/2) on the Cayley rows, whose residual rows are scaled by Δψ/z
    cay = np.asarray(scene.cayley_index, dtype=int)
    assert cay.size == (body.node_dofs.shape[0] if case != "mid-point rates" else 0)
    z, ratio = x.copy(), np.ones(x.size)
    z[cay], ratio[cay] = cayley(x[cay]), cayley_ratio(x[cay])
    mass = dense(body.mass_matrix(q0))
    v1 = 2.0 * z / h - v0
    g = body.potential_discrete_gradient(q0, q0 + x)[0]
    ref = mass @ (v1 - v0) + ratio * (h * g)
    scale = max(np.abs(mass @ v1).max(), h * np.abs(g).max())
    assert np.abs(r - ref).max() <= PARTS_TOL * scale


@pytest.mark.parametrize("case", ["linear", "quadratic"])
def test_newmark_step_is_the_beams_contract(case):
    body = beam(**CASES[case])
    scene = sf.Scene([body])
    rng = np.random.default_rng(2)
    q0, v0 = random_state(body, rng)
    a0 = rng.normal(size=q0.size)
    h = 0.05
    st = loaded_stepper(scene, "trapezoidal", q0, v0, acc=a0)
    x = increment(body, rng, h, v0)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL
    a1 = (x - h * v0 - 0.25 * h * h * a0) / (0.25 * h * h)
    m_a, grad = dense(body.mass_matrix(q0)) @ a1, body.potential_gradient(q0 + x)
    ref = h * (m_a + grad)
    assert np.abs(r - ref).max() <= PARTS_TOL * h * max(np.abs(m_a).max(), np.abs(grad).max())


def test_large_beam_in_csr_storage():
    """The very flexible pendulum with 64 elements (193 unknowns, stored as the values of the pattern) under both
    schemes; its root is prescribed, so a row and column of the beam's tangent are dropped."""
    scene = sf.scenes.very_flexible_pendulum(n_elements=64)
    body = scene.bodies[0]
    rng = np.random.default_rng(3)
    q0, v0 = random_state(body, rng, size=body.length / 64)
    q0[:2] = 0.0
    v0[:2] = 0.0
    free = scene.free_index
    for scheme in ("energy-momentum", "trapezoidal"):
        st = loaded_stepper(scene, scheme, q0, v0)
        assert st.packed.storage == 1
        x = 1e-3 * v0[free] + 1e-3 * rng.normal(size=free.size)
        assert fd_mismatch(st, 0.0, 1e-3, x)[0] < FD_TOL


def _status(st, h, x):
    st.evaluate(0.0, h, x)
    return int(st.ws.ctx[0]["status"])


def test_folded_elements_and_large_turns_are_refused():
    """A step that folds an element (stretch 1 + ε ≤ 0) is refused under both schemes; a section turn of π in one
    step too (mid-point rates: no Cayley coordinate, so the family's own check answers)."""
    rng = np.random.default_rng(4)
    for scheme, rate in (("energy-momentum", "cayley"), ("trapezoidal", "cayley"),
                         ("energy-momentum", "mid-point")):
        body = beam(rotation_rate=rate)
        q0, v0 = np.array(body.q0, dtype=float), np.zeros(body.n_dofs)
        st = loaded_stepper(sf.Scene([body]), scheme, q0, v0)
        x = 1e-3 * rng.normal(size=q0.size)
        assert _status(st, 0.01, x) == STATUS_OK
        folded = x.copy()
        x0 = body.nodal_positions(q0)
        folded[3:5] = -1.5 * (x0[1] - x0[0])                             # node 1 behind node 0
        assert _status(st, 0.01, folded) == STATUS_REFUSED
        if rate == "mid-point":
            turned = x.copy()
            turned[body.node_dofs[1, 2]] = 3.2
            assert _status(st, 0.01, turned) == STATUS_REFUSED


def test_recorded_strain_energy_is_the_beams():
    """TASK_ENERGY: the recorded V is the numpy potential_energy at the recorded states (no gravity here)."""
    body = beam(order=2)
    body.q0[body.node_dofs[-1, 2]] = 0.3
    body.v0[body.node_dofs[:, 2]] = 2.0
    rec, _ = run_new(sf.Scene([body]), "energy-momentum", 0.01, 5)
    for q, pot in zip(rec.q, rec.derived[:, 1]):
        assert pot == pytest.approx(body.potential_energy(q), rel=1e-12)
    assert rec.derived[:, 1].min() > 0.0


def free_beam(rate):
    """A free exact beam, bent and spinning: no loads, no constraints."""
    def make():
        body = beam(n_elements=4, rotation_rate=rate)
        body.q0[body.node_dofs[:, 2]] = np.linspace(0.0, 0.4, body.node_dofs.shape[0])
        body.v0[body.node_dofs[:, 2]] = 1.5
        body.v0[body.node_dofs[:, 0]] = 0.2
        return sf.Scene([body], name="free exact beam")
    return make


RUNS = {  # name: (scene factory, dt, steps, schemes)
    "very flexible pendulum": (lambda: sf.scenes.very_flexible_pendulum(n_elements=8), 2e-3, 50,
                               ("energy-momentum", "trapezoidal", "generalized-alpha")),
    "exact spin-up": (lambda: sf.scenes.spin_up_beam(body="exact", n_elements=4), 0.02, 40,
                      ("energy-momentum", "trapezoidal", "generalized-alpha")),
    # (past 27 steps the Newmark runs fold an element in a Newton iterate: both paths halve the step there)
    "free beam": (free_beam("cayley"), 0.01, 25, ("energy-momentum", "generalized-alpha")),
    "free beam, mid-point rates": (free_beam("mid-point"), 0.01, 25, ("energy-momentum", "trapezoidal")),
}


@pytest.mark.parametrize("name, scheme", [(name, s) for name, run in RUNS.items() for s in run[3]])
def test_trajectories_equal_the_python_path(name, scheme):
    factory, dt, steps, _ = RUNS[name]
    rec, ref = run_both(factory, scheme, dt, steps)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL


def test_energy_balance_of_the_very_flexible_pendulum():
    """Energy-momentum on a conservative scene: T + V (strain and gravity) stays E₀ to the Newton tolerance
    while the pendulum falls through a large swing."""
    scene = sf.scenes.very_flexible_pendulum(n_elements=8)
    rec, _ = run_new(scene, "energy-momentum", 5e-3, 100)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    kinetic = rec.derived[:, 0]
    assert np.abs(energy - energy[0]).max() <= 1e-8 * kinetic.max()
    assert kinetic.max() > 1.0 and np.ptp(rec.derived[:, 1]) > 1.0
