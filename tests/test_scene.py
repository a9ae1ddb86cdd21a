"""Scene assembly: blocks land on the right coordinates whatever order an element lists its bodies in."""
import numpy as np
import pytest

import skfem_flex as sf


def _fd_hessian(scene, q, h=1e-6):
    out = np.empty((scene.n, scene.n))
    for k in range(scene.n):
        e = np.zeros(scene.n)
        e[k] = h
        out[:, k] = (scene.potential_gradient(q + e) - scene.potential_gradient(q - e)) / (2 * h)
    return out


def test_element_listing_all_bodies_in_reverse_order_is_scattered():
    a = sf.RigidBody(1.0, 0.1, position=(0.0, 0.0), angle=0.3)
    b = sf.RigidBody(2.0, 0.2, position=(1.0, 0.5), angle=-0.2)
    # the spring lists b before a: its block must be permuted into the scene's (a, b) layout
    spring = sf.LinearSpring(b.point((0.1, 0.0)), a.point((0.0, 0.2)), stiffness=50.0, rest_length=0.5)
    scene = sf.Scene([a, b], forces=[spring])
    q = np.array([0.1, -0.2, 0.4, 1.2, 0.3, -0.5])
    np.testing.assert_allclose(scene.potential_hessian(q), _fd_hessian(scene, q), atol=1e-6)
    # the same spring listed in scene order gives the same Hessian
    ordered = sf.Scene([a, b], forces=[sf.LinearSpring(a.point((0.0, 0.2)), b.point((0.1, 0.0)),
                                                       stiffness=50.0, rest_length=0.5)])
    np.testing.assert_allclose(scene.potential_hessian(q), ordered.potential_hessian(q), atol=1e-12)


def test_fused_energy_momentum_terms_with_gravity_and_a_spring_equal_the_separate_terms():
    """The scene's fused evaluation (floating-frame bodies in one call, conservative forces added) gives
    the same residual terms as the general path through the contract methods."""
    def build():
        scene = sf.scenes.flexible_pendulum(n_elements=3)
        beam = scene.bodies[0]
        bar = sf.RigidBody.bar(1.0, 0.5, start=(2.0, 0.0), angle=0.2)
        spring = sf.LinearSpring(beam.point(0.5), bar.point((0.0, 0.0)), stiffness=30.0, rest_length=0.4)
        return sf.Scene([beam, bar], constraints=scene.constraints, forces=[sf.Gravity(), spring])
    fused, general = build(), build()
    general._fused = False
    rng = np.random.default_rng(5)
    q0 = np.concatenate([b.q0 for b in fused.bodies]) + 0.01 * rng.standard_normal(fused.n)
    q1 = q0 + 1e-3 * rng.standard_normal(fused.n)
    v0, v1 = 0.1 * rng.standard_normal(fused.n), 0.1 * rng.standard_normal(fused.n)
    a = fused.energy_momentum_terms(q0, q1, v0, v1, 0.01)
    b = general.energy_momentum_terms(q0, q1, v0, v1, 0.01)
    assert fused._fused is True
    dense = lambda m: m.toarray() if hasattr(m, "toarray") else np.asarray(m)  # noqa: E731
    for x, y in zip(a[:3], b[:3]):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * np.abs(y).max())
    np.testing.assert_allclose(dense(a[3]), dense(b[3]), rtol=1e-10, atol=1e-10 * np.abs(dense(b[3])).max())
    # the round-off floors are bounds: the fused one sums |blocks| separately, so it is not below
    assert np.all(a[4] >= b[4] * (1 - 1e-12)) and np.all(a[4] <= 1.1 * b[4] + 1e-12 * b[4].max())
    assert a[5] == pytest.approx(b[5], rel=1e-13)
