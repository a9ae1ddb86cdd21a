"""The spatial floating-frame beam (bodies/floating_spatial): its kinetic terms against central differences of
M(q) and against the beam's consistent mass and a rod's inertia, its Green–Lagrange strain energy, its modes
about a steady spin against the classical rotating-cantilever tables, and in scenes: a relative equilibrium
that stays put, a free flight that keeps energy and momentum, and the spin-up against the exact beam."""
import functools

import numpy as np
import pytest
import skfem
from scipy.spatial.transform import Rotation

import skfem_flex as sf
from skfem_flex.bodies.floating_spatial import kinetics
from skfem_flex.bodies.floating_spatial.body import FloatingBeam3D
from skfem_flex.bodies.floating_spatial.rotation import spinning_modes, steady_spin
from skfem_flex.elements.forces.spatial import SpatialPointForce
from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D
from skfem_flex.fem.spatial_section import SpatialSection
from helpers import ROTATING_TABLE, central_jacobian, relerr

SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.3, rhoI1=2.0, rhoI2=1.0)


def small_body(reference="clamped", strain="green-lagrange", order=2, n=3, **kw):
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, n + 1)), SECTION, order=order)
    return FloatingBeam3D(beam, reference=reference, strain=strain, **kw)


def turned(R, z):
    """x and the directors of z turned by R (the elastic coordinates stay)."""
    z = z.copy()
    for k in range(4):
        z[3 * k:3 * k + 3] = R @ z[3 * k:3 * k + 3]
    return z


@pytest.mark.parametrize("reference", ["clamped", "chord"])
def test_kinetic_terms_are_the_derivatives_of_the_mass_matrix(reference):
    body = small_body(reference)
    inv, n = body.inertia, body.n_dofs
    rng = np.random.default_rng(3)
    q, a, b, q1 = (rng.standard_normal(n) for _ in range(4))
    M = body.mass_matrix(q)
    assert np.abs(M - M.T).max() <= 1e-14 * np.abs(M).max()
    B = body.momentum_jacobian(q, a)
    assert relerr(B, central_jacobian(lambda z: body.mass_matrix(z) @ a, q)) <= 1e-8
    H = kinetics.kinetic_hessian(inv, a, b)
    assert relerr(H, central_jacobian(lambda z: body.momentum_jacobian(z, a).T @ b, q)) <= 1e-8
    f, fq, fv = body.quadratic_velocity_force(q, a)
    dT = central_jacobian(lambda z: 0.5 * a @ body.mass_matrix(z) @ a, q).ravel()
    assert relerr(f, dT - B @ a) <= 1e-8                       # Q_v = ∂T/∂q − Ṁ v
    assert relerr(fq, central_jacobian(lambda z: body.quadratic_velocity_force(z, a)[0], q)) <= 1e-8
    assert relerr(fv, central_jacobian(lambda z: body.quadratic_velocity_force(q, z)[0], a)) <= 1e-8
    # the mid-point gradient of ½ v₀ᵀ M(q) v₁ is exact, and so are its derivatives
    g, gq, gv = body.kinetic_discrete_gradient(q, q1, a, b)

    def G(z):
        return 0.5 * a @ body.mass_matrix(z) @ b
    assert abs(g @ (q1 - q) - (G(q1) - G(q))) <= 1e-13 * abs(G(q1) - G(q)) + 1e-13
    assert relerr(gq, central_jacobian(lambda z: body.kinetic_discrete_gradient(q, z, a, b)[0], q1)) <= 1e-8
    assert relerr(gv, central_jacobian(lambda z: body.kinetic_discrete_gradient(q, q1, a, z)[0], b)) <= 1e-8
    # turning x, the directors and both velocities together changes nothing
    R = Rotation.from_rotvec([0.3, -1.1, 0.7]).as_matrix()
    assert abs(turned(R, a) @ body.mass_matrix(turned(R, q)) @ turned(R, b) - a @ M @ b) <= 1e-12 * abs(a @ M @ b)


