"""The compiled FloatingBeam kernels (bodies/floating_kernel.py) against the body's contract methods.

The contract methods (mass_matrix, momentum_jacobian, kinetic_discrete_gradient,
potential_discrete_gradient, element_strain_energy) are separate numpy implementations of the same
equations, themselves checked against finite differences and quadrature (test_floating.py); the
fused compiled kernel must agree with them to round-off.
"""
import numpy as np
import pytest
import scipy.sparse as sps

from helpers import contract_terms, dense, floating_beam, random_floating_states, relerr

CASES = [dict(reference=ref, strain=strain, order=order, sparse=sparse)
         for ref in ("clamped", "pinned") for strain in ("green-lagrange", "linear") for order in (1, 2)
         for sparse in (False, True)]


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_energy_momentum_kernel_equals_the_contract_methods(case):
    body = floating_beam(5, **case)
    rng = np.random.default_rng(7)
    for dt in (1e-3, 2e-2):
        for _ in range(3):
            q0, q1, v0, v1 = random_floating_states(body, rng, 0.02, 1e-3)
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
    body = floating_beam(5, **case)
    rng = np.random.default_rng(11)
    for _ in range(3):
        q, _, v, _ = random_floating_states(body, rng, 0.02, 1e-3)
        p = dense(body.mass_matrix(q)) @ v
        assert relerr(body.momentum(q, v), p) < 1e-13
        assert body.potential_energy(q) == pytest.approx(body.element_strain_energy(q).sum(), rel=1e-12)
        assert body.kinetic_energy(q, v) == pytest.approx(0.5 * float(v @ p), rel=1e-13)


def test_momentum_cache_follows_the_state():
    """The one-entry momentum cache must never return p for another (q, v)."""
    body = floating_beam(3, "clamped", "green-lagrange", 1, False)
    rng = np.random.default_rng(1)
    q, _, v, _ = random_floating_states(body, rng, 0.02, 1e-3)
    p = body.momentum(q, v)
    q2 = q.copy()
    q2[2] += 0.1
    assert relerr(body.momentum(q2, v), dense(body.mass_matrix(q2)) @ v) < 1e-13
    v2 = v * 2.0
    assert relerr(body.momentum(q, v2), 2.0 * p) < 1e-13
