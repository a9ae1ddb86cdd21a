"""The compiled mechanism loop (skfem_flex/compiled_scene.py) against the numpy points, bodies and the Python step.

1. Its position-map kernels (value, Jacobian, exact discrete gradient and that gradient's Jacobian)
   are held to the numpy body points (PointMass, RigidBody, FloatingBeam and ModalBody points) and
   to the floating-frame bodies' gravity at 1e-12 of the entries' scale, at random states with large
   rotation increments (Δθ up to 2 rad) and tiny ones (the series branch of sinc(Δθ/2)).
2. Its trajectories (pendulum, flexible and double pendulum, rigid mechanisms with and without a
   prescribed coordinate) are those of the Python step to round-off amplified by the Newton tolerance.
3. Scenes with parts that have no compiled form are not eligible, and ``compiled=False`` is honoured.
4. A step the compiled loop cannot finish is re-run on the Python path, which halves or raises as usual.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.compiled import scene_loop as compiled_scene
from skfem_flex.bodies.base import to_dense
from skfem_flex.schemes.integrators import ConvergenceError, EnergyMomentum, NewtonSettings, Trapezoidal, make_integrator
from skfem_flex.bodies.probes import PointProbe
from skfem_flex.scenes.links import link

from helpers import dense

EPS = np.finfo(float).eps
SEC = dict(EA=1e6, EI=1e2, kGA=3.205e5, rhoA=1.0, rhoI=1e-4)
#: rotation increments of the random states: large ones and tiny ones (series branch of sinc(Δθ/2), |Δθ| < 2e-3)
DTHETAS = [2.0, -1.9, 0.6, 2.1e-3, -3e-5, 1e-9, 0.0]
#: relative tolerance of the kernels against the numpy points
KERNEL_TOL = 1e-12


def rel(a, ref, floor=0.0):
    """max |a − ref| over the larger of max |ref| and ``floor`` (0 if both are zero and a == ref)."""
    a, ref = dense(a), dense(ref)
    assert a.shape == ref.shape
    err = np.abs(a - ref).max() if a.size else 0.0
    scale = max(np.abs(ref).max() if ref.size else 0.0, floor)
    return err / scale if scale > 0 else (0.0 if err == 0 else np.inf)


# ==================================================================== 1. kernels
_POINTS = {}


def _flexible_pendulum_body():
    return sf.scenes.get("flexible_pendulum")().bodies[0]


def points():
    """{name: (body, BodyPoint)}: the body points the kernels must reproduce, built once."""
    if not _POINTS:
        pm = sf.PointMass(2.5, [0.3, -0.4], name="mass")
        rb = sf.RigidBody(2.0, 0.3, (0.2, -0.1), 0.4, name="rigid")
        beam = _flexible_pendulum_body()
        modal = link("beam-modal", 1.0, sf.Section(**SEC), 8, n_modes=3)
        _POINTS.update({
            "point-mass": (pm, pm.point()),
            "rigid-centre": (rb, rb.point()),
            "rigid-arm": (rb, rb.point((0.7, -0.2))),
            "rigid-far": (rb, rb.point((-3.0, 1.5))),
            "beam-root": (beam, beam.point(0.0)),
            "beam-tip": (beam, beam.point(None)),
            "beam-interior": (beam, beam.point(0.37)),          # inside an element
            "modal-root": (modal.body, modal.root),
            "modal-tip": (modal.body, modal.tip),
            "modal-interior": (modal.body, modal.mid),
        })
    return _POINTS


def random_states(body, rng, dtheta):
    """(q0, q1): reference coordinates of order 1, elastic ones of a few cm, θ1 = θ0 + dtheta."""
    nb = body.n_dofs
    q0 = rng.normal(size=nb)
    q1 = q0 + 0.5 * rng.normal(size=nb)
    if nb >= 3:
        q0[2] = rng.uniform(-4.0, 4.0)
        q1[2] = q0[2] + dtheta
        q0[3:] = 0.05 * rng.normal(size=nb - 3)
        q1[3:] = q0[3:] + 0.02 * rng.normal(size=nb - 3)
    return q0, q1


def kernel_errors(entry, nb, ref_position, ref_jacobian, ref_dgrad, ref_dgrad_jacobian, states, rng,
                  ref_hessian=None):
    """Largest relative deviations of the kernels on map ``entry`` from the numpy references, and of the
    exactness identity D (q1 − q0) = r(q1) − r(q0) (in units of ε times the scale of its terms)."""
    maps = compiled_scene.pack_maps([(entry, nb)])
    out = dict(position=0.0, jacobian=0.0, dgrad=0.0, dgrad_jacobian=0.0, hessian=0.0, exactness_eps=0.0)
    for q0, q1 in states:
        jac_scale = 0.0
        for q in (q0, q1):
            r = compiled_scene.map_position(maps, 0, q)
            jac = compiled_scene.map_jacobian(maps, 0, q)
            jac_scale = max(jac_scale, np.abs(jac).max())
            # the scale of r: its largest term (|m R| or |A s|), not |r| itself (which may cancel)
            out["position"] = max(out["position"], rel(r, ref_position(q), np.abs(jac).max() * max(1.0, np.abs(q).max())))
            out["jacobian"] = max(out["jacobian"], rel(jac, ref_jacobian(q)))
            if ref_hessian is not None:             # the tangent of a point load Jᵀ F
                f = rng.normal(size=2)
                hp = compiled_scene.map_hessian_product(maps, 0, q, f)
                ref = np.asarray(to_dense(ref_hessian(q, f)), dtype=float)
                out["hessian"] = max(out["hessian"], rel(hp, ref, np.abs(f).max() * np.abs(jac).max()))
        d = compiled_scene.map_dgrad(maps, 0, q0, q1)
        out["dgrad"] = max(out["dgrad"], rel(d, ref_dgrad(q0, q1)))
        for f in (rng.normal(size=2), np.array([0.0, -9.81])):
            h = compiled_scene.map_dgrad_jacobian(maps, 0, q0, q1, f)
            out["dgrad_jacobian"] = max(out["dgrad_jacobian"],
                                        rel(h, ref_dgrad_jacobian(q0, q1, f), np.abs(f).max() * jac_scale))
        # exactness: D (q1 − q0) = r(q1) − r(q0) to round-off of the terms involved
        r0, r1 = compiled_scene.map_position(maps, 0, q0), compiled_scene.map_position(maps, 0, q1)
        dq = q1 - q0
        terms = np.abs(d) @ np.abs(dq) + np.abs(r0) + np.abs(r1) + jac_scale * np.abs(np.concatenate([q0, q1])).max()
        out["exactness_eps"] = max(out["exactness_eps"], np.abs(d @ dq - (r1 - r0)).max() / (EPS * terms.max()))
    return out


def point_kernel_errors(name, seed=0):
    body, pt = points()[name]
    rng = np.random.default_rng(seed)
    states = [random_states(body, rng, dth) for dth in DTHETAS for _ in range(2)]
    return kernel_errors(pt.compiled_map(), body.n_dofs, pt.position, pt.position_jacobian,
                         pt.position_discrete_gradient, pt.position_discrete_gradient_jacobian, states, rng,
                         pt.position_hessian_product)


@pytest.mark.parametrize("name", ["point-mass", "rigid-centre", "rigid-arm", "rigid-far", "beam-root", "beam-tip",
                                  "beam-interior", "modal-root", "modal-tip", "modal-interior"])
def test_map_kernels_equal_the_numpy_points(name):
    err = point_kernel_errors(name)
    for k in ("position", "jacobian", "dgrad", "dgrad_jacobian", "hessian"):
        assert err[k] <= KERNEL_TOL, (name, k, err[k])
    assert err["exactness_eps"] <= 16, (name, err["exactness_eps"])


def gravity_kernel_errors(body, seed=1):
    """The first-moment map of ``body`` against its gravity potential and discrete gradient, for two fields.

    The loop adds −gᵀD to the discrete gradient of V and ∂(Dᵀ(−g))/∂q1 to its Jacobian; the body returns
    (−gᵀD, ∂(Dᵀ(−g))/∂q1) from ``gravity_discrete_gradient(q0, q1, g)``; V = −g · r, ∇V = −gᵀ ∂r/∂q."""
    kd = getattr(body, "compiled_kernel_data", lambda: None)()
    entry = ("frame", *body.mass_moment_map()) if kd is not None else ("linear", *body.mass_moment())
    nb = body.n_dofs
    maps = compiled_scene.pack_maps([(entry, nb)])
    rng = np.random.default_rng(seed)
    states = [random_states(body, rng, dth) for dth in DTHETAS]
    out = dict(potential=0.0, gradient=0.0, dgrad=0.0, dgrad_jacobian=0.0, exactness_eps=0.0)
    for g in (np.array([0.0, -9.81]), np.array([3.0, -7.5])):
        for q0, q1 in states:
            jac_scale = np.abs(compiled_scene.map_jacobian(maps, 0, q0)).max()
            for q in (q0, q1):
                v_ref, grad_ref, _ = body.gravity_potential(q, g)
                r = compiled_scene.map_position(maps, 0, q)
                out["potential"] = max(out["potential"], rel(-(g @ r), v_ref, np.abs(g).max() * jac_scale
                                                             * max(1.0, np.abs(q).max())))
                out["gradient"] = max(out["gradient"], rel(-(g @ compiled_scene.map_jacobian(maps, 0, q)), grad_ref))
            d = compiled_scene.map_dgrad(maps, 0, q0, q1)
            h = compiled_scene.map_dgrad_jacobian(maps, 0, q0, q1, -g)
            dg_ref, h_ref = body.gravity_discrete_gradient(q0, q1, g)
            out["dgrad"] = max(out["dgrad"], rel(-(g @ d), dg_ref))
            h_ref = np.zeros((nb, nb)) if h_ref is None else dense(h_ref)
            out["dgrad_jacobian"] = max(out["dgrad_jacobian"], rel(h, h_ref, np.abs(g).max() * jac_scale))
            v0, v1 = body.gravity_potential(q0, g)[0], body.gravity_potential(q1, g)[0]
            out["exactness_eps"] = max(out["exactness_eps"], abs(float(dg_ref @ (q1 - q0)) - (v1 - v0))
                                       / (EPS * max(abs(v0), abs(v1), np.abs(g).max() * jac_scale
                                                    * np.abs(np.concatenate([q0, q1])).max())))
    return out


@pytest.mark.parametrize("kind", ["point-mass", "rigid", "beam", "modal"])
def test_gravity_map_equals_the_bodies_gravity(kind):
    body = points()[{"point-mass": "point-mass", "rigid": "rigid-arm", "beam": "beam-tip", "modal": "modal-tip"}[kind]][0]
    err = gravity_kernel_errors(body)
    for k in ("potential", "gradient", "dgrad", "dgrad_jacobian"):
        assert err[k] <= KERNEL_TOL, (kind, k, err[k])
    assert err["exactness_eps"] <= 64, (kind, err["exactness_eps"])


def test_pack_maps_keeps_several_maps_apart():
    """Maps of different kinds and sizes packed together: map k is entry k."""
    pts = points()
    names = ["beam-interior", "point-mass", "rigid-far", "modal-tip", "rigid-centre"]
    maps = compiled_scene.pack_maps([(pts[n][1].compiled_map(), pts[n][0].n_dofs) for n in names])
    rng = np.random.default_rng(5)
    for k, n in enumerate(names):
        body, pt = pts[n]
        q0, q1 = random_states(body, rng, 1.3)
        assert rel(compiled_scene.map_position(maps, k, q1), pt.position(q1)) <= KERNEL_TOL
        assert rel(compiled_scene.map_dgrad(maps, k, q0, q1), pt.position_discrete_gradient(q0, q1)) <= KERNEL_TOL


# ==================================================================== 2. trajectories
def rigid_pendulum(angular_velocity=2.0):
    """A rigid bar pinned at one end to the ground, released from 30° below horizontal, under gravity."""
    bar = sf.RigidBody.bar(1.5, 0.8, start=(0.0, 0.0), angle=-np.pi / 6, name="bar")
    bar.v0[2] = angular_velocity
    pin = sf.Pin(bar.point((-0.4, 0.0)), (0.0, 0.0), name="pivot")
    tip = bar.point((0.4, 0.0))
    return sf.Scene([bar], constraints=[pin], forces=[sf.Gravity((0.0, -9.81))], name="rigid pendulum",
                    probes={"tip": lambda s, t, q, v: tip.position(q)})


def driven_rigid_mechanism():
    """A crank turned by a prescribed angle (θ = 3 t + t², pinned at one end) carrying a pendulum bar and,
    at the bar's end, a point mass on a third, pinned bar: prescribed coordinate, Pin, Revolute and gravity."""
    crank = sf.RigidBody.bar(0.5, 0.3, start=(0.0, 0.0), angle=0.0, name="crank")
    bar = sf.RigidBody.bar(1.0, 0.6, start=(0.3, 0.0), angle=-0.5 * np.pi, name="bar")
    law = sf.MotionLaw(lambda t: 3.0 * t + t * t, lambda t: 3.0 + 2.0 * t, lambda t: 2.0)
    cons = [sf.Pin(crank.point((-0.15, 0.0)), (0.0, 0.0), name="crank pin"),
            sf.Revolute(crank.point((0.15, 0.0)), bar.point((-0.3, 0.0)), name="hinge")]
    return sf.Scene([crank, bar], constraints=cons, forces=[sf.Gravity((0.0, -9.81))],
                    prescribed=[sf.Prescribed(crank, "theta", law)], name="driven mechanism",
                    probes={"bar_end": lambda s, t, q, v: bar.point((0.3, 0.0)).position(s.coordinates(bar, q))})