def test_mass_is_the_beams_consistent_mass_and_a_turning_rod_has_the_rods_inertia():
    body = small_body("chord")
    beam, free = body.beam, body.free_dofs
    M = body.mass_matrix(body.q0)
    assert relerr(M[12:, 12:], beam.mass().toarray()[np.ix_(free, free)]) <= 1e-13
    # a rigid turn ω of the undeformed beam: T = ½ ωᵀ J ω about the root with the rod's J (axis along d₃)
    L, rhoA = 2.0, SECTION.rhoA
    J = np.diag([rhoA * L ** 3 / 3 + SECTION.rhoI1 * L, rhoA * L ** 3 / 3 + SECTION.rhoI2 * L,
                 (SECTION.rhoI1 + SECTION.rhoI2) * L])
    for omega in ([1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.3, -0.4, 1.5]):
        v = np.zeros(body.n_dofs)
        v[3:12] = np.cross(omega, np.eye(3)).ravel()
        assert body.kinetic_energy(body.q0, v) == pytest.approx(0.5 * np.dot(omega, J @ omega), rel=1e-13)
    assert body.inertia.mass == pytest.approx(rhoA * L, rel=1e-15)


@pytest.mark.parametrize("strain", ["green-lagrange", "linear"])
def test_strain_energy_gradient_hessian_and_exact_discrete_gradient(strain):
    body = small_body("clamped", strain)
    rng = np.random.default_rng(5)
    q0, q1 = body.q0.copy(), body.q0.copy()
    q0[12:], q1[12:] = (0.05 * rng.standard_normal(body.n_elastic) for _ in range(2))
    V = body.potential_energy
    assert relerr(body.potential_gradient(q0), central_jacobian(V, q0, 1e-5).ravel()) <= 1e-7
    assert relerr(body.potential_hessian(q0), central_jacobian(body.potential_gradient, q0, 1e-6)) <= 1e-7
    g, jac = body.potential_discrete_gradient(q0, q1)
    assert abs(g @ (q1 - q0) - (V(q1) - V(q0))) <= 1e-12 * max(V(q0), V(q1))
    assert relerr(jac, central_jacobian(lambda z: body.potential_discrete_gradient(q0, z)[0], q1, 1e-6)) <= 1e-7
    if strain == "linear":
        K = body.beam.stiffness().toarray()[np.ix_(body.free_dofs, body.free_dofs)]
        assert V(q0) == pytest.approx(0.5 * q0[12:] @ K @ q0[12:], rel=1e-13)
    else:
        # a pure stretch u₃ = e s: ε = e + e²/2 exactly, V = ½ EA L ε²
        e = 0.01
        full = np.zeros(body.beam.n_dofs)
        full[body.beam.node_dofs[:, 2]] = e * body.beam.x_nodes
        q = body.q0.copy()
        q[12:] = body.elastic_vector(full)
        assert V(q) == pytest.approx(0.5 * SECTION.EA * 2.0 * (e + 0.5 * e * e) ** 2, rel=1e-12)


@functools.lru_cache(maxsize=2)
def rotor(strain):
    """EI = ρA = L = 1, nearly Euler–Bernoulli and inextensible (EA = 1e7 EI/L²): the model of the tables."""
    sec = SpatialSection(EA=1e7, GA1=1e5, GA2=1e5, GJ=1.0, EI1=1.0, EI2=1.0, rhoA=1.0, rhoI1=1e-6, rhoI2=1e-6)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, 7)), sec, order=2)
    return FloatingBeam3D(beam, strain=strain)


@pytest.mark.parametrize("lam, flap, lag", ROTATING_TABLE)
def test_spinning_modes_against_the_classical_rotating_cantilever_table(lam, flap, lag):
    """Flapwise (along the spin axis d₁) and lead-lag frequencies of the floating-frame beam linearized about
    its stretched steady spin: the centrifugal stiffening comes from the Green–Lagrange axis alone."""
    modes = spinning_modes(rotor("green-lagrange"), lam)
    (f, gf), (g, gg) = modes.first(True), modes.first(False)
    assert f == pytest.approx(flap, rel=5e-4) and g == pytest.approx(lag, rel=5e-4)
    assert max(gf, gg) <= 1e-6 * f


@pytest.mark.parametrize("n_points", [7, 9, 13])
def test_repeated_frequency_at_rest_splits_into_a_flapwise_and_a_lead_lag_mode(n_points):
    """Without spin the two bending planes share every frequency; the state-space eigensolver may hand back two
    nearly parallel vectors for such a pair (seen on the 9-point mesh), which the modes replace by the pair's
    eigenspace before they sort it into a flapwise and a lead-lag mode."""
    sec = SpatialSection(EA=1e7, GA1=1e5, GA2=1e5, GJ=1.0, EI1=1.0, EI2=1.0, rhoA=1.0, rhoI1=1e-6, rhoI2=1e-6)
    body = FloatingBeam3D(TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, n_points)), sec, order=2))
    modes = spinning_modes(body, 0.0)
    assert list(modes.flapwise[:6]) == [True, False] * 3 or list(modes.flapwise[:6]) == [False, True] * 3
    assert modes.first(True)[0] == pytest.approx(3.5160, rel=5e-4)
    assert modes.first(False)[0] == pytest.approx(3.5160, rel=5e-4)


