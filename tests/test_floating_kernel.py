"""The compiled FloatingBeam kernels (bodies/floating_kernel.py) against the body's contract methods.

The contract methods (mass_matrix, momentum_jacobian, kinetic_discrete_gradient,
potential_discrete_gradient, element_strain_energy) are separate numpy implementations of the same
equations, themselves checked against finite differences and quadrature (test_floating.py); the
fused compiled kernel must agree with them to round-off.
"""
import numpy as np
import pytest
import scipy.sparse as sps
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating.body import FloatingBeam

SEC = dict(EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4)
CASES = [dict(reference=ref, strain=strain, order=order, sparse=sparse)
         for ref in ("clamped", "pinned") for strain in ("green-lagrange", "linear") for order in (1, 2)
         for sparse in (False, True)]


def make_body(n_elements, reference, strain, order, sparse):
    beam = sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, 10.0, n_elements + 1)), sf.Section(**SEC),
                             order=order)
    return FloatingBeam(beam, reference=reference, strain=strain, sparse=sparse)


def random_states(body, rng, dt):
    n = body.n_dofs
    q0 = rng.normal(size=n) * 0.02
    q0[:3] = rng.normal(size=3) * [1.0, 1.0, 3.0]
    q1 = q0 + rng.normal(size=n) * 1e-3
    q1[2] = q0[2] + rng.choice([1e-5, 0.3])           # both branches of sinc(Δθ/2)
    v0, v1 = rng.normal(size=n), rng.normal(size=n)
    return q0, q1, v0, v1


def dense(a):
    return a.toarray() if sps.issparse(a) else np.asarray(a)


def relerr(a, b):
    a, b = dense(a), dense(b)
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def contract_terms(body, q0, q1, v0, v1, dt):
    """The fused terms assembled from the contract methods (the scene's general path)."""
    gk, gk_q, gk_v = body.kinetic_discrete_gradient(q0, q1, v0, v1)
    gp, gp_q = body.potential_discrete_gradient(q0, q1)
    jac = ((2.0 / dt) * dense(body.mass_matrix(q1)) + dense(body.momentum_jacobian(q1, v1))
           - dt * dense(gk_q) - 2.0 * dense(gk_v) + dt * dense(gp_q))
    floor = dt * (np.abs(dense(gp_q)) @ (np.abs(q0) + np.abs(q1)))
    return dense(body.mass_matrix(q1)) @ v1, gk, gp, jac, floor


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_energy_momentum_kernel_equals_the_contract_methods(case):
    body = make_body(5, **case)
    rng = np.random.default_rng(7)
    for dt in (1e-3, 2e-2):
        for _ in range(3):
            q0, q1, v0, v1 = random_states(body, rng, dt)
            got = body.energy_momentum_terms(q0, q1, v0, v1, dt)
            ref = contract_terms(body, q0, q1, v0, v1, dt)
            for name, a, b, tol in zip(("p1", "g_kin", "g_pot", "jac", "floor"), got, ref,
                                       (1e-13, 1e-12, 1e-12, 1e-11, 1e-11)):
                assert relerr(a, b) < tol, (name, relerr(a, b))
            assert isinstance(got[3], sps.csr_matrix) if case["sparse"] else isinstance(got[3], np.ndarray)
            if case["sparse"]:                                       # the fixed pattern, in canonical form
                assert got[3].has_canonical_format


@pytest.mark.parametrize("case", CASES[::2], ids=lambda c: "-".join(str(v) for v in c.values()))
def test_momentum_and_strain_energy_kernels_equal_the_contract_methods(case):
    body = make_body(5, **case)
    rng = np.random.default_rng(11)
    for _ in range(3):
        q, _, v, _ = random_states(body, rng, 1e-3)
        p = dense(body.mass_matrix(q)) @ v
        assert relerr(body.momentum(q, v), p) < 1e-13
        assert body.potential_energy(q) == pytest.approx(body.element_strain_energy(q).sum(), rel=1e-12)
        assert body.kinetic_energy(q, v) == pytest.approx(0.5 * float(v @ p), rel=1e-13)


def test_momentum_cache_follows_the_state():
    """The one-entry momentum cache must never return p for another (q, v)."""
    body = make_body(3, "clamped", "green-lagrange", 1, False)
    rng = np.random.default_rng(1)
    q, _, v, _ = random_states(body, rng, 1e-3)
    p = body.momentum(q, v)
    q2 = q.copy()
    q2[2] += 0.1
    assert relerr(body.momentum(q2, v), dense(body.mass_matrix(q2)) @ v) < 1e-13
    v2 = v * 2.0
    assert relerr(body.momentum(q, v2), 2.0 * p) < 1e-13