def run_both(scene_factory, t_end, dt, **kw):
    """(compiled run, Python run) of fresh scenes; the compiled one must have gone through the loop, every
    step of it (no step fell back to Python)."""
    scene = scene_factory()
    assert compiled_scene.eligible(scene, EnergyMomentum())
    real, statuses = compiled_scene.run_chunk, []

    def spy(*args, **kwargs):
        out = real(*args, **kwargs)
        statuses.append(out["status"])
        return out
    compiled_scene.run_chunk = spy
    try:
        a = sf.simulate(scene_factory(), t_end=t_end, dt=dt, compiled=True, **kw)
    finally:
        compiled_scene.run_chunk = real
    assert statuses and all(s == compiled_scene.OK for s in statuses)
    return a, sf.simulate(scene_factory(), t_end=t_end, dt=dt, compiled=False, **kw)


def run_deviations(a, b):
    """Largest deviations of the compiled run a from the Python run b, each relative to its scale."""
    q_scale = np.abs(b.q).max()
    v_scale = np.abs(b.v).max()
    e_scale = np.abs(b.kinetic).max() + np.abs(b.potential).max() + np.abs(b.external_work).max()
    p_scale = np.abs(b.linear_momentum).max() + 1e-300
    L_scale = np.abs(b.angular_momentum).max() + p_scale * np.abs(b.q).max()
    lam_scale = np.abs(b.lam).max() if b.lam.size else 1.0
    out = dict(q=rel(a.q, b.q), v=rel(a.v, b.v))
    out["lam"] = np.abs(a.lam - b.lam).max() / lam_scale if b.lam.size else 0.0
    for k in ("kinetic", "potential", "total_energy", "external_work"):
        out[k] = np.abs(getattr(a, k) - getattr(b, k)).max() / e_scale
    out["linear_momentum"] = np.abs(a.linear_momentum - b.linear_momentum).max() / p_scale
    out["angular_momentum"] = np.abs(a.angular_momentum - b.angular_momentum).max() / L_scale
    # the residuals are round-off on both paths: compared on the scale of Φ (q) and of Φ_q v (v)
    out["constraint_residual"] = np.abs(a.constraint_residual - b.constraint_residual).max() / q_scale
    out["velocity_constraint_residual"] = (np.abs(a.velocity_constraint_residual - b.velocity_constraint_residual).max()
                                           / v_scale)
    out["prescribed_force"] = (np.abs(a.prescribed_force - b.prescribed_force).max()
                               / np.abs(b.prescribed_force).max() if b.prescribed_force.size else 0.0)
    out["reactions"] = max([rel(a.reactions[k], b.reactions[k]) for k in b.reactions] or [0.0])
    out["probes"] = max([rel(a.probes[k], b.probes[k]) for k in b.probes] or [0.0])
    out["energy_balance"] = np.abs(a.total_energy - a.total_energy[0] - a.external_work).max() / e_scale
    out["energy_balance_python"] = np.abs(b.total_energy - b.total_energy[0] - b.external_work).max() / e_scale
    return out