def test_linear_strain_lead_lag_mode_diverges_beyond_the_first_frequency():
    body = rotor("linear")
    for lam in (2.0, 3.4):
        g, growth = spinning_modes(body, lam).first(False)
        assert g == pytest.approx(np.sqrt(3.51602 ** 2 - lam ** 2), rel=1e-3) and growth <= 1e-6
    g, growth = spinning_modes(body, 3.7).first(False)
    assert g == 0.0 and growth == pytest.approx(np.sqrt(3.7 ** 2 - 3.51602 ** 2), rel=1e-3)
    # the stiffened flapwise mode does not notice the strain measure's missing tension any less: it stays at ω̄₀
    f, _ = spinning_modes(body, 3.7).first(True)
    assert f == pytest.approx(3.51602, rel=1e-3)


def test_steady_spin_is_a_relative_equilibrium_of_the_scene():
    """Started in its steady state, the spinning beam stays there: to round-off with the trapezoidal rule; the
    energy–momentum scheme starts from the exact rates, not its own discrete ones, and wanders by O(Δt²)."""
    scene = sf.scenes.rotating_beam_3d(perturbation=0.0, n_elements=4)
    res = sf.simulate(scene, 0.2, 0.01, scheme="trapezoidal")
    tip = res.probes["tip"]
    assert tip[0, 0] > 1e-4                                 # it is stretched
    assert np.ptp(tip, axis=0).max() <= 1e-8
    drift = [np.ptp(sf.simulate(sf.scenes.rotating_beam_3d(perturbation=0.0, n_elements=4), 0.5,
                                dt).probes["tip"][:, 1]) for dt in (0.01, 0.005)]
    assert 3.5 <= drift[0] / drift[1] <= 4.5


def test_free_flight_keeps_energy_and_linear_momentum_and_gravity_gives_m_g_t():
    body = small_body("chord", order=1, n=4, angular_velocity=(0.3, 0.5, 0.1), velocity=(0.1, 0.0, 0.0))
    res = sf.simulate(sf.Scene([body], name="free"), 1.0, 0.05, scheme="energy-momentum")
    assert relerr(res.total_energy, np.full(res.t.size, res.total_energy[0])) <= 1e-11
    p = np.array([body.linear_momentum(q, v) for q, v in zip(res.q, res.v)])
    assert np.abs(p - p[0]).max() <= 1e-11 * np.abs(p[0]).max()
    L = np.array([body.angular_momentum(q, v) for q, v in zip(res.q, res.v)])
    assert np.abs(L - L[0]).max() <= 1e-3 * np.abs(L[0]).max()           # O(Δt²): not a conserved quantity here
    g = np.array([0.0, 0.0, -9.81])
    falling = small_body("chord", order=1, n=4)
    res = sf.simulate(sf.Scene([falling], forces=[sf.Gravity(g)], name="falling"), 0.5, 0.05)
    assert relerr(falling.linear_momentum(res.q[-1], res.v[-1]), falling.inertia.mass * g * 0.5) <= 1e-10


def test_a_point_force_on_the_axis_is_the_gradient_of_its_work():
    body = small_body("chord")
    rng = np.random.default_rng(2)
    q = body.q0 + 0.1 * rng.standard_normal(body.n_dofs)
    F = np.array([0.3, -1.0, 2.0])
    point = body.point(1.3)
    Q, Qq, _ = SpatialPointForce(point, F).generalized_force(q, np.zeros(body.n_dofs), 0.0)
    assert relerr(Q, central_jacobian(lambda z: F @ point.position(z), q).ravel()) <= 1e-9
    assert relerr(Qq, central_jacobian(lambda z: SpatialPointForce(point, F).generalized_force(z, 0 * z, 0.0)[0], q)) <= 1e-8
    # the clamped root is the frame's own point: affine, with the frame's orientation
    assert hasattr(small_body("clamped").point(0.0), "G")


