"""The compiled Newmark terms of floating-frame bodies (bodies/floating_kernel.py: newmark_terms) against the
body's numpy contract methods.

mass_matrix, momentum_jacobian, quadratic_velocity_force, potential_gradient and potential_hessian are
separate numpy implementations of the same equations, themselves checked against finite differences
(test_floating.py, test_modal.py); the kernel must agree with them to round-off, and must write nothing
the body's CSR pattern cannot hold.
"""
import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies import PlaneStress
from skfem_flex.bodies.floating import kernel as fk

from helpers import SPIN_UP_SECTION as SEC, dense, floating_beam, relerr

# a section whose stiffness is of the size of the kinetic terms at ω, α ~ 1: the tangent's comparison
# then also tests B and ∂Q_v/∂q to round-off instead of below K's
SOFT = dict(EA=20.0, EI=2.0, kGA=8.0, rhoA=1.2, rhoI=6e-4)
BEAMS = [dict(reference=ref, strain=strain, order=order, sparse=sparse, section="stiff")
         for ref in ("clamped", "pinned") for strain in ("green-lagrange", "linear") for order in (1, 2)
         for sparse in (False, True)]
BEAMS += [dict(reference=ref, strain="green-lagrange", order=1, sparse=False, section="soft")
          for ref in ("clamped", "pinned")]
MODALS = ["beam-gl", "beam-linear", "plate-gl"]

_BODIES = {}


def beam_body(n_elements, reference, strain, order, sparse, section):
    return floating_beam(n_elements, reference, strain, order, sparse, SEC if section == "stiff" else SOFT)


def modal_body(kind):
    """Reduced bodies: a beam (quartic stiffening or linear), a plate whose frame origin is a corner (S_0 has
    both components); built once."""
    if kind not in _BODIES:
        if kind == "plate-gl":
            mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3))
            b = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01, order=2).reduced(4)
        else:
            b = sf.scenes.spin_up_beam(body="beam-modal",
                                       strain="linear" if kind == "beam-linear" else "green-lagrange").bodies[0]
        _BODIES[kind] = b
    return _BODIES[kind]


def random_state(body, rng, scale):
    """q with elastic coordinates of size ``scale`` and arbitrary angle; v, a of order 1."""
    n = body.n_dofs
    q = rng.normal(size=n) * scale
    q[:3] = rng.normal(size=3) * [1.0, 1.0, 3.0]
    return q, rng.normal(size=n), rng.normal(size=n), np.abs(rng.normal(size=n))


def reference_terms(body, q, v, a, c_a, c_v, terms):
    M = dense(body.mass_matrix(q))
    g, gq, gv = body.quadratic_velocity_force(q, v)
    data = (c_a * M + dense(body.momentum_jacobian(q, a)) + dense(body.potential_hessian(q))
            - (dense(gq) + c_v * dense(gv)))
    return M @ a, body.potential_gradient(q), g, data, np.abs(M) @ terms


def pattern_mask(kd):
    n = kd.n
    mask = np.zeros((n, n), dtype=bool)
    mask[np.repeat(np.arange(n), np.diff(kd.pat_ptr)), kd.pat_idx] = True
    return mask


def scatter(kd, data):
    n = kd.n
    out = np.zeros((n, n))
    np.add.at(out, (np.repeat(np.arange(n), np.diff(kd.pat_ptr)), kd.pat_idx), data)
    return out


def check_body(body, rng, scales):
    kd = body.compiled_kernel_data()
    outside = ~pattern_mask(kd)
    for scale in scales:
        for dt in (1e-3, 2e-2):
            # trapezoidal rule, then terms that each dominate: M alone, ∂Q_v/∂v alone, neither
            for c_a, c_v in ((4.0 / dt ** 2, 2.0 / dt), (1e9, 0.0), (0.0, 1e9), (0.0, 0.0)):
                q, v, a, terms = random_state(body, rng, scale)
                got = fk.newmark_terms(kd, q, v, a, c_a, c_v, terms)
                ref = reference_terms(body, q, v, a, c_a, c_v, terms)
                # the numpy matrices hold nothing the pattern cannot
                for mat in (body.mass_matrix(q), body.momentum_jacobian(q, a), body.potential_hessian(q),
                            *body.quadratic_velocity_force(q, v)[1:]):
                    assert not np.any(dense(mat)[outside])
                got = got[:3] + (scatter(kd, got[3]),) + got[4:]
                for name, x, y in zip(("inertia", "grad", "qv", "data", "mass_terms"), got, ref):
                    assert relerr(x, y) < 1e-12, (name, relerr(x, y), c_a, c_v)


@pytest.mark.parametrize("case", BEAMS, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_newmark_terms_of_a_floating_beam_equal_the_contract_methods(case):
    body = beam_body(5, **case)
    assert body.compiled_kernel_data().green == (case["strain"] == "green-lagrange")
    check_body(body, np.random.default_rng(7), (1e-3, 0.02))


@pytest.mark.parametrize("reference", ["clamped", "pinned"])
def test_newmark_terms_of_a_large_sparse_beam(reference):
    body = beam_body(60, reference, "green-lagrange", 1, None, "stiff")
    assert body.sparse                                             # by size, not by request
    check_body(body, np.random.default_rng(5), (1e-3,))


@pytest.mark.parametrize("kind", MODALS)
def test_newmark_terms_of_a_modal_body_equal_the_contract_methods(kind):
    body = modal_body(kind)
    assert body.compiled_kernel_data().quartic == (not body.energy.linear)
    # η whose displacements Φη are 1e-3 and 0.1 of the body's size: the quartic terms small and large
    size = np.abs(body.model.position).max() / np.abs(body.Phi).max()
    check_body(body, np.random.default_rng(3), (1e-3 * size, 0.1 * size))


@pytest.mark.parametrize("kind", ["beam", "modal"])
def test_newmark_gradient_and_tangent_are_derivatives(kind):
    """Independent of the numpy methods: grad is ∂V/∂q of the compiled energy, and the tangent (c_a = c_v = 0,
    a = const) is ∂(M a + ∇V − Q_v)/∂q, by central differences."""
    body = beam_body(4, "pinned", "green-lagrange", 2, False, "soft") if kind == "beam" else modal_body("beam-gl")
    kd = body.compiled_kernel_data()
    rng = np.random.default_rng(2)
    scale = 0.02 if kind == "beam" else 0.05 * np.abs(body.model.position).max() / np.abs(body.Phi).max()
    q, v, a, terms = random_state(body, rng, scale)
    n = body.n_dofs
    h = 1e-6 * np.maximum(np.abs(q), scale)

    def force(x):
        inertia, grad, qv, _, _ = fk.newmark_terms(kd, x, v, a, 0.0, 0.0, terms)
        return inertia + grad - qv

    _, grad, _, data, _ = fk.newmark_terms(kd, q, v, a, 0.0, 0.0, terms)
    fd_grad, fd_jac = np.zeros(n), np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h[j]
        fd_grad[j] = (fk.potential_energy(kd, q + e) - fk.potential_energy(kd, q - e)) / (2 * h[j])
        fd_jac[:, j] = (force(q + e) - force(q - e)) / (2 * h[j])
    assert relerr(grad, fd_grad) < 1e-6
    assert relerr(scatter(kd, data), fd_jac) < 1e-6
