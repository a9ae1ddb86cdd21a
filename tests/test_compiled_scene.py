"""The compiled core against the numpy points, the bodies and the Python path.

1. The position maps of ``skfem_flex/compiled/points.py`` (value, Jacobian, exact discrete gradient, that
   gradient's Jacobian, the Hessian product and the velocity Jacobian), packed by ``MapStore``, are held to
   the numpy body points (PointMass, RigidBody, FloatingBeam and ModalBody points) and to the bodies'
   gravity at 1e-12 of the entries' scale, at random states with large rotation increments (Δθ up to 2 rad)
   and tiny ones (the series branch of sinc(Δθ/2)).
2. Runs of the compiled families (``simulate(..., compiled=True)``: no element through Python) equal those
   of the Python path (``compiled=False``: every element through its own numpy methods, the
   ``python_elements`` family of the same loop) to round-off amplified by the Newton tolerance, under every
   scheme: catalogue mechanisms, rigid mechanisms with and without a prescribed coordinate, springs,
   dampers, follower forces, lines on moving bodies, large scenes on CSR storage, a long chain.
3. Elements without a compiled form, and subclasses that redefine their class's equations, run through
   their Python methods (``run_path["python_elements"]`` names them), with their own equations.
4. A step the loop cannot finish is halved as on the Python path, or raises the same ConvergenceError.
5. The divergence guard's block check equals its record-by-record check.
6. The Newton matrix of the step (``Stepper.evaluate``) is the derivative of its residual, every entry
   lies in the scene's pattern, and CSR storage reports an entry written outside it.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.bodies.base import COMPILED_SIZE_LIMIT, to_dense
from skfem_flex.bodies.probes import PointProbe
from skfem_flex.compiled import pack
from skfem_flex.compiled.pack import packed_scene
from skfem_flex.compiled.points import (FRAME, KIND, NB, OFF, MapStore, dgrad_into, dgrad_jacobian_parts,
                                        hessian_parts, jacobian_into, position_into, velocity_jacobian_into)
from skfem_flex.compiled.storage import CSR, DENSE
from skfem_flex.compiled.tasks import STATUS_MISSED, STATUS_OK
from skfem_flex.errors import ConvergenceError, DivergenceError
from skfem_flex.numerics import rotations
from skfem_flex.numerics.band_plans import MAX_BORDER
from skfem_flex.schemes import EnergyMomentum, NewtonSettings, Trapezoidal, make_scheme
from skfem_flex.schemes.stepper import Stepper
from skfem_flex.scenes.links import link

from helpers import dense

EPS = np.finfo(float).eps
SEC = dict(EA=1e6, EI=1e2, kGA=3.205e5, rhoA=1.0, rhoI=1e-4)
#: rotation increments of the random states: large ones and tiny ones (series branch of sinc(Δθ/2), |Δθ| < 2e-3)
DTHETAS = [2.0, -1.9, 0.6, 2.1e-3, -3e-5, 1e-9, 0.0]
#: relative tolerance of the kernels against the numpy points
KERNEL_TOL = 1e-12
SCHEMES = ["energy-momentum", "trapezoidal", "generalized-alpha"]


def rel(a, ref, floor=0.0):
    """max |a − ref| over the larger of max |ref| and ``floor`` (0 if both are zero and a == ref)."""
    a, ref = dense(a), dense(ref)
    assert a.shape == ref.shape
    err = np.abs(a - ref).max() if a.size else 0.0
    scale = max(np.abs(ref).max() if ref.size else 0.0, floor)
    return err / scale if scale > 0 else (0.0 if err == 0 else np.inf)


# ==================================================================== 1. position maps
def map_data(entries):
    """The MapData of ``entries`` [(compiled_map() entry, n_b), ...], each on its own block (offsets one
    after another), as ``Packer.point_map`` builds a scene's: map k is entry k."""
    store, off = MapStore(), 0
    for entry, nb in entries:
        store.add(entry, off, nb)
        off += nb
    return store.data()


def _nb(maps, k):
    return int(maps.ints[k, NB])


def map_position(maps, k, q):
    out = np.zeros(2)
    position_into(maps, k, np.ascontiguousarray(q, dtype=float), out)
    return out


def map_jacobian(maps, k, q):
    out = np.zeros((2, _nb(maps, k)))
    jacobian_into(maps, k, np.ascontiguousarray(q, dtype=float), out)
    return out


def map_dgrad(maps, k, q0, q1):
    out = np.zeros((2, _nb(maps, k)))
    dgrad_into(maps, k, np.ascontiguousarray(q0, dtype=float), np.ascontiguousarray(q1, dtype=float), out)
    return out


def map_dgrad_jacobian(maps, k, q0, q1, f):
    """∂(Dᵀf)/∂q1 (n_b, n_b) assembled from ``dgrad_jacobian_parts`` (zero for a LINEAR map)."""
    nb = _nb(maps, k)
    out = np.zeros((nb, nb))
    if maps.ints[k, KIND] == FRAME:
        row, col = np.zeros(nb - 3), np.zeros(nb - 3)
        out[2, 2] = dgrad_jacobian_parts(maps, k, np.ascontiguousarray(q0, dtype=float),
                                         np.ascontiguousarray(q1, dtype=float), np.asarray(f, dtype=float), row, col)
        out[2, 3:], out[3:, 2] = row, col
    return out


