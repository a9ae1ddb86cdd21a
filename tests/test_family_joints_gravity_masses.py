"""Five families of the compiled core: point constraints (skfem_flex/compiled/families/point_rows.py: forms
"points" and "projected" — Pin, Revolute, the position rows of Weld, Slider and Prismatic on the ground), linear
constraint rows (linear_rows.py: the angle rows of Weld and Prismatic, Driver of a coordinate, of a section's
angle and of a relative angle with its motion law), distance constraints (distance_rows.py: Distance), gravity
(gravity.py: the first moments of point masses, rigid bodies, exact beams — linear maps — and floating-frame
beams — frame maps) and constant-mass bodies (constant_mass.py: the momenta of point masses in one and two
dimensions, rigid bodies and exact beams).

1. Kernels against the specification (compiled/tasks.py), for every element kind in a minimal scene at a random
   state, unknowns and multipliers (seeded), under energy-momentum, trapezoidal and generalized-α: the Newton
   matrix is the central difference of the residual (family_checks.fd_mismatch, ≤ 1e-10 of each row's scale),
   and the residual's parts are the numpy contract (≤ 1e-10): the constraint force r(μ) − r(0) = Dᵀμ and the
   rows Φ(q₁, t₁) | (Φ_q v₁ + Φ_t)/c_v with D = constraint_discrete_gradient(q₀, q₁) | constraint_jacobian(q₁),
   and the recorded constraint residuals (TASK_ROWS) max|Φ|, max|Φ_q v + Φ_t|; gravity's part g_p of the
   residual is Gravity.potential_discrete_gradient(q₀, q₁) | potential_gradient(q₁) and its recorded potential
   is Gravity.potential_energy; the recorded T, p and L of a constant-mass body are ½vᵀMv, linear_momentum and
   angular_momentum of the numpy body (and p_z = L_x = L_y = 0).
2. Trajectories: ≤ 100 steps of a small mechanism per family equal the Python path (sf.simulate(...,
   compiled=False): every element through its numpy methods) in q to 1e-10 relative under all three schemes
   (and the recorded momenta, for the constant-mass bodies).
3. Physics of the energy-momentum scheme, to the Newton tolerance: T + V is conserved by ideal joints, distance
   constraints and gravity; with drivers E − E₀ is the recorded work, itself −Σ λ̄ Δx of the drivers' laws; free
   bodies hinged together keep their linear and angular momenta.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.numerics.rotations import cayley_ratio
from skfem_flex.scenes.rotating import hub_beam

from family_checks import dense, fd_mismatch, loaded_stepper, rel_dev, run_both, run_new
from helpers import random_scene_state

#: the Newton matrix against central differences, relative to each row's largest entry (family_checks)
FD_TOL = 1e-10
#: the residual's parts and the records against the numpy contract
PARTS_TOL = 1e-10
#: trajectories against the Python path, relative to the largest |q|
RUN_TOL = 1e-10
#: energy and momentum balances of the energy-momentum scheme, relative to their scale (Newton tolerance)
BALANCE_TOL = 1e-8

SCHEME_NAMES = ("energy-momentum", "trapezoidal", "generalized-alpha")
SEC = dict(EA=1e5, EI=50.0, kGA=3e4, rhoA=1.0, rhoI=1e-3)


# ==================================================================== bodies and laws
def bar(mass=1.0, length=1.0, start=(0.0, 0.0), angle=0.3, name="bar"):
    return sf.RigidBody.bar(mass, length, start=start, angle=angle, name=name)


def point_mass(position=(0.3, -0.4), mass=0.5, name="mass"):
    return sf.PointMass(mass, list(position), name=name)


def beam(n_elements=2, origin=(0.0, 0.0), angle=0.0, name="beam"):
    """A floating-frame beam of length 1 (frame maps: its points and its first moment)."""
    b = hub_beam(length=1.0, n_elements=n_elements, name=name, **SEC)
    b.q0[:3] = (origin[0], origin[1], angle)
    return b


def exact_beam(start=(0.0, 0.0), end=(1.0, 0.0), name="exact"):
    """An exact beam on 2 elements (linear maps; Cayley coordinates ψ)."""
    return sf.ExactBeam.from_points(sf.Section(EA=1e4, EI=100.0, kGA=1e4, rhoA=1.0, rhoI=1.0), start, end,
                                    n_elements=2, name=name)


def law(x0, amplitude, omega):
    """x(t) = x₀ + a (1 − cos ωt): starts at rest at x₀."""
    return sf.MotionLaw(lambda t: x0 + amplitude * (1.0 - np.cos(omega * t)),
                        lambda t: amplitude * omega * np.sin(omega * t),
                        lambda t: amplitude * omega ** 2 * np.cos(omega * t))


def scene(bodies, constraints=(), forces=()):
    return sf.Scene(list(bodies), constraints=list(constraints), forces=list(forces))


# ==================================================================== minimal scenes per element kind
def pin_mass():
    m = point_mass()
    return scene([m], [sf.Pin(m.point(), (0.2, -0.5))])


def pin_bar():
    a = bar()
    return scene([a], [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0))])


def revolute_bar_mass():
    a, m = bar(), point_mass((1.0, 0.3))
    return scene([a, m], [sf.Revolute(a.point((0.5, 0.0)), m.point())])


def revolute_bar_beam():
    a, b = bar(start=(-1.0, 0.0), angle=0.0), beam()
    return scene([a, b], [sf.Revolute(a.point((0.5, 0.0)), b.point(0.0))])


def revolute_exact_bar():
    e, a = exact_beam(), bar(start=(1.0, 0.0), angle=-0.4)
    return scene([e, a], [sf.Revolute(e.point(1.0), a.point((-0.5, 0.0)))])


def weld_bars():
    a, b = bar(), bar(0.6, 0.8, start=(np.cos(0.3), np.sin(0.3)), angle=-0.8, name="b")
    return scene([a, b], [sf.Weld(a.point((0.5, 0.0)), b.point((-0.4, 0.0)))])


def weld_ground():
    a = bar()
    return scene([a], [sf.Weld(a.point((-0.5, 0.0)))])


def slider_mass():
    m = point_mass()
    return scene([m], [sf.Slider(m.point(), (1.0, 0.4))])


def prismatic_bar():
    a = bar()
    return scene([a], [sf.Prismatic(a.point((0.2, 0.05)), (0.8, -0.3))])


def weld_beam_bar():
    b, a = beam(), bar(start=(1.0, 0.0), angle=0.2)
    return scene([b, a], [sf.Weld(b.point(1.0), a.point((-0.5, 0.0)))])


def driver_coordinate():
    a = bar()
    return scene([a], [sf.Driver(a, law(0.3, 0.5, 3.0), coordinate="theta")])


def driver_relative_angle():
    b, a = beam(), bar(start=(1.0, 0.0), angle=0.2)
    return scene([b, a], [sf.Driver(b.point(0.7), law(-0.2, 0.4, 2.0), relative_to=a.point())])


def driver_exact_section():
    e = exact_beam()
    return scene([e], [sf.Driver(e.point(0.5), law(0.0, 0.6, 4.0))])


def distance_mass():
    m = point_mass((0.6, -0.8))
    return scene([m], [sf.Distance(m, (0.1, 0.2), 0.9)])


POINT_ROWS, LINEAR_ROWS, DISTANCE_ROWS = "point constraints", "linear constraint rows", "distance constraints"

#: name: (scene factory, the constraint families it packs)
CONSTRAINT_KINDS = {
    "pin, point mass": (pin_mass, {POINT_ROWS}),
    "pin, bar": (pin_bar, {POINT_ROWS}),
    "revolute, bar-mass": (revolute_bar_mass, {POINT_ROWS}),
    "revolute, bar-beam": (revolute_bar_beam, {POINT_ROWS}),
    "revolute, exact beam-bar": (revolute_exact_bar, {POINT_ROWS}),
    "weld, bar-bar": (weld_bars, {POINT_ROWS, LINEAR_ROWS}),
    "weld, bar-ground": (weld_ground, {POINT_ROWS, LINEAR_ROWS}),
    "slider, point mass on the ground": (slider_mass, {POINT_ROWS}),
    "prismatic, bar on the ground": (prismatic_bar, {POINT_ROWS, LINEAR_ROWS}),
    "weld, beam section-bar": (weld_beam_bar, {POINT_ROWS, LINEAR_ROWS}),
    "driver, coordinate": (driver_coordinate, {LINEAR_ROWS}),
    "driver, relative angle": (driver_relative_angle, {LINEAR_ROWS}),
    "driver, exact beam section": (driver_exact_section, {LINEAR_ROWS}),
    "distance": (distance_mass, {DISTANCE_ROWS}),
}

#: bodies for gravity (linear first moments: point mass, rigid body, exact beam; frame: floating-frame beam)
GRAVITY_BODIES = {
    "point mass": point_mass,
    "rigid body": bar,
    "floating-frame beam": lambda: beam(angle=-0.4),
    "exact beam": exact_beam,
}
G = (1.5, -9.81)

#: constant-mass bodies (the family records their momenta)
MASS_BODIES = {
    "point mass": point_mass,
    "1-D point mass": lambda: sf.PointMass(0.7, [0.4], name="line mass"),
    "rigid body": bar,
    "exact beam": exact_beam,
}


def families_of(st):
    assert not st.packed.python_elements          # every element in a compiled family
    return {f[0].NAME for f in st.packed.families}


def stepper_at_start(sc, scheme):
    """A stepper of ``sc`` loaded with its initial state."""
    return loaded_stepper(sc, scheme, *sc.initial_state())


def random_step(sc, scheme, seed, h):
    """A stepper of ``sc`` loaded with a random state (and pseudo-acceleration), and random unknowns
    x = (Δq = Δt v₀ + 0.01 N, μ = N): (stepper, q₀, v₀, x); the acceleration is ``st.acc``."""
    rng = np.random.default_rng(seed)
    q0, v0 = random_scene_state(sc, rng)
    acc = rng.normal(size=q0.size)
    st = loaded_stepper(sc, scheme, q0, v0, acc=acc)
    st.acc = acc
    dq = h * v0 + 1e-2 * rng.normal(size=sc.n)
    mu = rng.normal(size=sc.n_constraints)
    return st, q0, v0, np.concatenate([dq, mu])


# ==================================================================== 1. kernels against the specification
@pytest.mark.parametrize("scheme", SCHEME_NAMES)
@pytest.mark.parametrize("kind", list(CONSTRAINT_KINDS))
def test_constraint_step_is_the_numpy_contract(kind, scheme):
    """Newton matrix = ∂r/∂x; r(μ) − r(0) = Dᵀμ (energy-momentum: D(q₀, q₁), with the Cayley rows scaled by
    Δψ/z; Newmark: Φ_q(q₁)); the rows Φ(q₁, t₁) (trapezoidal: (Φ_q v₁ + Φ_t)/c_v, c_v = 2/Δt); the recorded
    max|Φ| and max|Φ_q v + Φ_t| at the loaded state."""
    factory, expected = CONSTRAINT_KINDS[kind]
    sc = factory()
    h, nf, t1 = 0.02, sc.n, 0.02
    st, q0, v0, x = random_step(sc, scheme, 7, h)
    assert expected <= families_of(st)
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL, mismatch
    dq, mu = x[:nf], x[nf:]
    r0 = st.evaluate(0.0, h, np.concatenate([dq, np.zeros(mu.size)]))[0]
    q1 = q0 + dq
    rows = sc.constraint_value(q1, t1)
    if scheme == "energy-momentum":
        dmat = dense(sc.constraint_discrete_gradient(q0, q1, t1))
    else:
        dmat = dense(sc.constraint_jacobian(q1, t1))
        if scheme == "trapezoidal":               # velocity rows (Φ_q v₁ + Φ_t)/c_v
            a0 = st.acc
            a1 = (dq - h * v0 - 0.25 * h * h * a0) / (0.25 * h * h)
            v1 = v0 + 0.5 * h * (a0 + a1)
            rows = (dmat @ v1 + sc.constraint_time_derivative(q1, t1)) / (2.0 / h)
    force = dmat.T @ mu
    if scheme == "energy-momentum":             # rows of Cayley coordinates: conjugate to their rate
        cay = np.asarray(sc.cayley_index, dtype=int)
        force[cay] *= cayley_ratio(dq[cay])
    assert np.abs((r - r0)[:nf] - force).max() <= PARTS_TOL * np.abs(force).max()
    scale = max(np.abs(dmat).max() * np.abs(q1).max(), np.abs(rows).max())
    assert np.abs(r[nf:] - rows).max() <= PARTS_TOL * scale
    # TASK_ROWS at the loaded state, at a time where the laws move
    t = 0.3
    d = st.record_now(t).derived[0]
    phi = sc.constraint_value(q0, t)
    rate = dense(sc.constraint_jacobian(q0, t)) @ v0 + sc.constraint_time_derivative(q0, t)
    assert abs(d[8] - np.abs(phi).max()) <= PARTS_TOL * scale
    assert abs(d[9] - np.abs(rate).max()) <= PARTS_TOL * max(np.abs(dmat).max() * np.abs(v0).max(), 1.0)


def gravity_scene(kind, with_gravity=True):
    return scene([GRAVITY_BODIES[kind]()], forces=[sf.Gravity(G)] if with_gravity else [])


def numpy_gravity(sc, q0, q1, scheme):
    """The Gravity elements' g_p: potential_discrete_gradient(q₀, q₁) (energy-momentum) or ∇V(q₁)."""
    out = np.zeros(sc.n)
    for f, idx in sc.conservative_forces:
        idx = np.asarray(idx)
        g = f.potential_discrete_gradient(q0[idx], q1[idx])[0] if scheme == "energy-momentum" \
            else f.potential_gradient(q1[idx])
        np.add.at(out, idx, g)
    return out


