"""A meshed 3D solid in the spatial floating frame (fem/elasticity3d.py, bodies/floating_spatial/solid.py):
the Craig–Bampton reduction against the full mesh and beam theory, energy conservation of a free tumbling
reduced body, stresses against beam theory and under rigid motion, and clear errors for bad input."""
import functools

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse.linalg as spla
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating_spatial.rotation import spinning_modes
from skfem_flex.bodies.floating_spatial.solid import FloatingSolid3D
from skfem_flex.bodies.floating_spatial.solid_strain import SolidGreenLagrange
from skfem_flex.fem.elasticity3d import ElasticSolid3D
from skfem_flex.numerics.quaternions import rotation_vector_matrix
from helpers import ROTATING_TABLE, central_jacobian, relerr

E, NU, RHO, L, H = 2e11, 0.3, 7800.0, 1.0, 0.1


def root(X):
    return np.isclose(X[0], 0.0)


def tip(X):
    return np.isclose(X[0], L)


@functools.lru_cache(maxsize=2)
def bar(nx=20):
    """A steel bar 1 × 0.1 × 0.1 m of P2 tetrahedra (hexahedra split in six)."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, H, 3), np.linspace(0, H, 3))
    return ElasticSolid3D(mesh.to_meshtet(), E, NU, RHO)


def test_craig_bampton_against_the_full_mesh_and_beam_theory():
    """20 fixed-interface modes and the tip's six constraint modes: the two first bending pairs, the first
    torsion and the first axial frequencies within 1e-3 of the full mesh with the same rigid tip (measured
    ≤ 4e-4); the first bending frequency within 1 % of our linear Timoshenko beam's (k = 5/6)."""
    solid = bar()
    body = FloatingSolid3D(solid, root, 20, interfaces={"tip": tip})
    M, K = body.mass_matrix(body.q0)[12:, 12:], body.strain_energy.K
    reduced = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[:6])
    full = solid.natural_frequencies(6, solid.nodes(root), [solid.nodes(tip)])
    assert np.abs(reduced / full - 1.0).max() <= 1e-3
    G = E / (2 * (1 + NU))
    A, I = H * H, H ** 4 / 12
    sec = sf.SpatialSection(EA=E * A, GA1=5 / 6 * G * A, GA2=5 / 6 * G * A, GJ=G * 0.1406 * H ** 4, EI1=E * I,
                            EI2=E * I, rhoA=RHO * A, rhoI1=RHO * I, rhoI2=RHO * I)
    beam = sf.TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0, L, 21)), sec, order=2)
    timoshenko = beam.modes(fixed=beam.dofs_at(0.0), n_modes=1)[0][0]
    assert reduced[0] == pytest.approx(timoshenko, rel=1e-2)
    # the invariants: the mass and the first moment of the bar about the root's centre
    assert body.inertia.mass == pytest.approx(RHO * L * H * H, rel=1e-12)
    assert np.allclose(body.inertia.S0, [RHO * H * H * L * L / 2, 0.0, 0.0], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("strain", ["linear", "green-lagrange"])
def test_free_tumbling_reduced_solid_keeps_its_energy(strain):
    solid = bar(6)
    body = FloatingSolid3D(solid, root, 4, interfaces={"tip": tip}, angular_velocity=(3.0, 20.0, 5.0), strain=strain)
    res = sf.simulate(sf.Scene([body], name="tumbling"), 0.004, 2e-4, scheme="energy-momentum")
    e = np.asarray(res.total_energy)
    assert np.ptp(e) <= 1e-9 * np.abs(e).max()
    assert np.abs(np.asarray(res.q)[:, 12:]).max() > 0.0                 # it does deform as it tumbles


def test_stresses_against_beam_theory_and_under_rigid_motion():
    """A tip force F along z on the clamped bar (static): σ_xx in the cells between x = 0.3 and 0.7 m equals
    F (L − x) z / I at their centroids within 2 %; the same deformation with the frame moved anywhere has the
    same stresses, and the undeformed body none at all."""
    solid = bar()
    body = FloatingSolid3D(solid, root, 20, interfaces={"tip": tip})
    F = 1e4
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point("frame"))],
                     forces=[sf.SpatialPointForce(body.point("tip"), (0.0, 0.0, F))])
    q = sf.static_equilibrium(scene).q
    sigma = body.stresses(q)
    centroids = solid.mesh.p[:, solid.mesh.t].mean(axis=1).T
    x, z = centroids[:, 0], centroids[:, 2] - H / 2
    mid = (x > 0.3) & (x < 0.7) & (np.abs(z) > 0.02)
    beam = F * (L - x[mid]) * (-z[mid]) / (H ** 4 / 12)
    assert np.abs(sigma[mid, 0] - beam).max() <= 0.02 * np.abs(beam).max()
    moved = q.copy()
    R = rotation_vector_matrix([0.7, -1.2, 0.4])
    moved[:3] = [3.0, -2.0, 5.0]
    moved[3:12] = (R @ q[3:12].reshape(3, 3).T).T.ravel()
    assert np.abs(body.stresses(moved) - sigma).max() <= 1e-9 * np.abs(sigma).max()
    assert np.abs(body.stresses(body.q0)).max() == 0.0


