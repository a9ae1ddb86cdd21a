"""The rotation-interpolated beam's compiled kernel on a reused work (:class:`RotationWork`, as the family packs
it): every evaluation writes all it returns, so a work that held another evaluation's numbers gives the same
results as a new one, bit for bit."""
import numpy as np
import pytest

from skfem_flex.bodies.exact import rotation_kernel
from skfem_flex.bodies.exact.spatial_body import SpatialExactBeam
from skfem_flex.fem.spatial_section import SpatialSection

SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.0, rhoI1=10.0,
                         rhoI2=5.0)


@pytest.fixture(scope="module")
def beam():
    return SpatialExactBeam.straight(SECTION, (0.0, 0.0, 0.0), (2.0, 0.0, 1.0), n_elements=5,
                                     interpolation="rotations")


def states(beam, seed):
    rng = np.random.default_rng(seed)
    q0 = beam.q0 + 0.05 * rng.standard_normal(beam.n_dofs)
    return q0, q0 + 0.05 * rng.standard_normal(beam.n_dofs)


def test_a_reused_work_gives_the_results_of_a_new_one(beam):
    kd = beam.compiled_strain_data()
    wk = rotation_kernel.rotation_work(kd)
    for seed in range(3):
        q0, q1 = states(beam, seed)
        for residual in (False, True, False):
            ok, g, data, floor = rotation_kernel.discrete_gradient_terms(kd, q0, q1, residual)
            assert ok and rotation_kernel.discrete_gradient_terms_into(kd, wk, q0, q1, residual)
            assert np.array_equal(wk.g, g) and np.array_equal(wk.floor, floor)
            if not residual:
                assert np.array_equal(wk.data, data)
        v = rotation_kernel.potential_energy_into(kd, wk, q1)
        assert v == rotation_kernel.potential_energy(kd, q1) == pytest.approx(beam.potential_energy(q1), rel=1e-14)


def test_the_work_holds_an_array_per_field(beam):
    """The family reads the work from its pools field by field, with the dimensions of ``rotation_work``."""
    wk = rotation_kernel.rotation_work(beam.compiled_strain_data())
    assert all(isinstance(a, np.ndarray) and 1 <= a.ndim <= 3 for a in wk)
    assert wk.g.shape == wk.floor.shape == (beam.n_dofs,)
    assert wk.data.shape == beam.compiled_strain_data().pat_idx.shape


def test_a_turned_element_is_refused_on_a_reused_work(beam):
    kd = beam.compiled_strain_data()
    wk = rotation_kernel.rotation_work(kd)
    q = beam.q0.copy()
    q[15:24] = (q[15:24].reshape(3, 3) @ np.diag([-1.0, -1.0, 1.0])).ravel()    # node 1 turned by π about d₃
    assert not rotation_kernel.discrete_gradient_terms_into(kd, wk, beam.q0, q, False)
    assert np.isnan(rotation_kernel.potential_energy_into(kd, wk, q))
    assert rotation_kernel.first_turned(kd, q) == 0
    q0, q1 = states(beam, 7)
    assert rotation_kernel.discrete_gradient_terms_into(kd, wk, q0, q1, False)
    assert np.array_equal(wk.g, rotation_kernel.discrete_gradient_terms(kd, q0, q1, False)[1])
