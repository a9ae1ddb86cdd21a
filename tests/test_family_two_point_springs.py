"""The two-point-spring family of the compiled core (skfem_flex/compiled/families/two_point_springs.py):
LinearSpring V = ½ k (‖r_a − r_b‖ − l₀)² between body points or a body point and the ground, l₀ > 0 and
l₀ = 0 (κ = ½ k), on rigid bodies (frame maps: ∂(Dᵀf)/∂q_b) and point masses (linear maps).

1. At random states and unknowns, the Newton matrix of the energy-momentum and trapezoidal steps equals
   5-point central differences of the residual, and the potential part g_p of the residual equals the
   springs' own ``potential_discrete_gradient`` (energy-momentum: from q0 to q1; Newmark: at q1, q1).
2. Runs of ≤ 200 steps equal the Python path (compiled=False) under energy-momentum, trapezoidal and generalized-α,
   and the recorded potential (TASK_ENERGY) equals the springs' ``potential_energy``.
3. Energy-momentum conserves T + V to the Newton tolerance.
"""
import pytest

import skfem_flex as sf
from force_family_checks import check_spring_run, check_spring_step


def free_springs(forces=True):
    """Two free bars and a point mass: a spring between the bars (l₀ = 0.3 m), one from a bar to a ground
    point (l₀ its initial length), one from the point mass to a bar (l₀ = 0) and one from the point mass
    to the ground point where it starts (l₀ = 0, zero length at the start)."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="a")
    b = sf.RigidBody.bar(0.5, 0.6, start=(1.2, 0.3), angle=0.5, name="b")
    m = sf.PointMass(0.3, [0.2, -0.5], [0.4, 0.1])
    a.v0[:] = (0.1, 0.0, 0.8)
    b.v0[:] = (0.2, -0.4, 1.5)
    springs = [sf.LinearSpring(a.point((0.5, 0.0)), b.point((-0.3, 0.0)), 200.0, rest_length=0.3),
               sf.LinearSpring(b.point((0.3, 0.0)), (1.5, 1.0), 80.0),
               sf.LinearSpring(m.point(), a.point((0.0, 0.1)), 50.0, rest_length=0.0),
               sf.LinearSpring(m.point(), None, 10.0)]
    return sf.Scene([a, b, m], forces=springs if forces else [], name="free springs")


def spring_mechanism():
    """The former compiled-scene tests' spring mechanism without its dampers: a pinned bar, a free bar and a
    point mass joined by two-point springs (l₀ > 0, to a ground point, l₀ = 0), under gravity."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="pinned")
    b = sf.RigidBody.bar(0.5, 0.6, start=(1.2, 0.3), angle=0.5, name="free")
    m = sf.PointMass(0.3, [0.2, -0.5])
    b.v0[:] = (0.2, -0.4, 1.5)
    forces = [sf.Gravity(), sf.LinearSpring(a.point((0.5, 0.0)), b.point((-0.3, 0.0)), 200.0, rest_length=0.3),
              sf.LinearSpring(b.point((0.3, 0.0)), (1.5, 1.0), 80.0),
              sf.LinearSpring(m.point(), a.point((0.0, 0.0)), 50.0, rest_length=0.0)]
    return sf.Scene([a, b, m], constraints=[sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0))], forces=forces,
                    name="spring mechanism")


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
@pytest.mark.parametrize("factory", [free_springs])
def test_newton_matrix_and_potential_part_follow_the_specification(factory, scheme):
    """Newton matrix = 5-point differences of the residual to 1e-10 of its scale; g_p = the elements'
    discrete gradients to 1e-12 relative; the springs' share of the matrix is not negligible."""
    check_spring_step(factory, scheme)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("factory, t_end, dt", [(free_springs, 0.5, 0.005),
                                                (spring_mechanism, 0.5, 0.005)])
def test_runs_equal_the_python_path(factory, t_end, dt, scheme):
    """q to 1e-10 relative (they agree to ~1e-15), the recorded potential to 1e-12 of the energy scale;
    energy-momentum keeps T + V − work to the Newton tolerance."""
    check_spring_run(factory, t_end, dt, scheme)