#: allowed deviations (relative; see run_deviations)
RUN_TOL = dict(q=1e-10, v=1e-10, lam=1e-9, kinetic=1e-9, potential=1e-9, total_energy=1e-9, external_work=1e-9,
               linear_momentum=1e-9, angular_momentum=1e-9, constraint_residual=1e-9,
               velocity_constraint_residual=1e-9, prescribed_force=1e-9, reactions=1e-9, probes=1e-9,
               energy_balance=1e-10)


def assert_same_run(a, b, tol=None):
    np.testing.assert_array_equal(a.t, b.t)
    assert a.steps == b.steps and a.halvings == b.halvings
    assert a.completed and b.completed
    assert set(a.reactions) == set(b.reactions) and set(a.probes) == set(b.probes)
    dev = run_deviations(a, b)
    for k, limit in dict(RUN_TOL, **(tol or {})).items():
        assert dev[k] <= limit, (k, dev[k])
    # a step decided at the round-off floor may take one Newton iteration more or less on either path
    total_a, total_b = a.newton_iterations.sum(), b.newton_iterations.sum()
    assert abs(total_a - total_b) <= 0.05 * total_b + 0.3 * a.t.size
    return dev


@pytest.mark.parametrize("name, dt, t_end", [("pendulum", None, 0.3), ("flexible_pendulum", 2e-3, 0.3),
                                             ("double_pendulum", 2e-3, 0.3), ("spin_up_pinned", None, 0.3),
                                             ("slider_crank", 5e-4, 0.05), ("free_beam", None, 0.3),
                                             ("very_flexible_pendulum", None, 0.05), ("flying_beam", None, 1.0)])
def test_catalogue_mechanisms_compiled_equal_python(name, dt, t_end):
    """Joints, drivers (motion laws through the time table), ground sliders, loads in time, exact beams
    (Cayley rates)."""
    factory = sf.scenes.get(name)
    scene = factory()
    assert compiled_scene.eligible(scene, EnergyMomentum())
    a, b = run_both(factory, t_end=t_end, dt=factory.defaults["dt"] if dt is None else dt)
    # the free beam's stiff steps end at the round-off floor of its internal forces after about five
    # Newton iterations on both paths: their velocities (2Δq/Δt − v0) agree to 7e-10, not 1e-10
    assert_same_run(a, b, tol=dict(v=3e-9) if name == "free_beam" else None)
    if scene.n_constraints:
        assert a.lam.shape == (a.t.size, scene.n_constraints) and np.abs(a.lam).max() > 0
    if name in ("free_beam", "flying_beam"):
        assert np.abs(a.external_work).max() > 0          # the load in time did work


