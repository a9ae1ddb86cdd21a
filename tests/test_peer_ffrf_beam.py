"""The rotating beam shared with exudyn's reduced floating-frame body (skfem_flex.apps.peer_ffrf_beam): the
arrays exudyn gets reproduce our reduced model, checked against our own invariants and closed forms, without
exudyn; with exudyn, a short run of both codes agrees to round-off."""
import numpy as np
import pytest

from skfem_flex.apps import peer_ffrf_beam as peer

P = peer.ROTATING_BEAM


@pytest.fixture(scope="module")
def data():
    return peer.beam_data()


def _rotation(angles):
    """A rotation matrix from three angles (x, then y, then z), to turn the frame anywhere."""
    out = np.eye(3)
    for axis, a in enumerate(angles):
        c, s = np.cos(a), np.sin(a)
        i, j = [k for k in range(3) if k != axis]
        R = np.eye(3)
        R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
        out = R @ out
    return out


def test_rotations_carry_no_mass(data):
    """ρI = 0: the beam's consistent mass has no entry on a section rotation, and its translational block
    (the one exudyn gets) is ρA ∫N_aN_b per component: its total over one component is ρA L."""
    beam = data["body"].beam
    M = beam.mass().toarray()
    theta = beam.node_dofs[:, 3:].ravel()
    assert np.abs(M[theta]).max() == 0.0 and np.abs(M[:, theta]).max() == 0.0
    Mt = data["M"].toarray()
    mass = P["rhoA"] * P["length"]
    for c in range(3):
        assert Mt[c::3, c::3].sum() == pytest.approx(mass, rel=1e-13)
        for other in range(3):
            if other != c:
                assert np.abs(Mt[c::3, other::3]).max() == 0.0


def test_kinetic_energy_of_the_nodes_is_ours(data):
    """½ vᵀM(q)v of our reduced body (its invariants, inertia.py) equals ½ Σ M_t,ab u̇_a·u̇_b of the nodes exudyn
    gets, u̇_a = ẋ + Ḋ(X_a + Φ_a η) + D Φ_a η̇, at a turned, deformed, moving state (any ẋ, Ḋ, η̇: M(q) is a
    quadratic form in them)."""
    body, H = data["body"], data["H"]
    rng = np.random.default_rng(3)
    m = body.n_elastic
    X = data["nodes"] @ H                      # back to our frame's axes (H symmetric, H² = I)
    Phi = np.einsum("ij,ajm->aim", H, data["modes"].reshape(-1, 3, m))
    Mt = data["M"].toarray()
    for _ in range(3):
        D = _rotation(rng.uniform(-3, 3, 3))
        eta = rng.normal(size=m)
        q = np.concatenate([rng.normal(size=3), D.T.ravel(), eta])
        v = rng.normal(size=12 + m)
        Ddot = v[3:12].reshape(3, 3).T
        u = v[:3] + (X + np.einsum("aim,m->ai", Phi, eta)) @ Ddot.T + np.einsum("aim,m->ai", Phi, v[12:]) @ D.T
        nodes = 0.5 * np.einsum("ab,ac,bc->", Mt[::3, ::3], u, u)
        ours = 0.5 * v @ body.mass_matrix(q) @ v
        assert ours == pytest.approx(nodes, rel=1e-12)


def test_exudyns_invariants_are_ours(data):
    """exudyn's invariants as its ObjectFFRFreducedOrderInterface forms them from M_t, the nodes and Φ_t (total
    mass, centre of mass, inertia about the frame origin, Φ_tᵀMΦ_t, Φ_tᵀM times a rigid translation) against
    ours (inertia.py, in the hub's axes) and the uniform bar's closed forms."""
    body, H = data["body"], data["H"]
    inv = body.inertia
    M = data["M"].toarray()
    Phi = data["modes"]
    n = data["nodes"].shape[0]
    Phit = np.kron(np.ones(n), np.eye(3)).T
    x = data["nodes"].ravel()
    L, rhoA = P["length"], P["rhoA"]
    Mtt = Phit.T @ M @ Phit
    assert np.allclose(Mtt, rhoA * L * np.eye(3), rtol=1e-13, atol=0)
    assert np.allclose(Phit.T @ M @ x / Mtt[0, 0], [L / 2, 0, 0], rtol=1e-13, atol=1e-13)
    tilde = np.zeros((3 * n, 3))                # columns e_k × X_a
    for k in range(3):
        tilde[:, k] = np.cross(np.eye(3)[k], data["nodes"]).ravel()
    inertia = tilde.T @ M @ tilde
    assert np.allclose(inertia, np.diag([0.0, 1.0, 1.0]) * rhoA * L ** 3 / 3, rtol=1e-12, atol=1e-9)
    assert np.allclose(Phit.T @ M @ Phi, H @ inv.Sbar, rtol=1e-12, atol=1e-12)
    assert np.allclose(Phi.T @ M @ Phi, np.einsum("kkab->ab", inv.N), rtol=1e-12, atol=1e-12)


