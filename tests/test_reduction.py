"""Reduced floating-frame bodies: Craig–Bampton against full-model frequencies, quartic Green–Lagrange energy,
exact discrete gradients, spin-up stiffening, the pendulum against the full beam, conservation, bad input."""
import numpy as np
import pytest
import scipy.linalg as sla
import skfem

import skfem_flex as sf
from skfem_flex.fem.beam import TimoshenkoBeam
from skfem_flex.bodies import FloatingBeam, PlaneStress, craig_bampton, free_modes, reduce
from skfem_flex.scene import Scene
from skfem_flex.fem.section import Section

SPIN = Section(EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4)       # the catalogue spin-up beam


def beam(n, length=10.0, section=SPIN, **kw):
    return FloatingBeam(TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, length, n + 1)), section), **kw)


def full_frequencies(tb, fixed=()):
    free = np.setdiff1d(np.arange(tb.n_dofs), fixed)
    K, M = tb.stiffness().toarray()[np.ix_(free, free)], tb.mass().toarray()[np.ix_(free, free)]
    return np.sqrt(np.abs(np.sort(sla.eigvalsh(K, M))))


def ritz_frequencies(K, M, B):
    """Rayleigh–Ritz frequencies (rad/s) of span(B): columns scaled to unit M-norm, M-orthonormalised, dependent ones
    dropped (the modal derivatives are many orders of magnitude larger than the modes)."""
    B = B / np.sqrt(np.einsum("ij,ij->j", B, M @ B))
    mu, V = np.linalg.eigh(B.T @ M @ B)
    keep = mu > 1e-13 * mu.max()
    W = B @ (V[:, keep] / np.sqrt(mu[keep]))
    return np.sqrt(np.abs(np.sort(sla.eigvalsh(W.T @ K @ W, W.T @ M @ W))))


def test_craig_bampton_beam_frequencies_against_the_full_model():
    """64-element beam, interfaces at both ends, 6 fixed-interface modes, against the full model (scipy).

    Plain Craig–Bampton spans exactly the subspace of a textbook reduction made here from K and M; its pinned–pinned
    and first two free–free frequencies are within 1e-3, the third free–free mode 1.285e-3 off — a property of
    Craig–Bampton with 6 modes, not of our implementation (7 modes: 4.6e-4). The default reduced body adds the
    modal derivatives of the tip's constraint modes, whose cross terms with the axial one are transverse fields:
    that Rayleigh–Ritz subspace meets 1e-3 for all six frequencies (measured ≤ 1.2e-5)."""
    fb = beam(64)
    tb, model = fb.beam, fb.elastic_model()
    K, M = model.stiffness.toarray(), model.total_mass().toarray()
    ff = full_frequencies(tb)[3:6]
    fixed = [tb.dofs_at(0.0)[0], tb.dofs_at(0.0)[1], tb.dofs_at(10.0)[1]]
    pp = full_frequencies(tb, fixed)[:3]
    # the textbook reduction: T = [[Ψ, φ], [I, 0]] on (interior, boundary) rows
    b = np.r_[tb.dofs_at(0.0), tb.dofs_at(10.0)]
    o = np.setdiff1d(np.arange(K.shape[0]), b)
    T = np.zeros((K.shape[0], 12))
    T[np.ix_(o, np.arange(6))] = -np.linalg.solve(K[np.ix_(o, o)], K[np.ix_(o, b)])
    T[b, np.arange(6)] = 1.0
    T[np.ix_(o, np.arange(6, 12))] = sla.eigh(K[np.ix_(o, o)], M[np.ix_(o, o)], subset_by_index=[0, 5])[1]
    for n, tol in ((6, [1e-3, 1e-3, 1.3e-3]), (7, [1e-3] * 3)):
        cb = craig_bampton(model, ["root", "tip"], n)
        if n == 6:
            assert np.sin(sla.subspace_angles(cb.basis, T).max()) < 1e-8
            assert ritz_frequencies(K, M, T)[5] / ff[2] - 1 == pytest.approx(1.285e-3, rel=1e-2)
        Kr, Mr = cb.reduced_matrices(model)
        red_ff = np.sqrt(np.abs(np.sort(sla.eigvalsh(Kr, Mr))))[3:6]
        assert np.all(np.abs(red_ff / ff - 1) <= tol)
        keep = [i for i in range(Kr.shape[0]) if i not in (0, 1, 4)]    # CB DOFs: root (u, w, φ), tip (u, w, φ)
        red_pp = np.sqrt(np.sort(sla.eigvalsh(Kr[np.ix_(keep, keep)], Mr[np.ix_(keep, keep)])))[:3]
        assert np.all(np.abs(red_pp / pp - 1) <= 1e-3)
        assert np.all(red_ff >= ff * (1 - 1e-12))                         # Rayleigh–Ritz: from above
    body = fb.reduced(6)
    B = np.hstack([model.rigid_modes(), body.Phi])                       # the body's subspace with its frame motion
    red_ff = ritz_frequencies(K, M, B)[3:6]
    red_pp = ritz_frequencies(K, M, B @ sla.null_space(B[fixed]))[:3]
    assert np.all(np.abs(red_ff / ff - 1) <= 1e-3) and np.all(np.abs(red_pp / pp - 1) <= 1e-3)
    # from above up to the round-off of this Ritz basis, whose modal derivatives are orders of magnitude
    # larger than its modes (seen 3e-9 below with numpy 2.4 and scipy 1.17)
    assert np.all(red_ff >= ff * (1 - 1e-8)) and np.all(red_pp >= pp * (1 - 1e-8))


