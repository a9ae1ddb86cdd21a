"""The spatial geometrically exact beam (rotation-interpolated two-node elements, and the director
interpolation): its strain energy against central differences, its discrete gradient's exactness and
equivariance, closed-form statics, the 45° bend, the roll-up into a circle, and the conservation laws of the
energy–momentum step on the flying beam and the right-angle frame."""
import numpy as np
import pytest
import scipy.sparse as sps
from scipy.spatial.transform import Rotation

import skfem_flex as sf
from skfem_flex.bodies.exact.spatial_body import SpatialExactBeam
from skfem_flex.fem.spatial_section import SpatialSection
from skfem_flex.io.output import VTKSeries, read_pvd
from skfem_flex.numerics.quaternions import rotation_vector_matrix
from skfem_flex.scenes.spatial_beams import BEND_45_REFERENCE

SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.0, rhoI1=10.0,
                         rhoI2=5.0)


def dense(a):
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


@pytest.fixture(params=[(1, "rotations"), (1, "directors"), (2, "directors")],
                ids=["P1", "P1-directors", "P2"])
def beam(request):
    order, interpolation = request.param
    return SpatialExactBeam.straight(SECTION, (0.0, 0.0, 8.0), (6.0, 0.0, 0.0), n_elements=3, order=order,
                                     interpolation=interpolation)


@pytest.fixture(params=[1, 2], ids=["P1", "P2"])
def director_beam(request):
    return SpatialExactBeam.straight(SECTION, (0.0, 0.0, 8.0), (6.0, 0.0, 0.0), n_elements=3, order=request.param,
                                     interpolation="directors")


def states(beam, seed=0, size=0.1):
    rng = np.random.default_rng(seed)
    q0 = beam.q0 + size * rng.standard_normal(beam.n_dofs)
    return q0, q0 + size * rng.standard_normal(beam.n_dofs)


def test_gradient_hessian_and_discrete_gradient_against_central_differences(beam):
    q0, q1 = states(beam)
    h = 1e-6
    V = beam.potential_energy
    for i in (0, 5, 13, beam.n_dofs - 1):
        e = np.zeros(beam.n_dofs)
        e[i] = h
        assert beam.potential_gradient(q0)[i] == pytest.approx((V(q0 + e) - V(q0 - e)) / (2 * h), rel=1e-6)
        col = (beam.potential_gradient(q0 + e) - beam.potential_gradient(q0 - e)) / (2 * h)
        assert np.abs(dense(beam.potential_hessian(q0))[:, i] - col).max() <= 1e-6 * np.abs(col).max()
        g_plus, g_minus = (beam.potential_discrete_gradient(q0, q1 + s * e)[0] for s in (1, -1))
        col = (g_plus - g_minus) / (2 * h)
        assert np.abs(dense(beam.potential_discrete_gradient(q0, q1)[1])[:, i] - col).max() <= 1e-6 * np.abs(col).max()


def test_discrete_gradient_is_exact_and_exerts_no_net_force_or_moment(beam):
    for seed in range(3):
        q0, q1 = states(beam, seed, size=0.3)
        g, _ = beam.potential_discrete_gradient(q0, q1)
        dV = beam.potential_energy(q1) - beam.potential_energy(q0)
        assert g @ (q1 - q0) == pytest.approx(dV, rel=1e-12, abs=1e-9)
        vec, mid = g.reshape(-1, 3), (0.5 * (q0 + q1)).reshape(-1, 3)
        scale = np.abs(g).max() * 10.0
        assert np.abs(vec[0::4].sum(axis=0)).max() <= 1e-12 * scale            # forces on positions
        assert np.abs(np.cross(mid, vec).sum(axis=0)).max() <= 1e-12 * scale    # moment of all of them


def test_compiled_kernel_matches_the_numpy_strain_energy(director_beam):
    """The compiled copy (director_kernel) against DirectorStrainPoints: energy, discrete gradient, tangent.
    (The rotation-interpolated beam has one implementation, the compiled one, which its Python methods
    call: the tests above hold it to central differences.)"""
    from skfem_flex.bodies.exact.director_kernel import discrete_gradient_terms, potential_energy

    beam = director_beam
    kd = beam.compiled_strain_data()
    n = beam.n_dofs
    for q0, q1 in (states(beam, 5), (states(beam, 6)[0],) * 2):
        g_ref, jac_ref = beam.potential_discrete_gradient(q0, q1)
        g, data, floor = discrete_gradient_terms(kd, q0, q1, False)
        jac = sps.csr_matrix((data, kd.pat_idx, kd.pat_ptr), shape=(n, n)).toarray()
        scale = np.abs(g_ref).max()
        assert np.abs(g - g_ref).max() <= 1e-12 * scale
        assert np.abs(jac - dense(jac_ref)).max() <= 1e-12 * np.abs(jac).max()
        assert potential_energy(kd, q1) == pytest.approx(beam.potential_energy(q1), rel=1e-13)
        assert np.all(floor >= 0.0)