def test_stiffness_and_basis(data):
    """exudyn's Φ_tᵀK_tΦ_t is our reduced stiffness (the body's own strain energy, strain.py); Φ vanishes at the
    clamped root and Φ_t has full column rank (no rigid motion, no column without mass)."""
    body = data["body"]
    Phi, K = data["modes"], data["K"].toarray()
    ours = body.strain_energy.hessian(np.zeros(body.n_elastic))
    assert np.allclose(Phi.T @ K @ Phi, ours, rtol=1e-10, atol=1e-10 * np.abs(ours).max())
    assert np.allclose(data["K_reduced"], ours, rtol=1e-10, atol=1e-10 * np.abs(ours).max())
    assert np.abs(Phi[:3]).max() == 0.0 and data["nodes"][0] @ data["nodes"][0] == 0.0
    assert np.linalg.matrix_rank(Phi) == Phi.shape[1] == P["n_modes"] + 1
    # no rigid motion in the span: the M-Gram matrix of [R Φ_t] (columns M-normalized) is regular, R the
    # translations and the turns about y and z (a turn about the axis x moves no node); its smallest eigenvalue,
    # 1e-4, is the first bending modes' likeness to a turn about the root (sin² of their angle), not round-off
    X = data["nodes"]
    R = np.zeros((X.shape[0], 3, 5))
    R[:, :, :3] = np.eye(3)
    R[:, :, 3] = np.cross([0.0, 1.0, 0.0], X)
    R[:, :, 4] = np.cross([0.0, 0.0, 1.0], X)
    Z = np.hstack([R.reshape(-1, 5), Phi])
    Z = Z / np.sqrt(np.einsum("ij,ik,kj->j", Z, data["M"].toarray(), Z))
    gram = Z.T @ data["M"].toarray() @ Z
    assert np.linalg.eigvalsh(gram).min() > 1e-5
    # the lowest frequencies of the reduced ρI = 0 beam: the clamped cantilever's 1.875² √(EI/(ρA L⁴)) in both
    # planes (a Timoshenko beam of 8 linear elements: within 0.5 %)
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(Phi.T @ data["M"].toarray() @ Phi, ours)).real)
    first = 1.8751 ** 2 * np.sqrt(P["EI"] / (P["rhoA"] * P["length"] ** 4))
    assert np.sqrt(lam[:2]) == pytest.approx([first, first], rel=5e-3)


def test_initial_state(data):
    """The steady stretch of the linear-strain bar, u(L) = ρAΩ²L³/(3EA) (nodal values of linear elements are
    exact; the stretch's own centrifugal load adds a part in ρAΩ²L²/EA ≈ 2e-5), and the two modes' tip
    deflections; the scene's Python probe equals :func:`tip_map`."""
    eta = data["eta"]
    tip = peer.tip_map(data) @ eta
    om, L = P["omega"], P["length"]
    assert tip[0] == pytest.approx(P["rhoA"] * om ** 2 * L ** 3 / (3 * P["EA"]), rel=2e-5)
    assert np.abs(tip[1:]) == pytest.approx([P["perturbation"]] * 2, rel=1e-9)
    scene = peer.scene(data)
    q, v = scene.initial_state()[:2]
    probe = scene.probes["tip"](scene, 0.0, q, v)
    assert np.allclose(probe, tip, rtol=0, atol=1e-15)


def test_basis_of_the_massless_rotations_is_the_limit_of_small_rotary_inertia(data):
    """reduction_basis condenses the ρI = 0 beam's massless rotations out statically; its modal frequencies
    are the limit of those of the same beam with a small ρI (a regular mass matrix, plain eigh): at
    ρI = 1e-6 ρA L² they differ by O(ρI) (rotary inertia lowers bending frequencies)."""
    import scipy.linalg
    from skfem_flex.bodies.floating_spatial.reduction import reduction_basis
    from skfem_flex.scenes.spatial_rotors import floating_hub_beam_3d

    def frequencies(body, basis):
        K = body.strain_energy.hessian(np.zeros(body.n_elastic))
        M = body.mass_matrix(body.q0)[12:, 12:]
        return np.sqrt(scipy.linalg.eigh(basis.T @ K @ basis, basis.T @ M @ basis, eigvals_only=True))[:8]

    massless = peer.hub_beam(dict(P))
    basis = reduction_basis(massless, P["n_modes"])
    ours = np.sort(frequencies(massless, basis))
    heavy = floating_hub_beam_3d(P["length"], P["EA"], P["EI"], P["GJ"], P["kGA"], P["rhoA"],
                                 1e-6 * P["rhoA"] * P["length"] ** 2, P["n_elements"], P["order"], strain="linear")
    limit = np.sort(frequencies(heavy, reduction_basis(heavy, P["n_modes"])))
    assert np.all(limit < ours) and ours == pytest.approx(limit, rel=1e-4)


needs_exudyn = pytest.mark.skipif(not peer.peer_available(), reason="exudyn is not installed")


@needs_exudyn
def test_exudyn_has_our_reduced_matrices_and_agrees_with_ours(data):
    """A 0.5 s run: exudyn's reduced mass and stiffness are ours, and its trapezoidal rule and ours (the same
    rule on the same reduced ODE) agree to round-off (ours at its default Newton tolerance, 1e-12; exudyn's
    1e-8 is enough for its modified Newton here); its generalized-α stays within the step's error."""
    import skfem_flex as sf
    run = peer.rotating_beam(dt=1e-2, t_end=0.5, scheme="trapezoidal", data=data)
    t, tip, _ = run()
    body = data["body"]
    Mr = np.einsum("kkab->ab", body.inertia.N)
    assert np.allclose(run.stats["mass_reduced"], Mr, rtol=0, atol=1e-12)
    Kr = data["K_reduced"]
    assert np.allclose(run.stats["stiffness_reduced"], Kr, rtol=0, atol=1e-9 * np.abs(Kr).max())
    ours = sf.simulate(peer.scene(data), t_end=0.5, dt=1e-2, scheme="trapezoidal", record_every=1)
    assert np.allclose(ours.t, t, rtol=0, atol=1e-12)
    assert np.abs(ours.probes["tip"] - tip).max() < 1e-9
    ga = peer.rotating_beam(dt=1e-2, t_end=0.5, scheme="generalized-alpha", data=data)
    _, tip_ga, _ = ga()
    assert 1e-9 < np.abs(tip_ga - tip).max() < 1e-4