def test_modal_derivatives_of_the_constraint_modes():
    """The default derivative set of a link is the constraint modes of the interface the frame is not attached to:
    each derivative is the static second-order response with the interfaces held (K_oo θ = −∂²f, P θ = 0); the
    beam's axial constraint mode with itself gives none (a uniform axial force, held by the interfaces). A body held
    at its reference interface only falls back to the derivatives of its fixed-interface modes."""
    from skfem_flex.bodies.modal.reduction import modal_derivatives
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 9), np.linspace(0, 0.04, 3))
    ps = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01, interfaces={"root": lambda X: np.isclose(X[0], 0.0),
                                                                       "tip": lambda X: np.isclose(X[0], 0.4)})
    model = ps.model()
    cb = craig_bampton(model, ["root", "tip"], 3)
    D = modal_derivatives(model, cb, 0, ["tip"])
    assert D.shape == (model.n_dofs, 6)
    tip = cb.basis[:, 3:6]
    pairs = [(i, j) for i in range(3) for j in range(i, 3)]
    K = model.stiffness
    for k, (i, j) in enumerate(pairs):
        f = model.strain.second_derivative(tip[:, i], tip[:, j])
        r = cb.interior.T @ (K @ D[:, k] + f)
        assert np.abs(r).max() <= 1e-9 * np.abs(cb.interior.T @ f).max()
        for name in ("root", "tip"):
            assert np.abs(model.interface(name).P @ D[:, k]).max() <= 1e-12 * np.abs(D[:, k]).max()
    # the reduced body spans the constraint modes, the fixed-interface modes and these derivatives: 12 coordinates
    body = ps.reduced(3)
    assert body.n_elastic == 12 and body.reference == "interface root"
    coef = np.linalg.lstsq(body.Phi, D, rcond=None)[0]
    assert np.abs(body.Phi @ coef - D).max() <= 1e-8 * np.abs(D).max()
    old = ps.reduced(3, interface_derivatives=False)                   # the fixed-interface set instead
    Dm = modal_derivatives(model, cb, 3)
    coef = np.linalg.lstsq(old.Phi, Dm, rcond=None)[0]
    assert old.n_elastic == 12 and np.abs(old.Phi @ coef - Dm).max() <= 1e-8 * np.abs(Dm).max()
    assert 12 < ps.reduced(3, n_derivatives=3).n_elastic <= 3 + 3 + 21     # the union (less near-dependent ones)
    # beam: 5 of the 6 (axial × axial vanishes); clamped at the root only: the 6 derivatives of the 3 modes
    fb = beam(8)
    bcb = craig_bampton(fb.elastic_model(), ["root", "tip"], 3)
    assert modal_derivatives(fb.elastic_model(), bcb, 0, ["tip"]).shape[1] == 5
    assert fb.reduced(3, interfaces=("root",)).n_elastic == 3 + 6
    assert fb.reduced(3, strain="linear").n_elastic == 3 + 3