def test_compiled_run_follows_the_python_run():
    scene = sf.scenes.flying_spaghetti_3d(n_elements=8)
    fast = sf.simulate(scene, 1.0, 0.1, scheme="energy-momentum")
    slow = sf.simulate(scene, 1.0, 0.1, scheme="energy-momentum", compiled=False)
    assert not any("SpatialExactBeam" in e for e in fast.run_path["python_elements"]), fast.run_path
    assert any("SpatialExactBeam" in e for e in slow.run_path["python_elements"]), slow.run_path
    assert np.abs(np.asarray(fast.q) - np.asarray(slow.q)).max() <= 1e-9


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_compiled_following_loads_follow_their_python_methods(scheme):
    """The spatial-load family (following forces and moments, on a rigid body and on beam nodes, with time
    functions) against the elements' own generalized_force, step by step."""
    body = sf.SpatialRigidBody(2.0, [0.3, 0.4, 0.5], position=(0, 0, 0), name="b")
    beam = SpatialExactBeam.straight(SECTION, (1, 0, 0), (3, 0, 0), n_elements=4)
    loads = [sf.SpatialPointForce(body.point([0.1, 0.2, 0.3]), lambda t: np.array([np.sin(t), 0.5, -1.0]),
                                  following=True),
             sf.SpatialMoment(body, lambda t: np.array([0.2, np.cos(t), 0.1]), following=True),
             sf.SpatialMoment(beam.point(2.0), (1.0, -2.0, 3.0), following=True),
             sf.SpatialPointForce(beam.point(1.0), (0.0, 3.0, 1.0), following=True),
             sf.SpatialMoment(beam.point(0.0), lambda t: np.array([0.0, 0.0, 5.0 * t]))]
    scene = sf.Scene([body, beam], forces=loads)
    fast, slow = (sf.simulate(scene, 0.1, 0.01, scheme=scheme, compiled=c) for c in (None, False))
    assert fast.run_path["python_elements"] == []
    assert np.abs(np.asarray(fast.q) - np.asarray(slow.q)).max() <= 1e-11


def test_a_singular_band_interior_switches_to_pivoting():
    """A clamped cantilever of 4 P2 elements under gravity: its bordered band's interior is singular (the
    directors d₃ carry no inertia of their own); the run switches to a factorization with pivoting, says so in
    run_path, and follows the Python path."""
    sec = SpatialSection(EA=1e6, GA1=4e5, GA2=4e5, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=1e-3, rhoI2=1e-3)
    b = SpatialExactBeam.straight(sec, (0, 0, 0), (2, 0, 0), n_elements=4, order=2, normal=(0, 0, 1))
    scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))], forces=[sf.Gravity((0, 0, -9.81))])
    fast = sf.simulate(scene, 0.02, 1e-3)
    slow = sf.simulate(scene, 0.02, 1e-3, compiled=False)
    assert fast.run_path["solver"] == "sparse (SuperLU)" and fast.halvings == 0
    assert np.abs(np.asarray(fast.q) - np.asarray(slow.q)).max() <= 1e-12


def test_strain_energy_is_objective(beam):
    q0, _ = states(beam, 4, size=0.2)
    R = Rotation.random(random_state=3).as_matrix()
    moved = q0.reshape(-1, 3) @ R.T
    moved[0::4] += [1.0, -2.0, 3.0]
    assert beam.potential_energy(moved.ravel()) == pytest.approx(beam.potential_energy(q0), rel=1e-12)
    assert beam.potential_energy(beam.q0) == 0.0


