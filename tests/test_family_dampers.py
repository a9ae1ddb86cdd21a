"""The damper family of the compiled core (skfem_flex/compiled/families/dampers.py): torsion dampers
Q = −c (g·v) g (RotationalDamper, to the ground and between bodies) and two-point dampers along r_a − r_b
(LinearDamper, between rigid bodies, a point mass and a rigid body, a body and a ground point).

1. At random states and unknowns, the Newton matrix of the energy-momentum and trapezoidal steps equals
   5-point central differences of the residual (∂Q/∂q and ∂Q/∂v through ∂v/∂x), and the load part Q of
   the residual equals the dampers' own ``generalized_force`` where the scheme evaluates loads.
2. Runs of ≤ 200 steps equal the Python path (compiled=False) under energy-momentum, trapezoidal and generalized-α,
   external work included.
3. Energy-momentum: each step's work is the dissipated −Δt Σ c ṡ², ṡ the dampers' rates at the mid-point
   (from the points' own position and velocity methods), and T + V − work stays constant.
4. A two-point damper whose points coincide refuses the state (ctx.status = STATUS_REFUSED, the loop
   returns REFUSED), the element's numpy method raises the damper's ValueError, and the family's
   ``refusal_error`` hands that error to the driver.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.compiled.families import dampers
from skfem_flex.compiled.loop import REFUSED
from skfem_flex.compiled.tasks import STATUS_OK, STATUS_REFUSED
from skfem_flex.schemes.stepper import Stepper
from force_family_checks import (SCHEMES, compare_runs, derivative_check, evaluation_points, initial_energy, local,
                                 random_stepper, run_new, scatter)


def free_dampers(forces=True):
    """Two free bars and a point mass: torsion dampers to the ground and between the bars, two-point dampers
    between the bars, from a bar to a ground point and from the point mass to a bar."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="a")
    b = sf.RigidBody.bar(0.5, 0.6, start=(1.2, 0.3), angle=0.5, name="b")
    m = sf.PointMass(0.3, [0.2, -0.5], [0.4, 0.1])
    a.v0[:] = (0.1, 0.0, 0.8)
    b.v0[:] = (0.2, -0.4, 1.5)
    dampers = [sf.RotationalDamper(a.point(), None, damping=0.8),
               sf.RotationalDamper(b.point(), a.point(), damping=0.5),
               sf.LinearDamper(a.point((0.5, 0.0)), b.point((0.3, 0.0)), 2.0),
               sf.LinearDamper(b.point((0.0, 0.0)), (1.0, -0.4), 1.0),
               sf.LinearDamper(m.point(), a.point((0.0, 0.1)), 1.5)]
    return sf.Scene([a, b, m], forces=dampers if forces else [], name="free dampers")


def torsion_mechanism():
    """The former compiled-scene tests' torsion mechanism: two hinged bars, the first pinned, torsion springs
    and dampers on the pivot and the hinge, gravity."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="upper")
    b = sf.RigidBody.bar(0.6, 0.8, start=(np.cos(-0.3), np.sin(-0.3)), angle=-1.2, name="lower")
    cons = [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0)), sf.Revolute(a.point((0.5, 0.0)), b.point((-0.4, 0.0)))]
    forces = [sf.Gravity(), sf.RotationalSpring(a.point(), None, stiffness=20.0, rest_angle=0.2),
              sf.RotationalSpring(b.point(), a.point(), stiffness=5.0),
              sf.RotationalDamper(b.point(), a.point(), damping=0.3), sf.RotationalDamper(a.point(), damping=0.1)]
    return sf.Scene([a, b], constraints=cons, forces=forces, name="torsion mechanism")


def spring_mechanism():
    """The former compiled-scene tests' spring mechanism: a pinned bar, a free bar and a point mass joined by
    two-point springs and dampers (between the bars and to the ground), under gravity."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="pinned")
    b = sf.RigidBody.bar(0.5, 0.6, start=(1.2, 0.3), angle=0.5, name="free")
    m = sf.PointMass(0.3, [0.2, -0.5])
    b.v0[:] = (0.2, -0.4, 1.5)
    forces = [sf.Gravity(), sf.LinearSpring(a.point((0.5, 0.0)), b.point((-0.3, 0.0)), 200.0, rest_length=0.3),
              sf.LinearSpring(b.point((0.3, 0.0)), (1.5, 1.0), 80.0),
              sf.LinearSpring(m.point(), a.point((0.0, 0.0)), 50.0, rest_length=0.0),
              sf.LinearDamper(a.point((0.5, 0.0)), b.point((0.3, 0.0)), 2.0),
              sf.LinearDamper(b.point((0.0, 0.0)), (1.0, -0.4), 1.0)]
    return sf.Scene([a, b, m], constraints=[sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0))], forces=forces,
                    name="spring mechanism")