def test_spin_up_3d_floating_frame_follows_the_exact_beam():
    """The spin-up with its out-of-plane tip load: floating-frame and geometrically exact beams (8 P1 elements
    each) agree to far less than the planar pair's 1 % of the peak (measured 4e-5 of it over 2 s)."""
    runs = {body: sf.simulate(sf.scenes.spin_up_3d(body=body), 1.0, 0.01).probes["tip"]
            for body in ("floating", "exact")}
    peak = np.abs(runs["exact"]).max(axis=0)
    assert peak[1] > 0.01 and peak[2] > 0.002
    assert np.abs(runs["floating"] - runs["exact"]).max() <= 1e-3 * peak.max()


def test_reduced_beam_keeps_the_stiffening_and_follows_the_full_one():
    """Craig–Bampton (clamped frame) with the centrifugal shapes keeps the stiffening of the full beam: the
    spinning modes of 6 modes + shapes are within 2 % of the full beam's up to λ = 12, 1e-4 at λ = 3 (measured
    5e-5 and 9e-5), where the bending modes alone miss the tension and fall (the linear-strain failure)."""
    full = rotor("green-lagrange")
    red = full.reduced(6)
    bare = full.reduced(6, n_derivatives=0, centrifugal=False)
    assert red.n_elastic < full.n_elastic / 3
    for lam, tol in ((3.0, 1e-4), (12.0, 2e-2)):
        f_full, f_red, f_bare = (b.spinning_modes(lam) for b in (full, red, bare))
        for flap in (True, False):
            assert f_red.first(flap)[0] == pytest.approx(f_full.first(flap)[0], rel=tol)
            assert f_bare.first(flap)[0] < 0.9 * f_full.first(flap)[0]
    # the basis is M-orthonormal, and a reduced body is a body like the full one: the same kinetic terms on η
    M = red.mass_matrix(red.q0)[12:, 12:]
    assert relerr(M, np.eye(red.n_elastic)) <= 1e-8
    chord = small_body("chord").reduced(4)
    rng = np.random.default_rng(7)
    q, a = chord.q0 + 0.1 * rng.standard_normal(chord.n_dofs), rng.standard_normal(chord.n_dofs)
    assert relerr(chord.momentum_jacobian(q, a), central_jacobian(lambda z: chord.mass_matrix(z) @ a, q)) <= 1e-8
    with pytest.raises(ValueError, match="already reduced"):
        red.reduced(2)
    with pytest.raises(ValueError, match="n_modes must be"):
        full.reduced(0)


def test_following_force_at_a_point_of_the_axis_turns_with_its_section():
    """A force given in the section's axes at a point of a floating-frame beam's axis: at the undeformed state it
    is the frame's turn of f; a section turned elastically by θ about d₁ turns it by θ about d₁ too (to the
    first order of the linear elastic kinematics); its Jacobian (the point's and the turning's parts) by
    central differences; and it works on the Python path (the compiled core refuses it and names it)."""
    body = small_body("clamped", n=4)
    tip = body.point(2.0)
    f = np.array([0.3, -0.2, 0.5])
    load = SpatialPointForce(tip, f, following=True)
    R = Rotation.from_rotvec([0.4, -0.3, 0.2]).as_matrix()
    q = turned(R, body.q0)
    Q = load.generalized_force(q, np.zeros_like(q), 0.0)[0]
    assert np.abs(Q[:3] - R @ f).max() <= 1e-14
    # the tip section turned by a small θ about d₁: f turns with it
    _, Nth = body.shape_at(2.0)
    y = 1e-4 * np.linalg.lstsq(Nth, np.array([1.0, 0.0, 0.0]), rcond=None)[0]
    qy = q.copy()
    qy[12:] = y
    F = tip.turned(qy, f)[0]
    theta = Nth @ y
    assert np.abs(F - R @ (f + np.cross(theta, f))).max() <= 1e-14
    rng = np.random.default_rng(4)
    q1 = q + 0.01 * rng.normal(size=q.size)
    _, fq, _ = load.generalized_force(q1, np.zeros_like(q1), 0.0)
    fd = central_jacobian(lambda x: load.generalized_force(x, np.zeros_like(x), 0.0)[0], q1)
    assert np.abs(fq - fd).max() <= 1e-7 * np.abs(fd).max()
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point(0.0))], forces=[load])
    r = sf.simulate(scene, 0.02, 0.01)
    assert any("SpatialPointForce" in why for why in r.run_path["python_elements"])
    with pytest.raises(ValueError, match="needs a point with an orientation"):
        SpatialPointForce(sf.SpatialPointMass(1.0).point(), f, following=True)