def test_cayley_terms_are_the_rotations_formulas():
    """The compiled step's Cayley rate terms against the numpy functions of skfem_flex.numerics.rotations."""
    from skfem_flex.numerics import rotations
    for x in np.concatenate([np.linspace(-2.8, 2.8, 57), [0.0, 1e-9, -3e-5, 0.0099, 0.0101, -0.0101]]):
        z, ratio, dratio, dz = compiled_scene.cayley_terms(x)
        assert z == pytest.approx(float(rotations.cayley(x)), rel=1e-15, abs=1e-300)
        assert ratio == pytest.approx(float(rotations.cayley_ratio(np.array([x]))[0]), rel=1e-15)
        assert dratio == pytest.approx(float(rotations.cayley_ratio_derivative(x)), rel=1e-14, abs=1e-300)
        assert dz == pytest.approx(float(rotations.cayley_derivative(x)), rel=1e-15)


def test_spring_mass_compiled_equals_python():
    """A coordinate spring V = ½ k u⁴ (a potential of one coordinate, not a body's)."""
    a, b = run_both(sf.scenes.get("spring_mass"), t_end=2.0, dt=0.05)
    assert_same_run(a, b)
    assert np.abs(a.potential).max() > 0.1


def weld_prismatic_moment():
    """A bar welded to a bar that slides without turning along a ground line (Prismatic) under gravity and a
    moment M(t) = sin 3t on the first: a weld, a locked angle and a generalized load in time."""
    a = sf.RigidBody.bar(1.0, 0.5, start=(0.0, 0.0), angle=0.3, name="slider bar")
    b = sf.RigidBody.bar(0.7, 0.4, start=(0.5 * np.cos(0.3), 0.5 * np.sin(0.3)), angle=0.3 + 0.5 * np.pi,
                         name="welded bar")
    cons = [sf.Prismatic(a.point((0.0, 0.0)), direction=(1.0, 0.2), name="guide"),
            sf.Weld(a.point((0.25, 0.0)), b.point((-0.2, 0.0)), name="weld")]
    a.v0[:] = (0.5, 0.1, 0.0)
    b.v0[:] = (0.5, 0.1, 0.0)
    moment = sf.PointMoment(a.point((0.0, 0.0)), lambda t: np.sin(3.0 * t))
    return sf.Scene([a, b], constraints=cons, forces=[sf.Gravity((0.0, -9.81)), moment], name="weld and prismatic")


def test_weld_prismatic_and_moment_compiled_equal_python():
    a, b = run_both(weld_prismatic_moment, t_end=0.5, dt=1e-2)
    assert_same_run(a, b)
    assert np.abs(a.lam).max() > 0 and np.abs(a.external_work).max() > 0


def test_rigid_pendulum_compiled_equals_python():
    a, b = run_both(rigid_pendulum, t_end=0.5, dt=1e-2)
    assert_same_run(a, b)
    # a fixed pin does no work (−λ̄·ΔΦ is round-off) and the energy is conserved
    e_scale = np.abs(a.kinetic).max() + np.abs(a.potential).max()
    assert np.abs(a.external_work).max() <= 1e-12 * e_scale
    assert np.abs(a.total_energy - a.total_energy[0]).max() <= 1e-10 * e_scale


def test_prescribed_coordinate_with_joints_compiled_equals_python():
    """No catalogue scene has a prescribed coordinate together with joints: a driven rigid mechanism."""
    a, b = run_both(driven_rigid_mechanism, t_end=0.4, dt=1e-2)
    dev = assert_same_run(a, b)
    assert np.abs(a.prescribed_force).max() > 0 and np.abs(a.external_work).max() > 0
    assert dev["prescribed_force"] <= 1e-9


# ==================================================================== 3. eligibility
def _bar():
    return sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=0.0, name="bar")


def _ineligible_scenes():
    """Scenes with one part that has no compiled form (and the same scene with a counterpart that is
    eligible)."""
    m2 = sf.PointMass(1.0, [1.0, 0.0])
    user = sf.UserConstraint([m2], lambda q, t: np.array([0.5 * (q @ q - 1.0)]), lambda q, t: q[None, :])
    m3 = sf.PointMass(1.0, [1.0, 0.0])
    return {"user constraint": (sf.Scene([m2], constraints=[user], forces=[sf.Gravity()]),
                                sf.Scene([m3], constraints=[sf.Distance(m3, (0.0, 0.0))],
                                         forces=[sf.Gravity()]))}


def test_parts_without_compiled_form_are_not_eligible():
    em = EnergyMomentum()
    for name, (scene, counterpart) in _ineligible_scenes().items():
        assert not compiled_scene.eligible(scene, em), name
        assert compiled_scene.pack(scene) is None, name
        if counterpart is not None:
            assert compiled_scene.eligible(counterpart, em), name

    class Custom(EnergyMomentum):
        pass
    assert not compiled_scene.eligible(sf.scenes.get("pendulum")(), Custom())


def _boom(*args, **kwargs):
    raise AssertionError("compiled_scene.run_chunk was called")


def test_compiled_false_and_ineligible_scenes_never_call_the_loop(monkeypatch):
    monkeypatch.setattr(compiled_scene, "run_chunk", _boom)
    # the spy works: an eligible scene with compiled=True reaches it
    with pytest.raises(AssertionError, match="run_chunk was called"):
        sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2, compiled=True)
    res = sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2, compiled=False)
    assert res.completed and res.steps == 5
    class MyTrapezoidal(Trapezoidal):       # a scheme subclass may change the step: Python path
        pass
    sf.simulate(rigid_pendulum(), t_end=0.05, dt=1e-2, integrator=MyTrapezoidal())
    for name, (scene, _) in _ineligible_scenes().items():
        sf.simulate(scene, t_end=0.02, dt=1e-2)
    monkeypatch.setenv("SKFEM_FLEX_COMPILED", "0")
    sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2)


# ==================================================================== 4. fallback
def _spy_run_chunk(monkeypatch):
    """Wrap run_chunk; the list of statuses it returned."""
    statuses = []
    real = compiled_scene.run_chunk

    def spy(*args, **kwargs):
        out = real(*args, **kwargs)
        statuses.append(out["status"])
        return out
    monkeypatch.setattr(compiled_scene, "run_chunk", spy)
    return statuses


@pytest.mark.parametrize("omega, dt, t_end, newton, scheme", [
    (12.0, 0.3, 1.5, None, "energy-momentum"),                                   # steps too large
    (2.0, 1e-2, 0.4, NewtonSettings(max_iterations=2), "energy-momentum"),      # too few iterations
    (12.0, 0.3, 1.5, None, "trapezoidal")])                                      # the Newmark step's hand-over
