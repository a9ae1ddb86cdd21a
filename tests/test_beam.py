"""TimoshenkoBeam: statics against Timoshenko theory, eq. (42), loads, input checks."""
import math

import numpy as np
import pytest
import scipy.sparse
import skfem
from hypothesis import given, settings
from hypothesis import strategies as st

from skfem_flex.fem.beam import TimoshenkoBeam, gauss_line
from skfem_flex.fem.section import Section

E, NU, B, RHO = 210e9, 0.3, 0.1, 7850.0
SECTION = Section.rectangle(E=E, nu=NU, b=B, h=0.1, rho=RHO)


def beam_on(x, section=SECTION, **kwargs):
    return TimoshenkoBeam(skfem.MeshLine(np.asarray(x, dtype=float)), section, **kwargs)


def uniform_beam(length, n_elements, **kwargs):
    return beam_on(np.linspace(0.0, length, n_elements + 1), **kwargs)


def cantilever_tip_ratio(slenderness, n_elements, order=1, shear="reduced", h=0.1):
    """FE tip deflection / (P L³/(3EI) + P L/(kGA)) of a cantilever with tip load P."""
    section = Section.rectangle(E=E, nu=NU, b=B, h=h, rho=RHO)
    length, P = slenderness * h, -1e3
    beam = uniform_beam(length, n_elements, section=section, order=order, shear=shear)
    q = beam.solve_static(beam.load(Q=(length, P)), fixed=beam.dofs_at(0.0))
    exact = P * length**3 / (3 * section.EI) + P * length / section.kGA
    return q[beam.dofs_at(length)[1]] / exact


# ---------------------------------------------------------------- statics


@pytest.mark.parametrize("slenderness", [5, 100, 1000])
def test_tip_deflection_p1_reduced_shear(slenderness):
    ratio = cantilever_tip_ratio(slenderness, 32, order=1)
    assert abs(ratio - 1) < 1e-3


@pytest.mark.parametrize("slenderness", [5, 100, 1000])
def test_tip_deflection_p2_is_nodally_exact(slenderness):
    # P2 with two-point shear reproduces the tip value exactly; what is left
    # is round-off, which grows with the condition number of K (about
    # (L/h)² n²): 4e-10 with two elements at L/h = 1000, 4e-8 with 32.
    ratio = cantilever_tip_ratio(slenderness, 2, order=2)
    assert abs(ratio - 1) < 1e-8


def test_full_integration_locks():
    assert cantilever_tip_ratio(100, 8, order=1, shear="full") < 0.5


@pytest.mark.parametrize("slenderness", [5, 100, 1000])
def test_p1_tip_error_converges_at_second_order(slenderness):
    n_elements = np.array([4, 8, 16, 32, 64])
    errors = np.array([abs(cantilever_tip_ratio(slenderness, n) - 1) for n in n_elements])
    observed_order = -np.polyfit(np.log(n_elements), np.log(errors), 1)[0]
    assert observed_order == pytest.approx(2.0, abs=0.1)
    assert np.all(-np.diff(np.log(errors)) / np.log(2) == pytest.approx(2.0, abs=0.1))


def test_axial_bar_under_end_force():
    length, h_force = 2.0, 5e4
    beam = uniform_beam(length, 3)
    q = beam.solve_static(beam.load(h=(length, h_force)), fixed=beam.dofs_at(0.0))
    assert q[beam.dofs_at(length)[0]] == pytest.approx(h_force * length / SECTION.EA, rel=1e-12)


def test_single_supports_leave_rigid_motion_free():
    beam = uniform_beam(1.0, 4)
    load = beam.load(Q=(1.0, 1.0))
    with pytest.raises(ValueError, match="singular"):
        beam.solve_static(load, fixed=[])
    with pytest.raises(ValueError, match="singular"):
        beam.solve_static(load, fixed=beam.dofs_at(0.0)[1:])  # u left free
    with pytest.raises(ValueError, match="length"):
        beam.solve_static(load[:-1], fixed=beam.dofs_at(0.0))
    with pytest.raises(ValueError, match="fixed"):
        beam.solve_static(load, fixed=[beam.n_dofs])


# ---------------------------------------------------------------- eq. (42)


def eq42(l, EA, EI, kGA):
    """Element stiffness of eq. (42) of Liu & Yun, written out as printed."""
    A_I = EA / EI  # the paper's A/I with the common factor EI/l = E·I/l
    c = kGA / EI
    return EI / l * np.array([
        [A_I, 0, 0, -A_I, 0, 0],
        [0, c, l * c / 2, 0, -c, l * c / 2],
        [0, l * c / 2, l**2 * c / 3 + 1, 0, -l * c / 2, l**2 * c / 6 - 1],
        [-A_I, 0, 0, A_I, 0, 0],
        [0, -c, -l * c / 2, 0, c, -l * c / 2],
        [0, l * c / 2, l**2 * c / 6 - 1, 0, -l * c / 2, l**2 * c / 3 + 1],
    ])