def test_free_interface_modes_are_the_full_free_free_modes():
    fb = beam(16)
    om, phi = free_modes(fb.elastic_model(), 3)
    assert np.allclose(om, full_frequencies(fb.beam)[3:6], rtol=1e-9)
    body = fb.reduced(3, interfaces=(), method="free", strain="linear")
    assert body.reference == "mean-axes" and np.allclose(body.frequencies, om, rtol=1e-9)
    # mean axes: no momentum of the elastic field (∫ρu = 0, ∫ρ X × u + ρI φ = 0)
    assert np.abs(body._Sbar).max() < 1e-9 and np.abs(body._k0n + body._H @ np.zeros(3)).max() < 1e-9


def test_quartic_energy_gradient_hessian_and_exact_discrete_gradient():
    """V, ∇V, ∇²V of the quartic Green–Lagrange energy agree by finite differences; g·Δη = ΔV to round-off."""
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 0.4, 7), np.linspace(0, 0.1, 3))
    body = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01).reduced(5)
    en = body.energy
    rng = np.random.default_rng(1)
    e0, e1 = 3e-2 * rng.standard_normal((2, 5))
    assert not en.linear
    h = 1e-7
    fd = np.array([(en.energy(e1 + h * d) - en.energy(e1 - h * d)) / (2 * h) for d in np.eye(5)])
    assert np.allclose(fd, en.gradient(e1), rtol=1e-6, atol=1e-8 * np.abs(fd).max())
    fd = np.array([(en.gradient(e1 + h * d) - en.gradient(e1 - h * d)) / (2 * h) for d in np.eye(5)])
    assert np.allclose(fd, en.hessian(e1), rtol=1e-6, atol=1e-7 * np.abs(fd).max())
    g, dg = en.discrete_gradient(e0, e1)
    assert g @ (e1 - e0) == pytest.approx(en.energy(e1) - en.energy(e0), rel=1e-12)
    fd = np.array([(en.discrete_gradient(e0, e1 + h * d)[0] - en.discrete_gradient(e0, e1 - h * d)[0]) / (2 * h)
                   for d in np.eye(5)]).T
    assert np.allclose(fd, dg, rtol=1e-6, atol=1e-7 * np.abs(fd).max())
    assert np.allclose(en.discrete_gradient(e1, e1)[0], en.gradient(e1))
    # the quartic energy is the Green–Lagrange energy ½ Σ w Eᵀ C E of the displacement field Φη
    st = body.model.strain
    gq = np.stack([G @ (body.Phi @ e1) for G in st.gradients], axis=1)
    E = gq @ st.linear.T + 0.5 * np.einsum("qg,agh,qh->qa", gq, st.quadratic, gq)
    assert en.energy(e1) == pytest.approx(0.5 * np.sum(st.weights * np.einsum("qa,ab,qb->q", E, st.material, E)),
                                          rel=1e-10)


def test_kinetic_discrete_gradient_of_a_body_off_its_frame_origin():
    """S₀ has both components (the plate's frame origin is at a corner): G(q1) − G(q0) = g·Δq exactly."""
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3))
    body = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01).reduced(3)
    assert abs(body._S0[1]) > 0.1 * abs(body._S0[0]) > 0
    rng = np.random.default_rng(2)
    q0 = 1e-2 * rng.standard_normal(body.n_dofs)
    q1 = q0 + 0.3 * rng.standard_normal(body.n_dofs)
    v0, v1 = rng.standard_normal((2, body.n_dofs))
    g, _, _ = body.kinetic_discrete_gradient(q0, q1, v0, v1)
    G = lambda q: 0.5 * v0 @ body.mass_matrix(q) @ v1          # noqa: E731
    assert g @ (q1 - q0) == pytest.approx(G(q1) - G(q0), rel=1e-11)