def test_failing_steps_are_halved_as_on_the_python_path(monkeypatch, omega, dt, t_end, newton, scheme):
    """Steps the compiled loop cannot finish (too large, or too few Newton iterations allowed) leave it and are
    halved by the Python path: the same halvings and the same trajectory as the pure-Python run (for the
    Newmark step the state handed over includes its accelerations)."""
    statuses = _spy_run_chunk(monkeypatch)
    a = sf.simulate(rigid_pendulum(omega), t_end=t_end, dt=dt, max_halvings=8, newton=newton, compiled=True,
                    integrator=scheme)
    assert statuses and any(s != compiled_scene.OK for s in statuses)
    b = sf.simulate(rigid_pendulum(omega), t_end=t_end, dt=dt, max_halvings=8, newton=newton, compiled=False,
                    integrator=scheme)
    assert a.halvings == b.halvings > 0
    dev = assert_same_run(a, b, tol=None if scheme == "energy-momentum" else dict(energy_balance=np.inf))
    assert abs(dev["energy_balance"] - dev["energy_balance_python"]) <= 1e-9


@pytest.mark.parametrize("newton, dt, max_halvings", [(NewtonSettings(max_iterations=1), 1e-2, 2),
                                                      (None, 0.3, 0)])
def test_convergence_error_is_the_python_paths(monkeypatch, newton, dt, max_halvings):
    """A step that fails on the Python path too raises the same ConvergenceError with the same partial result."""
    statuses = _spy_run_chunk(monkeypatch)
    errors = []
    for c in (True, False):
        with pytest.raises(ConvergenceError) as info:
            sf.simulate(rigid_pendulum(12.0), t_end=2.0, dt=dt, newton=newton, max_halvings=max_halvings,
                        compiled=c)
        errors.append(info.value)
    assert statuses and statuses[-1] != compiled_scene.OK
    assert type(errors[0]) is type(errors[1])
    assert str(errors[0]) == str(errors[1])
    ra, rb = errors[0].result, errors[1].result
    assert ra.steps == rb.steps and ra.halvings == rb.halvings
    np.testing.assert_array_equal(ra.t, rb.t)
    np.testing.assert_allclose(ra.q, rb.q, rtol=0, atol=1e-10 * np.abs(rb.q).max())


def test_subclasses_that_redefine_the_equations_run_in_python():
    """A compiled form stands for its class's equations: a user subclass that redefines them is not packed."""
    class MovingPin(sf.Pin):
        def value(self, q, t):
            return super().value(q, t) - np.array([0.01 * t, 0.0])

    class FastDriver(sf.Driver):
        def time_derivative(self, q, t):
            return 2.0 * super().time_derivative(q, t)

    class StiffGravity(sf.Gravity):
        def potential_energy(self, q):
            return 2.0 * super().potential_energy(q)
    em = EnergyMomentum()
    bar = _bar()
    assert compiled_scene.eligible(sf.Scene([bar], constraints=[sf.Pin(bar.point((-0.5, 0.0)))],
                                            forces=[sf.Gravity()]), em)
    assert not compiled_scene.eligible(sf.Scene([bar], constraints=[MovingPin(bar.point((-0.5, 0.0)))]), em)
    assert not compiled_scene.eligible(sf.Scene([bar], forces=[StiffGravity()]), em)
    law = sf.MotionLaw(lambda t: t, lambda t: 1.0, lambda t: 0.0)
    assert not compiled_scene.eligible(sf.Scene([bar], constraints=[FastDriver(bar, law, coordinate="theta")]), em)
    assert compiled_scene.eligible(sf.Scene([bar], constraints=[sf.Driver(bar, law, coordinate="theta")]), em)

    class SoftSpring(sf.LinearSpring):
        def potential_energy(self, q):
            return 0.5 * super().potential_energy(q)

    class ViscousHinge(sf.RotationalDamper):
        def generalized_force(self, q, v, t):
            f, fq, fv = super().generalized_force(q, v, t)
            return 2.0 * f, fq, 2.0 * fv
    for spring, damper in ((sf.LinearSpring, sf.RotationalDamper), (SoftSpring, sf.RotationalDamper),
                           (sf.LinearSpring, ViscousHinge)):
        scene = sf.Scene([bar], forces=[spring(bar.point((0.5, 0.0)), (1.0, 1.0), 10.0),
                                        damper(bar.point(), damping=0.1)])
        assert compiled_scene.eligible(scene, em) == (spring is sf.LinearSpring and damper is sf.RotationalDamper)


def test_block_energy_guard_stops_where_the_record_by_record_guard_does():
    """first_energy_violation on a block equals check_energy applied record by record (scale window
    included), for a blow-up at every position, a NaN energy and a run that never diverges."""
    from skfem_flex.errors import DivergenceError
    from skfem_flex.run.simulate import _DivergenceGuard, _SCALE_RECORDS

    class Scene_:
        length_scale = 1.0
    rng = np.random.default_rng(5)
    n = 3 * _SCALE_RECORDS
    for stop in list(range(n)) + [None, "nan"]:
        kin = 1.0 + rng.random(n)
        pot = -0.5 * rng.random(n)
        work = np.cumsum(0.01 * rng.random(n))
        if stop == "nan":
            kin[n // 2] = np.nan
        elif stop is not None:
            kin[stop] = 1e9
        expected = None                       # record by record
        guard = _DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])
        for i in range(1, n):
            try:
                guard.check_energy(float(i), kin[i], pot[i], work[i])
            except DivergenceError:
                expected = i
                break
        guard = _DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])    # records 1 … n − 1 as a block
        got = guard.first_energy_violation(np.arange(1.0, n), kin[1:], pot[1:], work[1:])
        assert (None if got is None else got + 1) == expected, stop
        # as two blocks, the second starting inside the scale window: the guard counts the records it saw
        cut = _SCALE_RECORDS // 2
        guard = _DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])
        got = guard.first_energy_violation(np.arange(1.0, cut), kin[1:cut], pot[1:cut], work[1:cut])
        if got is not None:
            got += 1
        else:
            got = guard.first_energy_violation(np.arange(cut, n), kin[cut:], pot[cut:], work[cut:])
            got = None if got is None else got + cut
        assert got == expected, stop


# ==================================================================== 6. the Newmark family
NEWMARK_CASES = [("pendulum", None, 0.3), ("spring_mass", None, 2.0), ("flexible_pendulum", 2e-3, 0.2),
                 ("double_pendulum", 2e-3, 0.2), ("spin_up_pinned", None, 0.3), ("slider_crank", 5e-4, 0.03),
                 ("free_beam", None, 0.3), ("very_flexible_pendulum", None, 0.03), ("flying_beam", None, 0.5),
                 ("spin_up_beam", None, 0.4)]


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("name, dt, t_end", NEWMARK_CASES)
def test_catalogue_newmark_compiled_equal_python(name, dt, t_end, scheme):
    """The compiled Newmark step (velocity-level constraints for the trapezoidal rule, position level for
    generalized-α; floating-frame kernels, exact beams, drivers, sliders, loads at the step's end) gives
    the Python step's run: states, multipliers, energies, work (loads and prescribed laws trapezoidal in
    time), reactions and probes, and the same energy balance error."""
    factory = sf.scenes.get(name)
    assert compiled_scene.eligible(factory(), make_integrator(scheme))
    a, b = run_both(factory, t_end=t_end, dt=factory.defaults["dt"] if dt is None else dt, integrator=scheme)
    dev = assert_same_run(a, b, tol=dict(energy_balance=np.inf, v=3e-9 if name == "free_beam" else 1e-10))
    assert abs(dev["energy_balance"] - dev["energy_balance_python"]) <= 1e-9