@pytest.mark.parametrize("scheme", SCHEME_NAMES)
@pytest.mark.parametrize("kind", list(GRAVITY_BODIES))
def test_gravity_step_is_the_numpy_gravity(kind, scheme):
    """Newton matrix = ∂r/∂x; with gravity minus without: g_p is the Gravity element's numpy discrete gradient
    (Newmark: gradient at q₁), the residual differs by Δt g_p, the recorded potential by Gravity.potential_energy."""
    sc, bare = gravity_scene(kind), gravity_scene(kind, False)
    h, n = 0.02, sc.n
    st, q0, v0, x = random_step(sc, scheme, 11, h)
    assert "gravity" in families_of(st) and "gravity" not in families_of(stepper_at_start(bare, scheme))
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL, mismatch
    gp = st.ws.vectors["gp"][:n].copy()
    st0 = loaded_stepper(bare, scheme, q0, v0, acc=st.acc)
    r0 = st0.evaluate(0.0, h, x)[0]
    gp0 = st0.ws.vectors["gp"][:n].copy()
    expected = numpy_gravity(sc, q0, q0 + x, scheme)
    assert np.abs(gp - gp0 - expected).max() <= PARTS_TOL * np.abs(expected).max()
    assert np.abs(r - r0 - h * expected).max() <= PARTS_TOL * h * np.abs(expected).max()
    potential = sum(f.potential_energy(q0[np.asarray(idx)]) for f, idx in sc.conservative_forces)
    v_rec = st.record_now(0.0).derived[0, 1] - st0.record_now(0.0).derived[0, 1]
    assert abs(v_rec - potential) <= PARTS_TOL * max(abs(potential), 1.0)