@pytest.mark.parametrize("following", [False, True])
def test_moment_at_a_point_of_the_axis_bends_the_cantilever(following):
    """A moment M about d₁ at the tip of a clamped floating-frame beam (linear strain, nearly Euler–Bernoulli):
    the tip deflects by M L²/(2 EI) and turns by M L/EI (1e-3; the following moment is the same to first
    order); the moment's generalized force and its Jacobian by central differences at a turned, deformed
    state."""
    sec = SpatialSection(EA=1e9, GA1=1e9, GA2=1e9, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=1e-4, rhoI2=1e-4)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 9)), sec, order=2)
    body = FloatingBeam3D(beam, strain="linear")
    M, L, EI = 1e-3, 2.0, 1e3
    tip = body.point(L)
    moment = sf.SpatialMoment(tip, (M, 0.0, 0.0), following=following)
    assert moment.compiled_form() is None
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point(0.0))], forces=[moment])
    q = sf.static_equilibrium(scene, load_steps=2).q
    u = tip.position(q) - tip.position(body.q0)
    assert abs(u[1]) == pytest.approx(M * L ** 2 / (2 * EI), rel=1e-3)
    assert np.linalg.norm(body.shape_at(L)[1] @ q[12:]) == pytest.approx(M * L / EI, rel=1e-3)
    rng = np.random.default_rng(8)
    q1 = turned(Rotation.from_rotvec([0.3, 0.2, -0.5]).as_matrix(), body.q0)
    q1[12:] = 1e-2 * rng.normal(size=body.n_elastic)
    q1 += 1e-3 * rng.normal(size=q1.size)
    _, fq, _ = moment.generalized_force(q1, np.zeros_like(q1), 0.0)
    fd = central_jacobian(lambda x: moment.generalized_force(x, np.zeros_like(x), 0.0)[0], q1)
    assert np.abs(fq - fd).max() <= 1e-7 * np.abs(fd).max()


@pytest.mark.parametrize("joint, closed_form", [("weld", 1.0 / 192.0), ("hinge", 7.0 / 768.0)])
def test_joints_with_an_axis_at_a_point_of_the_axis_hold_it_against_the_ground(joint, closed_form):
    """The frame welded at the root and the tip held to the ground at a point of the elastic axis by a weld
    (clamped–clamped) or by a hinge about the normal of the bending plane (propped): the mid-span deflection
    under P is P L³/(192 EI) or 7 P L³/(768 EI) (1e-3); the joint's rows are quadratic (the section's turned
    direction against fixed ones) and run compiled; a hinge between two material points is not quadratic."""
    sec = SpatialSection(EA=1e9, GA1=1e9, GA2=1e9, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=1e-4, rhoI2=1e-4)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 9)), sec, order=2)
    body = FloatingBeam3D(beam, strain="linear")
    P, L, EI = 1e-3, 2.0, 1e3
    held = sf.Weld3D(body.point(L)) if joint == "weld" else sf.Revolute3D(body.point(L), None, axis=(0, 1, 0))
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point(0.0)), held],
                     forces=[SpatialPointForce(body.point(1.0), (P, 0.0, 0.0))])
    q = sf.static_equilibrium(scene).q
    mid = body.point(1.0)
    assert (mid.position(q) - mid.position(body.q0))[0] == pytest.approx(closed_form * P * L ** 3 / EI, rel=1e-3)
    assert held.compiled_form() is not None
    # the rows' quadratic form of a turned direction is the section's turn of it (ElasticPoint.turned)
    rng = np.random.default_rng(2)
    qr = turned(Rotation.from_rotvec([0.2, -0.4, 0.3]).as_matrix(), body.q0)
    qr[12:] = 1e-2 * rng.normal(size=body.n_elastic)
    e = np.array([0.6, 0.0, 0.8])
    H, A, a = body.point(L).direction(e).quadratic()
    u = 0.5 * np.einsum("cij,i,j->c", H, qr, qr) + A @ qr + a
    assert np.abs(u - body.point(L).turned(qr, kinetics.split(body.q0)[1].T @ e)[0]).max() <= 1e-14
    r = sf.simulate(scene, 0.05, 0.01)
    assert not r.run_path["python_elements"]
    # between two material points the hinge's rows are cubic and quartic: products of invariants, in their own
    # compiled family (tests/test_ffrf_axis_joints.py)
    other = FloatingBeam3D(beam, strain="linear", position=(0.0, 0.0, 2.0), name="other")
    assert sf.Revolute3D(body.point(L), other.point(0.0), axis=(0, 1, 0)).compiled_form()[0] == "product"