def test_velocity_jacobian_of_frame_maps_is_the_derivative_of_j_v():
    """∂(J(q) v)/∂q of the floating-frame and rigid-body point maps against central differences of
    J(q) v (map_jacobian)."""
    scene = sf.scenes.get("slider_crank")()
    maps = compiled_scene._packed(scene)[0][3]
    rng = np.random.default_rng(3)
    checked = 0
    for k in range(maps[0].size):
        if maps[0][k] != compiled_scene.FRAME:
            continue
        nb = maps[2][k]
        q = rng.normal(size=nb) * np.r_[1.0, 1.0, 2.0, 1e-2 * np.ones(nb - 3)]
        v = rng.normal(size=nb)
        out = np.zeros((2, nb))
        compiled_scene._velocity_jacobian_into(maps, k, q, v, out)
        fd = np.zeros((2, nb))
        for j in range(nb):
            e = np.zeros(nb)
            e[j] = 1e-6
            fd[:, j] = (compiled_scene.map_jacobian(maps, k, q + e) @ v
                        - compiled_scene.map_jacobian(maps, k, q - e) @ v) / 2e-6
        np.testing.assert_allclose(out, fd, rtol=0, atol=1e-8 * np.abs(fd).max())
        checked += 1
    assert checked >= 3


# ==================================================================== 7. springs, dampers and follower forces
def torsion_mechanism():
    """Two bars hinged together, the first pinned to the ground: torsion springs to the ground and between
    the bars, torsion dampers on the pivot and the hinge, gravity."""
    a = sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.3, name="upper")
    b = sf.RigidBody.bar(0.6, 0.8, start=(np.cos(-0.3), np.sin(-0.3)), angle=-1.2, name="lower")
    cons = [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0)), sf.Revolute(a.point((0.5, 0.0)), b.point((-0.4, 0.0)))]
    forces = [sf.Gravity(), sf.RotationalSpring(a.point(), None, stiffness=20.0, rest_angle=0.2),
              sf.RotationalSpring(b.point(), a.point(), stiffness=5.0),
              sf.RotationalDamper(b.point(), a.point(), damping=0.3), sf.RotationalDamper(a.point(), damping=0.1)]
    return sf.Scene([a, b], constraints=cons, forces=forces, name="torsion mechanism")


def spring_mechanism():
    """A pinned bar, a free bar and a point mass joined by two-point springs (rest length l₀ > 0, l₀ = 0, and
    to a ground point) and dampers (between the bars and to the ground), under gravity."""
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


def follower_mechanism():
    """A pinned flexible beam loaded at its tip by a follower force in time, held by a spring to the ground
    and a damper to a pinned bar that carries a constant follower force; gravity."""
    beam = link("beam", 1.0, sf.Section(**SEC), 4, name="beam").body
    bar = sf.RigidBody.bar(0.5, 0.6, start=(0.0, -0.5), angle=0.0, name="bar")
    cons = [sf.Pin(beam.point(0.0), (0.0, 0.0)), sf.Pin(bar.point((-0.3, 0.0)), (0.0, -0.5))]
    forces = [sf.Gravity(), sf.PointForce(beam.point(), lambda t: (-2.0, 5.0 * np.sin(3.0 * t)), follower=True),
              sf.PointForce(bar.point((0.3, 0.0)), (0.0, 3.0), follower=True),
              sf.LinearSpring(beam.point(0.6), (0.6, 0.5), 50.0, rest_length=0.4),
              sf.LinearDamper(beam.point(), bar.point((0.3, 0.0)), 0.5)]
    return sf.Scene([beam, bar], constraints=cons, forces=forces, name="follower mechanism")


def sliding_mechanism():
    """A bar pinned at its centre, turning, with a point mass sliding along it on a spring to the pivot, and a
    block riding a prismatic joint along a section of a pinned flexible beam: lines that turn (and, on the
    beam, move with its deformation)."""
    guide = sf.RigidBody.bar(1.0, 2.0, start=(-1.0, 0.0), angle=0.0, name="guide")
    guide.v0[2] = 2.0
    m = sf.PointMass(0.4, [0.5, 0.0])
    m.v0[:] = (0.3, 1.0)                         # on the line and turning with it: ṙ = ω E r + u̇ d
    beam = link("beam", 1.0, sf.Section(**SEC), 4, name="beam").body
    for b in (beam,):
        b.q0[:2] = (0.0, -1.0)
    block = sf.RigidBody.bar(0.3, 0.2, start=(0.4, -1.0), angle=0.0, name="block")
    cons = [sf.Pin(guide.point(), (0.0, 0.0)), sf.Slider(m.point(), (1.0, 0.0), on=guide.point()),
            sf.Pin(beam.point(0.0), (0.0, -1.0)), sf.Prismatic(block.point(), (1.0, 0.0), on=beam.point(0.5))]
    forces = [sf.Gravity(), sf.LinearSpring(m.point(), guide.point(), 30.0, rest_length=0.3)]
    return sf.Scene([guide, m, beam, block], constraints=cons, forces=forces, name="sliding mechanism")


ELEMENT_SCENES = [(torsion_mechanism, 1e-2, 0.5), (spring_mechanism, 1e-2, 0.5), (follower_mechanism, 2e-3, 0.1),
                  (sliding_mechanism, 2e-3, 0.2)]


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("factory, dt, t_end", ELEMENT_SCENES)
def test_springs_dampers_and_followers_compiled_equal_python(factory, dt, t_end, scheme):
    """Torsion springs and dampers, two-point springs (l₀ > 0, l₀ = 0, to the ground) and dampers, follower
    point forces on a rigid body and a beam's section, sliders and prismatic joints on moving bodies: the
    compiled step gives the Python step's run under
    every scheme, and the energy-momentum run keeps the energy balance (the dampers' work included)."""
    assert compiled_scene.eligible(factory(), make_integrator(scheme))
    a, b = run_both(factory, t_end=t_end, dt=dt, integrator=scheme)
    newmark = scheme != "energy-momentum"
    tol = dict(energy_balance=np.inf) if newmark else {}
    if factory is sliding_mechanism:
        # q agree to 5e-14; the prismatic joint's moment on the stiff beam (EA = 1e6) is 2e-9 of its own
        # scale apart under generalized-α (position-level rows: the multipliers carry the beam's stiffness)
        tol["reactions"] = 5e-9
    dev = assert_same_run(a, b, tol=tol)
    if newmark:
        assert abs(dev["energy_balance"] - dev["energy_balance_python"]) <= 1e-9
    if factory is sliding_mechanism:                   # the lines turned and carried their sliders
        assert np.ptp(a.q[:, 2]) > 0.2 and np.abs(a.lam).max() > 0
    else:
        assert np.abs(a.external_work).max() > 1e-3      # dampers and forces did work