def test_vtk_series_of_the_mesh_with_its_stresses(tmp_path):
    """The series holds the mesh's vertices and cells, moved with the body, and the cell stresses; hexahedra in
    VTK's corner order (every cell of a box mesh keeps a positive volume in the file)."""
    import meshio

    from skfem_flex.io.output import VTKSeries, read_pvd
    hexes = ElasticSolid3D(skfem.MeshHex.init_tensor(np.linspace(0, L, 5), np.linspace(0, H, 2), np.linspace(0, H, 2)),
                           E, NU, RHO, order=1)
    for solid, cell in ((bar(6), "tetra"), (hexes, "hexahedron")):
        body = FloatingSolid3D(solid, root, 3, angular_velocity=(0.0, 0.0, 2.0))
        sf.simulate(sf.Scene([body], forces=[sf.SpatialPointForce(body.point((L, H, H)), (0.0, 0.0, 1e5))]),
                    2e-3, 1e-3, output=VTKSeries(tmp_path / cell, "solid"))
        frames = read_pvd(tmp_path / cell / "solid.pvd")
        mesh = meshio.read(tmp_path / cell / frames[-1][1])
        assert mesh.cells_dict[cell].shape[0] == solid.mesh.t.shape[1]
        assert mesh.points.shape[0] == solid.mesh.p.shape[1]
        assert np.abs(mesh.cell_data["von_mises"][0]).max() > 0.0
        if cell == "hexahedron":
            p = mesh.points[mesh.cells_dict[cell]]
            vol = np.einsum("ni,ni->n", p[:, 1] - p[:, 0], np.cross(p[:, 3] - p[:, 0], p[:, 4] - p[:, 0]))
            assert np.all(vol > 0)


