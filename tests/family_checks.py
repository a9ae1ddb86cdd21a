"""Checks the family tests share: a scene's step on the new compiled core (``Stepper``) at given unknowns,
central differences of its residual, and runs on the new core and on the old Python path."""
import numpy as np
import scipy.sparse as sps

import skfem_flex as sf
from skfem_flex.schemes.stepper import Stepper
from skfem_flex.schemes.energy_momentum import EnergyMomentum
from skfem_flex.schemes.newmark import GeneralizedAlpha, Trapezoidal

SCHEMES = {"energy-momentum": EnergyMomentum, "trapezoidal": Trapezoidal, "generalized-alpha": GeneralizedAlpha}


def dense(a):
    return a.toarray() if sps.issparse(a) else np.asarray(a, dtype=float)


def loaded_stepper(scene, scheme, q, v, acc=None, lam=None):
    """A Stepper of ``scene`` under ``scheme`` (a name) loaded with the state (q, v, acc = pseudo, λ) at t = 0."""
    sch = SCHEMES[scheme]()
    st = Stepper(scene, sch)
    acc = np.zeros(scene.n) if acc is None else acc
    lam = np.zeros(scene.n_constraints) if lam is None else lam
    st.load(sch.make_state(0.0, np.array(q, dtype=float), np.array(v, dtype=float), acc=np.array(acc, dtype=float),
                           pseudo=np.array(acc, dtype=float), lam=np.array(lam, dtype=float)))
    return st


def fd_mismatch(st, t0, h, x, delta=3e-3):
    """max over rows of |J − J_fd| / max|J_row|, J the Newton matrix at x and J_fd the derivative of the
    residual by central differences with steps d_j = δ·max(|x_j|, 1e-3) and d_j/2, Richardson-extrapolated
    ((4 D(d/2) − D(d))/3: truncation O(d⁴), round-off ε/d). At δ = 3e-3 they reach 1e-13–6e-11 of a row's
    scale for these residuals (plain central differences 1e-10 at best: a stiff beam's internal forces are
    differences of terms far larger than they are). Also returns (residual, J)."""
    r, jac, _ = st.evaluate(t0, h, x)
    jac = dense(jac)
    fd = np.empty_like(jac)
    for j in range(x.size):
        d = delta * max(abs(x[j]), 1e-3)
        e = np.zeros(x.size)
        cols = []
        for step in (d, 0.5 * d):
            e[j] = step
            cols.append((st.evaluate(t0, h, x + e)[0] - st.evaluate(t0, h, x - e)[0]) / (2.0 * step))
        fd[:, j] = (4.0 * cols[1] - cols[0]) / 3.0
    st.evaluate(t0, h, x)
    row = np.maximum(np.abs(jac).max(axis=1), np.abs(fd).max(axis=1))
    row[row == 0.0] = 1.0
    return (np.abs(jac - fd) / row[:, None]).max(), r, jac


def run_new(scene, scheme, dt, steps):
    """``steps`` steps of size dt on the new core from the scene's consistent start; (Records, Stepper)."""
    sch = SCHEMES[scheme]()
    st = Stepper(scene, sch)
    q0, v0 = scene.initial_state()
    acc, lam, reaction = st.start(0.0, q0, v0)
    st.load(sch.make_state(0.0, q0, v0, acc=acc, pseudo=acc.copy(), lam=lam, prescribed_force=reaction))
    chunk = st.advance(0.0, np.full(steps, dt), np.ones(steps, dtype=bool), 25, True)
    assert chunk.status == 0 and chunk.steps == steps
    return chunk.records, st


def run_both(factory, scheme, dt, steps):
    """The same run on the new core and on the old Python path: (new Records, old Result)."""
    rec, _ = run_new(factory(), scheme, dt, steps)
    ref = sf.simulate(factory(), steps * dt, dt, integrator=scheme, compiled=False)
    assert len(ref.t) == steps + 1
    return rec, ref


def rel_dev(a, ref):
    """max|a − ref| / max|ref|."""
    return np.abs(a - ref).max() / max(np.abs(ref).max(), 1e-300)


def em_reference(body, q0, q1, v0, v1, h, gravity=None):
    """r = p(q₁, v₁) − p(q₀, v₀) + Δt g_V − Δt g_G from a body's numpy methods (with ``gravity``, g (m/s²): its
    discrete gradient joins g_V), and the scale of the terms."""
    p1, p0 = dense(body.mass_matrix(q1)) @ v1, dense(body.mass_matrix(q0)) @ v0
    gk = body.kinetic_discrete_gradient(q0, q1, v0, v1)[0]
    gp = body.potential_discrete_gradient(q0, q1)[0]
    if gravity is not None:
        gp = gp + body.gravity_discrete_gradient(q0, q1, gravity)[0]
    scale = max(np.abs(p1).max(), np.abs(p0).max(), h * np.abs(gk).max(), h * np.abs(gp).max())
    return p1 - p0 + h * gp - h * gk, scale


def assert_constraint_contract(scene, scheme, seed=3, h=0.02):
    """At a random state, unknowns and multipliers: the Newton matrix is the central difference of the residual
    (:func:`fd_mismatch` < 1e-9); the constraint force r(μ) − r(0) is the constraints' D(q₀, q₁)ᵀμ (energy-momentum)
    or Φ_q(q₁)ᵀμ (Newmark), and the rows (but the trapezoidal rule's velocity rows) are Φ(q₁)."""
    from helpers import random_scene_state

    rng = np.random.default_rng(seed)
    q0, v0 = random_scene_state(scene, rng)
    m, nf = scene.n_constraints, scene.n
    st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=q0.size))
    dq = h * v0 + 1e-2 * rng.normal(size=nf)
    mu = rng.normal(size=m)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, np.concatenate([dq, mu]))
    assert mismatch < 1e-9
    r0 = st.evaluate(0.0, h, np.concatenate([dq, np.zeros(m)]))[0]
    q1 = q0 + dq
    if scheme == "energy-momentum":
        dmat = dense(scene.constraint_discrete_gradient(q0, q1, h))
    else:
        dmat = dense(scene.constraint_jacobian(q1, h))
    force = dmat.T @ mu
    assert np.abs((r - r0)[:nf] - force).max() <= 1e-10 * np.abs(force).max()
    if scheme != "trapezoidal":
        rows = scene.constraint_value(q1, h)
        assert np.abs(r[nf:] - rows).max() <= 1e-10 * max(np.abs(dmat).max() * np.abs(q1).max(), 1.0)
