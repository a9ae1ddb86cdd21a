"""Scene assembly: blocks land on the right coordinates whatever order an element lists its bodies in."""
import numpy as np

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