@pytest.mark.parametrize("factory", [torsion_mechanism, spring_mechanism, follower_mechanism, sliding_mechanism])
def test_energy_momentum_newton_matrix_is_the_residuals_derivative(factory):
    """The compiled energy-momentum Newton matrix (every element's tangent: torsion and two-point springs'
    discrete gradients, dampers and follower forces at the mid-point, joints) against central differences
    of the residual, at a state with large velocities and a large step."""
    scene = factory()
    rng = np.random.default_rng(3)
    q0 = scene.initial_state()[0]
    v0 = rng.normal(size=q0.size)
    system, x0 = compiled_scene.newton_system(scene, q0, v0, 0.05, t=0.3,
                                              lam=rng.normal(size=scene.n_constraints))
    x = x0 + 0.01 * rng.normal(size=x0.size)
    compiled_scene._evaluate(system, x)
    mat = compiled_scene.newton_matrix(system)
    fd = np.empty_like(mat)
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = 1e-6
        compiled_scene._evaluate(system, x + e)
        rp = system[2][0].copy()
        compiled_scene._evaluate(system, x - e)
        fd[:, j] = (rp - system[2][0]) / 2e-6
    assert np.abs(mat - fd).max() <= 1e-6 * np.abs(fd).max()


def test_line_on_a_moving_body_row_and_its_derivatives():
    """The compiled row of a slider and a prismatic joint on moving bodies (a rigid bar, a flexible beam's
    section): its discrete gradient D (q1 − q0) = Φ(q1) − Φ(q0) exactly, and Φ_q, ∂(Φ_q v)/∂q, the Hessian
    μ ∂²Φ/∂q² and ∂(μ D)/∂q1 against central differences, at states with large turns."""
    scene = sliding_mechanism()
    packed = compiled_scene._packed(scene)[0]
    maps, cons = packed[3], packed[5]
    n, m = scene.n, scene.n_constraints
    rotated = np.flatnonzero(cons[0] == compiled_scene.ROTATED)
    assert rotated.size == 2                        # the slider's row and the prismatic joint's first row
    ws = compiled_scene._workspace(n, m, n, n * n + 1, int(maps[2].max()))
    index = compiled_scene._matrix_index(np.arange(n), n)           # dense storage, no prescribed coordinates
    rng = np.random.default_rng(5)
    q_ref = scene.initial_state()[0]

    def row(i, q0, q1, v, mu=0.0, scale=1.0):
        cq, d, cv, mat = np.zeros((m, n)), np.zeros((m, n)), np.zeros((m, n)), np.zeros(n * n + 1)
        phi = compiled_scene._rotated_row(maps, cons, i, q0, q1, v, mu, scale, cq, d, cv, mat, index, ws)
        r = cons[1][i]
        return phi, cq[r], d[r], cv[r], mat[:n * n].reshape(n, n)

    def fd(fun, q, eps=1e-6):
        return np.column_stack([(fun(q + eps * e) - fun(q - eps * e)) / (2 * eps) for e in np.eye(n)])

    for i in rotated:
        for _ in range(3):
            q0 = q_ref + 0.05 * rng.normal(size=n)
            q1 = q0 + 0.05 * rng.normal(size=n)
            for j in (2, 5, 8):                     # large turns of the bodies' frames
                q1[j] += rng.uniform(-1.5, 1.5)
            v = rng.normal(size=n)
            phi0, cq0, _, _, _ = row(i, q0, q0, v)
            phi1, cq1, d, cv, _ = row(i, q0, q1, v)
            scale = abs(phi0) + abs(phi1) + np.abs(cq1).max() * np.abs(q1 - q0).max()
            assert abs(d @ (q1 - q0) - (phi1 - phi0)) <= 1e-13 * scale
            assert np.abs(cq1 - fd(lambda q: np.array([row(i, q, q, v)[0]]), q1)[0]).max() <= 1e-8
            assert np.abs(cv - fd(lambda q: np.array([row(i, q, q, v)[1] @ v]), q1)[0]).max() <= 1e-7
            hess = row(i, q1, q1, v, mu=1.0, scale=2.0)[4]
            assert np.abs(hess - fd(lambda q: row(i, q, q, v)[1], q1)).max() <= 1e-7
            djac = row(i, q0, q1, v, mu=1.0)[4]
            assert np.abs(djac - fd(lambda q: row(i, q0, q, v)[2], q1)).max() <= 1e-7


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
@pytest.mark.parametrize("params, storage", [(dict(n_elements=64), compiled_scene.CSR),
                                             (dict(body="plane-stress", n_elements=8), compiled_scene.DENSE),
                                             (dict(n_elements=220), compiled_scene.CSR)])
def test_large_scenes_compiled_equal_python(params, storage, scheme):
    """Scenes with more coordinates than the Python path keeps dense (DENSE_LIMIT: sparse matrices there)
    run compiled and give the Python step's run: a 64-element flexible pendulum (195 coordinates) and a
    220-element one (663, more than any dense storage takes: COMPILED_SIZE_LIMIT), their Newton matrices
    stored as the values of their patterns, and one made of an unreduced plane-stress strip, whose dense
    173 × 173 tangent has no band plan and is stored dense. No step leaves the loop (``run_both``): a
    pattern that missed an entry would send it to Python."""
    factory = sf.scenes.get("flexible_pendulum")
    scene = factory(**params)
    assert sf.scene.DENSE_LIMIT < scene.n and not scene.dense
    assert compiled_scene.eligible(scene, make_integrator(scheme))
    assert compiled_scene._planned(scene)[9][4][-1] == storage
    a, b = run_both(lambda: factory(**params), t_end=0.01, dt=1e-3, integrator=scheme)
    # short stiff elements: the steps end at the round-off floor of the internal forces, and the
    # velocities 2Δq/Δt − v0 of the two paths agree to 3e-10 (as the free beam's, see above)
    tol = dict(v=3e-9, energy_balance=np.inf if scheme != "energy-momentum" else 1e-10)
    if "body" in params:
        # the stiff strip's steps end at that floor after 4 or 5 iterations, not always the same number
        # on both paths (41 against 42 in all): positions agree to the Newton tolerance, 1.1e-10
        tol.update(q=3e-10, probes=3e-10)
    assert_same_run(a, b, tol=tol)


