"""The quadratic-constraint family (skfem_flex/compiled/families/quadratic_rows.py) and the linear-potential
family (spatial gravity), on a mechanism with every spatial joint (tests/spatial_scenes.py).

1. Kernel against the specification (compiled/tasks.py): at random states, unknowns and multipliers the Newton
   matrix is the central difference of the residual under each scheme; the constraint force and rows are the
   constraints' numpy contract.
2. Trajectories equal the Python path (every element through its numpy methods) under every scheme.
3. Energy balance of the energy-momentum scheme: E − E₀ = the driver's work, to round-off.
"""
import numpy as np
import pytest

from family_checks import assert_constraint_contract, rel_dev, run_both, run_new
from spatial_scenes import spatial_mechanism

SCHEMES = ["energy-momentum", "trapezoidal", "generalized-alpha"]


@pytest.mark.parametrize("scheme", SCHEMES)
def test_step_is_the_constraints_contract(scheme):
    assert_constraint_contract(spatial_mechanism(), scheme)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_trajectories_equal_the_python_path(scheme):
    rec, ref = run_both(spatial_mechanism, scheme, 2e-3, 60)
    assert rel_dev(rec.q, ref.q[1:]) < 1e-10
    assert rel_dev(rec.v, ref.v[1:]) < 1e-8
    assert rel_dev(rec.lam, ref.lam[1:]) < 1e-7
    assert np.abs(rec.q[-1] - rec.q[0]).max() > 1e-3          # it moved


def test_energy_balance_with_a_driver():
    """Energy-momentum: T + V − E₀ equals the driver's work to round-off (ideal joints, gravity, a driver)."""
    rec, _ = run_new(spatial_mechanism(), "energy-momentum", 2e-3, 150)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    assert np.abs(energy - energy[0] - (rec.work - rec.work[0])).max() <= 1e-9 * rec.derived[:, 0].max()
    assert rec.derived[:, 0].max() > 1.0 and np.abs(rec.work).max() > 1e-3