def _loads(scene, q, v, t):
    return sum(scatter(scene, f, f.generalized_force(local(scene, f, q), local(scene, f, v), t)[0])
               for f, _ in scene.loads)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_newton_matrix_and_load_part_follow_the_specification(scheme):
    """Newton matrix = 5-point differences of the residual to 1e-10 of its scale; Q = the dampers'
    generalized forces to 1e-13 relative; the dampers' share of the matrix is not negligible."""
    scene = free_dampers()
    for seed in range(3):
        st = random_stepper(scene, scheme, seed)[0]
        x = 0.3 * np.random.default_rng(10 + seed).normal(size=st.packed.nx)
        h, t0 = 0.2, 0.3
        mat, err = derivative_check(st, t0, h, x)
        assert err <= 1e-10, err
        _, (qe, ve, te) = evaluation_points(st, t0, h)
        expected = _loads(scene, qe, ve, te)
        assert np.abs(st.ws.vectors["ext"] - expected).max() <= 1e-13 * np.abs(expected).max()
        mat0 = random_stepper(free_dampers(forces=False), scheme, seed)[0].evaluate(t0, h, x)[1]
        assert np.abs(mat - mat0).max() >= 0.01 * np.abs(mat).max()


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("factory, t_end, dt", [(free_dampers, 0.5, 0.005), (torsion_mechanism, 0.5, 0.005),
                                                (spring_mechanism, 0.5, 0.005)])
def test_runs_equal_the_python_path(factory, t_end, dt, scheme):
    """q to 1e-10 relative (they agree to ~1e-15), the external work to 1e-10 of the energy scale."""
    new, old, dq = compare_runs(factory, scheme, t_end, dt)
    assert dq <= 1e-10, dq
    e_scale = np.abs(old.total_energy).max()
    assert np.abs(old.external_work).max() > 1e-3 * e_scale       # the dampers dissipated
    assert np.abs(new.work - old.external_work[1:]).max() <= 1e-10 * e_scale


def _rate(scene, damper, q, v):
    """ṡ of a damper: the relative angular rate, or the rate of the two points' distance (m/s)."""
    ql, vl = local(scene, damper, q), local(scene, damper, v)
    if isinstance(damper, sf.RotationalDamper):
        return damper.grad @ vl
    ends = []
    for point in damper.points:
        if point is None:
            ends.append((damper.anchor, np.zeros(2)))
            continue
        sl = damper.layout.slices[damper.points.index(point)]
        ends.append((point.position(ql[sl]), point.velocity(ql[sl], vl[sl])))
    d = ends[0][0] - ends[1][0]
    return d @ (ends[0][1] - ends[1][1]) / np.hypot(*d)


@pytest.mark.parametrize("factory", [free_dampers, torsion_mechanism, spring_mechanism])
def test_energy_momentum_work_is_the_dissipation_at_the_mid_point(factory):
    """Work of a step = −Δt Σ c ṡ(q_m, v̄)² (1e-12 of its scale), never positive; E − W constant to the
    Newton tolerance."""
    dt = 0.005
    new = run_new(factory(), "energy-momentum", 1.0, dt)
    scene = factory()
    q = np.vstack([scene.initial_state()[0], new.q])
    work = np.cumsum([-dt * sum(f.c * _rate(scene, f, q[k] + 0.5 * (q[k + 1] - q[k]), (q[k + 1] - q[k]) / dt) ** 2
                                for f, _ in scene.loads) for k in range(new.t.size)])
    assert np.abs(work).max() > 1e-2
    assert np.abs(new.work - work).max() <= 1e-12 * np.abs(work).max()
    assert np.all(np.diff(np.concatenate([[0.0], new.work])) <= 0.0)
    e0 = initial_energy(scene)
    energy = new.derived[:, 0] + new.derived[:, 1] - new.work
    assert np.abs(energy - e0).max() <= 1e-8 * abs(e0)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_a_damper_whose_points_coincide_refuses_and_python_raises(scheme):
    """The damper from the free bar's centre to the ground point (1.0, −0.4): with the centre there the
    direction is undefined; the kernel sets STATUS_REFUSED (the dampers family reported), the loop returns
    REFUSED with the state before the step, and the element's numpy method raises the Python path's error."""
    scene = spring_mechanism()
    q0, v0 = scene.initial_state()
    q0[3:5] = (1.0, -0.4)
    v0[:] = 0.0
    scheme_obj = SCHEMES[scheme]()
    st = Stepper(scene, scheme_obj)
    st.load(scheme_obj.make_state(0.0, q0, v0, acc=np.zeros(q0.size), pseudo=np.zeros(q0.size),
                                  lam=np.zeros(st.packed.m)))
    st.evaluate(0.0, 1e-2, np.zeros(st.packed.nx))
    ctx = st.ws.ctx[0]
    assert ctx["status"] == STATUS_REFUSED and st.ws.family_name(int(ctx["bad_family"])) == "dampers"
    chunk = st.advance(0.0, np.full(3, 1e-2), np.ones(3, dtype=bool), 25, True)
    assert chunk.status == REFUSED and chunk.steps == 0
    np.testing.assert_array_equal(st.state(0.0).q, q0)
    with pytest.raises(ValueError, match="coincide"):
        scene.external_force(q0, v0, 0.0)
    # the driver's way to that error: the family's refusal_error at the loads' evaluation point
    st.evaluate(0.0, 1e-2, np.zeros(st.packed.nx))
    _, (qe, ve, te) = evaluation_points(st, 0.0, 1e-2)
    err = dampers.refusal_error(scene, qe, ve, te)
    assert isinstance(err, ValueError) and "coincide" in str(err)
    assert dampers.refusal_error(scene, qe + 0.1, ve, te) is None
    # a step later the points are apart: the same run goes on
    q0[3] += 0.1
    st.load(scheme_obj.make_state(0.0, q0, v0, acc=np.zeros(q0.size), pseudo=np.zeros(q0.size),
                                  lam=np.zeros(st.packed.m)))
    st.evaluate(0.0, 1e-2, np.zeros(st.packed.nx))
    assert st.ws.ctx[0]["status"] == STATUS_OK