def rigid_chain(n_links, length=0.1):
    """A chain of n_links rigid bars hanging from a pin, joined by revolute joints, under gravity: 3 n_links
    coordinates and 2 n_links multipliers."""
    bars, cons = [], []
    for i in range(n_links):
        bar = sf.RigidBody.bar(length, 0.1, start=(i * length, 0.0), angle=0.0, name=f"bar {i}")
        if i == 0:
            cons.append(sf.Pin(bar.point((-0.5 * length, 0.0)), (0.0, 0.0), name="pin"))
        else:
            cons.append(sf.Revolute(bars[-1].point((0.5 * length, 0.0)), bar.point((-0.5 * length, 0.0)),
                                    name=f"hinge {i}"))
        bars.append(bar)
    return sf.Scene(bars, constraints=cons, forces=[sf.Gravity((0.0, -9.81))], name="chain",
                    probes={"tip": PointProbe(bars[-1].point((0.5 * length, 0.0)))})


@pytest.mark.parametrize("scheme", ["energy-momentum"])
def test_a_long_chain_runs_compiled_in_a_reordered_band(scheme):
    """A chain of 70 bars (210 coordinates, 140 multipliers): in its natural order every multiplier would be a
    border coordinate (no diagonal entry), more than MAX_BORDER; reordered (reverse Cuthill–McKee) its Newton
    matrix is a band of half-width 5 without border, stored as CSR, and the run is the Python step's. (The
    Newmark step on CSR storage: the large pendulums above; a second scheme here would cost CI a compile.)"""
    scene = rigid_chain(70)
    assert compiled_scene.eligible(scene, make_integrator(scheme))
    interior, border, lo, up, index = compiled_scene._planned(scene)[9][:5]
    assert index[-1] == compiled_scene.CSR and border.size == 0 and lo + up <= 12
    a, b = run_both(lambda: rigid_chain(70), t_end=0.01, dt=1e-3, integrator=scheme)
    # the energy-momentum steps end once the force residual is at the Newton tolerance; a chain's multipliers
    # follow from that residual through D, which is badly conditioned for a long chain, so the two paths'
    # last iterates give λ and the pin's reaction to 3e-8 and 6e-8 (7e-9 and 1.4e-8 at 20 bars, where both
    # store the matrix dense): positions and velocities agree to 3e-11
    tol = dict(lam=1e-7, reactions=2e-7) if scheme == "energy-momentum" else dict(energy_balance=np.inf)
    assert_same_run(a, b, tol=tol)


PATTERN_SCENES = [lambda: sf.scenes.get(name)() for name in
                  ("pendulum", "flexible_pendulum", "double_pendulum", "spin_up_pinned", "slider_crank",
                   "free_beam", "very_flexible_pendulum", "flying_beam")]
PATTERN_SCENES += [driven_rigid_mechanism]


@pytest.mark.parametrize("make", PATTERN_SCENES + ["torsion", "spring", "follower", "sliding"])
def test_newton_pattern_holds_every_entry(make):
    """Every entry the energy-momentum step writes into its Newton matrix, at random states, steps and
    multipliers, lies in the scene's Newton pattern (what CSR storage keeps; dense storage here, so
    that an entry outside it would be seen)."""
    if isinstance(make, str):
        make = globals()[f"{make}_mechanism"]
    scene = make()
    rng = np.random.default_rng(11)
    q0 = scene.initial_state()[0]
    pattern = compiled_scene._newton_pattern(scene, compiled_scene._planned(scene)).toarray().astype(bool)
    for _ in range(3):
        v0 = rng.normal(size=q0.size)
        system, x0 = compiled_scene.newton_system(scene, q0, v0, 0.05, t=0.3,
                                                  lam=rng.normal(size=scene.n_constraints))
        compiled_scene._evaluate(system, x0 + 0.01 * rng.normal(size=x0.size))
        mat = compiled_scene.newton_matrix(system)
        outside = (mat != 0.0) & ~pattern
        assert not outside.any(), np.argwhere(outside)[:5]


def test_csr_storage_counts_an_entry_outside_its_pattern(monkeypatch):
    """With CSR storage a value written outside the pattern is counted, not lost silently: the step then goes
    to Python. Here the pattern of a 64-element pendulum is made to lack the pin's first row's entry on the
    beam's R_x (and its transpose); the evaluation counts them and flags the step."""
    scene = sf.scenes.get("flexible_pendulum")(n_elements=64)
    real = compiled_scene._newton_pattern
    nf = scene.free_index.size

    def lacking(scene_, packed):
        pat = real(scene_, packed).tolil()
        pat[nf, 0] = pat[0, nf] = 0
        pat = pat.tocsr()
        pat.eliminate_zeros()
        return pat
    monkeypatch.setattr(compiled_scene, "_newton_pattern", lacking)
    q0, v0 = scene.initial_state()
    system, x0 = compiled_scene.newton_system(scene, q0, v0 + 0.3, 1e-3)
    assert compiled_scene._planned(scene)[9][4][-1] == compiled_scene.CSR
    compiled_scene._evaluate(system, x0)
    assert compiled_scene.missed_entries(system) > 0 and system[2][8][0] == 1
    fresh = sf.scenes.get("flexible_pendulum")(n_elements=64)
    monkeypatch.setattr(compiled_scene, "_newton_pattern", real)
    system, x0 = compiled_scene.newton_system(fresh, q0, v0 + 0.3, 1e-3)
    compiled_scene._evaluate(system, x0)
    assert compiled_scene.missed_entries(system) == 0 and system[2][8][0] == 0


def test_a_damper_whose_points_coincide_sends_the_step_to_python():
    """The direction of a two-point damper is undefined when its points coincide: the compiled evaluation
    flags the step (the loop hands it to Python), and the Python step raises the damper's error."""
    scene = spring_mechanism()
    q0, v0 = scene.initial_state()
    q0[3:5] = (1.0, -0.4)                       # the free bar's centre on its damper's ground point
    system, x0 = compiled_scene.newton_system(scene, q0, v0, 1e-2)
    compiled_scene._evaluate(system, np.zeros_like(x0))
    assert system[2][8][0] == 1
    with pytest.raises(ValueError, match="coincide"):
        scene.external_force(q0, v0, 0.0)
