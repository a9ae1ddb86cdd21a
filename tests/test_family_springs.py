"""The springs family of the compiled core (skfem_flex/compiled/families/springs.py): coordinate springs
V = ½ k u^p (NonlinearSpring) and quadratic springs V = ½ k (g·q + c)² (RotationalSpring).

1. At random states and unknowns, the Newton matrix of the energy-momentum and trapezoidal steps equals
   5-point central differences of the residual, and the potential part g_p of the residual equals the
   elements' own ``potential_discrete_gradient`` (energy-momentum: from q0 to q1; Newmark: at q1, q1).
2. Runs of ≤ 200 steps equal the Python path (compiled=False) under energy-momentum, trapezoidal and generalized-α,
   and the recorded potential (TASK_ENERGY) equals the elements' ``potential_energy``.
3. Energy-momentum conserves T + V to the Newton tolerance.
"""
import numpy as np
import pytest

import skfem_flex as sf
from force_family_checks import check_spring_run, check_spring_step, local, random_stepper


def coordinate_springs(forces=True):
    """A free bar and a point mass held by coordinate springs: p = 4 on the bar's angle, p = 2 and p = 3
    (unbounded below) on the point's coordinates."""
    bar = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=0.3, name="bar")
    bar.v0[:] = (0.1, -0.2, 1.5)
    m = sf.PointMass(0.5, [0.4, -0.3], [0.3, 0.5])
    springs = [sf.NonlinearSpring(bar, 40.0, exponent=2.0, coordinate=2),
               sf.NonlinearSpring(m, 25.0, exponent=1.0, coordinate=1),
               sf.NonlinearSpring(m, 2.0, exponent=1.5, coordinate="x")]
    return sf.Scene([bar, m], forces=springs if forces else [], name="coordinate springs")


def torsion_springs(forces=True):
    """Two free bars: a torsion spring from the first to the ground and one between the bars."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="upper")
    b = sf.RigidBody.bar(0.6, 0.8, start=(1.0, 0.2), angle=-1.2, name="lower")
    a.v0[:] = (0.0, 0.1, 2.0)
    b.v0[:] = (0.2, 0.0, -1.0)
    springs = [sf.RotationalSpring(a.point((0.2, 0.0)), None, stiffness=20.0, rest_angle=0.2),
               sf.RotationalSpring(b.point(), a.point(), stiffness=5.0)]
    return sf.Scene([a, b], forces=springs if forces else [], name="torsion springs")


def torsion_mechanism():
    """Two bars hinged together, the first pinned to the ground, under gravity: torsion springs to the
    ground and between the bars (as the former compiled-scene tests' torsion mechanism, without its dampers)."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="upper")
    b = sf.RigidBody.bar(0.6, 0.8, start=(np.cos(-0.3), np.sin(-0.3)), angle=-1.2, name="lower")
    cons = [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0)), sf.Revolute(a.point((0.5, 0.0)), b.point((-0.4, 0.0)))]
    forces = [sf.Gravity(), sf.RotationalSpring(a.point(), None, stiffness=20.0, rest_angle=0.2),
              sf.RotationalSpring(b.point(), a.point(), stiffness=5.0)]
    return sf.Scene([a, b], constraints=cons, forces=forces, name="torsion mechanism")


def spring_mass():
    return sf.scenes.spring_mass(exponent=1.5)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
@pytest.mark.parametrize("factory", [coordinate_springs, torsion_springs])
def test_newton_matrix_and_potential_part_follow_the_specification(factory, scheme):
    """Newton matrix = 5-point differences of the residual to 1e-10 of its scale; g_p = the elements'
    discrete gradients to 1e-12 relative; the springs' share of the matrix is not negligible."""
    check_spring_step(factory, scheme)


def test_coordinate_spring_tangent_at_equal_points_is_half_the_hessian():
    """Newmark's c_dg = 2 convention: at q_a = q_b the divided difference's derivative is half the Hessian,
    so the trapezoidal matrix's spring part is Δt ∇²V (against the elements' potential_hessian)."""
    scene, bare = coordinate_springs(), coordinate_springs(forces=False)
    st, _, _ = random_stepper(scene, "trapezoidal", 4)
    st0, _, _ = random_stepper(bare, "trapezoidal", 4)
    x, h = 0.1 * np.ones(scene.n), 0.05
    mat = st.evaluate(0.0, h, x)[1] - st0.evaluate(0.0, h, x)[1]
    q1 = st.ws.vectors["q1"]
    hess = np.zeros((scene.n, scene.n))
    for f, idx in scene.conservative_forces:
        hess[np.ix_(idx, idx)] += f.potential_hessian(local(scene, f, q1))
    np.testing.assert_allclose(mat, h * hess, rtol=0, atol=1e-12 * np.abs(h * hess).max())


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("factory, t_end, dt", [(spring_mass, 1.0, 0.01), (coordinate_springs, 1.0, 0.01),
                                                (torsion_mechanism, 0.5, 0.005)])
def test_runs_equal_the_python_path(factory, t_end, dt, scheme):
    """q to 1e-10 relative (they agree to ~1e-15), the recorded potential to 1e-12 of the energy scale;
    energy-momentum keeps T + V − work to the Newton tolerance."""
    check_spring_run(factory, t_end, dt, scheme)