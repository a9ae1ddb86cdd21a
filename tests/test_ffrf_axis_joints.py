"""Joints with axes at a floating-frame body's material points against other moving bodies: rows that are sums
of products of two quadratic invariants (elements/constraints/product_rows.py). Their discrete gradient is
exact, their derivatives are those of their values, their values are the geometric conditions (read from the
point's own turned direction), the axis rows are orthogonal to a common rotation and translation at the
mid-point (the momenta they keep), and in scenes: a free flight on a hinge keeps energy and linear momentum,
a symmetric wheel on a hinge at the tip of a bending cantilever keeps its spin about its axis (Euler)."""
import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating_spatial.body import FloatingBeam3D
from skfem_flex.elements.constraints.quadratic import perpendiculars
from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D
from skfem_flex.fem.spatial_section import SpatialSection
from helpers import central_jacobian, relerr

SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.3, rhoI1=2.0, rhoI2=1.0)


def bodies():
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 4)), SECTION, order=1)
    a = FloatingBeam3D(beam, reference="chord", strain="linear", name="A", angular_velocity=(0.3, 0.5, 0.1))
    b = FloatingBeam3D(beam, reference="chord", strain="linear", name="B", position=(0.0, 0.0, 2.0))
    r = sf.SpatialRigidBody(mass=1.0, inertia=(0.1, 0.2, 0.3), position=(0.0, 0.0, 2.5), name="R",
                            angular_velocity=(0.0, 2.0, 0.3))
    return a, b, r


def joints():
    """(name, joint, its invariant rows: dot products, not differences of points)."""
    a, b, r = bodies()
    tip, root_b, end_r = a.point(2.0), b.point(0.0), r.point((0.0, 0.0, -0.5))
    return [("revolute beam-rigid", sf.Revolute3D(tip, end_r, axis=(0, 1, 0)), [3, 4]),
            ("revolute beam-beam", sf.Revolute3D(tip, root_b, axis=(0, 1, 0)), [3, 4]),
            ("revolute rigid-beam", sf.Revolute3D(end_r, tip, axis=(1, 0, 0)), [3, 4]),
            ("universal", sf.Universal(tip, root_b), [3]),
            ("cylindrical", sf.Cylindrical(tip, root_b, axis=(0, 0, 1)), [0, 1, 2, 3]),
            ("prismatic", sf.Prismatic3D(tip, end_r, axis=(0, 0, 1)), [0, 1, 2, 3, 4]),
            ("weld", sf.Weld3D(tip, root_b), [3, 4, 5]),
            ("distance", sf.Distance3D(tip, r.point((0.0, 0.0, 0.5))), [0]),
            ("translation driver", sf.TranslationDriver(tip, end_r, axis=(0, 0, 1),
                                                        law=sf.MotionLaw.constant_rate(0.1)), [0]),
            # against the ground: a difference of the material point and a fixed one, dotted (no symmetry left)
            ("cylindrical to the ground", sf.Cylindrical(tip, None, axis=(0, 0, 1)), []),
            ("prismatic to the ground", sf.Prismatic3D(tip, None, axis=(0, 0, 1)), []),
            ("distance to the ground", sf.Distance3D(tip, None, anchor=(0.0, 1.0, 2.0)), []),
            ("translation driver to the ground", sf.TranslationDriver(tip, None, axis=(1, 0, 0),
                                                                      law=sf.MotionLaw.constant_rate(0.1)), [])]


def _dense(m):
    return m.toarray() if hasattr(m, "toarray") else np.asarray(m)


def _turn(c, q, w, shift):
    """The rate of q under a common rotation w (rad/s) and translation ``shift`` (m/s) of every body: positions
    and directors turn, elastic coordinates stay."""
    out = np.zeros_like(q)
    for body, sl in zip(c.layout.bodies, c.layout.slices):
        qb, ob = q[sl], np.zeros(q[sl].size)
        positions, directors = body.vector_layout()
        for o in positions:
            ob[o:o + 3] = np.cross(w, qb[o:o + 3]) + shift
        for o in directors:
            ob[o:o + 3] = np.cross(w, qb[o:o + 3])
        out[sl] = ob
    return out