@pytest.mark.parametrize("load, closed_form", [
    ("z", lambda P, L: P * L ** 3 / (3 * 300.0) + P * L / 8e3),      # along d₁: bends about d₂ (EI₂), shears Γ₁
    ("y", lambda P, L: P * L ** 3 / (3 * 500.0) + P * L / 6e3),      # along −d₂: bends about d₁ (EI₁), shears Γ₂
    ("twist", lambda P, L: P * L / 400.0),
])
def test_linear_cantilever_against_timoshenko(load, closed_form):
    """P2, 6 elements: the tip deflections in both principal planes and the end twist, to 1e-3."""
    L, P = 2.0, 1e-3
    b = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (L, 0.0, 0.0), n_elements=6, order=2,
                                  normal=(0.0, 0.0, 1.0))
    tip = b.point(L)
    force = {"z": (0.0, 0.0, P), "y": (0.0, P, 0.0)}.get(load, (0.0, 0.0, 0.0))
    moment = (P, 0.0, 0.0) if load == "twist" else (0.0, 0.0, 0.0)
    scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))],
                     forces=[sf.SpatialPointForce(tip, force), sf.SpatialMoment(tip, moment)])
    q = sf.static_equilibrium(scene).q
    if load == "twist":
        d1 = b.node_frames(q)[-1][:, 0]
        value = np.arctan2(-d1[1], d1[2])
    else:
        value = (tip.position(q) - tip.position(b.q0))[{"z": 2, "y": 1}[load]]
    assert value == pytest.approx(closed_form(P, L), rel=1e-3)


def test_distributed_load_and_gravity_against_the_linear_beam():
    """A uniform force per length and gravity (ρA g per length) on the exact cantilever at a tiny load: the
    tip deflection of the linear Timoshenko cantilever, q L⁴/(8 EI₂) + q L²/(2 kGA₁); the load's resultant
    is q L."""
    L, q = 2.0, 1e-4
    b = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (L, 0.0, 0.0), n_elements=6, order=2,
                                  normal=(0.0, 0.0, 1.0))
    load = sf.SpatialDistributedLoad(b, (0.0, 0.0, q))
    assert np.abs(load.generalized_force(b.q0, b.q0, 0.0)[0].reshape(-1, 3)[0::4].sum(axis=0)
                  - [0.0, 0.0, q * L]).max() <= 1e-15
    expected = q * L ** 4 / (8 * 300.0) + q * L ** 2 / (2 * 8e3)
    for force in (load, sf.Gravity((0.0, 0.0, q / SECTION.rhoA))):
        scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))], forces=[force])
        tip = b.point(L)
        z = (tip.position(sf.static_equilibrium(scene).q) - tip.position(b.q0))[2]
        assert z == pytest.approx(expected, rel=1e-3)


def test_distributed_moment_and_following_load():
    """A uniform moment per length m about d₂ on the cantilever: no shear, tip deflection m L³/(3 EI₂) and
    tip turn m L²/(2 EI₂). A following force per length turns with the beam (Q(R q) = R Q(q)), has the
    resultant L Σ f_i d_i on the straight beam and, small, bends it as the same load fixed in space does."""
    L, m = 2.0, 1e-4
    b = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (L, 0.0, 0.0), n_elements=6, order=2,
                                  normal=(0.0, 0.0, 1.0))
    d2 = b.node_frames(b.q0)[0][:, 1]
    moments = sf.distributed_moments(b, m * d2)
    assert len(moments) == b.n_nodes
    scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))], forces=moments)
    q = sf.static_equilibrium(scene).q
    tip = b.point(L)
    assert (tip.position(q) - tip.position(b.q0))[2] == pytest.approx(m * L ** 3 / (3 * 300.0), rel=1e-3)
    d3 = b.node_frames(q)[-1][:, 2]
    assert np.arctan2(d3[2], d3[0]) == pytest.approx(m * L ** 2 / (2 * 300.0), rel=1e-3)
    # following: turns with the beam, resultant, and small-load agreement with the fixed load
    f = np.array([0.3, -0.2, 0.5])
    follow = sf.SpatialDistributedLoad(b, f, following=True)
    Q0 = follow.generalized_force(b.q0, b.q0, 0.0)[0].reshape(-1, 3)[0::4].sum(axis=0)
    assert np.abs(Q0 - L * b.node_frames(b.q0)[0] @ f).max() <= 1e-14
    R = rotation_vector_matrix([0.4, -0.9, 0.3])
    qs = states(b, seed=3)[0]
    turned = (qs.reshape(-1, 3) @ R.T).ravel()
    Q, Qq, _ = follow.generalized_force(qs, qs, 0.0)
    assert np.abs(follow.generalized_force(turned, turned, 0.0)[0] - (Q.reshape(-1, 3) @ R.T).ravel()).max() \
        <= 1e-13 * np.abs(Q).max()
    assert np.abs(Qq @ qs - Q).max() <= 1e-14 * np.abs(Q).max()
    small = 1e-4 * np.array([1.0, 0.0, 0.0])                   # along d₁ = z
    ends = []
    for load in (sf.SpatialDistributedLoad(b, small, following=True), sf.SpatialDistributedLoad(b, 1e-4 * np.array(
            [0.0, 0.0, 1.0]))):
        scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))], forces=[load])
        ends.append(tip.position(sf.static_equilibrium(scene).q) - tip.position(b.q0))
    assert np.abs(ends[0] - ends[1]).max() <= 1e-3 * np.abs(ends[1]).max()