def map_hessian_product(maps, k, q, f):
    """∂(r_qᵀf)/∂q (n_b, n_b) assembled from ``hessian_parts`` (symmetric; zero for a LINEAR map)."""
    nb = _nb(maps, k)
    out = np.zeros((nb, nb))
    if maps.ints[k, KIND] == FRAME:
        row = np.zeros(nb - 3)
        out[2, 2] = hessian_parts(maps, k, np.ascontiguousarray(q, dtype=float), np.asarray(f, dtype=float), row)
        out[2, 3:] = out[3:, 2] = row
    return out


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
    """Largest relative deviations of the map kernels on ``entry`` from the numpy references, and of the
    exactness identity D (q1 − q0) = r(q1) − r(q0) (in units of ε times the scale of its terms)."""
    maps = map_data([(entry, nb)])
    out = dict(position=0.0, jacobian=0.0, dgrad=0.0, dgrad_jacobian=0.0, hessian=0.0, exactness_eps=0.0)
    for q0, q1 in states:
        jac_scale = 0.0
        for q in (q0, q1):
            r = map_position(maps, 0, q)
            jac = map_jacobian(maps, 0, q)
            jac_scale = max(jac_scale, np.abs(jac).max())
            # the scale of r: its largest term (|m R| or |A s|), not |r| itself (which may cancel)
            out["position"] = max(out["position"], rel(r, ref_position(q), np.abs(jac).max() * max(1.0, np.abs(q).max())))
            out["jacobian"] = max(out["jacobian"], rel(jac, ref_jacobian(q)))
            if ref_hessian is not None:             # the tangent of a point load Jᵀ F
                f = rng.normal(size=2)
                hp = map_hessian_product(maps, 0, q, f)
                ref = np.asarray(to_dense(ref_hessian(q, f)), dtype=float)
                out["hessian"] = max(out["hessian"], rel(hp, ref, np.abs(f).max() * np.abs(jac).max()))
        d = map_dgrad(maps, 0, q0, q1)
        out["dgrad"] = max(out["dgrad"], rel(d, ref_dgrad(q0, q1)))
        for f in (rng.normal(size=2), np.array([0.0, -9.81])):
            h = map_dgrad_jacobian(maps, 0, q0, q1, f)
            out["dgrad_jacobian"] = max(out["dgrad_jacobian"],
                                        rel(h, ref_dgrad_jacobian(q0, q1, f), np.abs(f).max() * jac_scale))
        # exactness: D (q1 − q0) = r(q1) − r(q0) to round-off of the terms involved
        r0, r1 = map_position(maps, 0, q0), map_position(maps, 0, q1)
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
    """The first-moment map of ``body`` (as ``pack.py`` packs it for the gravity family) against the body's
    gravity potential and discrete gradient, for two fields.

    The gravity family adds −gᵀD to the discrete gradient of V and ∂(Dᵀ(−g))/∂q1 to its Jacobian; the body
    returns (−gᵀD, ∂(Dᵀ(−g))/∂q1) from ``gravity_discrete_gradient(q0, q1, g)``; V = −g · r, ∇V = −gᵀ ∂r/∂q."""
    kd = getattr(body, "compiled_kernel_data", lambda: None)()
    entry = ("frame", *body.mass_moment_map()) if kd is not None else ("linear", *body.mass_moment())
    nb = body.n_dofs
    maps = map_data([(entry, nb)])
    rng = np.random.default_rng(seed)
    states = [random_states(body, rng, dth) for dth in DTHETAS]
    out = dict(potential=0.0, gradient=0.0, dgrad=0.0, dgrad_jacobian=0.0, exactness_eps=0.0)
    for g in (np.array([0.0, -9.81]), np.array([3.0, -7.5])):
        for q0, q1 in states:
            jac_scale = np.abs(map_jacobian(maps, 0, q0)).max()
            for q in (q0, q1):
                v_ref, grad_ref, _ = body.gravity_potential(q, g)
                r = map_position(maps, 0, q)
                out["potential"] = max(out["potential"], rel(-(g @ r), v_ref, np.abs(g).max() * jac_scale
                                                             * max(1.0, np.abs(q).max())))
                out["gradient"] = max(out["gradient"], rel(-(g @ map_jacobian(maps, 0, q)), grad_ref))
            d = map_dgrad(maps, 0, q0, q1)
            h = map_dgrad_jacobian(maps, 0, q0, q1, -g)
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


def test_map_store_keeps_several_maps_apart():
    """Maps of different kinds and sizes packed together: map k is entry k, on its own block."""
    pts = points()
    names = ["beam-interior", "point-mass", "rigid-far", "modal-tip", "rigid-centre"]
    maps = map_data([(pts[n][1].compiled_map(), pts[n][0].n_dofs) for n in names])
    np.testing.assert_array_equal(maps.ints[:, NB], [pts[n][0].n_dofs for n in names])
    np.testing.assert_array_equal(maps.ints[:, OFF], np.cumsum([0] + [pts[n][0].n_dofs for n in names[:-1]]))
    rng = np.random.default_rng(5)
    for k, n in enumerate(names):
        body, pt = pts[n]
        q0, q1 = random_states(body, rng, 1.3)
        assert rel(map_position(maps, k, q1), pt.position(q1)) <= KERNEL_TOL
        assert rel(map_dgrad(maps, k, q0, q1), pt.position_discrete_gradient(q0, q1)) <= KERNEL_TOL


def test_velocity_jacobian_of_frame_maps_is_the_derivative_of_j_v():
    """∂(J(q) v)/∂q of the floating-frame and rigid-body point maps of a packed scene (the slider-crank's)
    against central differences of J(q) v (``jacobian_into``)."""
    maps = packed_scene(sf.scenes.get("slider_crank")()).maps.data
    rng = np.random.default_rng(3)
    checked = 0
    for k in range(maps.ints.shape[0]):
        if maps.ints[k, KIND] != FRAME:
            continue
        nb = _nb(maps, k)
        q = rng.normal(size=nb) * np.r_[1.0, 1.0, 2.0, 1e-2 * np.ones(nb - 3)]
        v = rng.normal(size=nb)
        out = np.zeros((2, nb))
        velocity_jacobian_into(maps, k, q, v, out)
        fd = np.zeros((2, nb))
        for j in range(nb):
            e = np.zeros(nb)
            e[j] = 1e-6
            fd[:, j] = (map_jacobian(maps, k, q + e) @ v - map_jacobian(maps, k, q - e) @ v) / 2e-6
        np.testing.assert_allclose(out, fd, rtol=0, atol=1e-8 * np.abs(fd).max())
        checked += 1
    assert checked >= 3