@pytest.mark.parametrize("scheme", SCHEME_NAMES)
@pytest.mark.parametrize("kind", list(MASS_BODIES))
def test_constant_mass_step_and_records(kind, scheme):
    """Newton matrix = ∂r/∂x (the scheme's constant-mass inertia); the recorded T, p_x, p_y, L are ½vᵀMv,
    linear_momentum and angular_momentum of the numpy body, p_z = L_x = L_y = 0."""
    body = MASS_BODIES[kind]()
    sc = scene([body])
    h = 0.02
    st, q0, v0, x = random_step(sc, scheme, 13, h)
    assert "constant-mass bodies" in families_of(st)
    mismatch = fd_mismatch(st, 0.0, h, x)[0]
    assert mismatch < FD_TOL, mismatch
    d = st.record_now(0.0).derived[0]
    p = dense(body.mass_matrix(q0)) @ v0
    assert abs(d[0] - 0.5 * v0 @ p) <= PARTS_TOL * (np.abs(v0) @ np.abs(p))
    lin, ang = body.linear_momentum(q0, v0), body.angular_momentum(q0, v0)
    scale = np.abs(p).max() * max(np.abs(q0).max() + 1.0, 1.0)
    assert np.abs(d[2:4] - lin).max() <= PARTS_TOL * scale
    assert abs(d[7] - ang) <= PARTS_TOL * scale
    assert np.all(d[4:7] == 0.0)
    assert np.abs(lin).max() > 0.1 and (abs(ang) > 0.1 or body.n_dofs == 1)


