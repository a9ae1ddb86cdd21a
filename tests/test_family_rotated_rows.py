"""The family of lines on moving bodies (skfem_flex/compiled/families/rotated_rows.py): sliders and prismatic
joints guided by a rigid bar, by a floating-frame beam's section and by an exact beam's node.

1. Kernel against the specification (compiled/tasks.py): at random states, unknowns and multipliers the Newton
   matrix is the central difference of the residual under energy-momentum (position rows, D(q₀, q₁)ᵀμ),
   trapezoidal (velocity rows: ∂(Φ_q v)/∂q) and generalized-α (position rows at q₁); the residual's constraint
   force and rows are the constraints' numpy contract (constraint_discrete_gradient, constraint_value,
   constraint_jacobian); the recorded constraint residuals (TASK_ROWS) are the numpy Φ and Φ_q v.
2. Trajectories of a mechanism with lines that turn (and, on the beam, move with its deformation) equal the
   old Python path under every scheme.
3. Energy balance of the energy-momentum scheme (ideal scleronomic joints do no work) while the lines turn.
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
#: the residual against the numpy contract
PARTS_TOL = 1e-10
#: trajectories against the old Python path, relative to the largest |q|
RUN_TOL = 1e-10

SEC = dict(EA=1e5, EI=50.0, kGA=3e4, rhoA=1.0, rhoI=1e-3)


def bar_slider():
    """A point mass on a line along a free bar (rigid: a LINEAR map and the bar's angle)."""
    guide = sf.RigidBody.bar(1.0, 2.0, start=(-1.0, 0.0), angle=0.3, name="guide")
    m = sf.PointMass(0.4, [0.5, 0.0])
    return sf.Scene([guide, m], constraints=[sf.Slider(m.point(), (1.0, 0.0), on=guide.point())])


def beam_prismatic():
    """A block on a prismatic joint along a floating-frame beam's section (a FRAME map; the section's angle θ + w')."""
    beam = hub_beam(length=1.0, n_elements=3, **SEC)
    block = sf.RigidBody.bar(0.3, 0.2, start=(0.4, 0.0), angle=0.0, name="block")
    return sf.Scene([beam, block], constraints=[sf.Prismatic(block.point(), (1.0, 0.0), on=beam.point(0.5))])


def exact_slider():
    """A point mass on a line through an exact beam's node, turning with its section (a Cayley coordinate)."""
    beam = sf.ExactBeam.from_points(sf.Section(EA=1e4, EI=100.0, kGA=1e4, rhoA=1.0, rhoI=1.0), (0.0, 0.0),
                                    (1.0, 0.0), n_elements=2, name="beam")
    m = sf.PointMass(0.3, [0.7, 0.0])
    return sf.Scene([beam, m], constraints=[sf.Slider(m.point(), (1.0, 0.0), on=beam.point(0.5))])


SCENES = {"bar": bar_slider, "beam": beam_prismatic, "exact beam": exact_slider}


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
@pytest.mark.parametrize("kind", list(SCENES))
def test_step_is_the_constraints_contract(kind, scheme):
    scene = SCENES[kind]()
    rng = np.random.default_rng(7)
    q0, v0 = random_scene_state(scene, rng)
    h, m, nf = 0.02, scene.n_constraints, scene.n
    st = loaded_stepper(scene, scheme, q0, v0, acc=rng.normal(size=q0.size))
    dq = h * v0 + 1e-2 * rng.normal(size=nf)
    mu = rng.normal(size=m)
    x = np.concatenate([dq, mu])
    mismatch, r, _ = fd_mismatch(st, 0.0, h, x)
    assert mismatch < FD_TOL
    # the constraint force is linear in μ: r(μ) − r(0) = D(q_a, q_b)ᵀ μ
    r0 = st.evaluate(0.0, h, np.concatenate([dq, np.zeros(m)]))[0]
    q1 = q0 + dq
    if scheme == "energy-momentum":
        dmat, rows = dense(scene.constraint_discrete_gradient(q0, q1, 0.5 * h)), scene.constraint_value(q1, h)
    else:
        dmat = dense(scene.constraint_jacobian(q1, h))
        rows = scene.constraint_value(q1, h)
        if scheme == "trapezoidal":               # velocity rows (Φ_q v₁)/c_v, c_v = γ/(βΔt)
            a1 = (dq - h * v0 - 0.25 * h * h * st.data.array("pseudo")) / (0.25 * h * h)
            v1 = v0 + 0.5 * h * (st.data.array("pseudo") + a1)
            rows = dmat @ v1 / (2.0 / h)
    force = dmat.T @ mu
    if scheme == "energy-momentum":             # the scheme's scaling of the Cayley rows: conjugate to their rate
        cay = np.asarray(scene.cayley_index, dtype=int)
        force[cay] *= cayley_ratio(dq[cay])
    assert np.abs((r - r0)[:nf] - force).max() <= PARTS_TOL * np.abs(force).max()
    assert np.abs(r[nf:] - rows).max() <= PARTS_TOL * max(np.abs(dmat).max() * np.abs(q1).max(), np.abs(rows).max())


def sliding_mechanism():
    """A bar pinned at its centre, turning, with a point mass sliding along it, and a block riding a prismatic
    joint along a section of a pinned flexible beam, under gravity: lines that turn, and on the beam move with
    its deformation."""
    guide = sf.RigidBody.bar(1.0, 2.0, start=(-1.0, 0.0), angle=0.0, name="guide")
    guide.v0[2] = 2.0
    m = sf.PointMass(0.4, [0.5, 0.0])
    m.v0[:] = (0.3, 1.0)                         # on the line and turning with it: ṙ = ω E r + u̇ d
    beam = hub_beam(length=1.0, n_elements=4, **SEC)
    beam.q0[:2] = (0.0, -1.0)
    block = sf.RigidBody.bar(0.3, 0.2, start=(0.4, -1.0), angle=0.0, name="block")
    cons = [sf.Pin(guide.point(), (0.0, 0.0)), sf.Slider(m.point(), (1.0, 0.0), on=guide.point()),
            sf.Pin(beam.point(0.0), (0.0, -1.0)), sf.Prismatic(block.point(), (1.0, 0.0), on=beam.point(0.5))]
    return sf.Scene([guide, m, beam, block], constraints=cons, forces=[sf.Gravity()], name="sliding mechanism")


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_trajectories_equal_the_python_path(scheme):
    rec, ref = run_both(sliding_mechanism, scheme, 2e-3, 100)
    assert rel_dev(rec.q, ref.q[1:]) < RUN_TOL
    assert rel_dev(rec.v, ref.v[1:]) < 1e3 * RUN_TOL
    assert rel_dev(rec.lam, ref.lam[1:]) < 1e4 * RUN_TOL     # λ carries the stiff beam's forces
    assert np.ptp(rec.q[:, 2]) > 0.1 and np.abs(rec.lam).max() > 0      # the lines turned and carried loads


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_recorded_constraint_residuals(scheme):
    """TASK_ROWS at the recorded states: max|Φ| and max|Φ_q v| are the numpy constraint_value and
    constraint_jacobian's (both at round-off, or Φ at the velocity-level scheme's drift)."""
    scene = sliding_mechanism()
    rec, _ = run_new(scene, scheme, 2e-3, 20)
    for i, (q, v) in enumerate(zip(rec.q, rec.v)):
        phi = np.abs(scene.constraint_value(q, rec.t[i])).max()
        rate = np.abs(dense(scene.constraint_jacobian(q, rec.t[i])) @ v).max()
        assert abs(rec.derived[i, 8] - phi) <= 1e-13 and abs(rec.derived[i, 9] - rate) <= 1e-12


def test_energy_balance():
    """Energy-momentum: T + V stays E₀ to the Newton tolerance (ideal joints, gravity, elastic beam)."""
    rec, _ = run_new(sliding_mechanism(), "energy-momentum", 2e-3, 150)
    energy = rec.derived[:, 0] + rec.derived[:, 1]
    assert np.abs(energy - energy[0]).max() <= 1e-8 * rec.derived[:, 0].max()