def test_green_lagrange_energy_of_the_reduced_solid():
    """The reduced Green–Lagrange energy: its gradient and Hessian against central differences, its discrete
    gradient exact, its quadratic part the linear stiffness ΦᵀKΦ, and zero under a finite rigid rotation of the
    displacement field itself (a rigid turn strains nothing)."""
    solid = bar(4)
    body = FloatingSolid3D(solid, root, 3, interfaces={"tip": tip}, strain="green-lagrange")
    V = body.strain_energy
    assert body.n_elastic > 3 + 6                                # derivatives and spin shapes joined the basis
    rng = np.random.default_rng(1)
    scale = 1e-3 / np.abs(body.basis).max()
    y0, y1 = (scale * rng.standard_normal(body.n_elastic) for _ in range(2))
    assert relerr(V.gradient(y0), central_jacobian(V.energy, y0, 1e-3 * scale).ravel()) <= 1e-6
    assert relerr(V.hessian(y0), central_jacobian(V.gradient, y0, 1e-3 * scale)) <= 1e-6
    g, jac = V.discrete_gradient(y0, y1)
    assert abs(g @ (y1 - y0) - (V.energy(y1) - V.energy(y0))) <= 1e-10 * abs(V.energy(y1) - V.energy(y0))
    assert relerr(jac, central_jacobian(lambda z: V.discrete_gradient(y0, z)[0], y1, 1e-3 * scale)) <= 1e-6
    K = body.basis.T @ (solid.stiffness @ body.basis)
    assert relerr(V.hessian(np.zeros(body.n_elastic)), K) <= 1e-10
    # a finite rigid turn as a displacement field, u = (R − I) X: the Green–Lagrange energy is zero (round-off),
    # the linear energy of the same field is not
    R = rotation_vector_matrix([0.4, -0.3, 0.8])
    u = (solid.node_positions @ (R - np.eye(3)).T)
    turn = np.zeros((solid.n_dofs, 1))
    for k in range(3):
        turn[solid.component_dofs[k], 0] = u[:, k]
    linear = 0.5 * float(turn[:, 0] @ (solid.stiffness @ turn[:, 0]))
    assert linear > 0.0
    assert abs(SolidGreenLagrange(solid, turn).energy(np.ones(1))) <= 1e-12 * linear


def test_green_lagrange_tensors_are_the_quadrature_sums():
    """The quartic polynomial the solid's energy is evaluated as (K, K3, K4 summed once) equals the definition at
    the mesh's quadrature points (E = ½(U + Uᵀ + UᵀU), S = λ tr E I + 2μ E, V = ½ Σ w E : S; the discrete gradient
    Σ w S̄ : sym(F̄ᵀ G_m) with S̄ the stress at the mean strain and F̄ at the mean state) to round-off, at an
    amplitude where the cubic and quartic parts are three quarters of the energy."""
    from skfem.models.elasticity import lame_parameters
    solid = bar(4)
    body = FloatingSolid3D(solid, root, 3, interfaces={"tip": tip}, strain="green-lagrange")
    V = body.strain_energy
    # the definition's ingredients from scikit-fem: each basis vector's gradient at every quadrature point
    m = body.n_elastic
    grads = np.stack([solid.basis.interpolate(body.basis[:, k]).grad for k in range(m)], axis=-1)
    G = grads.transpose(2, 3, 0, 1, 4).reshape(-1, 3, 3, m)
    w, (lam, mu) = solid.basis.dx.ravel(), lame_parameters(E, NU)

    def strain(y):
        U = np.einsum("qijm,m->qij", G, y)
        return U, 0.5 * (U + U.transpose(0, 2, 1) + U.transpose(0, 2, 1) @ U)

    def stress(E):
        return lam * np.trace(E, axis1=1, axis2=2)[:, None, None] * np.eye(3) + 2.0 * mu * E

    def energy(y):
        E = strain(y)[1]
        return 0.5 * np.einsum("q,qij,qij->", w, E, stress(E))

    def discrete_gradient(y0, y1):
        Um = strain(0.5 * (y0 + y1))[0]
        S = stress(0.5 * (strain(y0)[1] + strain(y1)[1]))
        FtG = np.einsum("qki,qkjm->qijm", np.eye(3) + Um, G)
        return np.einsum("q,qij,qijm->m", w, S, 0.5 * (FtG + FtG.transpose(0, 2, 1, 3)))

    rng = np.random.default_rng(3)
    scale = 0.2 / np.abs(body.basis).max()
    y0, y1 = (scale * rng.standard_normal(body.n_elastic) for _ in range(2))
    assert 1.0 - 0.5 * y1 @ V.K @ y1 / energy(y1) > 0.5                 # the nonlinear part dominates
    assert abs(V.energy(y1) - energy(y1)) <= 1e-12 * energy(y1)
    assert relerr(V.discrete_gradient(y0, y1)[0], discrete_gradient(y0, y1)) <= 1e-12
    assert relerr(V.gradient(y1), discrete_gradient(y1, y1)) <= 1e-12


