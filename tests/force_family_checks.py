"""Shared checks of the force-element families of the compiled core (tests/test_family_*.py of springs,
two-point springs, point loads and dampers): a scene run by :class:`~skfem_flex.schemes.stepper.Stepper`, its
Newton matrix against differences of its residual, its residual parts against the elements' numpy
contracts, and its trajectories against the Python path (``sf.simulate(..., compiled=False)``: every element
through its own numpy methods)."""
import numpy as np

import skfem_flex as sf
from skfem_flex.schemes.stepper import Stepper
from skfem_flex.schemes.energy_momentum import EnergyMomentum
from skfem_flex.schemes.newmark import GeneralizedAlpha, Trapezoidal

SCHEMES = {"energy-momentum": EnergyMomentum, "trapezoidal": Trapezoidal, "generalized-alpha": GeneralizedAlpha}


def random_stepper(scene, scheme_name, seed, spread=0.2):
    """A Stepper of ``scene`` with a random loaded state near the initial one: (stepper, q0, v0)."""
    rng = np.random.default_rng(seed)
    scheme = SCHEMES[scheme_name]()
    st = Stepper(scene, scheme)
    q0, _ = scene.initial_state()
    q0 = q0 + spread * rng.normal(size=q0.size)
    v0 = rng.normal(size=q0.size)
    acc = rng.normal(size=q0.size)
    st.load(scheme.make_state(0.0, q0, v0, acc=acc, pseudo=acc.copy(), lam=np.zeros(st.packed.m)))
    return st, q0, v0


def derivative_check(st, t0, h, x, eps=3e-4):
    """(Newton matrix, its largest difference from the residual's 5-point central differences (error
    O(ε⁴), round-off O(u |r| / ε): ε = 3e-4 balances them near 1e-12 for unknowns of order 0.1–1), relative
    to the matrix's largest entry)."""
    _, mat, _ = st.evaluate(t0, h, x)
    fd = np.empty_like(mat)
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = eps
        r = [st.evaluate(t0, h, x + s * e)[0] for s in (2.0, 1.0, -1.0, -2.0)]
        fd[:, j] = (-r[0] + 8.0 * r[1] - 8.0 * r[2] + r[3]) / (12.0 * eps)
    st.evaluate(t0, h, x)               # the context back at x
    return mat, np.abs(mat - fd).max() / np.abs(mat).max()


def evaluation_points(st, t0, h):
    """After an evaluation: (q_a, q_b) of the discrete gradients, (q_e, v_e, t_e) of the loads, as the
    scheme defined them (.tasks): energy-momentum q0, q1 and the mid-point; Newmark q1, q1 and (q1, v1, t1)."""
    ws, data = st.ws, st.data
    q1, v1 = ws.vectors["q1"].copy(), ws.vectors["v1"].copy()
    if st.scheme.mid_point_loads:
        return (data.array("q").copy(), q1), (data.array("qm").copy(), data.array("vm").copy(), t0 + 0.5 * h)
    return (q1, q1), (q1, v1, t0 + h)


def scatter(scene, element, local):
    """The element's local vector on the scene's coordinates."""
    out = np.zeros(scene.n)
    idx = dict((id(f), i) for f, i in scene.conservative_forces + scene.loads)[id(element)]
    np.add.at(out, np.asarray(idx), local)
    return out


def local(scene, element, q):
    idx = dict((id(f), i) for f, i in scene.conservative_forces + scene.loads)[id(element)]
    return q[np.asarray(idx)]


def run_new(scene, scheme_name, t_end, dt):
    """Steps of the new core from the scene's initial state (consistent start): its Records."""
    scheme = SCHEMES[scheme_name]()
    st = Stepper(scene, scheme)
    assert not st.packed.python_elements            # every element in a compiled family
    q0, v0 = scene.initial_state()
    acc, lam, reaction = st.start(0.0, q0, v0)
    st.load(scheme.make_state(0.0, q0, v0, acc=acc, pseudo=acc.copy(), lam=lam, prescribed_force=reaction))
    ns = int(round(t_end / dt))
    chunk = st.advance(0.0, np.full(ns, dt), np.ones(ns, dtype=bool), 25, True)
    assert chunk.status == 0 and chunk.steps == ns, (chunk.status, chunk.steps)
    return chunk.records


def initial_energy(scene):
    """T + V of the scene's initial state, J (the Records hold the steps after it)."""
    q0, v0 = scene.initial_state()
    return scene.kinetic_energy(q0, v0) + scene.potential_energy(q0)


def compare_runs(factory, scheme_name, t_end, dt):
    """The new core's and the Python path's runs (compiled=False) of ``factory()``: (new records, old result, largest q
    difference relative to max |q|)."""
    new = run_new(factory(), scheme_name, t_end, dt)
    old = sf.simulate(factory(), t_end, dt, integrator=scheme_name, compiled=False)
    np.testing.assert_allclose(new.t, old.t[1:], rtol=1e-14)
    return new, old, np.abs(new.q - old.q[1:]).max() / np.abs(old.q).max()

def spring_potential(scene, q):
    """V(q) of the scene's springs (gravity left out), J."""
    return sum(f.potential_energy(local(scene, f, q)) for f, _ in scene.conservative_forces
               if not isinstance(f, sf.Gravity))


def check_spring_step(factory, scheme):
    """Newton matrix = 5-point differences of the residual to 1e-10 of its scale; g_p = the elements'
    discrete gradients to 1e-12 relative; the springs' share of the matrix is not negligible."""
    scene = factory()
    for seed in range(3):
        st, q0, v0 = random_stepper(scene, scheme, seed)
        x = 0.3 * np.random.default_rng(10 + seed).normal(size=st.packed.nx)
        h = 0.2
        mat, err = derivative_check(st, 0.3, h, x)
        assert err <= 1e-10, err
        (qa, qb), _ = evaluation_points(st, 0.3, h)
        expected = sum(scatter(scene, f, f.potential_discrete_gradient(local(scene, f, qa), local(scene, f, qb))[0])
                       for f, _ in scene.conservative_forces)          # no gravity in these scenes
        gp = st.ws.vectors["gp"]
        assert np.abs(gp - expected).max() <= 1e-12 * np.abs(expected).max()
        bare = random_stepper(factory(forces=False), scheme, seed)[0]
        mat0 = bare.evaluate(0.3, h, x)[1]
        assert np.abs(mat - mat0).max() >= 0.05 * np.abs(mat).max()


def check_spring_run(factory, t_end, dt, scheme):
    """q to 1e-10 relative (they agree to ~1e-15), the recorded potential to 1e-12 of the energy scale;
    energy-momentum keeps T + V − work to the Newton tolerance."""
    new, old, dq = compare_runs(factory, scheme, t_end, dt)
    assert dq <= 1e-10, dq
    scene = factory()
    e_scale = np.abs(old.total_energy).max()
    pot = np.array([spring_potential(scene, q) for q in new.q])
    grav = old.potential[1:] - np.array([spring_potential(scene, q) for q in old.q[1:]])       # gravity's share
    assert np.abs(new.derived[:, 1] - grav - pot).max() <= 1e-12 * e_scale
    assert np.abs(new.derived[:, 1] - old.potential[1:]).max() <= 1e-10 * e_scale
    assert np.ptp(pot) > 0.01 * e_scale                 # the springs did work
    if scheme == "energy-momentum":
        energy = new.derived[:, 0] + new.derived[:, 1] - new.work
        assert np.abs(energy - initial_energy(scene)).max() <= 1e-8 * e_scale