@pytest.mark.parametrize("kind", ["plane-stress-modal", "plane-stress", "beam-modal"])
def test_free_spinning_body_conserves_energy_and_linear_momentum(kind):
    """Free flight (no gravity), spinning at 20 rad/s with an elastic start: energy to 1e-9, linear momentum exact."""
    if kind == "beam-modal":
        body = beam(8, length=2.0).reduced(4, interfaces=("root", "tip"), velocity=(1.0, -0.5),
                                             angular_velocity=20.0)
    else:
        mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3))
        ps = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01, order=1 if kind == "plane-stress" else 2)
        state = dict(position=(0.1, 0.2), angle=0.3, velocity=(1.0, -0.5), angular_velocity=20.0)
        body = ps.reduced(4, **state) if kind == "plane-stress-modal" else ps.body(**state)
    body.v0[3] = 0.2 * np.abs(body.v0).max()
    res = sf.simulate(Scene([body]), 0.02, 2e-4)
    assert res.completed
    assert res.relative_energy_error() <= 1e-9
    p = res.linear_momentum
    assert np.abs(p - p[0]).max() <= 1e-12 * np.abs(p[0]).max()


def test_reduced_spin_up_beam_matches_the_full_green_lagrange_beam():
    """Spin-up ω = 4 with 10 modal coordinates (3 modes, 6 modal derivatives, 1 centrifugal mode; the root is the
    only interface and carries the frame, so there are no constraint modes to differentiate): minimum transverse
    tip deflection within 1 % of the full 8-element Green–Lagrange beam (same Δt); the linear reduced body
    diverges with the linear full beam."""
    sc = sf.scenes.spin_up_beam(body="beam-modal")
    assert sc.bodies[0].n_elastic == 10
    red = sf.simulate(sc, 8.0, 2e-2)
    full = sf.simulate(sf.scenes.spin_up_beam(), 8.0, 2e-2)
    wr, wf = red.probes["tip"][:, 1].min(), full.probes["tip"][:, 1].min()
    assert wf == pytest.approx(-0.40, abs=0.01)
    assert wr == pytest.approx(wf, rel=1e-2)
    assert np.max(np.abs(red.energy_balance_error)) <= 1e-9 * np.max(np.abs(red.total_energy))
    lin = sf.simulate(sf.scenes.spin_up_beam(body="beam-modal", strain="linear"), 12.0, 2e-2)
    lin_full = sf.simulate(sf.scenes.spin_up_beam(strain="linear"), 12.0, 2e-2)
    a, b = np.abs(lin.probes["tip"][:, 1]).max(), np.abs(lin_full.probes["tip"][:, 1]).max()
    assert b > 2.0 and a == pytest.approx(b, rel=2e-2)


def test_plane_stress_pendulum_against_the_full_beam():
    """Pendulum: strip of the catalogue section reduced to 12 coordinates (the tip's 3 constraint modes, 3 modes, the
    6 derivatives of those constraint modes) against the 16-element FloatingBeam (both at Δt = 2 ms): tip within
    3e-3 m at t = 1 s and 2 s (measured 1.2e-4 and 3.8e-4 m: the strip's own difference from the beam; the 12
    coordinates agree with a 38-coordinate reduction of the strip to 2e-5 m); energy balance 1e-9 of m g L/2;
    |Φ| ≤ 1e-10."""
    red_scene = sf.scenes.flexible_pendulum(body="plane-stress-modal", n_elements=40)
    assert red_scene.bodies[0].n_elastic == 12
    red = sf.simulate(red_scene, 2.0, 2e-3, record_every=250)
    ref = sf.simulate(sf.scenes.flexible_pendulum(n_elements=16), 2.0, 2e-3, record_every=250)
    assert np.allclose(red.t, [0.0, 0.5, 1.0, 1.5, 2.0]) and np.allclose(ref.t, red.t)
    assert np.abs(red.probes["tip"][[2, 4]] - ref.probes["tip"][[2, 4]]).max() <= 3e-3
    assert np.max(np.abs(red.energy_balance_error)) <= 1e-9 * 9.81 / 2
    assert np.max(red.constraint_residual) <= 1e-10


