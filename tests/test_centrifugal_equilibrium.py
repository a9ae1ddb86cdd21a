"""The steady state of a spinning floating-frame beam at any mesh size (rotating_beam builds at N = 101, 1000, ...).

The centrifugal balance ∇V(q_f) = ω²(c + M_A q_f) is solved by the package's Newton core with a
residual scaled by the balance's own terms and their round-off floor; the rotating modes of large
beams come from a sparse shift-invert solve. ExactBeam.solve_static runs the same core.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex import scenes
from skfem_flex.bodies.floating import rotation
from skfem_flex.errors import ConvergenceError

#: the catalogue beam (scenes.rotating_beam defaults)
LENGTH, EA, RHOA, OMEGA = 10.0, 2.8e7, 1.2, 4.0
#: mesh sizes from one element to 2000, with sizes whose fixed tolerance failed (101, 106, 128, ...)
SIZES = [1, 2, 7, 64, 101, 106, 128, 256, 1000, 2000]


def _residual(body, qf, omega):
    """r = ∇V(q_f) − ω²(c + M_A q_f), N (an independent evaluation of the balance)."""
    q = body.q0.copy()
    q[3:] = qf
    return body.potential_gradient(q)[3:] - omega ** 2 * (body._c + body._MA @ qf)


@pytest.mark.parametrize("n_elements", SIZES)
def test_rotating_beam_builds_and_its_steady_state_is_the_spinning_bar(n_elements):
    scene = scenes.rotating_beam(n_elements=n_elements)             # as `skfem-flex run` builds it
    body = scene.bodies[0]
    assert np.all(np.isfinite(body.q0))
    S, _ = body.shape_at(body.x_max)
    # the start is the steady state plus the lowest bending mode scaled to a 1 cm tip deflection
    assert float(S[1] @ body.q0[3:]) == pytest.approx(0.01, rel=1e-9)

    steady = scenes.rotating_beam(n_elements=n_elements, perturbation=0.0).bodies[0].q0[3:]
    # the residual against the centrifugal force scale: the root force ρA ω² L²/2 (960 N)
    root_force = RHOA * OMEGA ** 2 * LENGTH ** 2 / 2
    assert np.abs(_residual(body, steady, OMEGA)).max() <= 1e-9 * root_force
    # slowly spinning bar (ρA ω² L²/EA = 7e-5): u(L) = ρA ω² L³ / (3 EA), exact at the nodes of
    # linear elements; the stretch's own centrifugal load and the Green–Lagrange terms add O(1e-5)
    tip_axial, tip_transverse = S @ steady
    assert tip_axial == pytest.approx(RHOA * OMEGA ** 2 * LENGTH ** 3 / (3 * EA), rel=1e-4)
    assert abs(tip_transverse) <= 1e-12 * LENGTH


def test_the_balance_is_solved_to_the_same_relative_accuracy_at_every_size():
    """One tolerance for 8 and 2000 elements: at equilibrium the residual is at the round-off of the
    internal forces, ε |K| |q_f|, whatever the size (the former fixed fraction of the nodal load
    was below that floor from 101 elements on)."""
    for n in (8, 2000):
        body = scenes.hub_beam(n_elements=n)
        qf = body.centrifugal_equilibrium(OMEGA)
        q = body.q0.copy()
        q[3:] = qf
        floor = np.abs(abs(body.potential_hessian(q)[3:, 3:]) @ np.abs(qf)).max()
        assert np.abs(_residual(body, qf, OMEGA)).max() <= 16 * np.finfo(float).eps * floor + 1e-12 * floor


def test_load_stepping_in_omega_squared_when_the_direct_solve_fails(monkeypatch):
    """If Newton from the undeformed state fails, the balance is followed in ω² and ends on the
    same state."""
    body = scenes.hub_beam(n_elements=16)
    direct = body.centrifugal_equilibrium(OMEGA)
    real = rotation.newton_solve
    seen = []

    def failing_first(fun, x0, settings, name, where, *args, **kw):
        seen.append(where)
        if len(seen) == 1:
            raise ConvergenceError(f"{name}: Newton did not converge at {where} (forced by the test)")
        return real(fun, x0, settings, name, where, *args, **kw)

    monkeypatch.setattr(rotation, "newton_solve", failing_first)
    stepped = body.centrifugal_equilibrium(OMEGA)
    assert len(seen) > 2 and seen[-1] == f"omega = {OMEGA:.6g} rad/s"
    np.testing.assert_allclose(stepped, direct, rtol=1e-9, atol=1e-12 * np.abs(direct).max())


def test_sparse_rotating_modes_equal_the_dense_solve(monkeypatch):
    body = scenes.hub_beam(n_elements=60)                              # 180 elastic coordinates
    assert body.n_elastic > rotation.DENSE_MODES_LIMIT
    sparse = body.rotating_modes(OMEGA, 3)
    monkeypatch.setattr(rotation, "DENSE_MODES_LIMIT", 10 ** 6)
    dense = body.rotating_modes(OMEGA, 3)
    np.testing.assert_allclose(sparse[0], dense[0], rtol=1e-7)
    np.testing.assert_allclose(np.abs(sparse[1]), np.abs(dense[1]), atol=1e-6)


def test_large_rotating_beam_frequencies_converge_to_the_fine_mesh_values():
    """Southwell at small spin: ω₁² ≈ ω₁,₀² + (S − 1) ω² with ω₁,₀ = 3.516 √(EI/(ρA L⁴)); the 1000-element
    frequency (sparse path) and the 8-element one (dense path) bracket nothing odd."""
    fine = scenes.rotating_beam_frequencies(0.5, n_elements=1000, n_modes=1)[0]
    w10 = 1.875104 ** 2 * np.sqrt(1.4e4 / (RHOA * LENGTH ** 4))
    assert fine == pytest.approx(np.sqrt(w10 ** 2 + 0.193 * 0.5 ** 2), rel=1e-4)


def test_exact_beam_static_solve_runs_the_newton_core(monkeypatch):
    """ExactBeam.solve_static solves each load level by newton_solve (one call per level), and the
    tip of a cantilever under a small end load matches Euler–Bernoulli P L³/(3EI) + P L/kGA."""
    from skfem_flex.bodies.exact import body as exact_body

    calls = []
    real = exact_body.newton_solve

    def counting(*args, **kw):
        calls.append(args[4])
        return real(*args, **kw)

    monkeypatch.setattr(exact_body, "newton_solve", counting)
    sec = sf.Section(EA=1e8, EI=1e4, kGA=1e7, rhoA=1.0, rhoI=1e-3)
    beam = sf.ExactBeam.from_points(sec, (0.0, 0.0), (2.0, 0.0), n_elements=32)
    P = -1.0
    q = beam.solve_static(beam.point_load_vector(2.0, force=(0.0, P)), beam.dofs_at(0.0), load_steps=3)
    assert calls == [f"load level {k / 3:.4g}" for k in (1, 2, 3)]
    tip = beam.point(2.0).position(q)
    assert tip[1] == pytest.approx(P * 2.0 ** 3 / (3 * 1e4) + P * 2.0 / 1e7, rel=1e-3)