def test_cayley_terms_are_the_rotations_formulas():
    """The energy-momentum step's compiled Cayley rate terms (``rotations.cayley_terms``) against the numpy
    functions of skfem_flex.numerics.rotations."""
    for x in np.concatenate([np.linspace(-2.8, 2.8, 57), [0.0, 1e-9, -3e-5, 0.0099, 0.0101, -0.0101]]):
        z, ratio, dratio, dz = rotations.cayley_terms(x)
        assert z == pytest.approx(float(rotations.cayley(x)), rel=1e-15, abs=1e-300)
        assert ratio == pytest.approx(float(rotations.cayley_ratio(np.array([x]))[0]), rel=1e-15)
        assert dratio == pytest.approx(float(rotations.cayley_ratio_derivative(x)), rel=1e-14, abs=1e-300)
        assert dz == pytest.approx(float(rotations.cayley_derivative(x)), rel=1e-15)


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
    """(compiled run, Python run) of fresh scenes. The compiled run has every element in a compiled family
    (``compiled=True`` refuses a scene with an element that has none, and ``run_path`` names none); the
    Python run has the scene's elements in the Python family (``compiled=False``)."""
    a = sf.simulate(scene_factory(), t_end=t_end, dt=dt, compiled=True, **kw)
    assert a.run_path["loop"] == "compiled" and a.run_path["python_elements"] == []
    b = sf.simulate(scene_factory(), t_end=t_end, dt=dt, compiled=False, **kw)
    assert b.run_path["python_elements"] and all(p.endswith("compiled=False") for p in b.run_path["python_elements"])
    return a, b


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
    np.testing.assert_array_equal(a.t, b.t)         # times from step numbers: the same under any chunking
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
    (Cayley rates), under the energy-momentum scheme."""
    factory = sf.scenes.get(name)
    scene = factory()
    a, b = run_both(factory, t_end=t_end, dt=factory.defaults["dt"] if dt is None else dt)
    # the free beam's stiff steps end at the round-off floor of its internal forces after about five
    # Newton iterations on both paths: their velocities (2Δq/Δt − v0) agree to 7e-10, not 1e-10
    assert_same_run(a, b, tol=dict(v=3e-9) if name == "free_beam" else None)
    if scene.n_constraints:
        assert a.lam.shape == (a.t.size, scene.n_constraints) and np.abs(a.lam).max() > 0
    if name in ("free_beam", "flying_beam"):
        assert np.abs(a.external_work).max() > 0          # the load in time did work


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


NEWMARK_CASES = [("pendulum", None, 0.3), ("spring_mass", None, 2.0), ("flexible_pendulum", 2e-3, 0.2),
                 ("double_pendulum", 2e-3, 0.2), ("spin_up_pinned", None, 0.3), ("slider_crank", 5e-4, 0.03),
                 ("free_beam", None, 0.3), ("very_flexible_pendulum", None, 0.03), ("flying_beam", None, 0.5),
                 ("spin_up_beam", None, 0.4)]


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("name, dt, t_end", NEWMARK_CASES)
def test_catalogue_newmark_compiled_equal_python(name, dt, t_end, scheme):
    """The compiled Newmark step (velocity-level constraints for the trapezoidal rule, position level for
    generalized-α; floating-frame kernels, exact beams, drivers, sliders, loads at the step's end) gives
    the Python path's run: states, multipliers, energies, work (loads and prescribed laws trapezoidal in
    time), reactions and probes, and the same energy balance error."""
    factory = sf.scenes.get(name)
    a, b = run_both(factory, t_end=t_end, dt=factory.defaults["dt"] if dt is None else dt, scheme=scheme)
    dev = assert_same_run(a, b, tol=dict(energy_balance=np.inf, v=3e-9 if name == "free_beam" else 1e-10))
    assert abs(dev["energy_balance"] - dev["energy_balance_python"]) <= 1e-9


# ==================================================================== springs, dampers, followers, lines
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
    beam.q0[:2] = (0.0, -1.0)
    block = sf.RigidBody.bar(0.3, 0.2, start=(0.4, -1.0), angle=0.0, name="block")
    cons = [sf.Pin(guide.point(), (0.0, 0.0)), sf.Slider(m.point(), (1.0, 0.0), on=guide.point()),
            sf.Pin(beam.point(0.0), (0.0, -1.0)), sf.Prismatic(block.point(), (1.0, 0.0), on=beam.point(0.5))]
    forces = [sf.Gravity(), sf.LinearSpring(m.point(), guide.point(), 30.0, rest_length=0.3)]
    return sf.Scene([guide, m, beam, block], constraints=cons, forces=forces, name="sliding mechanism")


ELEMENT_SCENES = [(torsion_mechanism, 1e-2, 0.5), (spring_mechanism, 1e-2, 0.5), (follower_mechanism, 2e-3, 0.1),
                  (sliding_mechanism, 2e-3, 0.2)]


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("factory, dt, t_end", ELEMENT_SCENES)
def test_springs_dampers_and_followers_compiled_equal_python(factory, dt, t_end, scheme):
    """Torsion springs and dampers, two-point springs (l₀ > 0, l₀ = 0, to the ground) and dampers, follower
    point forces on a rigid body and a beam's section, sliders and prismatic joints on moving bodies: the
    compiled families give the Python path's run under every scheme, and the energy-momentum run keeps the
    energy balance (the dampers' work included)."""
    a, b = run_both(factory, t_end=t_end, dt=dt, scheme=scheme)
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


def loaded_stepper(scene, scheme, q0, v0, lam=None, acc=None):
    """A Stepper of ``scene`` under ``scheme`` (a name) loaded with (q0, v0, λ, acceleration) at t = 0."""
    sch = make_scheme(scheme)
    st = Stepper(scene, sch)
    acc = np.zeros(scene.n) if acc is None else np.asarray(acc, dtype=float)
    lam = np.zeros(scene.n_constraints) if lam is None else np.asarray(lam, dtype=float)
    st.load(sch.make_state(0.0, np.array(q0, dtype=float), np.array(v0, dtype=float), acc=acc, pseudo=acc.copy(),
                           lam=lam))
    return st


def central_differences(fun, x, eps=1e-6, points=3):
    """∂fun/∂x by central differences (columns) on 3 points (error O(ε²)) or 5 (O(ε⁴), for residuals
    whose round-off, large against the part differentiated, needs a larger ε)."""
    cols = []
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = eps
        if points == 3:
            cols.append((fun(x + e) - fun(x - e)) / (2.0 * eps))
        else:
            cols.append((8.0 * (fun(x + e) - fun(x - e)) - (fun(x + 2 * e) - fun(x - 2 * e))) / (12.0 * eps))
    return np.column_stack(cols)


@pytest.mark.parametrize("factory", [torsion_mechanism, spring_mechanism, follower_mechanism, sliding_mechanism])
def test_energy_momentum_newton_matrix_is_the_residuals_derivative(factory):
    """The compiled energy-momentum Newton matrix (every element's tangent: torsion and two-point springs'
    discrete gradients, dampers and follower forces at the mid-point, joints) against central differences
    of the residual (``Stepper.evaluate``), at a state with large velocities and a large step."""
    scene = factory()
    rng = np.random.default_rng(3)
    q0 = scene.initial_state()[0]
    v0 = rng.normal(size=q0.size)
    lam = rng.normal(size=scene.n_constraints)
    st = loaded_stepper(scene, "energy-momentum", q0, v0, lam=lam)
    h, t0 = 0.05, 0.3
    x = np.concatenate([h * v0[st.packed.free], h * lam]) + 0.01 * rng.normal(size=st.packed.nx)
    mat = dense(st.evaluate(t0, h, x)[1])
    fd = central_differences(lambda y: st.evaluate(t0, h, y)[0], x)
    assert np.abs(mat - fd).max() <= 1e-6 * np.abs(fd).max()


@pytest.mark.parametrize("scheme", SCHEMES)
def test_line_on_a_moving_body_row_and_its_derivatives(scheme):
    """The compiled rows of a slider and a prismatic joint on moving bodies (a rigid bar, a flexible beam's
    section; the family of lines on moving bodies), at states with large turns of the bodies' frames:

    * energy-momentum: the row's discrete gradient is exact, D (q1 − q0) = Φ(q1) − Φ(q0) (Φ from the
      constraints' numpy ``constraint_value``), and the row's value is Φ(q1);
    * every scheme: the border row (Φ_q; for the trapezoidal rule's velocity rows with ∂(Φ_q v)/∂q) and the
      constraint force's derivative (∂(μ D)/∂q1; the Hessian μ ∂²Φ/∂q² of the Newmark schemes), the latter
      isolated as J(μ) − J(0) with μ on these rows only, against central differences of the residual (5 points,
      ε = 1e-4: the stiff beam's internal forces in the residual are 1e4 times the constraint force)."""
    scene = sliding_mechanism()
    n, m = scene.n, scene.n_constraints
    rotated = [int(rows[0]) for c, (_, rows) in zip(scene.constraints, scene.constraint_layout)
               if isinstance(c, (sf.Slider, sf.Prismatic))]
    assert len(rotated) == 2                        # the slider's row and the prismatic joint's first row
    fams = {mod.NAME: count for mod, _, count in packed_scene(scene).families}
    assert fams.get("lines on moving bodies") == 2
    angles = [scene.slice(b).start + 2 for b in scene.bodies if b.n_dofs >= 3]
    rng = np.random.default_rng(5)
    q_ref = scene.initial_state()[0]
    h = 0.02
    for _ in range(3):
        q0 = q_ref + 0.05 * rng.normal(size=n)
        q1 = q0 + 0.05 * rng.normal(size=n)
        q1[angles] += rng.uniform(-1.5, 1.5, size=len(angles))          # large turns of the bodies' frames
        v0 = rng.normal(size=n)
        st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=n))
        nf = st.packed.free.size
        assert nf == n
        mu = np.zeros(m)
        mu[rotated] = rng.normal(size=2)
        dq = q1 - q0

        def residual(dq_, mu_):
            return st.evaluate(0.0, h, np.concatenate([dq_, mu_]))[0]
        res, mat, _ = st.evaluate(0.0, h, np.concatenate([dq, mu]))
        mat = dense(mat)
        if scheme == "energy-momentum":
            ddphi, phi = st.ws.vectors["ddphi"][:m].copy(), st.ws.vectors["phi"][:m].copy()
            phi0, phi1 = scene.constraint_value(q0, 0.0), scene.constraint_value(q1, 0.0)
            jac1 = dense(scene.constraint_jacobian(q1, 0.0))
            for r in rotated:
                scale = abs(phi0[r]) + abs(phi1[r]) + np.abs(jac1[r]).max() * np.abs(dq).max()
                assert abs(ddphi[r] - (phi1[r] - phi0[r])) <= 1e-13 * scale
                assert abs(phi[r] - phi1[r]) <= 1e-13 * scale
        border = [nf + r for r in rotated]
        fd_rows = central_differences(lambda y: residual(y, mu)[border], dq, eps=1e-4, points=5)
        assert np.abs(mat[border, :nf] - fd_rows).max() <= 1e-7 * np.abs(fd_rows).max()
        mat0 = dense(st.evaluate(0.0, h, np.concatenate([dq, np.zeros(m)]))[1])
        fd_force = central_differences(lambda y: residual(y, mu)[:nf] - residual(y, np.zeros(m))[:nf], dq,
                                       eps=1e-4, points=5)
        assert np.abs(fd_force).max() > 1e-3
        assert np.abs((mat - mat0)[:nf, :nf] - fd_force).max() <= 1e-7 * np.abs(fd_force).max()