# ==================================================================== mechanisms
def joints_mechanism():
    """A slider-crank under gravity (crank pinned, coupler on revolute joints, a point mass on a ground slider,
    a plate welded to the coupler) and a cart on a prismatic ground joint carrying a hinged pendulum."""
    crank = bar(1.0, 0.6, start=(0.0, 0.0), angle=0.5, name="crank")
    tip = 0.6 * np.array([np.cos(0.5), np.sin(0.5)])
    phi = -np.arcsin(tip[1] / 1.2)
    coupler = bar(0.8, 1.2, start=tip, angle=phi, name="coupler")
    end = tip + 1.2 * np.array([np.cos(phi), np.sin(phi)])
    slider = point_mass(end, 0.5, name="slider")
    centre = tip + 0.6 * np.array([np.cos(phi), np.sin(phi)])
    plate = bar(0.3, 0.4, start=centre, angle=phi + 1.2, name="plate")
    cart = bar(1.0, 0.3, start=(2.5, -1.0), angle=0.0, name="cart")
    cart.v0[:] = (0.5, 0.0, 0.0)
    pend = bar(0.4, 0.7, start=(2.65, -1.0), angle=-1.0, name="pendulum")
    pend.v0[:] = (0.5, 0.0, 0.0)
    cons = [sf.Pin(crank.point((-0.3, 0.0)), (0.0, 0.0)),
            sf.Revolute(crank.point((0.3, 0.0)), coupler.point((-0.6, 0.0))),
            sf.Revolute(coupler.point((0.6, 0.0)), slider.point()),
            sf.Slider(slider.point(), (1.0, 0.0)),
            sf.Weld(plate.point((-0.2, 0.0)), coupler.point()),
            sf.Prismatic(cart.point(), (1.0, 0.0)),
            sf.Revolute(cart.point(), pend.point((-0.35, 0.0)))]
    return sf.Scene([crank, coupler, slider, plate, cart, pend], constraints=cons, forces=[sf.Gravity()],
                    name="joints")