@pytest.mark.parametrize("case", range(13))
def test_product_rows_exact_discrete_gradient_derivatives_and_invariance(case):
    name, c, invariant = joints()[case]
    assert c.products is not None and c.compiled_form()[0] == "product" and not c.quadratic, name
    rng = np.random.default_rng(case)
    q0, q1 = (c.layout.initial() + 1e-2 * rng.normal(size=c.layout.n) for _ in range(2))
    t = 0.3
    D = c.discrete_gradient(q0, q1, t)
    jump = c.value(q1, t) - c.value(q0, t)
    assert np.abs(D @ (q1 - q0) - jump).max() <= 1e-13 * max(1.0, np.abs(jump).max()), name
    mu, v = rng.normal(size=c.n_equations), rng.normal(size=c.layout.n)
    assert relerr(c.jacobian(q0, t), central_jacobian(lambda z: c.value(z, t), q0)) <= 1e-7
    assert relerr(_dense(c.hessian_product(q0, mu, t)), central_jacobian(lambda z: c.jacobian(z, t).T @ mu, q0)) <= 1e-7
    assert relerr(c.velocity_jacobian(q0, v, t), central_jacobian(lambda z: c.jacobian(z, t) @ v, q0)) <= 1e-7
    assert relerr(_dense(c.discrete_gradient_jacobian(q0, q1, mu, t)),
                  central_jacobian(lambda z: c.discrete_gradient(q0, z, t).T @ mu, q1)) <= 1e-7
    qm = 0.5 * (q0 + q1)
    for e in np.eye(3) if invariant else ():
        for rate in (_turn(c, qm, e, np.zeros(3)), _turn(c, qm, np.zeros(3), e)):
            assert np.abs(D[invariant] @ rate).max() <= 1e-14 * np.abs(D).max() * np.abs(qm).max(), name
    # a row dropped (a redundant joint's): the others' values and discrete gradient unchanged
    if c.n_equations > 1:
        fewer = c.without_equations([0])
        assert np.abs(fewer.value(q1, t) - c.value(q1, t)[1:]).max() <= 1e-15 * max(1.0, np.abs(jump).max())
        assert np.abs(fewer.discrete_gradient(q0, q1, t) - D[1:]).max() <= 1e-15 * np.abs(D).max()


def test_factored_form_is_the_quadratic_form():
    """A material point's and a section direction's factored form (product rows) and quadratic form (quadratic
    rows) are one vector, at a turned and bent state; the position is the point's own ``position``."""
    a, _, _ = bodies()
    rng = np.random.default_rng(11)
    q = a.q0 + 0.05 * rng.normal(size=a.n_dofs)
    point = a.point(1.3)
    for vector in (point, point.direction((0.6, 0.0, 0.8))):
        H, A, c = vector.quadratic()
        A0, a0, terms = vector.factored()
        factored = A0 @ q + a0 + sum((beta @ q + gamma) * (W @ q) for beta, gamma, W in terms)
        assert np.abs(factored - (0.5 * np.einsum("cij,i,j->c", H, q, q) + A @ q + c)).max() <= 1e-14
    A0, a0, terms = point.factored()
    assert np.abs(A0 @ q + a0 + sum((b @ q + g) * (W @ q) for b, g, W in terms) - point.position(q)).max() <= 1e-14