@pytest.mark.parametrize("params, storage, solver, scheme", [
    (dict(n_elements=50), "sparse", "bordered band (CSR)", "energy-momentum"),
    (dict(n_elements=50), "sparse", "bordered band (CSR)", "trapezoidal"),
    (dict(body="plane-stress", n_elements=8), "dense", "dense", "energy-momentum")])
def test_large_scenes_compiled_equal_python(params, storage, solver, scheme):
    """Scenes with more coordinates than the package keeps dense (DENSE_LIMIT: sparse matrices there) run
    compiled and give the Python path's run over five steps: a 50-element flexible pendulum (153 coordinates),
    its Newton matrix stored as the values of its pattern (CSR) and solved as a band with a border, and one
    made of an unreduced plane-stress strip, whose 165 × 165 Newton matrix has no band plan and is stored
    dense (its Python path costs seconds a run: one scheme). A kernel writing outside a CSR pattern would stop
    the run (AssertionError, see below)."""
    factory = sf.scenes.get("flexible_pendulum")
    scene = factory(**params)
    assert sf.scene.DENSE_LIMIT < scene.n and not scene.dense
    a, b = run_both(lambda: factory(**params), t_end=5e-3, dt=1e-3, scheme=scheme)
    assert (a.run_path["storage"], a.run_path["solver"]) == (storage, solver)
    # short stiff elements: the steps end at the round-off floor of the internal forces, and the
    # velocities 2Δq/Δt − v0 of the two paths agree to 3e-10 (as the free beam's, see above)
    tol = dict(v=3e-9, energy_balance=np.inf if scheme != "energy-momentum" else 1e-10)
    if "body" in params:
        # the stiff strip's steps end at that floor after 4 or 5 iterations, not always the same number
        # on both paths: positions agree to a few Newton tolerances (1.1e-10 on one machine; 3.1e-10 at the
        # tip probe on another, with numpy 2.4), velocities to 3.6e-9 and the multipliers and the pin's
        # reaction (the trapezoidal rule's velocity-level rows) to 2.3e-9
        tol.update(q=1e-9, probes=1e-9, v=1e-8, lam=1e-8, reactions=1e-8)
    assert_same_run(a, b, tol=tol)


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_above_the_compiled_size_limit_csr_storage_equals_dense_storage(monkeypatch, scheme):
    """A 220-element flexible pendulum (665 unknowns, more than any dense storage takes: COMPILED_SIZE_LIMIT)
    runs with its Newton matrix stored as the values of its pattern (CSR) and solved as a band with a border;
    its run is that of the same families with the matrix stored dense (the limits raised for the reference).
    (Its Python path, the reference of the smaller scenes above, has no band plan at this size:
    test_a_matrix_without_band_plan_above_the_dense_limit_is_solved.)"""
    factory = sf.scenes.get("flexible_pendulum")
    assert packed_scene(factory(n_elements=220)).nx > COMPILED_SIZE_LIMIT
    a = sf.simulate(factory(n_elements=220), t_end=0.01, dt=1e-3, scheme=scheme, compiled=True)
    assert (a.run_path["storage"], a.run_path["solver"]) == ("sparse", "bordered band (CSR)")
    monkeypatch.setattr(pack, "DENSE_STORAGE_LIMIT", 10 ** 6)
    monkeypatch.setattr(pack, "COMPILED_SIZE_LIMIT", 10 ** 6)
    b = sf.simulate(factory(n_elements=220), t_end=0.01, dt=1e-3, scheme=scheme, compiled=True)
    assert (b.run_path["storage"], b.run_path["solver"]) == ("dense", "bordered band")
    assert_same_run(a, b, tol=dict(v=3e-9, energy_balance=np.inf if scheme != "energy-momentum" else 1e-10))