def test_single_p1_element_full_integration_is_eq42():
    section = Section(EA=3.0e6, EI=2.0e3, kGA=7.0e5, rhoA=1.0, rhoI=1e-3)
    beam = beam_on([0.3, 1.5], section=section, shear="full")
    expected = eq42(1.2, section.EA, section.EI, section.kGA)
    np.testing.assert_allclose(beam.stiffness().toarray(), expected, rtol=1e-13, atol=1e-9)


def test_single_p1_element_reduced_shear_replaces_thirds_and_sixths_by_quarters():
    section = Section(EA=3.0e6, EI=2.0e3, kGA=7.0e5, rhoA=1.0, rhoI=1e-3)
    l = 1.2
    expected = eq42(l, section.EA, section.EI, section.kGA)
    for i, j in [(2, 2), (5, 5), (2, 5), (5, 2)]:
        sixth_or_third = 1 / 3 if i == j else 1 / 6
        expected[i, j] += section.kGA * l * (1 / 4 - sixth_or_third)
    beam = beam_on([0.3, 1.5], section=section)
    np.testing.assert_allclose(beam.stiffness().toarray(), expected, rtol=1e-13, atol=1e-9)


# ---------------------------------------------------------------- operators


@pytest.mark.parametrize("order", [1, 2])
def test_operators_are_cached_symmetric_csr(order):
    beam = uniform_beam(1.0, 5, order=order)
    for matrix in (beam.stiffness(), beam.mass()):
        assert matrix.format == "csr"
        assert abs(matrix - matrix.T).max() <= 1e-12 * abs(matrix).max()
    assert beam.stiffness() is beam.stiffness()
    assert beam.mass() is beam.mass()


@pytest.mark.parametrize("order", [1, 2])
def test_mass_of_rigid_motions(order):
    length = 2.5
    beam = uniform_beam(length, 4, order=order)
    for field, density in [(0, SECTION.rhoA), (1, SECTION.rhoA), (2, SECTION.rhoI)]:
        uniform = np.zeros(beam.n_dofs)
        uniform[beam.field_dofs[field]] = 1.0
        assert uniform @ beam.mass() @ uniform == pytest.approx(density * length, rel=1e-13)
        if field < 2:  # rigid translations are strain-free
            assert np.abs(beam.stiffness() @ uniform).max() < 1e-9 * abs(beam.stiffness()).max()


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("shear", ["reduced", "full"])
def test_element_arrays_rebuild_the_operators(order, shear):
    """element_dofs and the quadrature arrays suffice for vectorised kernels."""
    beam = beam_on([0.0, 0.2, 0.7, 0.9, 1.6], order=order, shear=shear)
    s, qa, qs = beam.section, beam.quadrature, beam.shear_quadrature

    def block(a, b, weight):  # ∫ weight a_i b_j dx per element
        return np.einsum("iek,jek,ek->eij", a, b, weight)

    n_local = qa.N.shape[0]
    K_e = np.zeros((len(beam.element_lengths), 3 * n_local, 3 * n_local))
    M_e = np.zeros_like(K_e)
    u, w, th = (slice(f, None, 3) for f in range(3))
    K_e[:, u, u] = block(qa.dNdx, qa.dNdx, s.EA * qa.dx)
    K_e[:, th, th] = block(qa.dNdx, qa.dNdx, s.EI * qa.dx)
    K_e[:, w, w] += block(qs.dNdx, qs.dNdx, s.kGA * qs.dx)
    K_e[:, w, th] -= block(qs.dNdx, qs.N, s.kGA * qs.dx)
    K_e[:, th, w] -= block(qs.N, qs.dNdx, s.kGA * qs.dx)
    K_e[:, th, th] += block(qs.N, qs.N, s.kGA * qs.dx)
    M_e[:, u, u] = M_e[:, w, w] = block(qa.N, qa.N, s.rhoA * qa.dx)
    M_e[:, th, th] = block(qa.N, qa.N, s.rhoI * qa.dx)

    rows = np.repeat(beam.element_dofs, 3 * n_local, axis=1).ravel()
    cols = np.tile(beam.element_dofs, 3 * n_local).ravel()
    for local, assembled in [(K_e, beam.stiffness()), (M_e, beam.mass())]:
        rebuilt = scipy.sparse.coo_matrix((local.ravel(), (rows, cols)), shape=assembled.shape)
        np.testing.assert_allclose(rebuilt.toarray(), assembled.toarray(),
                                   rtol=1e-12, atol=1e-12 * abs(assembled).max())
    assert beam.element_dofs.shape == (4, 3 * (order + 1))
    np.testing.assert_allclose(beam.element_lengths, [0.2, 0.5, 0.2, 0.7])
    np.testing.assert_allclose(qa.dx.sum(axis=1), beam.element_lengths)