def test_beam_modal_pendulum_conserves_energy_and_holds_the_pin():
    res = sf.simulate(sf.scenes.flexible_pendulum(body="beam-modal"), 0.3, 1e-3)
    assert res.relative_energy_error(9.81 / 2) <= 1e-9 and np.max(res.constraint_residual) <= 1e-10


def test_bad_reduction_input():
    fb = beam(4)
    model = fb.elastic_model()
    with pytest.raises(ValueError, match="n_modes"):
        craig_bampton(model, ["root", "tip"], 100)
    with pytest.raises(ValueError, match="n_modes"):
        free_modes(model, model.n_dofs)
    with pytest.raises(ValueError, match="no interface 'middle'"):
        fb.reduced(2, interfaces=("root", "middle"))
    with pytest.raises(ValueError, match="method"):
        reduce(model, 2, method="guyan")
    with pytest.raises(ValueError, match="reference"):
        reduce(model, 2, reference="centre")
    with pytest.raises(ValueError, match="interface_derivatives must name"):
        reduce(model, 2, interface_derivatives=["root"])              # the frame's own interface
    with pytest.raises(ValueError, match="interface_derivatives needs the body frame"):
        reduce(model, 2, reference="mean-axes", interface_derivatives=True)
    with pytest.raises(ValueError, match="craig-bampton"):
        reduce(model, 2, interfaces=(), method="free", interface_derivatives=True)
    with pytest.raises(ValueError, match="outside"):
        fb.reduced(2).point((11.0, 0.0))
    with pytest.raises(ValueError, match="body must be"):
        sf.scenes.flexible_pendulum(body="shell")
    with pytest.raises(ValueError, match="testset"):
        sf.scenes.slider_crank(body="beam-modal", start="testset")


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
def test_reduced_bodies_run_with_the_other_schemes(scheme):
    """The contract's M(q), Q_v, ∇V, ∇²V serve the other two schemes: the reduced strip pendulum follows the
    energy-momentum run closely over 0.2 s and holds its pin."""
    scene = lambda: sf.scenes.flexible_pendulum(body="plane-stress-modal", n_elements=10)   # noqa: E731
    ref = sf.simulate(scene(), 0.2, 1e-3, record_every=200)
    res = sf.simulate(scene(), 0.2, 1e-3, integrator=scheme, record_every=200)
    assert res.completed and np.max(res.constraint_residual) <= 1e-10
    assert np.abs(res.probes["tip"][-1] - ref.probes["tip"][-1]).max() < 1e-3


def test_point_force_on_a_meshed_body_point_balances_its_work():
    """A force pulse at a material point (X, Y) of a free reduced plate: the energy gained equals the pulse's work
    (1e-9) and the momentum gained equals the impulse 2τF/π (to the midpoint rule's (πΔt/τ)²/24 = 1e-3)."""
    from skfem_flex.elements.forces import PointForce, half_sine_pulse
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 9), np.linspace(0, 0.1, 3))
    body = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01).reduced(4)
    F, tau = np.array([0.0, 50.0]), 2e-3
    scene = Scene([body], forces=[PointForce(body.point((0.35, 0.08)), half_sine_pulse(F, tau))])
    res = sf.simulate(scene, 4e-3, 1e-4)
    assert np.max(np.abs(res.energy_balance_error)) <= 1e-9 * np.max(res.total_energy)
    assert res.external_work[-1] > 0
    assert np.allclose(res.linear_momentum[-1], 2 * tau * F / np.pi, rtol=3e-3, atol=1e-9)