def test_a_matrix_without_band_plan_above_the_dense_limit_is_solved(monkeypatch):
    """A Newton matrix with no band plan (an unreduced plane-stress strip's dense tangent) above the dense
    storage limit is stored as CSR and solved by SuperLU (compiled/sparse_solver.py), and the run is the dense
    storage's. The limits are
    lowered here so that a small scene takes that path (the 220-element pendulum's Python path takes it at
    the real limits, after a minute of packing)."""
    factory = sf.scenes.get("flexible_pendulum")
    a = sf.simulate(factory(body="plane-stress", n_elements=2), t_end=3e-3, dt=1e-3)
    assert a.run_path["storage"] == "dense"
    monkeypatch.setattr(pack, "DENSE_STORAGE_LIMIT", 10)
    monkeypatch.setattr(pack, "COMPILED_SIZE_LIMIT", 10)
    b = sf.simulate(factory(body="plane-stress", n_elements=2), t_end=3e-3, dt=1e-3)
    assert (b.run_path["storage"], b.run_path["solver"]) == ("sparse", "sparse (SuperLU)")
    assert_same_run(b, a, tol=dict(v=1e-8, q=3e-10, probes=3e-10, lam=1e-8))


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


def test_a_long_chain_runs_compiled_in_a_reordered_band():
    """A chain of 70 bars (210 coordinates, 140 multipliers): in its natural order every multiplier would be a
    border coordinate (no diagonal entry), more than MAX_BORDER; reordered (reverse Cuthill–McKee) its Newton
    matrix is a band without border (lo + up = 16 on the scene's pattern, test_compiled_band_solve.py),
    stored as CSR, and the energy-momentum run is the Python path's. (The Newmark steps on CSR storage:
    the large pendulums above.)"""
    scene = rigid_chain(70)
    packed = packed_scene(scene)
    assert scene.n_constraints > MAX_BORDER
    interior, border, lo, up = packed.plan
    assert packed.storage == CSR and border.size == 0 and lo + up <= 16
    a, b = run_both(lambda: rigid_chain(70), t_end=5e-3, dt=1e-3)
    assert (a.run_path["storage"], a.run_path["solver"]) == ("sparse", "bordered band (CSR)")
    # the energy-momentum steps end once the force residual is at the Newton tolerance; a chain's multipliers
    # follow from that residual through D, which is badly conditioned for a long chain, so the two paths'
    # last iterates give λ and the pin's reaction to 3e-8 and 6e-8: positions and velocities agree to 3e-11
    assert_same_run(a, b, tol=dict(lam=1e-7, reactions=2e-7))


PATTERN_SCENES = {name: (lambda name=name: sf.scenes.get(name)()) for name in
                  ("pendulum", "flexible_pendulum", "double_pendulum", "spin_up_pinned", "slider_crank",
                   "free_beam", "very_flexible_pendulum", "flying_beam")}