def test_swept_section_output(tmp_path):
    """With a section_size the VTK series holds the section's rectangle swept along the axis: a hexahedron per
    segment, of volume w h × segment length on the straight beam, with the segments' strains."""
    import meshio
    b = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 0.0), n_elements=2, order=2,
                                  normal=(0.0, 0.0, 1.0), section_size=(0.2, 0.1))
    scene = sf.Scene([b], constraints=[sf.Weld3D(b.point(0.0))],
                     forces=[sf.SpatialPointForce(b.point(2.0), (0.0, 1.0, 1.0))])
    sf.simulate(scene, 0.02, 0.01, output=VTKSeries(tmp_path, "beam"))
    frames = read_pvd(tmp_path / "beam.pvd")
    mesh = meshio.read(tmp_path / frames[0][1])
    hexes = mesh.cells_dict["hexahedron"]
    assert hexes.shape == (b.n_nodes - 1, 8)
    p = mesh.points[hexes]
    # a box: edge vectors along d₁ (w), d₂ (h) and the axis (the segment)
    vol = np.abs(np.einsum("ni,ni->n", p[:, 1] - p[:, 0], np.cross(p[:, 3] - p[:, 0], p[:, 4] - p[:, 0])))
    assert np.allclose(vol, 0.2 * 0.1 * 0.5, rtol=1e-12)
    assert "strains" in mesh.cell_data
    with pytest.raises(ValueError, match="section_size"):
        SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 0.0), section_size=(0.2, -0.1))


def test_bend_45_is_path_independent_and_converges_to_the_published_tip():
    """P2, 3 elements: the adaptive load path and 8 equal load steps end at the same tip, within 0.5 % of the
    converged published displacement (its norm, each component; 0.38 % here, 0.19 % from 4 elements on)."""
    scene = sf.scenes.bend_45(n_elements=3, order=2)
    tip = scene.probes["tip"].point
    ends = [tip.position(sf.static_equilibrium(scene, load_steps=n).q) for n in (None, 8)]
    assert np.abs(ends[0] - ends[1]).max() <= 1e-8 * 100.0
    u = ends[0] - tip.position(scene.bodies[0].q0)
    assert np.abs(u - BEND_45_REFERENCE).max() <= 5e-3 * np.linalg.norm(BEND_45_REFERENCE)


def test_bend_45_default_mesh_is_within_half_a_percent_after_3_8_or_30_load_steps():
    """The default mesh, 8 two-node elements interpolating the rotations: the adaptive load path and 3, 8 and
    30 equal load steps end at the same tip (1e-10 of the radius), within 0.5 % of the converged published
    displacement (0.30 % here; the director interpolation on this mesh: 1.6 %)."""
    scene = sf.scenes.bend_45()
    assert scene.bodies[0].interpolation == "rotations" and scene.bodies[0].strain_points.n_elements == 8
    tip = scene.probes["tip"].point
    ends = [tip.position(sf.static_equilibrium(scene, load_steps=n).q) for n in (None, 3, 8, 30)]
    assert max(np.abs(e - ends[0]).max() for e in ends) <= 1e-10 * 100.0
    u = ends[0] - tip.position(scene.bodies[0].q0)
    assert np.abs(u - BEND_45_REFERENCE).max() <= 5e-3 * np.linalg.norm(BEND_45_REFERENCE)