@pytest.mark.parametrize("lam, flap, lag", ROTATING_TABLE[::2] + [ROTATING_TABLE[-1]])
def test_spinning_meshed_bar_against_the_rotating_cantilever_table(lam, flap, lag):
    """A steel bar 1 × 0.05 × 0.05 m of P2 tetrahedra, clamped to its frame, spinning about z: with the
    Green–Lagrange strain (12 modes, the derivatives of 4, the spin shapes) its first flapwise (along z) and
    lead-lag frequencies follow the classical table within 1 % (measured ≤ 0.6 %, 0.4 % of it the mesh's error
    at rest); with linear strain the lead-lag mode diverges beyond λ = ω̄₀."""
    body = slender_bar("green-lagrange")
    ref = np.sqrt(E * 0.05 ** 2 / 12 / RHO)
    modes = spinning_modes(body, lam * ref, axis=(0.0, 0.0, 1.0), n_modes=6, flap_axis=2, lag_axis=1)
    if lam == 0.0:
        # at rest the square bar's two bending modes are one pair (split by 3e-4 by the mesh): any mix is one
        assert np.allclose(modes.omega[:2] / ref, flap, rtol=1e-2)
        return
    assert modes.first(True)[0] / ref == pytest.approx(flap, rel=1e-2)
    assert modes.first(False)[0] / ref == pytest.approx(lag, rel=1e-2)
    if lam == 12.0:
        g, growth = spinning_modes(slender_bar("linear"), 3.7 * ref, axis=(0.0, 0.0, 1.0), n_modes=6, flap_axis=2,
                                   lag_axis=1).first(False)
        assert g == 0.0 and growth > 0.0


@functools.lru_cache(maxsize=2)
def slender_bar(strain):
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, L, 21), np.linspace(0, 0.05, 3), np.linspace(0, 0.05, 3))
    solid = ElasticSolid3D(mesh.to_meshtet(), E, NU, RHO)
    return FloatingSolid3D(solid, root, 12, strain=strain, n_derivatives=4)


def test_meshed_rod_in_the_spatial_slider_crank():
    """The slider–crank with a meshed steel rod (6 modes): a cross joint at its frame, a ball joint at its
    far face (a point quadratic in q); the joints hold to round-off, the energy balance closes, and the slider
    follows the rigid benchmark's to a few mm (the bar's inertia is not the benchmark rod's)."""
    rigid = sf.simulate(sf.scenes.spatial_slider_crank(), 0.1, 1e-3)
    meshed = sf.simulate(sf.scenes.spatial_slider_crank(body="solid-modal"), 0.1, 1e-3)
    assert np.max(meshed.constraint_residual) <= 1e-10
    assert meshed.relative_energy_error() <= 1e-9
    assert np.abs(np.asarray(meshed.probes["slider"]) - np.asarray(rigid.probes["slider"])).max() <= 5e-3
    with pytest.raises(ValueError, match="body must be"):
        sf.scenes.spatial_slider_crank(body="beam")