PATTERN_SCENES.update(driven=driven_rigid_mechanism, torsion=torsion_mechanism, spring=spring_mechanism,
                      follower=follower_mechanism, sliding=sliding_mechanism)


#: velocities of the random states (m/s, rad/s) where 1 makes an element refuse the state: the very flexible
#: pendulum's short exact-beam elements fold in a step of 0.05 s
PATTERN_SPEED = dict(very_flexible_pendulum=0.3)


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("name", list(PATTERN_SCENES))
def test_newton_pattern_holds_every_entry(name, scheme):
    """Every entry the step writes into its Newton matrix, at random states, steps and multipliers, lies in
    the scene's Newton pattern (what CSR storage keeps; dense storage here, so that an entry outside it
    would be seen)."""
    scene = PATTERN_SCENES[name]()
    rng = np.random.default_rng(11)
    q0 = scene.initial_state()[0]
    for _ in range(3):
        v0 = PATTERN_SPEED.get(name, 1.0) * rng.normal(size=q0.size)
        lam = rng.normal(size=scene.n_constraints)
        st = loaded_stepper(scene, scheme, q0, v0, lam=lam, acc=rng.normal(size=q0.size))
        pk = st.packed
        assert pk.storage == DENSE
        pattern = pk.pattern.toarray().astype(bool)
        x = np.concatenate([0.05 * v0[pk.free], 0.05 * lam]) + 0.01 * rng.normal(size=pk.nx)
        mat = dense(st.evaluate(0.3, 0.05, x)[1])
        assert st.ws.ctx[0]["status"] == STATUS_OK
        outside = (mat != 0.0) & ~pattern
        assert not outside.any(), np.argwhere(outside)[:5]
        assert np.count_nonzero(mat) > 0.5 * pattern.diagonal().sum()


def lacking_pattern(real):
    """``pack._newton_pattern`` without the first constraint row's entry on coordinate 0 (and its transpose)."""
    def lacking(scene, packed, packs):
        pat = real(scene, packed, packs).tolil()
        nf = scene.free_index.size
        pat[nf, 0] = pat[0, nf] = 0
        pat = pat.tocsr()
        pat.eliminate_zeros()
        return pat
    return lacking


def test_csr_storage_reports_an_entry_outside_its_pattern(monkeypatch):
    """With CSR storage a value written outside the pattern is counted, not lost silently: the evaluation
    stops with an AssertionError that names the family (a bug of the package, to be reported), and so does
    a run. Here the pattern of a 64-element pendulum is made to lack the pin's first row's entry on the
    beam's R_x (and its transpose)."""
    real = pack._newton_pattern
    monkeypatch.setattr(pack, "_newton_pattern", lacking_pattern(real))
    scene = sf.scenes.get("flexible_pendulum")(n_elements=64)
    q0, v0 = scene.initial_state()
    st = loaded_stepper(scene, "energy-momentum", q0, v0 + 0.3)
    assert st.packed.storage == CSR
    x0 = np.concatenate([1e-3 * (v0 + 0.3), np.zeros(scene.n_constraints)])
    with pytest.raises(AssertionError, match="the point constraints family wrote an entry outside"):
        st.evaluate(0.0, 1e-3, x0)
    assert st.ws.ctx[0]["missed"] > 0 and st.ws.ctx[0]["status"] == STATUS_MISSED
    monkeypatch.setattr(pack, "_newton_pattern", real)
    fresh = sf.scenes.get("flexible_pendulum")(n_elements=64)
    st = loaded_stepper(fresh, "energy-momentum", q0, v0 + 0.3)
    st.evaluate(0.0, 1e-3, x0)
    assert st.ws.ctx[0]["missed"] == 0 and st.ws.ctx[0]["status"] == STATUS_OK


def test_a_run_reports_an_entry_outside_its_pattern(monkeypatch):
    """A run whose kernels write outside the Newton matrix's CSR pattern stops with the AssertionError that
    names the family, from its first evaluation on (the consistent start included)."""
    monkeypatch.setattr(pack, "_newton_pattern", lacking_pattern(pack._newton_pattern))
    with pytest.raises(AssertionError, match="the point constraints family wrote an entry outside"):
        sf.simulate(sf.scenes.get("flexible_pendulum")(n_elements=64), t_end=2e-3, dt=1e-3)


def crossing_mass():
    """A point mass at (−0.5, 0) m moving at 64 m/s towards the ground point of a strong damper (c/m = 100/s):
    the start's damper force is so large that the first step's Newton start is Δq = Δt v0, and with
    Δt = 2⁻⁶ s its mid-point, where the energy-momentum step evaluates loads, is the ground point exactly."""
    m = sf.PointMass(0.01, [-0.5, 0.0], [64.0, 0.0], name="mass")
    return sf.Scene([m], forces=[sf.LinearDamper(m.point(), (0.0, 0.0), 1.0)], name="crossing")


def test_a_damper_whose_points_coincide_during_a_step():
    """The direction of a two-point damper is undefined when its points coincide. The compiled dampers family
    refuses that state (STATUS_REFUSED, test_family_dampers.py): the run halves the step, whose halves
    evaluate the damper elsewhere, and goes on; without halvings it stops with a ConvergenceError that names
    the family and the damper's own error. On the Python path the damper's ``generalized_force`` raises that
    error, and the run stops with it."""
    dt = 2.0 ** -6
    a = sf.simulate(crossing_mass(), t_end=2 * dt, dt=dt, compiled=True)
    assert a.completed and a.halvings == 1 and a.steps == 2
    assert a.external_work[-1] < 0.0
    with pytest.raises(ConvergenceError, match=r"the dampers refused the step \(damper 'damper': its two points "
                                               r"coincide") as info:
        sf.simulate(crossing_mass(), t_end=2 * dt, dt=dt, compiled=True, max_halvings=0)
    assert info.value.result.steps == 0
    with pytest.raises(ValueError, match="coincide"):
        sf.simulate(crossing_mass(), t_end=2 * dt, dt=dt, compiled=False)


