"""The point-load family of the compiled core (skfem_flex/compiled/families/point_loads.py): point forces
Q = J_rᵀ F(t) on point masses (linear maps) and rigid bodies (frame maps: ∂(J_rᵀ f)/∂q), follower forces
Q = J_rᵀ A(ϑ) F(t) and point moments Q = M(t) ∇ϑ, with constant and time-dependent values.

1. At random states and unknowns, the Newton matrix of the energy-momentum and trapezoidal steps equals
   5-point central differences of the residual, and the load part Q of the residual equals the elements'
   own ``generalized_force`` where the scheme evaluates loads (energy-momentum: the mid-point q0 + Δq/2,
   v̄ = Δq/Δt, t0 + Δt/2; Newmark: q1, v1, t1).
2. Runs of ≤ 200 steps equal the Python path (compiled=False) under energy-momentum, trapezoidal and generalized-α,
   external work included (the Newmark work uses TASK_LOADS at the start of a chunk).
3. Energy-momentum: the recorded work equals Σ Q(q_m, v̄, t_m)·Δq recomputed from the recorded states
   with the elements' numpy methods, and T + V − work stays constant to the Newton tolerance.
"""
import numpy as np
import pytest

import skfem_flex as sf
from force_family_checks import (compare_runs, derivative_check, evaluation_points, initial_energy, local,
                                 random_stepper,
                                 run_new, scatter)


def free_loads(forces=True):
    """A point mass under a force in time, a bar with a constant point force and a follower force in time,
    a second bar with a moment in time and a constant follower force (no gravity, no joints)."""
    m = sf.PointMass(0.5, [0.4, -0.3], [0.3, 0.5])
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=0.3, name="a")
    b = sf.RigidBody.bar(0.6, 0.8, start=(1.0, 0.2), angle=-1.2, name="b")
    a.v0[:] = (0.1, -0.2, 1.5)
    b.v0[:] = (0.0, 0.3, -0.7)
    loads = [sf.PointForce(m.point(), lambda t: (2.0 * np.sin(3.0 * t), -1.0 + np.cos(t))),
             sf.PointForce(a.point((0.4, 0.1)), (3.0, -2.0)),
             sf.PointForce(a.point((-0.3, 0.0)), lambda t: (-2.0, 5.0 * np.sin(3.0 * t)), follower=True),
             sf.PointMoment(b.point((0.1, 0.0)), lambda t: 2.0 * np.sin(3.0 * t) + 0.5),
             sf.PointForce(b.point((0.3, 0.05)), (0.0, 3.0), follower=True)]
    return sf.Scene([m, a, b], forces=loads if forces else [], name="free loads")


def loaded_mechanism():
    """Two bars hinged together, the first pinned, under gravity, a follower force in time at the second's
    tip, a constant point force on the first, a moment in time on the second; a free point mass pushed by
    a force in time."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="upper")
    b = sf.RigidBody.bar(0.6, 0.8, start=(np.cos(-0.3), np.sin(-0.3)), angle=-1.2, name="lower")
    m = sf.PointMass(0.3, [0.2, -0.5], [0.1, 0.4])
    cons = [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0)), sf.Revolute(a.point((0.5, 0.0)), b.point((-0.4, 0.0)))]
    forces = [sf.Gravity(), sf.PointForce(b.point((0.4, 0.0)), lambda t: (-2.0, 5.0 * np.sin(3.0 * t)), follower=True),
              sf.PointForce(a.point((0.2, 0.0)), (1.0, 2.0)),
              sf.PointMoment(b.point(), lambda t: np.sin(3.0 * t)),
              sf.PointForce(m.point(), lambda t: (np.cos(2.0 * t), 1.0))]
    return sf.Scene([a, b, m], constraints=cons, forces=forces, name="loaded mechanism")


def _loads(scene, q, v, t):
    return sum(scatter(scene, f, f.generalized_force(local(scene, f, q), local(scene, f, v), t)[0])
               for f, _ in scene.loads)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_newton_matrix_and_load_part_follow_the_specification(scheme):
    """Newton matrix = 5-point differences of the residual to 1e-10 of its scale; Q = the elements'
    generalized forces to 1e-13 relative; the loads' share of the matrix is not negligible."""
    scene = free_loads()
    for seed in range(3):
        st = random_stepper(scene, scheme, seed)[0]
        x = 0.3 * np.random.default_rng(10 + seed).normal(size=st.packed.nx)
        h, t0 = 0.2, 0.3
        mat, err = derivative_check(st, t0, h, x)
        assert err <= 1e-10, err
        _, (qe, ve, te) = evaluation_points(st, t0, h)
        expected = _loads(scene, qe, ve, te)
        ext = st.ws.vectors["ext"]
        assert np.abs(ext - expected).max() <= 1e-13 * np.abs(expected).max()
        mat0 = random_stepper(free_loads(forces=False), scheme, seed)[0].evaluate(t0, h, x)[1]
        assert np.abs(mat - mat0).max() >= 0.01 * np.abs(mat).max()


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("factory, t_end, dt", [(free_loads, 0.5, 0.005), (loaded_mechanism, 0.5, 0.005)])
def test_runs_equal_the_python_path(factory, t_end, dt, scheme):
    """q to 1e-10 relative (they agree to ~1e-15), the external work to 1e-10 of its scale."""
    new, old, dq = compare_runs(factory, scheme, t_end, dt)
    assert dq <= 1e-10, dq
    w_scale = np.abs(old.external_work).max()
    assert w_scale > 0.1
    assert np.abs(new.work - old.external_work[1:]).max() <= 1e-10 * w_scale


@pytest.mark.parametrize("factory", [free_loads, loaded_mechanism])
def test_energy_momentum_work_is_the_loads_work_at_the_mid_point(factory):
    """W = Σ Q(q_m, v̄, t_m)·Δq from the recorded states and the elements' numpy methods (1e-12 of its scale),
    and E − W constant to the Newton tolerance."""
    dt = 0.005
    new = run_new(factory(), "energy-momentum", 1.0, dt)
    scene = factory()
    q = np.vstack([scene.initial_state()[0], new.q])
    t = np.concatenate([[0.0], new.t])
    work = np.zeros(new.t.size)
    acc = 0.0
    for k in range(new.t.size):
        dq = q[k + 1] - q[k]
        acc += dq @ _loads(scene, q[k] + 0.5 * dq, dq / dt, t[k] + 0.5 * dt)
        work[k] = acc
    assert np.abs(work).max() > 1.0
    assert np.abs(new.work - work).max() <= 1e-12 * np.abs(work).max()
    e0 = initial_energy(scene)
    energy = new.derived[:, 0] + new.derived[:, 1] - new.work
    assert np.abs(energy - e0).max() <= 1e-8 * max(abs(e0), np.abs(new.work).max())
