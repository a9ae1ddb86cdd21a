"""The spatial exudyn peer models (skfem_flex.apps.peer_spatial): short runs against published references."""
import numpy as np
import pytest

pytest.importorskip("exudyn")

from skfem_flex.apps import peer_spatial  # noqa: E402

#: Euler parameters (e0, e1, e2, e3) of the Brüls top at t = 0.2 s (published RK4 reference at dt = 1e-4 s;
#: also skfem_flex.scenes.spatial.BRULS_REFERENCE)
BRULS_E = np.array([-0.708279152974, 0.438781088127, 0.545728396145, 0.089399752824])

#: P3 of Bricard's mechanism (IFToMM A04, square-section rods) at t = 0.2 s, m: the row t = 0.2 of the
#: reference P3 trajectory computed for our catalogue (one-degree-of-freedom Lagrange equation in the
#: loop's joint angles, DOP853 at rtol 1e-11; agrees with a converged exudyn run to 3.4e-7 m over 10 s)
BRICARD_P3_AT_0_2 = np.array([0.9613495506, -0.9992814034, -0.03790352082])


def test_bruls_top_euler_parameters_at_0_2_s():
    run = peer_spatial.heavy_top("bruls", dt=1e-4, t_end=0.2, scheme="generalized-alpha")
    t, com, _ = run()
    e = run.stats["euler_parameters"]
    assert t.shape == (2001,) and com.shape == (2001, 3) and e.shape == (2001, 4)
    assert np.allclose(com[0], [0.0, 1.0, 0.0])
    assert np.allclose(np.linalg.norm(com, axis=1), 1.0, atol=1e-9)      # the pivot holds
    assert t[-1] == pytest.approx(0.2)
    assert min(np.abs(e[-1] - BRULS_E).max(), np.abs(e[-1] + BRULS_E).max()) < 5e-4


def test_simo_wong_top_starts_tilted_and_keeps_its_distance_to_the_pivot():
    run = peer_spatial.heavy_top("simo-wong", dt=1e-3, t_end=0.05, scheme="trapezoidal")
    t, com, seconds = run()
    assert t.shape == (51,) and seconds >= 0.0 and run.stats["steps"] >= 50
    assert np.allclose(com[0], [0.0, -np.sin(0.05), np.cos(0.05)])
    assert np.allclose(np.linalg.norm(com, axis=1), 1.0, atol=1e-9)


def _turn(delta):
    c1, s1, c2, s2 = np.cos(delta), np.sin(delta), np.cos(2 * delta), np.sin(2 * delta)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, c1, -s1], [0.0, s1, c1]])
    rz = np.array([[c2, -s2, 0.0], [s2, c2, 0.0], [0.0, 0.0, 1.0]])
    return rx @ rz


def test_rigid_chain_of_three_runs_and_starts_at_the_free_end():
    run = peer_spatial.rigid_chain(3, dt=1e-3, t_end=0.05)
    t, tip, _ = run()
    assert t.shape == (51,) and tip.shape == (51, 3)
    R, end = np.eye(3), np.zeros(3)
    for _ in range(3):                      # 3 bars of 0.4 m along the initial curve: 1.2 m of chain
        end, R = end + R @ [0.4, 0.0, 0.0], R @ _turn(0.01 * np.pi)
    assert np.allclose(tip[0], end, atol=1e-12)
    assert tip[-1, 2] < tip[0, 2]           # it falls
    assert run.stats["steps"] >= 50 and run.stats["newton"] > 0


def test_bricard_p3_matches_the_reference_at_0_2_s():
    t, p3, _ = peer_spatial.bricard(dt=1e-3, t_end=0.2)()
    assert np.allclose(p3[0], [1.0, -1.0, 0.0])
    assert t[-1] == pytest.approx(0.2)
    assert np.abs(p3[-1] - BRICARD_P3_AT_0_2).max() < 1e-3


def test_unknown_variant_and_scheme_are_refused():
    with pytest.raises(ValueError, match="variant"):
        peer_spatial.heavy_top("lagrange")
    with pytest.raises(ValueError, match="scheme"):
        peer_spatial.bricard(t_end=0.01, scheme="euler")()


def test_spatial_slider_crank_matches_the_reference_over_1_s():
    # the reference (x_C m, θ rad) at t = 0.1, 0.5, 1 s is our scene's SLIDER_CRANK_REFERENCE
    from skfem_flex.scenes.spatial import SLIDER_CRANK_REFERENCE
    run = peer_spatial.spatial_slider_crank(dt=1e-3, t_end=1.0)
    t, probe, _ = run()
    assert t.shape == (1001,) and probe.shape == (1001, 2) and run.stats["steps"] >= 1000
    assert np.allclose(probe[0], [0.2, 0.0], atol=1e-12)                 # upright crank, C = (0.2, 0, 0)
    assert np.all(np.diff(probe[:, 1]) > 0.0)                              # the crank turns one way (+x)
    for time, expected in SLIDER_CRANK_REFERENCE.items():
        if time <= 1.0:
            k = int(np.argmin(np.abs(t - time)))
            assert abs(t[k] - time) < 1e-9
            assert np.abs(probe[k] - expected).max() < 1e-3


def test_right_angle_frame_follows_our_rotation_interpolated_beam():
    """Both codes' two-node beams interpolate the rotations: on 5 elements per leg, 4 s at Δt = 0.05 s, the
    elbow's and the tip's positions agree to 2e-2 m of the 5.5 m the elbow swings out of its plane (the two
    schemes' step errors), and the clamp and the weld hold (the elbow starts at (0, 10, 0))."""
    import skfem_flex as sf
    run = peer_spatial.right_angle_frame(5, dt=0.05, t_end=4.0)
    t, probe, _ = run()
    assert t.shape == (81,) and probe.shape == (81, 6)
    assert np.allclose(probe[0], [0.0, 10.0, 0.0, -10.0, 10.0, 0.0])
    ours = sf.simulate(sf.scenes.right_angle_frame(n_elements=5), 4.0, 0.05)
    mine = np.hstack([ours.probes["elbow"], ours.probes["tip"]])
    assert np.abs(mine - probe).max() <= 2e-2
    assert probe[:, 2].max() == pytest.approx(5.47, abs=0.05)
