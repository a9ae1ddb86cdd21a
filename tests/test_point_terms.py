"""Public building blocks shared across layers: point terms and the scene's constraint layout."""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.elements import constraints
from skfem_flex.elements import point_terms
from skfem_flex.bodies.rigid import RigidBody
from skfem_flex.elements.constraints import Pin, Revolute, Weld
from skfem_flex.elements.point_terms import (Constant, Difference, Dot, PointLayout, Position, Rotated, angle_term,
                                    coordinate_term, linear_combination)

from helpers import dense


def two_bodies():
    a = RigidBody(2.0, 0.3, (0.1, 0.2), 0.3, name="a")
    b = RigidBody(1.0, 0.1, (0.5, -0.2), -0.7, name="b")
    return a, b


def test_point_layout_is_the_one_constraints_exports():
    assert constraints.PointLayout is point_terms.PointLayout


def test_layout_lists_each_body_once_and_the_ground_as_none():
    a, b = two_bodies()
    layout = PointLayout([a.point((0.1, 0.0)), None, b.point(), a.point()])
    assert layout.bodies == (a, b) and layout.n == 6
    assert layout.slices == [slice(0, 3), None, slice(3, 6), slice(0, 3)]
    assert np.allclose(layout.initial(), np.r_[a.q0, b.q0])


def terms_of_two_rigid_bodies():
    """Every term kind on two rigid bodies: name → term over the 6 local coordinates."""
    a, b = two_bodies()
    pa, pb = a.point((0.3, -0.1)), b.point((-0.2, 0.4))
    layout = PointLayout([pa, pb])
    n, (sa, sb) = layout.n, layout.slices
    d = Difference(n, pa, sa, pb, sb)
    ta, tb = angle_term(n, pa, sa), angle_term(n, pb, sb)
    rot = Rotated(n, tb, (0.6, 0.8))
    return layout, {
        "position": Position(n, pa, sa), "difference": d, "ground": Difference(n, pb, sb, anchor=(1.0, 2.0)),
        "angle": ta, "relative angle": linear_combination(n, [ta, tb], [1.0, -1.0], 0.2),
        "coordinate": coordinate_term(n, 4), "rotated": rot, "squared length": Dot(n, d, d),
        "normal distance": Dot(n, rot, d), "constant normal": Dot(n, Constant(n, (0.0, 1.0)), d),
    }


@pytest.mark.parametrize("name", list(terms_of_two_rigid_bodies()[1]))
def test_term_derivatives_and_exact_discrete_gradient(name):
    layout, terms = terms_of_two_rigid_bodies()
    term = terms[name]
    rng = np.random.default_rng(3)
    q0 = layout.initial()
    q1 = q0 + np.r_[0.3, -0.2, 1.4, -0.1, 0.25, -2.1]        # large rotations: exactness is not asymptotic
    # discrete gradient: D (q1 − q0) = s(q1) − s(q0) to round-off, whatever the step
    assert np.allclose(term.dgrad(q0, q1) @ (q1 - q0), term.value(q1) - term.value(q0), rtol=0, atol=1e-13)
    # Jacobian and Hessian product against central differences
    h = 1e-6
    f = rng.standard_normal(term.size)
    jac = np.column_stack([(term.value(q1 + h * e) - term.value(q1 - h * e)) / (2 * h) for e in np.eye(layout.n)])
    assert np.allclose(term.jacobian(q1), jac, atol=1e-8)
    hess = np.column_stack([(f @ term.jacobian(q1 + h * e) - f @ term.jacobian(q1 - h * e)) / (2 * h)
                            for e in np.eye(layout.n)])
    assert np.allclose(dense(term.hessian(q1, f)), hess, atol=1e-7)
    dgj = np.column_stack([(f @ term.dgrad(q0, q1 + h * e) - f @ term.dgrad(q0, q1 - h * e)) / (2 * h)
                           for e in np.eye(layout.n)])
    assert np.allclose(dense(term.dgrad_jacobian(q0, q1, f)), dgj, atol=1e-7)
    # a linear term says so, and then its Jacobian is its discrete gradient
    if term.linear:
        assert np.allclose(term.dgrad(q0, q1), term.jacobian(q1))


def test_difference_needs_exactly_one_of_a_second_point_and_an_anchor():
    a, b = two_bodies()
    layout = PointLayout([a.point(), b.point()])
    with pytest.raises(ValueError, match="exactly one"):
        Difference(layout.n, a.point(), layout.slices[0])
    with pytest.raises(ValueError, match="exactly one"):
        Difference(layout.n, a.point(), layout.slices[0], b.point(), layout.slices[1], anchor=(0.0, 0.0))


def test_angle_term_of_a_point_without_angle_raises_the_bodys_error():
    m = sf.PointMass(1.0, [0.3, 0.4], name="m")
    layout = PointLayout([m.point()])
    with pytest.raises(ValueError):
        angle_term(layout.n, m.point(), layout.slices[0])


def test_constraint_layout_places_each_constraint_on_its_bodies_and_rows():
    a, b = two_bodies()
    m = sf.PointMass(1.0, [0.3, 0.4], name="m")
    cons = [Weld(b.point()), Pin(a.point((0.2, 0.1))), Revolute(m.point(), b.point((0.1, 0.0)))]
    scene = sf.Scene([m, a, b], constraints=cons)
    layout = scene.constraint_layout
    assert len(layout) == len(cons)
    # coordinates: the constraint's bodies in its own order, wherever the scene put them
    for c, (idx, rows) in zip(cons, layout):
        assert np.array_equal(idx, np.concatenate([np.arange(scene.n)[scene.slice(body)] for body in c.bodies]))
    # rows: consecutive blocks of the constraint's equations covering Φ once
    assert np.array_equal(np.concatenate([rows for _, rows in layout]), np.arange(scene.n_constraints))
    assert [rows.size for _, rows in layout] == [c.n_equations for c in cons]
    # the layout is what the scene assembles with: Φ and the reactions read through it agree
    q, _ = scene.initial_state()
    q = q + 0.05 * np.arange(scene.n)
    phi = scene.constraint_value(q, 0.0)
    lam = np.linspace(-1.0, 2.0, scene.n_constraints)
    reactions = scene.constraint_reactions(q, lam)
    for name, c, (idx, rows) in zip(scene.reaction_names, cons, layout):
        assert np.array_equal(phi[rows], c.value(q[idx], 0.0))
        assert np.array_equal(reactions[name], np.atleast_1d(c.reaction(q[idx], lam[rows])))
    # read-only: the scene's own index arrays cannot be changed through the view
    for idx, rows in layout:
        with pytest.raises(ValueError):
            idx[...] = 0
        with pytest.raises(ValueError):
            rows[...] = 0


def test_scene_without_constraints_has_an_empty_layout():
    a, _ = two_bodies()
    assert sf.Scene([a]).constraint_layout == ()