def test_gauss_line_rules_are_exact():
    for n in (1, 2, 3):
        points, weights = gauss_line(n)
        for degree in range(2 * n):
            assert weights @ points[0] ** degree == pytest.approx(1 / (degree + 1), rel=1e-14)


# ---------------------------------------------------------------- DOFs


def test_dofs_at_p1_nodes_on_an_unsorted_mesh():
    beam = TimoshenkoBeam(skfem.MeshLine(np.linspace(0, 1, 3)).refined(), SECTION)
    np.testing.assert_allclose(beam.x_nodes, [0, 0.25, 0.5, 0.75, 1.0])
    for x in beam.x_nodes:
        dofs = beam.dofs_at(x)
        np.testing.assert_allclose(beam.basis.doflocs[0, dofs], x)
        assert list(dofs % 3) == [0, 1, 2]  # node-major u, w, θ
    assert beam.dofs_at(1.0)[0] == 3 * np.argmax(beam.mesh.p[0])


def test_dofs_at_p2_midpoints_are_nodes():
    beam = uniform_beam(1.0, 2, order=2)
    np.testing.assert_allclose(beam.x_nodes, [0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(beam.basis.doflocs[0, beam.dofs_at(0.25)], 0.25)
    assert sorted(np.concatenate([beam.dofs_at(x) for x in beam.x_nodes])) == list(range(15))


@pytest.mark.parametrize("x", [0.1, -0.5, 2.0, math.nan, "0"])
def test_dofs_at_without_a_node_raises(x):
    with pytest.raises(ValueError, match="x"):
        uniform_beam(1.0, 2).dofs_at(x)


# ---------------------------------------------------------------- loads, eq. (43)


def virtual_rigid_rotation(beam, angle=1.0):
    """Linear field w = angle·x with θ = angle (no shear strain)."""
    q = np.zeros(beam.n_dofs)
    q[beam.node_dofs[:, 1]] = angle * beam.x_nodes
    q[beam.node_dofs[:, 2]] = angle
    return q


@pytest.mark.parametrize("order", [1, 2])
def test_distributed_loads_resultants(order):
    length = 3.0
    beam = beam_on([0.0, 0.4, 1.9, 3.0], order=order)
    u_dofs, w_dofs = beam.field_dofs[0], beam.field_dofs[1]
    F = beam.load(f=2.5, p=-4.0)
    assert F[u_dofs].sum() == pytest.approx(2.5 * length, rel=1e-13)
    assert F[w_dofs].sum() == pytest.approx(-4.0 * length, rel=1e-13)
    # a linearly varying load: resultant and moment about x = 0
    F = beam.load(p=lambda x: 2.0 * x)
    assert F[w_dofs].sum() == pytest.approx(length**2, rel=1e-13)
    assert F @ virtual_rigid_rotation(beam) == pytest.approx(2.0 * length**3 / 3, rel=1e-13)
    assert np.all(F[beam.field_dofs[2]] == 0.0) and np.all(F[u_dofs] == 0.0)


@pytest.mark.parametrize("x", [0.0, 0.3, 0.4, 1.234, 3.0])
@pytest.mark.parametrize("order", [1, 2])
def test_point_loads_are_consistent_with_shape_functions(x, order):
    beam = beam_on([0.0, 0.4, 1.9, 3.0], order=order)
    h_force, Q_force, moment = 3.0, -7.0, 11.0
    F = beam.load(h=(x, h_force), Q=(x, Q_force), M=(x, moment))
    u, w, th = (beam.field_dofs[k] for k in range(3))
    for dofs, value in [(u, h_force), (w, Q_force), (th, moment)]:
        assert F[dofs].sum() == pytest.approx(value, rel=1e-13)
        # a field the elements reproduce (linear, or quadratic for P2)
        # does virtual work = field value at x times the force
        for field in (lambda s: 1 + 2 * s, lambda s: (s - 1.0) ** 2):
            if order == 1 and field(0.0) == 1.0 and field(1.0) == 0.0:
                continue  # quadratic field is not in the P1 space
            nodal = field(beam.basis.doflocs[0, dofs])
            assert F[dofs] @ nodal == pytest.approx(value * field(x), rel=1e-12, abs=1e-12)
    # rigid rotation: moment of Q about the origin plus M
    assert F @ virtual_rigid_rotation(beam) == pytest.approx(Q_force * x + moment, abs=1e-12)


def test_p1_point_load_between_nodes_is_split_linearly():
    beam = beam_on([0.0, 0.4, 1.9, 3.0])
    x, Q_force = 1.0, 6.0
    F = beam.load(Q=(x, Q_force))
    share_right = (x - 0.4) / 1.5
    expected = np.zeros(beam.n_dofs)
    expected[beam.dofs_at(0.4)[1]] = Q_force * (1 - share_right)
    expected[beam.dofs_at(1.9)[1]] = Q_force * share_right
    np.testing.assert_allclose(F, expected, rtol=1e-14, atol=1e-14)


def test_point_load_at_a_node_and_several_loads_add_up():
    beam = uniform_beam(2.0, 4)
    F = beam.load(Q=[(1.0, 2.0), (2.0, 3.0)], M=(0.5, -1.0))
    expected = np.zeros(beam.n_dofs)
    expected[beam.dofs_at(1.0)[1]] = 2.0
    expected[beam.dofs_at(2.0)[1]] = 3.0
    expected[beam.dofs_at(0.5)[2]] = -1.0
    np.testing.assert_allclose(F, expected, atol=1e-15)
    np.testing.assert_allclose(beam.point_load(1.0, Q=2.0) + beam.point_load(2.0, Q=3.0)
                               + beam.point_load(0.5, M=-1.0), expected, atol=1e-15)


@pytest.mark.parametrize("spec", [(2.5, 1.0), (-0.1, 1.0), (math.nan, 1.0), (1.0, math.inf),
                                  (1.0, 2.0, 3.0), "x", [(1.0,)]])
def test_bad_point_loads_raise(spec):
    with pytest.raises(ValueError):
        uniform_beam(2.0, 4).load(Q=spec)


def test_non_finite_distributed_load_raises():
    with pytest.raises(ValueError, match="p"):
        uniform_beam(2.0, 4).load(p=lambda x: np.where(x > 1, np.nan, 1.0))


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize("points, message", [
    ([], "no elements"),
    ([0.0], "no elements"),
    ([0.0, 0.5, 0.5, 1.0], "duplicate"),
    ([0.0, 0.0], "duplicate"),
    ([0.0, math.nan, 1.0], "finite"),
    ([0.0, math.inf], "finite"),
])
def test_bad_meshes_raise(points, message):
    mesh = skfem.MeshLine(np.asarray(points, dtype=float))
    with pytest.raises(ValueError, match=message):
        TimoshenkoBeam(mesh, SECTION)


def test_meshes_that_are_not_a_chain_raise():
    p = np.array([[0.0, 1.0, 2.0, 3.0]])
    for t, message in [
        ([[0, 1, 1], [1, 2, 2]], "chain"),  # the same element twice
        ([[0, 2], [1, 3]], "chain"),  # a gap
        ([[0, 1, 2], [2, 3, 3]], "chain"),  # overlapping elements
        ([[0], [1]], "chain"),  # unused points
    ]:
        with pytest.raises(ValueError, match=message):
            TimoshenkoBeam(skfem.MeshLine1(p, np.array(t)), SECTION)
    with pytest.raises(ValueError, match="1-D"):
        TimoshenkoBeam(skfem.MeshLine1(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0], [1]])),
                       SECTION)
    with pytest.raises(ValueError, match="MeshLine"):
        TimoshenkoBeam(skfem.MeshTri(), SECTION)


@settings(max_examples=30, deadline=None)
@given(
    points=st.lists(st.floats(-10, 10), min_size=2, max_size=8, unique=True),
    data=st.data(),
)
def test_generated_meshes_with_duplicate_points_raise(points, data):
    duplicated = data.draw(st.sampled_from(points))
    mesh = skfem.MeshLine(np.sort(np.array(points + [duplicated])))
    with pytest.raises(ValueError, match="duplicate"):
        TimoshenkoBeam(mesh, SECTION)


@pytest.mark.parametrize("order", [0, 3, 1.5, "1", True, None])
def test_bad_order_raises(order):
    with pytest.raises(ValueError, match=rf"order .*{order!r}"):
        uniform_beam(1.0, 2, order=order)


@pytest.mark.parametrize("shear", ["exact", "Reduced", "", None, 1])
def test_bad_shear_option_raises(shear):
    with pytest.raises(ValueError, match="shear"):
        uniform_beam(1.0, 2, shear=shear)


def test_section_must_be_a_section():
    with pytest.raises(ValueError, match="section"):
        uniform_beam(1.0, 2, section=dict(EA=1.0, EI=1.0, kGA=1.0, rhoA=1.0, rhoI=1.0))