@pytest.mark.parametrize("load_steps", [None, 8])
def test_end_moment_rolls_the_cantilever_into_a_full_circle(load_steps):
    """A straight cantilever (8 elements) under the end moment 2πEI/L about the normal of its bending plane
    (fixed in space) closes into a full circle: the tip back at the root to 1e-8 L, the end section turned
    by a full turn, every node on one circle. The curvature of an element is its nodes' relative rotation,
    so the constant curvature 2π/L is exact on any mesh of three or more elements (the interpolated directors of ``"directors"``
    give sin(κh)/h and cannot reach it)."""
    L, EI = 10.0, 500.0
    beam = SpatialExactBeam.straight(SECTION.__class__(EA=1e4, GA1=1e4, GA2=1e4, GJ=400.0, EI1=EI, EI2=700.0,
                                                       rhoA=1.0, rhoI1=10.0, rhoI2=10.0),
                                     (0.0, 0.0, 0.0), (L, 0.0, 0.0), n_elements=8, normal=(0.0, 0.0, 1.0))
    tip = beam.point(L)
    scene = sf.Scene([beam], constraints=[sf.Weld3D(beam.point(0.0))],
                     forces=[sf.SpatialMoment(tip, (0.0, 0.0, 2.0 * np.pi * EI / L))], name="roll-up")
    q = sf.static_equilibrium(scene, load_steps=load_steps).q
    assert np.linalg.norm(tip.position(q)) <= 1e-8 * L
    frames = beam.node_frames(q)
    assert np.abs(frames[-1] - frames[0]).max() <= 1e-8
    # half-way round: the section has turned by half a turn about the moment's axis e₃
    assert np.abs(frames[4] - np.diag([-1.0, -1.0, 1.0]) @ frames[0]).max() <= 1e-8
    x = beam.node_positions(q)[:-1]
    r = np.linalg.norm(x - x.mean(axis=0), axis=1)
    assert np.ptp(r) <= 1e-8 * r.mean()


def test_rotation_element_derivatives_at_large_relative_rotations_and_tiny_steps():
    """Off the series branch (nodal triads turned against each other by 0.5–2.5 rad): the gradient, Hessian
    and the discrete gradient's derivative against central differences; and on a step of 1e-12, where the
    Gonzalez correction would be round-off over |Δz|², the discrete gradient is the gradient and its
    derivative half the Hessian to 1e-6."""
    beam = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 1.0), n_elements=3)
    rng = np.random.default_rng(11)
    q = beam.q0.copy()
    for i, angle in enumerate((0.0, 0.5, 1.6, 2.5)):
        axis = rng.normal(size=3)
        R = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
        o = 12 * i
        q[o:o + 3] += 0.1 * rng.normal(size=3)
        q[o + 3:o + 12] = (q[o + 3:o + 12].reshape(3, 3) @ R.T).ravel()
    q0, q1 = q, q + 0.05 * rng.normal(size=q.size)
    h = 1e-6
    V = beam.potential_energy
    for i in (4, 17, 30, 45):
        e = np.zeros(beam.n_dofs)
        e[i] = h
        assert beam.potential_gradient(q0)[i] == pytest.approx((V(q0 + e) - V(q0 - e)) / (2 * h), rel=1e-6)
        col = (beam.potential_gradient(q0 + e) - beam.potential_gradient(q0 - e)) / (2 * h)
        assert np.abs(dense(beam.potential_hessian(q0))[:, i] - col).max() <= 1e-6 * np.abs(col).max()
        col = (beam.potential_discrete_gradient(q0, q1 + e)[0] - beam.potential_discrete_gradient(q0, q1 - e)[0]) / (2 * h)
        assert np.abs(dense(beam.potential_discrete_gradient(q0, q1)[1])[:, i] - col).max() <= 1e-6 * np.abs(col).max()
    g, jac = beam.potential_discrete_gradient(q0, q0 + 1e-12 * rng.normal(size=q.size))
    assert np.abs(g - beam.potential_gradient(q0)).max() <= 1e-6 * np.abs(g).max()
    half = 0.5 * dense(beam.potential_hessian(q0))
    assert np.abs(dense(jac) - half).max() <= 1e-6 * np.abs(half).max()


