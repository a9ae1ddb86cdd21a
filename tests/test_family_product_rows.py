"""The product-rows family (skfem_flex/compiled/families/product_rows.py): joints with axes at floating-frame
material points against moving bodies (tests/spatial_scenes.py: a cylinder with a driver, a cross joint and a
rod, every row a sum of products of two quadratic invariants).

1. Kernel against the specification (compiled/tasks.py): at random states, unknowns and multipliers the Newton
   matrix is the central difference of the residual under each scheme; the constraint force and rows are the
   constraints' numpy contract (elements/constraints/product_rows.py).
2. Trajectories equal the Python path (every element through its numpy methods) under every scheme.
3. Energy balance of the energy-momentum scheme: E − E₀ = the driver's work, to round-off.
"""
import numpy as np
import pytest

from family_checks import assert_constraint_contract, rel_dev, run_both, run_new
from spatial_scenes import floating_frame_joints

SCHEMES = ["energy-momentum", "trapezoidal", "generalized-alpha"]


def test_every_joint_is_in_the_family():
    scene = floating_frame_joints()
    forms = [c.compiled_form()[0] for c in scene.constraints if c.name not in ("A: rigidity", "R: rigidity",
                                                                               "B: rigidity")]
    assert forms.count("product") == 4


@pytest.mark.parametrize("scheme", SCHEMES)
def test_step_is_the_constraints_contract(scheme):
    assert_constraint_contract(floating_frame_joints(), scheme)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_trajectories_equal_the_python_path(scheme):
    rec, ref = run_both(floating_frame_joints, scheme, 2e-3, 40)
    assert rel_dev(rec.q, ref.q[1:]) < 1e-10
    assert rel_dev(rec.v, ref.v[1:]) < 1e-8
    assert rel_dev(rec.lam, ref.lam[1:]) < 1e-7
    assert np.abs(rec.q[-1] - rec.q[0]).max() > 1e-3          # it moved


def test_energy_balance_with_a_driver():
    """Energy-momentum: T + V − E₀ equals the driver's work to round-off (ideal joints, gravity, a driver)."""
    rec, _ = run_new(floating_frame_joints(), "energy-momentum", 2e-3, 100)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    assert np.abs(energy - energy[0] - (rec.work - rec.work[0])).max() <= 1e-9 * rec.derived[:, 0].max()
    assert rec.derived[:, 0].max() > 1e-3 and np.abs(rec.work).max() > 1e-5