def test_a_damper_whose_points_coincide_at_the_start_is_named():
    """A run started with a damper's points coincident stops with the damper's error on both paths (the
    Python path raises it from the damper's ``generalized_force``; the compiled start should name the
    refusing element rather than a singular matrix)."""
    q0, v0 = spring_mechanism().initial_state()
    q0[3:5] = (1.0, -0.4)                       # the free bar's centre on its damper's ground point
    with pytest.raises(ValueError, match="coincide"):
        sf.simulate(spring_mechanism(), t_end=0.02, dt=1e-2, start=(q0, v0), compiled=False)
    with pytest.raises(ValueError, match="coincide"):
        sf.simulate(spring_mechanism(), t_end=0.02, dt=1e-2, start=(q0, v0), compiled=True)


# ==================================================================== 3. elements through Python
def _bar():
    return sf.RigidBody.bar(1.0, 1.0, start=(0.0, 0.0), angle=0.0, name="bar")


def python_names(scene):
    """Class names of the scene's elements that run through their Python methods."""
    return sorted(type(e).__name__ for e, _ in packed_scene(scene).python_elements)


def test_compiled_false_and_the_environment_switch_run_every_element_through_python(monkeypatch):
    """``compiled=False`` (and ``SKFEM_FLEX_COMPILED=0`` as the default) puts the scene's elements into the
    Python family: ``run_path`` names each with the reason; the default runs them compiled."""
    fast = sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2)
    assert fast.run_path["python_elements"] == [] and fast.steps == 5
    slow = sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2, compiled=False)
    assert slow.completed and slow.steps == 5
    assert sorted(p.split()[0] for p in slow.run_path["python_elements"]) == ["Distance", "Gravity"]
    assert all(p.endswith(": compiled=False") for p in slow.run_path["python_elements"])
    monkeypatch.setenv("SKFEM_FLEX_COMPILED", "0")
    env = sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2)
    assert env.run_path == slow.run_path
    np.testing.assert_array_equal(env.q, slow.q)
    forced = sf.simulate(sf.scenes.get("pendulum")(), t_end=0.05, dt=1e-2, compiled=True)
    assert forced.run_path["python_elements"] == []
    np.testing.assert_array_equal(forced.q, fast.q)


def test_elements_without_a_compiled_form_run_through_python():
    """A user constraint has no compiled form: it runs through its Python methods inside the compiled loop
    (named in ``run_path``), ``compiled=True`` refuses it, and its run is that of the compiled Distance with
    the same equation Φ = ½(‖r‖² − 1)."""
    def user_scene():
        m = sf.PointMass(1.0, [1.0, 0.0], [0.0, 1.5])
        user = sf.UserConstraint([m], lambda q, t: np.array([0.5 * (q @ q - 1.0)]), lambda q, t: q[None, :])
        return sf.Scene([m], constraints=[user], forces=[sf.Gravity()])

    def distance_scene():
        m = sf.PointMass(1.0, [1.0, 0.0], [0.0, 1.5])
        return sf.Scene([m], constraints=[sf.Distance(m, (0.0, 0.0))], forces=[sf.Gravity()])
    assert python_names(user_scene()) == ["UserConstraint"]
    assert python_names(distance_scene()) == []
    with pytest.raises(ValueError, match="has no compiled form"):
        sf.simulate(user_scene(), t_end=0.02, dt=1e-2, compiled=True)
    a = sf.simulate(user_scene(), t_end=0.5, dt=1e-2)
    (entry,) = a.run_path["python_elements"]
    assert entry.startswith("UserConstraint") and entry.endswith("it has no compiled form")
    b = sf.simulate(distance_scene(), t_end=0.5, dt=1e-2)
    assert a.completed and a.steps == b.steps == 50 and a.halvings == b.halvings == 0
    assert rel(a.q, b.q) <= 1e-10 and rel(a.v, b.v) <= 1e-9
    assert rel(a.lam, b.lam) <= 1e-8


def test_a_scheme_subclass_runs_the_step_of_its_scheme():
    """The step is the scheme object's compiled kernel: a subclass that changes nothing runs the compiled
    step of its scheme, bit for bit."""
    class MyTrapezoidal(Trapezoidal):
        pass

    class MyEnergyMomentum(EnergyMomentum):
        pass
    for sub, name in ((MyTrapezoidal(), "trapezoidal"), (MyEnergyMomentum(), "energy-momentum")):
        a = sf.simulate(rigid_pendulum(), t_end=0.05, dt=1e-2, scheme=sub)
        b = sf.simulate(rigid_pendulum(), t_end=0.05, dt=1e-2, scheme=name)
        assert a.run_path == b.run_path and a.run_path["python_elements"] == []
        np.testing.assert_array_equal(a.q, b.q)
        np.testing.assert_array_equal(a.lam, b.lam)


class MovingPin(sf.Pin):
    """A pin whose anchor moves along x at 0.01 m/s."""

    def value(self, q, t):
        return super().value(q, t) - np.array([0.01 * t, 0.0])


class StiffGravity(sf.Gravity):
    """Gravity with twice the potential."""

    def potential_energy(self, q):
        return 2.0 * super().potential_energy(q)


