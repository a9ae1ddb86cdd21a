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