def test_load_mesh_3d_reads_gmsh_with_its_groups(tmp_path):
    """A gmsh file written by meshio (hexahedra in VTK's corner order, a physical group of quadrilaterals) comes
    back as the same MeshHex, positive volumes and all, with the group as a named boundary; bad files are clear
    errors."""
    import meshio

    from skfem_flex.fem.elasticity3d import load_mesh_3d
    grid = skfem.MeshHex.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 0.5, 3), np.linspace(0, 0.2, 2))
    vtk_order = grid.t[[0, 3, 6, 2, 1, 5, 7, 4]].T
    face = grid.facets[:, grid.boundaries["left"] if grid.boundaries and "left" in grid.boundaries
                       else np.flatnonzero(np.all(np.isclose(grid.p[0, grid.facets], 0.0), axis=0))]
    quads = face.T[:, [0, 1, 3, 2]] if face.shape[0] == 4 else face.T
    path = tmp_path / "box.msh"
    meshio.write(path, meshio.Mesh(grid.p.T, [("quad", quads), ("hexahedron", vtk_order)],
                                   cell_data={"gmsh:physical": [np.ones(len(quads), int), np.full(len(vtk_order), 2)],
                                              "gmsh:geometrical": [np.ones(len(quads), int),
                                                                   np.full(len(vtk_order), 2)]},
                                   field_data={"root": np.array([1, 2]), "box": np.array([2, 3])}),
                 file_format="gmsh22", binary=False)
    mesh = load_mesh_3d(path)
    assert isinstance(mesh, skfem.MeshHex) and mesh.t.shape == grid.t.shape
    assert np.allclose(mesh.p[:, mesh.t], grid.p[:, grid.t])                 # the same corners in the same order
    solid = ElasticSolid3D(mesh, E, NU, RHO, order=1)                        # no inverted element
    assert np.allclose(solid.node_positions[solid.nodes("root"), 0], 0.0) and solid.nodes("root").size == 6
    with pytest.raises(ValueError, match="does not exist"):
        load_mesh_3d(tmp_path / "none.msh")
    (tmp_path / "junk.msh").write_text("not a mesh")
    with pytest.raises(ValueError, match="not a mesh meshio can read"):
        load_mesh_3d(tmp_path / "junk.msh")
    meshio.write(tmp_path / "flat.msh", meshio.Mesh(grid.p.T, [("quad", quads)]), file_format="gmsh22", binary=False)
    with pytest.raises(ValueError, match="no tetrahedra or hexahedra"):
        load_mesh_3d(tmp_path / "flat.msh")


def test_averaged_interface_reproduces_a_static_load_and_leaves_the_face_free():
    """An averaging (RBE3-like) tip interface: a force there is spread over the face; the reduced body's mean tip
    displacement equals the full mesh's under the same spread load (the attachment modes make it exact,
    measured 6e-12), the face deforms (unlike a rigid one), and the free tip's frequencies are the full mesh's."""
    solid = bar()
    body = FloatingSolid3D(solid, root, 20, averaged={"tip": tip})
    F = np.array([0.0, 0.0, 1e4])
    scene = sf.Scene([body], constraints=[sf.Weld3D(body.point("frame"))],
                     forces=[sf.SpatialPointForce(body.point("tip"), F)])
    q = sf.static_equilibrium(scene).q
    point = body.point("tip")
    reduced = point.position(q) - point.position(body.q0)
    T, _ = solid.tie(solid.nodes(root), [])
    dofs, P = solid.average_map(solid.nodes(tip))
    load = np.zeros(solid.n_dofs)
    load[dofs] = P[:3].T @ F
    u = T @ spla.spsolve((T.T @ solid.stiffness @ T).tocsc(), T.T @ load)
    full = P[:3] @ u[dofs]
    assert np.abs(reduced - full).max() <= 1e-8 * np.abs(full).max()
    face = body.displacement_field(q)[solid.nodes(tip)]
    rigid_fit = solid.rigid_map(solid.nodes(tip), solid.node_positions[solid.nodes(tip)].mean(axis=0))[1] @ (
        P @ face.T.ravel())
    assert np.abs(face.T.ravel() - rigid_fit).max() > 1e-5 * np.abs(face).max()      # warps: not a rigid face
    M, K = body.mass_matrix(body.q0)[12:, 12:], body.strain_energy.K
    reduced_f = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[:6])
    assert np.abs(reduced_f / solid.natural_frequencies(6, solid.nodes(root)) - 1.0).max() <= 1e-6