@pytest.mark.parametrize("interpolation", ["rotations", "directors"])
def test_residual_only_strain_terms_are_the_full_terms(interpolation):
    """The elements' residual-only discrete gradient (an evaluation whose matrix the loop does not use) is the
    full one's g, bit for bit, without the tangent and the round-off floor."""
    from skfem_flex.bodies.exact import director_kernel, rotation_kernel
    beam = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 1.0), n_elements=4,
                                     interpolation=interpolation)
    q0, q1 = states(beam, seed=3, size=0.05)
    kd = beam.compiled_strain_data()
    if interpolation == "rotations":
        full = rotation_kernel.discrete_gradient_terms(kd, q0, q1, False)
        part = rotation_kernel.discrete_gradient_terms(kd, q0, q1, True)
        assert full[0] and part[0]
        full, part = full[1:], part[1:]
    else:
        full = director_kernel.discrete_gradient_terms(kd, q0, q1, False)
        part = director_kernel.discrete_gradient_terms(kd, q0, q1, True)
    (g, data, floor), (g_r, data_r, floor_r) = full, part
    assert np.array_equal(g, g_r) and np.any(g)
    assert data_r.size == 0 and not np.any(floor_r) and np.any(data) and np.any(floor)


@pytest.mark.parametrize("interpolation", ["rotations", "directors"])
def test_residual_only_checks_on_beam_elements_change_no_iterate(monkeypatch, interpolation):
    """A cantilever under gravity, energy–momentum at Newton rtol 1e-8: its steps converge in a steady two
    iterations, and the loop checks the second update with a residual-only evaluation of the beam
    (``RESIDUAL_ONLY`` of its family); trajectory and iterations are those of full evaluations."""
    from skfem_flex.compiled.families import director_beam, rotation_beam
    from skfem_flex.schemes.stepper import Stepper
    family = rotation_beam if interpolation == "rotations" else director_beam

    def cantilever():
        beam = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 0.0), n_elements=6,
                                         normal=(0.0, 1.0, 0.0), interpolation=interpolation)
        return sf.Scene([beam], constraints=[sf.Weld3D(beam.point(0.0))], forces=[sf.Gravity((0.0, 0.0, -9.81))])
    scheme = sf.EnergyMomentum(newton=sf.NewtonSettings(rtol=1e-8, ctol=1e-8, etol=1e-10))
    runs = []
    for lazy in (True, False):
        monkeypatch.setattr(family, "RESIDUAL_ONLY", lazy)
        runs.append(sf.simulate(cantilever(), 0.1, 0.005, scheme=scheme))
        assert Stepper(cantilever(), scheme).lazy == lazy        # the loop checks updates residual-only
    its = runs[0].newton_iterations[1:]
    assert np.mean(its == np.median(its)) > 0.8                # steady: the residual-only checks did run
    assert np.array_equal(runs[0].newton_iterations, runs[1].newton_iterations)
    assert np.array_equal(runs[0].q, runs[1].q)


def test_an_element_turned_half_a_turn_is_named():
    beam = SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 0.0), n_elements=2, name="arm")
    q = beam.q0.copy()
    q[15:24] = (q[15:24].reshape(3, 3) @ np.diag([-1.0, -1.0, 1.0])).ravel()    # node 1 turned by π about d₃
    for method in (beam.potential_energy, beam.potential_gradient, beam.strains):
        with pytest.raises(sf.ElementInversionError, match="arm: element 0 has turned half a turn"):
            method(q)
    with pytest.raises(sf.ElementInversionError, match="element 0"):
        beam.potential_discrete_gradient(beam.q0, q)


def test_flying_spaghetti_conserves_momenta_and_energy_after_the_pulse():
    scene = sf.scenes.flying_spaghetti_3d(n_elements=8)
    r = sf.simulate(scene, 6.0, 0.1, scheme="energy-momentum")
    t = np.asarray(r.t)
    free = t >= 5.0 - 1e-12
    p, L, E = np.asarray(r.linear_momentum), np.asarray(r.angular_momentum), np.asarray(r.total_energy)
    # the impulse of F_x = 0.1 h(t): 0.1 × ½ × 5 s × 200 N
    assert np.abs(p[free] - [50.0, 0.0, 0.0]).max() <= 1e-10 * 50.0
    assert np.ptp(E[free]) <= 1e-10 * np.abs(E[free]).max()
    assert np.abs(np.ptp(L[free], axis=0)).max() <= 1e-10 * np.abs(L[free]).max()
    frames = scene.bodies[0].node_frames(np.asarray(r.q)[-1])
    assert max(np.abs(R.T @ R - np.eye(3)).max() for R in frames) <= 1e-12