DRIVER_LAWS = (law(0.2, 0.5, 3.0), law(-0.2, 0.4, 2.0))


def driven_mechanism():
    """A crank pinned and driven in angle, a bar hinged to its tip with a plate welded on, and a second pinned
    bar whose angle relative to the crank is driven; gravity."""
    a = bar(1.0, 0.8, start=(0.0, 0.0), angle=0.2, name="crank")
    tip = 0.8 * np.array([np.cos(0.2), np.sin(0.2)])
    b = bar(0.6, 0.7, start=tip, angle=-1.0, name="arm")
    b_tip = tip + 0.7 * np.array([np.cos(-1.0), np.sin(-1.0)])
    c = bar(0.3, 0.3, start=b_tip, angle=-0.2, name="plate")
    e = bar(0.5, 0.6, start=(2.0, 0.0), angle=0.0, name="rocker")
    cons = [sf.Pin(a.point((-0.4, 0.0)), (0.0, 0.0)),
            sf.Driver(a, DRIVER_LAWS[0], coordinate="theta"),
            sf.Revolute(a.point((0.4, 0.0)), b.point((-0.35, 0.0))),
            sf.Weld(c.point((-0.15, 0.0)), b.point((0.35, 0.0))),
            sf.Pin(e.point((-0.3, 0.0)), (2.0, 0.0)),
            sf.Driver(e.point(), DRIVER_LAWS[1], relative_to=a.point(), name="relative driver")]
    return sf.Scene([a, b, c, e], constraints=cons, forces=[sf.Gravity()], name="driven")