def test_hinge_rows_are_the_turned_section_directions():
    """The revolute's rows n_i·e at a turned and bent state, n_i the beam section's material directions
    (ElasticPoint.turned: D (f + (Θ y) × f)) and e the rigid body's axis, against the rows' polynomial form."""
    a, _, r = bodies()
    tip, end_r = a.point(2.0), r.point((0.0, 0.0, -0.5))
    c = sf.Revolute3D(tip, end_r, axis=(0, 1, 0))
    rng = np.random.default_rng(5)
    q = c.layout.initial() + 0.05 * rng.normal(size=c.layout.n)
    qa, qr = q[c.layout.slices[0]], q[c.layout.slices[1]]
    e = np.array([0.0, 1.0, 0.0])
    n1, n2 = perpendiculars(e)
    D0 = a.rotation_matrix(a.q0)
    turned = [tip.turned(qa, D0.T @ n)[0] for n in (n1, n2)]
    axis = r.rotation_matrix(qr) @ r.rotation_matrix(r.q0).T @ e
    assert relerr(c.value(q, 0.0)[3:], np.array([u @ axis for u in turned])) <= 1e-13


def test_free_flight_on_a_hinge_keeps_energy_and_linear_momentum():
    """A free floating-frame beam and a rigid body on a hinge at its tip, both spinning: the energy–momentum
    step keeps the energy and the linear momentum to round-off, holds the hinge, and the compiled loop (the
    product-rows family) gives the Python path's motion."""
    a, _, r = bodies()
    scene = sf.Scene([a, r], constraints=[sf.Revolute3D(a.point(2.0), r.point((0.0, 0.0, -0.5)), axis=(0, 1, 0))])
    runs = [sf.simulate(scene, 0.3, 0.01, scheme="energy-momentum", compiled=c) for c in (True, False)]
    for res in runs:
        E = np.asarray(res.total_energy)
        assert np.ptp(E) <= 1e-12 * np.abs(E).max()
        p = np.array([a.linear_momentum(scene.coordinates(a, q), scene.coordinates(a, v))
                      + r.linear_momentum(scene.coordinates(r, q), scene.coordinates(r, v)) for q, v in zip(res.q, res.v)])
        assert np.abs(p - p[0]).max() <= 1e-12 * np.abs(p[0]).max()
        assert np.max(res.constraint_residual) <= 1e-10
    assert not runs[0].run_path["python_elements"]
    assert relerr(runs[0].q, runs[1].q) <= 1e-9
    for scheme in ("trapezoidal", "generalized-alpha"):
        res = sf.simulate(scene, 0.1, 0.01, scheme=scheme)
        assert np.isfinite(res.q).all() and np.max(res.constraint_residual) <= 1e-4


def test_wheel_on_a_hinge_at_the_tip_of_a_bending_cantilever_keeps_its_spin():
    """A wheel symmetric about its axis, on a hinge about that axis at the tip of a cantilever that bends
    under gravity: the hinge's moments are normal to the axis, so Euler's third equation keeps the spin
    ω₃ = 30 rad/s. The energy–momentum step holds it to O(Δt²) (directors keep a symmetric body's spin to
    that order) and the energy to round-off; the beam does bend (the tip swings by more than 0.1 m)."""
    sec = SpatialSection(EA=1e6, GA1=1e6, GA2=1e6, GJ=50.0, EI1=50.0, EI2=50.0, rhoA=1.0, rhoI1=1e-3, rhoI2=1e-3)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, 5)), sec, order=1)
    cantilever = FloatingBeam3D(beam, strain="linear", name="cantilever")
    wheel = sf.SpatialRigidBody(mass=2.0, inertia=(0.06, 0.06, 0.1), position=(0.0, 0.0, 1.1), name="wheel",
                                angular_velocity=(0.0, 0.0, 30.0))
    scene = sf.Scene([cantilever, wheel], forces=[sf.Gravity((-9.81, 0.0, 0.0))],
                     constraints=[sf.Weld3D(cantilever.point(0.0)),
                                  sf.Revolute3D(cantilever.point(1.0), wheel.point((0.0, 0.0, -0.1)), axis=(0, 0, 1))])
    drift = []
    for dt in (0.02, 0.01):
        res = sf.simulate(scene, 1.0, dt, scheme="energy-momentum")
        spin = np.array([wheel.body_angular_velocity(scene.coordinates(wheel, q), scene.coordinates(wheel, v))[2]
                         for q, v in zip(res.q, res.v)])
        tip = np.array([cantilever.point(1.0).position(scene.coordinates(cantilever, q))[0] for q in res.q])
        E = np.asarray(res.total_energy)
        assert np.ptp(E) <= 1e-11 * np.abs(E).max() and tip.min() < -0.1
        drift.append(np.abs(spin - 30.0).max() / 30.0)
    assert drift[1] <= 5e-5 and 3.0 <= drift[0] / drift[1] <= 5.0