def test_subclasses_that_redefine_the_equations_run_in_python():
    """A compiled form stands for its class's equations: a user subclass that redefines them is not packed
    into a compiled family but runs through its own methods (``python_elements``), and a run follows the
    subclass's equations (the moving pin's point moves with its anchor)."""
    class FastDriver(sf.Driver):
        def time_derivative(self, q, t):
            return 2.0 * super().time_derivative(q, t)

    def bar_scene(constraint=None, forces=()):
        bar = _bar()
        cons = [] if constraint is None else [constraint(bar)]
        return sf.Scene([bar], constraints=cons, forces=list(forces))
    assert python_names(bar_scene(lambda b: sf.Pin(b.point((-0.5, 0.0))), [sf.Gravity()])) == []
    assert python_names(bar_scene(lambda b: MovingPin(b.point((-0.5, 0.0))))) == ["MovingPin"]
    assert python_names(bar_scene(forces=[StiffGravity()])) == ["StiffGravity"]
    law = sf.MotionLaw(lambda t: t, lambda t: 1.0, lambda t: 0.0)
    assert python_names(bar_scene(lambda b: FastDriver(b, law, coordinate="theta"))) == ["FastDriver"]
    assert python_names(bar_scene(lambda b: sf.Driver(b, law, coordinate="theta"))) == []

    class SoftSpring(sf.LinearSpring):
        def potential_energy(self, q):
            return 0.5 * super().potential_energy(q)

    class ViscousHinge(sf.RotationalDamper):
        def generalized_force(self, q, v, t):
            f, fq, fv = super().generalized_force(q, v, t)
            return 2.0 * f, fq, 2.0 * fv
    for spring, damper in ((sf.LinearSpring, sf.RotationalDamper), (SoftSpring, sf.RotationalDamper),
                           (sf.LinearSpring, ViscousHinge)):
        bar = _bar()
        scene = sf.Scene([bar], forces=[spring(bar.point((0.5, 0.0)), (1.0, 1.0), 10.0),
                                        damper(bar.point(), damping=0.1)])
        expected = sorted(c.__name__ for c in (spring, damper) if c not in (sf.LinearSpring, sf.RotationalDamper))
        assert python_names(scene) == expected
    # the subclasses' own equations are what runs
    bar = _bar()
    point = bar.point((-0.5, 0.0))
    anchor = point.position(bar.q0)
    scene = sf.Scene([bar], constraints=[MovingPin(point)], forces=[StiffGravity()])
    res = sf.simulate(scene, t_end=0.2, dt=1e-2)
    assert sorted(p.split()[0] for p in res.run_path["python_elements"]) == ["MovingPin", "StiffGravity"]
    for t, q in zip(res.t, res.q):
        np.testing.assert_allclose(point.position(q), anchor + (0.01 * t, 0.0), rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.potential, 2.0 * 9.81 * bar.mass_matrix(bar.q0)[0, 0] * res.q[:, 1],
                               rtol=1e-12, atol=1e-12)
    assert np.ptp(res.q[:, 2]) > 0.05                 # it swung


# ==================================================================== 4. failing steps
@pytest.mark.parametrize("omega, dt, t_end, newton, scheme", [
    (12.0, 0.3, 1.5, None, "energy-momentum"),                                   # steps too large
    (2.0, 1e-2, 0.4, NewtonSettings(max_iterations=2), "energy-momentum"),      # too few iterations
    (12.0, 0.3, 1.5, None, "trapezoidal")])                                      # the Newmark step
def test_failing_steps_are_halved_as_on_the_python_path(omega, dt, t_end, newton, scheme):
    """Steps the loop cannot finish (too large, or too few Newton iterations allowed) are halved: the same
    halvings and the same trajectory on the compiled and on the Python path (for the Newmark step the
    state the halves start from includes its accelerations)."""
    a, b = run_both(lambda: rigid_pendulum(omega), t_end=t_end, dt=dt, max_halvings=8, newton=newton,
                    scheme=scheme)
    assert a.halvings == b.halvings > 0
    dev = assert_same_run(a, b, tol=None if scheme == "energy-momentum" else dict(energy_balance=np.inf))
    assert abs(dev["energy_balance"] - dev["energy_balance_python"]) <= 1e-9


@pytest.mark.parametrize("newton, dt, max_halvings", [(NewtonSettings(max_iterations=1), 1e-2, 2),
                                                      (None, 0.3, 0)])
def test_convergence_error_is_the_python_paths(newton, dt, max_halvings):
    """A step that fails on both paths raises the same ConvergenceError with the same partial result."""
    errors = []
    for c in (True, False):
        with pytest.raises(ConvergenceError) as info:
            sf.simulate(rigid_pendulum(12.0), t_end=2.0, dt=dt, newton=newton, max_halvings=max_halvings,
                        compiled=c)
        errors.append(info.value)
    assert type(errors[0]) is type(errors[1])
    assert str(errors[0]) == str(errors[1])
    assert "gave up after halving" in str(errors[0])
    ra, rb = errors[0].result, errors[1].result
    assert not ra.completed and ra.steps == rb.steps and ra.halvings == rb.halvings == max_halvings
    np.testing.assert_array_equal(ra.t, rb.t)
    np.testing.assert_allclose(ra.q, rb.q, rtol=0, atol=1e-10 * np.abs(rb.q).max())


# ==================================================================== 5. the divergence guard
def test_block_energy_guard_stops_where_the_record_by_record_guard_does():
    """first_energy_violation on a block equals check_energy applied record by record (scale window
    included), for a blow-up at every position, a NaN energy and a run that never diverges."""
    from skfem_flex.run.guard import SCALE_RECORDS, DivergenceGuard

    class Scene_:
        length_scale = 1.0
        n = 2
        bodies = ()
    rng = np.random.default_rng(5)
    n = 3 * SCALE_RECORDS
    for stop in list(range(n)) + [None, "nan"]:
        kin = 1.0 + rng.random(n)
        pot = -0.5 * rng.random(n)
        work = np.cumsum(0.01 * rng.random(n))
        if stop == "nan":
            kin[n // 2] = np.nan
        elif stop is not None:
            kin[stop] = 1e9
        expected = None                       # record by record
        guard = DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])
        for i in range(1, n):
            try:
                guard.check_energy(float(i), kin[i], pot[i], work[i])
            except DivergenceError:
                expected = i
                break
        guard = DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])    # records 1 … n − 1 as a block
        got = guard.first_energy_violation(np.arange(1.0, n), kin[1:], pot[1:], work[1:])
        assert (None if got is None else got + 1) == expected, stop
        # as two blocks, the second starting inside the scale window: the guard counts the records it saw
        cut = SCALE_RECORDS // 2
        guard = DivergenceGuard(Scene_(), np.zeros(2), kin[:1], pot[:1], work[:1])
        got = guard.first_energy_violation(np.arange(1.0, cut), kin[1:cut], pot[1:cut], work[1:cut])
        if got is not None:
            got += 1
        else:
            got = guard.first_energy_violation(np.arange(cut, n), kin[cut:], pot[cut:], work[cut:])
            got = None if got is None else got + cut
        assert got == expected, stop