def test_right_angle_frame_welds_two_beams_and_conserves_energy_after_the_load(tmp_path):
    scene = sf.scenes.right_angle_frame(n_elements=2)
    r = sf.simulate(scene, 2.5, 0.05, scheme="energy-momentum", output=VTKSeries(tmp_path, "frame"))
    t, E = np.asarray(r.t), np.asarray(r.total_energy)
    after = t >= 2.0 - 1e-12
    assert np.ptp(E[after]) <= 1e-10 * np.abs(E[after]).max()
    elbow = np.asarray(r.probes["elbow"])
    assert elbow[-1, 2] > 0.1                                   # pushed out of the plane along +z
    q = np.asarray(r.q)[-1]
    legs = scene.bodies
    # the weld: the elbow node of leg 1 and the first node of leg 2 coincide and keep their relative turn
    off = scene.coordinates(legs[0], q), scene.coordinates(legs[1], q)
    assert np.abs(legs[0].node_positions(off[0])[-1] - legs[1].node_positions(off[1])[0]).max() <= 1e-9
    relative = [a.node_frames(qa)[k].T @ b.node_frames(qb)[0] for a, b, qa, qb, k in
                ((legs[0], legs[1], legs[0].q0, legs[1].q0, -1), (legs[0], legs[1], off[0], off[1], -1))]
    assert np.abs(relative[0] - relative[1]).max() <= 1e-9
    assert np.abs(legs[0].node_frames(off[0])[-1] - legs[0].node_frames(legs[0].q0)[-1]).max() > 1e-2
    assert len(read_pvd(tmp_path / "frame.pvd")) == len(t)


def test_spin_up_3d_in_its_plane_follows_the_planar_exact_beam():
    """Without its out-of-plane load the spatial spin-up stays in the plane (to round-off) and its tip follows
    the planar geometrically exact beam's (same mesh) to 1e-4 of the deflection; with the load the tip leaves
    the plane along +z and the energy balance closes."""
    spatial = sf.simulate(sf.scenes.spin_up_3d(tip_load=0.0), 1.0, 0.01, scheme="energy-momentum")
    planar = sf.simulate(sf.scenes.exact_spin_up_beam(), 1.0, 0.01, scheme="energy-momentum")
    p3, p2 = np.asarray(spatial.probes["tip"]), np.asarray(planar.probes["tip"])
    assert np.abs(p3[:, 2]).max() <= 1e-12
    assert np.abs(p3[:, :2] - p2).max() <= 1e-4 * np.abs(p2[:, 1]).max()
    loaded = sf.simulate(sf.scenes.spin_up_3d(), 1.0, 0.01, scheme="energy-momentum")
    assert np.asarray(loaded.probes["tip"])[-1, 2] > 1e-3
    assert np.abs(np.asarray(loaded.energy_balance_error)).max() <= 1e-9


def test_bad_input_names_the_value():
    with pytest.raises(ValueError, match="parallel to the beam axis"):
        SpatialExactBeam.straight(SECTION, (0, 0, 0), (1, 0, 0), normal=(2.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="EA must be positive"):
        SpatialSection(EA=0.0, GA1=1, GA2=1, GJ=1, EI1=1, EI2=1)
    with pytest.raises(ValueError, match="rotation matrix"):
        SpatialExactBeam(SECTION, 1.0, lambda s: (np.zeros(3) + s, 2.0 * np.eye(3)), n_elements=2)
    with pytest.raises(ValueError, match="start and end must differ"):
        SpatialExactBeam.straight(SECTION, (1, 1, 1), (1, 1, 1))
    with pytest.raises(ValueError, match="outside beam"):
        SpatialExactBeam.straight(SECTION, (0, 0, 0), (1, 0, 0)).point(2.0)
    with pytest.raises(ValueError, match="needs order=1, got order=2"):
        SpatialExactBeam.straight(SECTION, (0, 0, 0), (1, 0, 0), order=2, interpolation="rotations")
    with pytest.raises(ValueError, match="interpolation must be 'rotations' or 'directors', got 'linear'"):
        SpatialExactBeam.straight(SECTION, (0, 0, 0), (1, 0, 0), interpolation="linear")
    with pytest.raises(ValueError, match="reference placement turns element 0 by half a turn"):
        SpatialExactBeam(SECTION, 1.0, lambda s: (np.array([s, 0.0, 0.0]), Rotation.from_rotvec(
            [np.pi * s, 0.0, 0.0]).as_matrix()), n_elements=1)