def test_rotor_3d_spins_up_as_its_inertia_says():
    """The meshed rotor on two ball bearings under a constant torque on its disk: its angular momentum about
    the axis grows as the torque's impulse τ t (the bearings sit on the axis), the disk turns at τ t / J_x with
    J_x = ∫ρ(y² + z²) of the mesh plus the unbalance's m r², the bearings hold and the energy balance closes
    with the torque's work."""
    scene = sf.scenes.rotor_3d()
    rotor, weight = scene.bodies
    J = rotor.inertia.I0[1, 1] + rotor.inertia.I0[2, 2] + weight.mass * 0.1 ** 2
    res = sf.simulate(scene, 0.03, 1e-3)
    t, spin = np.asarray(res.t), np.asarray(res.probes["spin"])
    assert np.abs(np.asarray(res.angular_momentum)[:, 0] - 20.0 * t).max() <= 1e-9 * 20.0 * t[-1]
    assert spin[-1] == pytest.approx(20.0 * t[-1] / J, rel=1e-6)
    assert np.max(res.constraint_residual) <= 1e-10
    assert res.relative_energy_error(np.max(np.abs(res.external_work))) <= 1e-9


def test_free_interface_modes_with_static_correction():
    """Free-interface reduction (the tip face rigid and free): the kept modes are the full mesh's free-interface
    modes (frequencies to 1e-9: they are its eigenvectors), the residual attachment modes make a static tip load
    exact (1e-9 of the full mesh's deflection), which the same number of free-interface modes alone misses by
    more than 1e-4; and ``frequency_errors`` reports the Craig–Bampton basis's errors, smaller with more modes."""
    solid = bar()
    body = FloatingSolid3D(solid, root, 8, interfaces={"tip": tip}, reduction="free-interface")
    check = body.frequency_errors(8)
    assert np.abs(check.error).max() <= 1e-9
    F = np.array([0.0, 2e3, 1e4])
    T, n_free = solid.tie(solid.nodes(root), [solid.nodes(tip)])
    load = np.zeros(T.shape[1])
    load[n_free:n_free + 3] = F
    full = spla.spsolve((T.T @ solid.stiffness @ T).tocsc(), load)[n_free:n_free + 3]

    def tip_deflection(b):
        scene = sf.Scene([b], constraints=[sf.Weld3D(b.point("frame"))],
                         forces=[sf.SpatialPointForce(b.point("tip"), F)])
        q = sf.static_equilibrium(scene).q
        return b.point("tip").position(q) - b.point("tip").position(b.q0)
    assert np.abs(tip_deflection(body) - full).max() <= 1e-9 * np.abs(full).max()
    # the same number of coordinates, free-interface modes alone: measured 5e-4 off
    modes_only = FloatingSolid3D(solid, root, 14, interfaces={"tip": tip}, reduction="free-interface")
    Phi = modes_only.basis[:, :14]
    S = modes_only.point("tip").S[:, :14]
    assert np.abs(S @ np.linalg.solve(Phi.T @ (solid.stiffness @ Phi), S.T @ F) - full).max() > 1e-4 * np.abs(full).max()
    errors = [np.abs(FloatingSolid3D(solid, root, m, interfaces={"tip": tip}).frequency_errors(4).error).max()
              for m in (4, 12)]
    assert errors[1] < errors[0] < 0.01