def distance_mechanism():
    """Two point-mass pendulums on distance constraints under gravity, one of them swinging."""
    m1 = point_mass((0.6, -0.8), 1.0, name="m1")
    m2 = sf.PointMass(0.5, [1.8, -0.4], [0.8, 0.6], name="m2")
    cons = [sf.Distance(m1, (0.0, 0.0), 1.0), sf.Distance(m2, (1.5, 0.0), 0.5)]
    return sf.Scene([m1, m2], constraints=cons, forces=[sf.Gravity()], name="pendulums")


def gravity_mechanism():
    """Under a slanted gravity: a bar pinned at its end, a floating-frame beam and an exact beam pinned at their
    roots (flexible pendulums) and a thrown point mass."""
    a = bar(1.0, 1.0, start=(0.0, 0.0), angle=-0.5, name="bar")
    b = beam(n_elements=2, origin=(2.0, 0.0), angle=-0.5)
    e = exact_beam((4.0, 0.0), (4.8, -0.6))
    m = sf.PointMass(0.4, [6.0, 0.0], [1.0, 2.0], name="ball")
    cons = [sf.Pin(a.point((-0.5, 0.0)), (0.0, 0.0)), sf.Pin(b.point(0.0), (2.0, 0.0)),
            sf.Pin(e.point(0.0), (4.0, 0.0))]
    return sf.Scene([a, b, e, m], constraints=cons, forces=[sf.Gravity((1.0, -9.81))], name="gravity")


def free_mechanism():
    """Free bodies, no gravity: two bars hinged together and a point mass hinged to the second, spinning; an
    exact beam and a 1-D point mass flying."""
    a = bar(1.0, 1.0, start=(0.0, 0.0), angle=0.0, name="a")
    a.v0[:] = (0.0, 0.0, 1.0)                     # turning about its centre (0.5, 0): its tip moves at (0, 0.5)
    start = np.array([1.0, 0.0])
    u = np.array([np.cos(0.5), np.sin(0.5)])
    b = bar(0.5, 0.6, start=start, angle=0.5, name="b")
    wb = -2.0
    b.v0[:] = (*(np.array([0.0, 0.5]) + wb * 0.3 * np.array([-u[1], u[0]])), wb)
    m = sf.PointMass(0.3, list(start + 0.6 * u), list(np.array([0.0, 0.5]) + wb * 0.6 * np.array([-u[1], u[0]])),
                     name="m")
    e = exact_beam((0.0, 2.0), (1.0, 2.5))
    e.v0[e.node_dofs[:, 0]] = 0.3
    e.v0[e.node_dofs[:, 1]] = -0.2
    line = sf.PointMass(0.7, [0.4], [0.5], name="line mass")
    cons = [sf.Revolute(a.point((0.5, 0.0)), b.point((-0.3, 0.0))), sf.Revolute(b.point((0.3, 0.0)), m.point())]
    return sf.Scene([a, b, m, e, line], constraints=cons, name="free")


MECHANISMS = {  # name: (factory, the family it is about, Δt)
    "joints": (joints_mechanism, POINT_ROWS, 5e-3),
    "driven": (driven_mechanism, LINEAR_ROWS, 5e-3),
    "distance": (distance_mechanism, DISTANCE_ROWS, 5e-3),
    "gravity": (gravity_mechanism, "gravity", 5e-3),
    "free": (free_mechanism, "constant-mass bodies", 5e-3),
}
STEPS = 100


# ==================================================================== 2. trajectories
@pytest.mark.parametrize("scheme", SCHEME_NAMES)
@pytest.mark.parametrize("name", list(MECHANISMS))
def test_trajectories_equal_the_python_path(name, scheme):
    """q (and v, λ, the recorded momenta) of the compiled core equal sf.simulate(..., compiled=False)."""
    factory, family, dt = MECHANISMS[name]
    assert family in families_of(stepper_at_start(factory(), scheme))
    rec, ref = run_both(factory, scheme, dt, STEPS)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL
    if rec.lam.size:
        assert rel_dev(rec.lam, ref.lam[1:]) < 1e4 * RUN_TOL
    assert np.abs(rec.q - rec.q[0]).max() > 0.05                  # it moved
    if name == "free":          # the numpy bodies' momenta of the Python path's states (its own records of
        sc = factory()          # p and L come from the same constant-mass family)
        states = list(zip(ref.q[1:], ref.v[1:]))
        assert rel_dev(rec.derived[:, 2:4], np.array([sc.linear_momentum(q, v) for q, v in states])) < RUN_TOL
        assert rel_dev(rec.derived[:, 7], np.array([sc.angular_momentum(q, v) for q, v in states])) < RUN_TOL
        assert rel_dev(rec.derived[:, 0], np.array([sc.kinetic_energy(q, v) for q, v in states])) < RUN_TOL