def test_spherical_joint_at_a_point_of_the_axis():
    """A clamped–pinned (propped) cantilever: the frame welded to the ground at the root, the tip held by a
    spherical joint at a point of the elastic axis (its position is quadratic in q), a force P at mid-span:
    the deflection there is 7 P L³/(768 EI) (linear strain, nearly Euler–Bernoulli); the joint's reaction is
    the propped end's 5P/16; and a free swing on the joint, or on a hinge there, keeps its energy and the
    joint."""
    sec = SpatialSection(EA=1e9, GA1=1e9, GA2=1e9, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=1e-4, rhoI2=1e-4)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 9)), sec, order=2)
    body = FloatingBeam3D(beam, strain="linear")
    P, L = 1e-3, 2.0
    pin = sf.Spherical(body.point(L), name="prop")
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point(0.0)), pin],
                     forces=[SpatialPointForce(body.point(1.0), (P, 0.0, 0.0))])
    state = sf.static_equilibrium(scene)
    mid = body.point(1.0)
    assert (mid.position(state.q) - mid.position(body.q0))[0] == pytest.approx(7 * P * L ** 3 / (768 * 1e3), rel=1e-3)
    force = pin.reaction(state.q, state.lam[scene.constraint_layout[-1][1]])[:3]
    assert force[0] == pytest.approx(-5 * P / 16, rel=1e-3)
    # a pendulum: the frame free, the tip pinned to the ground, released under gravity
    swing = FloatingBeam3D(beam, reference="chord", strain="linear", velocity=(0.0, 0.0, 0.0))
    scene = sf.Scene([swing], constraints=[sf.Spherical(swing.point(L))], forces=[sf.Gravity((-9.81, 0.0, 0.0))])
    res = sf.simulate(scene, 0.2, 0.01)
    swung = np.asarray(res.kinetic).max()
    assert swung > 1e-3                                        # it does swing (T reaches m g Δh)
    assert np.ptp(np.asarray(res.total_energy)) <= 1e-9 * swung and np.max(res.constraint_residual) <= 1e-9
    # the same swing on a hinge to the ground at the tip (about the normal of the plane it swings in): the
    # frame turns, the section's elastic turn adds to it in the hinge's rows, and the energy is kept
    swing = FloatingBeam3D(beam, reference="chord", strain="linear", velocity=(0.0, 0.0, 0.0))
    hinge = sf.Revolute3D(swing.point(L), None, axis=(0.0, 1.0, 0.0))
    res = sf.simulate(sf.Scene([swing], constraints=[hinge], forces=[sf.Gravity((-9.81, 0.0, 0.0))]), 0.2, 0.01)
    swung = np.asarray(res.kinetic).max()
    assert swung > 1e-3 and not res.run_path["python_elements"]
    assert np.ptp(np.asarray(res.total_energy)) <= 1e-9 * swung and np.max(res.constraint_residual) <= 1e-9


def test_bad_input():
    beam = small_body().beam
    with pytest.raises(ValueError, match="TimoshenkoBeam3D"):
        FloatingBeam3D("beam")
    with pytest.raises(ValueError, match="reference must be one of"):
        FloatingBeam3D(beam, reference="pinned")
    with pytest.raises(ValueError, match="strain must be"):
        FloatingBeam3D(beam, strain="quadratic")
    with pytest.raises(ValueError, match="rotation"):
        FloatingBeam3D(beam, orientation=np.diag([1.0, 1.0, -1.0]))
    body = FloatingBeam3D(beam)
    with pytest.raises(ValueError, match="outside beam"):
        body.point(2.5)
    with pytest.raises(ValueError, match="axis must be"):
        steady_spin(body, 1.0, axis=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="omega must be finite"):
        steady_spin(body, np.nan)
    with pytest.raises(ValueError, match="body must be"):
        sf.scenes.spin_up_3d(body="modal")
    with pytest.raises(ValueError, match="no vibrating lead-lag mode"):
        sf.scenes.rotating_beam_3d(strain="linear", omega=30.0, n_elements=4)