def test_rotor_3d_whirls_as_the_jeffcott_rotor_below_its_critical_speed():
    """A slow spin-up (6 N m): below the critical speed the disk centre whirls at the Jeffcott rotor's unbalance
    response e r²/(1 − r²), r = Ω/ω_c, e = m_u R/(M_eff + m_u), with ω_c and the modal mass M_eff of the first
    bending pair from ``sf.modes`` of the rotor at rest (an independent linear analysis): its mean over a few
    whirl periods within 3 % at Ω = 50 and 100 rad/s (measured 0.06 % and 0.4 %), and in phase with the
    unbalance (the cosine of the angle between the two 0.9999)."""
    m = sf.modes(sf.scenes.rotor_3d(unbalance=0.0, torque=0.0), "initial", n_modes=2)
    k = 1                                                      # after the free spin about the axis
    omega_c = abs(m.eigenvalues[k].imag)
    phi, phi_z = np.real(m.shapes[:, k]), np.real(m.reduced_shapes[:, k])
    mass = m.system.mass.toarray() if hasattr(m.system.mass, "toarray") else np.asarray(m.system.mass)
    m_eff = phi_z @ mass @ phi_z / np.sum(phi[1:3] ** 2)     # q[1:3]: the disk centre off the axis
    assert 230.0 < omega_c < 245.0
    res = sf.simulate(sf.scenes.rotor_3d(torque=6.0, T=2.0), 1.5, 1e-3)
    spin = np.asarray(res.probes["spin"])
    disk = np.asarray(res.probes["disk"])
    amplitude = np.linalg.norm(disk, axis=1)
    e = 0.01 * 0.1 / (m_eff + 0.01)
    for omega in (50.0, 100.0):
        window = np.abs(spin - omega) <= 5.0
        r = omega / omega_c
        assert amplitude[window].mean() == pytest.approx(e * r ** 2 / (1 - r ** 2), rel=0.03)
    # in phase: the disk centre is pushed towards the unbalance, on the rotor's turning d₂ axis
    d2 = np.asarray(res.q)[:, 7:9]                             # d₂'s y, z components (q = x, d₁, d₂, d₃, η)
    late = spin > 80.0
    cosine = np.sum(disk[late] * d2[late], axis=1) / (amplitude[late] * np.linalg.norm(d2[late], axis=1))
    assert cosine.mean() > 0.9


def test_bad_input():
    mesh = skfem.MeshTet()
    with pytest.raises(ValueError, match="Poisson's ratio"):
        ElasticSolid3D(mesh, E, 0.5, RHO)
    with pytest.raises(ValueError, match="E must be positive"):
        ElasticSolid3D(mesh, -1.0, NU, RHO)
    flat = skfem.MeshTet(np.array([[0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]]),
                         np.array([[0], [1], [2], [3]]))
    with pytest.raises(ValueError, match="degenerate"):
        ElasticSolid3D(flat, E, NU, RHO)
    with pytest.raises(ValueError, match="3D skfem.MeshTet"):
        ElasticSolid3D(skfem.MeshTri(), E, NU, RHO)
    solid = bar(6)
    with pytest.raises(ValueError, match="selects no nodes"):
        FloatingSolid3D(solid, lambda X: X[0] > 5.0, 2)
    with pytest.raises(ValueError, match="no boundary"):
        FloatingSolid3D(solid, "left", 2)
    with pytest.raises(ValueError, match="share"):
        FloatingSolid3D(solid, root, 2, interfaces={"tip": lambda X: X[0] < 0.2})
    with pytest.raises(ValueError, match="n_modes must be"):
        FloatingSolid3D(solid, root, 10 ** 6)
    body = FloatingSolid3D(solid, root, 2, interfaces={"tip": tip})
    with pytest.raises(ValueError, match="no interface"):
        body.point("middle")
    with pytest.raises(ValueError, match="as rigid and as averaged"):
        FloatingSolid3D(solid, root, 2, interfaces={"tip": tip}, averaged={"tip": tip})
    with pytest.raises(ValueError, match="strain must be"):
        FloatingSolid3D(solid, root, 2, strain="neo-hookean")
    with pytest.raises(ValueError, match="n_derivatives must be"):
        FloatingSolid3D(solid, root, 2, strain="green-lagrange", n_derivatives=5)
    with pytest.raises(ValueError, match="reduction must be"):
        FloatingSolid3D(solid, root, 2, reduction="guyan")
    with pytest.raises(ValueError, match="at most 60 elastic coordinates, got 61"):
        FloatingSolid3D(solid, root, 58, strain="green-lagrange", n_derivatives=0)      # 58 modes + 3 spin shapes
    with pytest.raises(ValueError, match="n must be in"):
        body.frequency_errors(100)