# ==================================================================== 3. physics
def initial_energy(sc):
    q0, v0 = sc.initial_state()
    return sc.kinetic_energy(q0, v0) + sc.potential_energy(q0)


@pytest.mark.parametrize("name", ["joints", "distance", "gravity"])
def test_energy_is_conserved(name):
    """Ideal joints, distance constraints and gravity (a potential) do no work: T + V = E₀."""
    factory, _, dt = MECHANISMS[name]
    sc = factory()
    rec, _ = run_new(sc, "energy-momentum", dt, 200)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    e0 = initial_energy(sc)
    scale = max(np.abs(rec.derived[:, 0]).max(), abs(e0))
    assert np.abs(energy - e0).max() <= BALANCE_TOL * scale
    assert np.abs(rec.work).max() <= BALANCE_TOL * scale
    assert np.ptp(rec.derived[:, 0]) > 0.1 * scale                 # energy went from V to T and back


def test_drivers_work():
    """E − E₀ = recorded work = −Σ λ̄ Δx over the drivers' rows (their laws' increments), to the Newton
    tolerance; the drivers did work."""
    sc = driven_mechanism()
    dt, steps = 5e-3, 200
    rec, _ = run_new(sc, "energy-momentum", dt, steps)
    energy = rec.derived[:, 0] + rec.derived[:, 1] - initial_energy(sc)
    scale = np.abs(energy).max()
    assert scale > 0.5
    assert np.abs(energy - rec.work).max() <= BALANCE_TOL * scale
    t = np.concatenate([[0.0], rec.t])
    drivers = [int(np.asarray(rows)[0]) for c, (_, rows) in zip(sc.constraints, sc.constraint_layout)
               if isinstance(c, sf.Driver)]
    assert len(drivers) == len(DRIVER_LAWS)
    work = np.zeros(steps)
    for row, lw in zip(drivers, DRIVER_LAWS):
        x = np.array([lw.position(s) for s in t])
        work -= np.cumsum(rec.lam[:, row] * np.diff(x))
    assert np.abs(rec.work - work).max() <= BALANCE_TOL * scale


def test_free_bodies_keep_their_momenta():
    """Free bodies hinged together: the recorded p, L and T (the constant-mass family's momenta) are the numpy
    bodies' (Scene.linear_momentum, angular_momentum, kinetic_energy) at every recorded state; p and T + V stay at
    their start values to round-off, L to the scheme's O(Δt²) (a midpoint rule on angle coordinates keeps L only
    to second order: the drift quarters when Δt halves)."""
    drift = []
    for dt, steps in ((1e-2, 100), (5e-3, 200)):
        sc = free_mechanism()
        rec, _ = run_new(sc, "energy-momentum", dt, steps)
        q0, v0 = sc.initial_state()
        p0, l0 = sc.linear_momentum(q0, v0), sc.angular_momentum(q0, v0)
        scale = max(np.abs(p0).max(), abs(l0))
        for i in range(0, steps, 20):
            q, v = rec.q[i], rec.v[i]
            assert np.abs(rec.derived[i, 2:4] - sc.linear_momentum(q, v)).max() <= PARTS_TOL * scale
            assert abs(rec.derived[i, 7] - sc.angular_momentum(q, v)) <= PARTS_TOL * scale
            assert abs(rec.derived[i, 0] - sc.kinetic_energy(q, v)) <= PARTS_TOL * rec.derived[i, 0]
        assert np.abs(rec.derived[:, 2:4] - p0).max() <= BALANCE_TOL * scale
        e0 = initial_energy(sc)
        assert np.abs(rec.derived[:, 0] + rec.derived[:, 1] - e0).max() <= BALANCE_TOL * e0
        drift.append(np.abs(rec.derived[:, 7] - l0).max() / abs(l0))
    assert drift[0] < 1e-7 and 3.5 < drift[0] / drift[1] < 4.5, drift