@pytest.mark.parametrize("joint, closed_form", [("weld", 1.0 / 192.0), ("hinge", 7.0 / 768.0)])
def test_statics_through_a_joint_to_another_body(joint, closed_form):
    """The beam's frame welded at the root, its tip joined to a rigid block (welded to the ground) by a weld
    (clamped–clamped) or by a hinge about the normal of the bending plane (propped: the hinge passes no moment
    about its axis): the mid-span deflection under P is P L³/(192 EI) or 7 P L³/(768 EI) (1e-4); the rows
    between the beam's tip and the block are product rows."""
    sec = SpatialSection(EA=1e9, GA1=1e9, GA2=1e9, GJ=1e3, EI1=1e3, EI2=1e3, rhoA=1.0, rhoI1=1e-4, rhoI2=1e-4)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 9)), sec, order=2)
    body = FloatingBeam3D(beam, strain="linear")
    block = sf.SpatialRigidBody(1.0, (0.1, 0.1, 0.1), position=(0.0, 0.0, 2.5), name="block")
    P, L, EI = 1e-3, 2.0, 1e3
    end = block.point((0.0, 0.0, -0.5))
    held = (sf.Weld3D(body.point(L), end) if joint == "weld" else
            sf.Revolute3D(body.point(L), end, axis=(0.0, 1.0, 0.0)))
    assert held.products is not None
    scene = sf.Scene([body, block], constraints=[sf.Weld3D(body.point(0.0)), sf.Weld3D(end), held],
                     forces=[sf.SpatialPointForce(body.point(1.0), (P, 0.0, 0.0))])
    state = sf.static_equilibrium(scene)
    q = scene.coordinates(body, state.q)
    mid = body.point(1.0)
    assert (mid.position(q) - mid.position(body.q0))[0] == pytest.approx(closed_form * P * L ** 3 / EI, rel=1e-4)
    if joint == "hinge":                        # the propped end's reaction on the beam, −5P/16
        rows = scene.constraint_layout[scene.constraints.index(held)][1]
        assert held.reaction(state.q[np.r_[scene.slice(body), scene.slice(block)]], state.lam[rows])[0] == \
            pytest.approx(-5 * P / 16, rel=1e-3)


def test_hinge_at_a_rigid_interface_of_a_meshed_solid():
    """The reduced rotor (a meshed solid) with a rigid arm on a hinge about the shaft axis at its far end face
    (a rigid interface: its point and directions are quadratic in q, the hinge's rows product rows), spun up by
    the torque: the energy balance with the torque's work closes to round-off, the hinge holds, and the run is
    compiled throughout."""
    sc = sf.scenes.rotor_3d(unbalance=0.0)
    rotor = sc.bodies[0]
    face = rotor.point("far end")
    centre = face.position(rotor.q0)
    arm = sf.SpatialRigidBody(0.5, (1e-3, 2e-3, 2e-3), position=centre + np.array([0.05, 0.0, 0.0]), name="arm")
    hinge = sf.Revolute3D(face, arm.point((-0.05, 0.0, 0.0)), axis=(1.0, 0.0, 0.0))
    assert hinge.products is not None
    keep = [c for c in sc.constraints if not c.name.endswith("rigidity") and c.name != "bearing 2"]
    scene = sf.Scene(list(sc.bodies) + [arm], constraints=keep + [hinge], forces=list(sc.forces))
    res = sf.simulate(scene, 0.02, 1e-3, scheme="energy-momentum")
    assert not res.run_path["python_elements"]
    assert res.relative_energy_error() <= 1e-11 and np.max(res.constraint_residual) <= 1e-12
    assert np.abs(res.external_work).max() > 0.0
