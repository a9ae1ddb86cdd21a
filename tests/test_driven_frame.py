"""A spatial body's frame driven by prescribed laws (``driven_frame``): the laws are a rotation with its
derivatives, the scene leaves out the rigidity equations they hold, and the motion is the one a hinge and a
rate driver give."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import skfem_flex as sf
from skfem_flex.apps import peer_ffrf_beam
from skfem_flex.compiled.pack import time_table
from skfem_flex.elements.constraints.spatial_joints import RotationDriver
from skfem_flex.elements.motion import MotionLaw, Prescribed, driven_frame, spin_up_law
from skfem_flex.bodies.spatial import SpatialRigidBody


@pytest.fixture(scope="module")
def beam_data():
    return peer_ffrf_beam.beam_data(n_elements=4, n_modes=4)


def _body():
    R = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    return SpatialRigidBody(2.0, np.diag([0.1, 0.2, 0.3]), position=(0.1, 0.2, -0.3), orientation=R, name="rotor")


def test_laws_are_the_rotation_about_the_axis_and_its_derivatives():
    body = _body()
    axis = np.array([1.0, 2.0, 2.0])
    angle = spin_up_law(omega=3.0, period=2.0)             # a law with a branch: not vectorized
    laws = driven_frame(body, axis, angle)
    assert len(laws) == 12 and [p.coordinate for p in laws] == list(range(12))
    q0 = body.q0
    for t in (0.0, 0.7, 1.3, 2.5):
        th, w, al = angle(t)
        R = Rotation.from_rotvec(th * axis / 3.0).as_matrix()
        q = np.array([p.law(t)[0] for p in laws])
        assert np.allclose(q[:3], q0[:3], rtol=0, atol=1e-15)
        D = q[3:].reshape(3, 3).T
        assert np.allclose(D, R @ q0[3:].reshape(3, 3).T, rtol=0, atol=1e-14)
        assert np.allclose(D.T @ D, np.eye(3), rtol=0, atol=1e-14)
        # rates and accelerations against central differences of the laws' own values
        e = 1e-5
        for p in laws[3:]:
            x0, v0, a0 = p.law(t)
            assert v0 == pytest.approx((p.law(t + e)[0] - p.law(t - e)[0]) / (2 * e), abs=1e-8)
            assert a0 == pytest.approx((p.law(t + e)[1] - p.law(t - e)[1]) / (2 * e), abs=1e-7)


def test_a_vectorized_law_tables_what_its_calls_give():
    laws = driven_frame(_body(), (0.0, 0.0, 1.0), MotionLaw.constant_rate(2.5, start=0.0))
    times = np.linspace(0.0, 3.0, 13)
    for p in laws:
        assert p.law.vectorized
        assert np.array_equal(p.law.table(times), np.array([p.law(t) for t in times]).T)
    slow = driven_frame(_body(), (0.0, 0.0, 1.0), spin_up_law(2.0, 1.0))
    assert not slow[5].law.vectorized
    assert np.array_equal(slow[5].law.table(times), np.array([slow[5].law(t) for t in times]).T)
    # the time table of a chunk takes a law's three columns from one evaluation
    columns = [("end", laws[4].law, c) for c in range(3)]
    hs = np.full(12, 0.25)
    table = time_table(columns, times, hs, False)
    assert np.array_equal(table, np.array([laws[4].law(t) for t in times]))


def test_the_scene_leaves_out_the_rigidity_the_laws_hold(beam_data):
    driven = peer_ffrf_beam.scene(beam_data, probe=False, hub="driven")
    joints = peer_ffrf_beam.scene(beam_data, probe=False, hub="joints")
    nf = driven.n - 12
    assert driven.n_constraints == 0 and driven.free_index.size == nf
    assert joints.n_constraints == 12 and joints.free_index.size == driven.n
    # the origin and d₁ alone prescribed: only d₁·d₁ = 1 is held by the laws, the other five stay rows
    body = _body()
    held = [Prescribed(body, c, MotionLaw.constant_rate(0.0, float(body.q0[c]))) for c in range(6)]
    scene = sf.Scene([body], constraints=[RotationDriver(body, None, body.q0[3:6], MotionLaw.constant_rate(1.0))],
                     prescribed=held)
    assert scene.n_constraints == 5 + 1
    assert scene.constraints[0].n_equations == 5


def test_driven_and_hinged_hubs_move_the_beam_alike(beam_data):
    G = peer_ffrf_beam.tip_map(beam_data)
    tight = sf.NewtonSettings(rtol=1e-12, ctol=1e-12, etol=1e-12)
    for scheme in ("energy-momentum", "trapezoidal"):
        runs = [sf.simulate(peer_ffrf_beam.scene(beam_data, probe=False, hub=hub), t_end=0.3, dt=0.01,
                            scheme=scheme, newton=tight) for hub in peer_ffrf_beam.HUBS]
        tips = [r.q[:, 12:] @ G.T for r in runs]
        swing = np.abs(tips[0] - tips[0][0]).max()
        assert swing > 1e-3                                  # the beam does move
        assert np.abs(tips[0] - tips[1]).max() < 1e-9 * (swing + 1.0)
        # the driven frame is the laws' rotation at every step, Rz(Ωt) of the start
        ang = np.arctan2(runs[1].q[:, 10], runs[1].q[:, 9])
        assert np.abs(ang - beam_data["parameters"]["omega"] * runs[1].t).max() < 1e-13
        if scheme == "energy-momentum":
            # position-level rows: the hinged frame is there too (the trapezoidal rule holds its rows at
            # velocity level, and its angle drifts by O(Δt²) a step)
            assert np.abs(runs[0].q[:, :12] - runs[1].q[:, :12]).max() < 1e-12


def test_energy_balance_holds_with_the_laws_work(beam_data):
    scene = peer_ffrf_beam.scene(beam_data, probe=False, hub="driven")
    r = sf.simulate(scene, t_end=0.5, dt=0.01, scheme="energy-momentum",
                    newton=sf.NewtonSettings(rtol=1e-12, ctol=1e-12, etol=1e-13))
    assert np.abs(r.external_work).max() > 1e-6 * np.abs(r.total_energy).max()   # the hub does work
    assert r.relative_energy_error() < 1e-10


def test_compiled_and_python_paths_agree(beam_data):
    scene = peer_ffrf_beam.scene(beam_data, probe=False, hub="driven")
    a = sf.simulate(scene, t_end=0.05, dt=0.01, scheme="energy-momentum")
    b = sf.simulate(peer_ffrf_beam.scene(beam_data, probe=False, hub="driven"), t_end=0.05, dt=0.01,
                    scheme="energy-momentum", compiled=False)
    assert a.run_path["loop"] == "compiled"
    assert np.abs(a.q - b.q).max() < 1e-10


def test_bad_input_is_named():
    body = _body()
    with pytest.raises(ValueError, match="axis must be a finite nonzero 3-vector"):
        driven_frame(body, (0.0, 0.0, 0.0), MotionLaw.constant_rate(1.0))
    with pytest.raises(ValueError, match="angle must be a MotionLaw"):
        driven_frame(body, (0.0, 0.0, 1.0), lambda t: t)
    with pytest.raises(ValueError, match="three director coordinates"):
        driven_frame(sf.SpatialPointMass(1.0, (0.0, 0.0, 0.0)), (0.0, 0.0, 1.0), MotionLaw.constant_rate(1.0))
    with pytest.raises(ValueError, match="not orthonormal at the start"):
        sf.Scene([body], prescribed=[Prescribed(body, c, MotionLaw.constant_rate(0.0, 1.0)) for c in range(3, 12)])
    with pytest.raises(ValueError, match="hub must be one of"):
        peer_ffrf_beam.scene(peer_ffrf_beam.beam_data(n_elements=2, n_modes=2), hub="free")
