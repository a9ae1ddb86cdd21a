"""The reduced rotor in exudyn (skfem_flex.apps.peer_reduced): the same body as our rotor_3d's, checked against the
full mesh, the rotor's closed-form mass and inertia, the torque impulse and our own run."""
import numpy as np
import pytest

pytest.importorskip("exudyn")

import skfem_flex as sf  # noqa: E402
from skfem_flex.apps import peer_reduced  # noqa: E402
from skfem_flex.scenes.spatial_rotors import ROTOR_3D  # noqa: E402

#: the rotor's mass (kg) and axial moment of inertia about the axis x (kg m²) in closed form: a square shaft
#: (side a, length L) through a square disk (side D, thickness h), density ρ; the mesh holds both exactly
_C = ROTOR_3D
MASS = _C["rho"] * ((_C["length"] - _C["disk_thickness"]) * _C["shaft"] ** 2 + _C["disk_thickness"] * _C["disk"] ** 2)
J_AXIAL = _C["rho"] * ((_C["length"] - _C["disk_thickness"]) * _C["shaft"] ** 4
                       + _C["disk_thickness"] * _C["disk"] ** 4) / 6.0
RIM = _C["disk"] / 2
TORQUE, T_END, DT = 20.0, 0.1, 1e-3


@pytest.fixture(scope="module")
def both():
    """A 0.1 s spin-up from rest (torque 20 N m, 0.01 kg unbalance) in exudyn and in ours, Δt = 1e-3 s."""
    run = peer_reduced.reduced_rotor(dt=DT, t_end=T_END, torque=TORQUE)
    t, disk, seconds = run()
    ours = sf.simulate(run.data["scene"], t_end=T_END, dt=DT, scheme="energy-momentum", record_every=1)
    return run, t, disk, seconds, ours


def test_our_basis_spans_no_rigid_motion_and_the_mean_axes_basis_strains_alike():
    """exudyn's frame needs a basis without rigid motion: ours (clamped to the disk) has none; the projected
    one is M-orthogonal to the rigid fields and has the same reduced stiffness (it differs by rigid fields)."""
    disk = peer_reduced.rotor_data()
    R = peer_reduced.rigid_fields(disk["nodes"])
    A = np.hstack([R, disk["basis"]])
    gram = np.linalg.eigvalsh(A.T @ (disk["M"] @ A))
    assert gram[0] > 1e-8 * gram[-1]
    mean = peer_reduced.rotor_data(frame="mean axes")
    assert np.abs(R.T @ (mean["M"] @ mean["basis"])).max() < 1e-10 * np.abs(disk["M"] @ disk["basis"]).max()
    K0 = disk["basis"].T @ (disk["K"] @ disk["basis"])
    assert np.allclose(mean["basis"].T @ (mean["K"] @ mean["basis"]), K0, rtol=0.0, atol=1e-9 * np.abs(K0).max())
    # the rigid motions strain nothing: K R = 0 (a check of the node-major reordering of K)
    assert np.abs(disk["K"] @ R).max() < 1e-6 * abs(disk["K"]).max()
    with pytest.raises(ValueError, match="frame"):
        peer_reduced.rotor_data(frame="tisserand")


def test_exudyn_body_has_our_mass_and_inertia(both):
    run = both[0]
    body = run.data["body"]
    assert run.stats["mass"] == pytest.approx(MASS, rel=1e-12)
    assert body.inertia.mass == pytest.approx(MASS, rel=1e-12)
    J = run.stats["inertia"]                          # about the frame origin, the disk centre
    I0 = body.inertia.I0                              # ours: second moments X₀ᵀ M_s X₀
    assert np.allclose(J, np.trace(I0) * np.eye(3) - I0, rtol=0.0, atol=1e-12)
    assert J[0, 0] == pytest.approx(J_AXIAL, rel=1e-12)
    assert run.stats["n_elastic"] == body.n_elastic == 20


def test_exudyn_spin_up_follows_the_torque_impulse_and_ours(both):
    run, t, disk, seconds, ours = both
    assert t.shape == (101,) and disk.shape == (101, 2) and seconds > 0.0
    assert run.stats["steps"] == 100 and run.stats["newton"] >= 100 and run.stats["cpu_seconds"] > 0.0
    spin = run.stats["spin"]
    assert spin[0] == 0.0
    # angular momentum about the axis gains τ t (the bearings sit on the axis); the body and the unbalance
    # turn together, the elastic shaft ends lag by a little
    rigid = TORQUE * t / (J_AXIAL + 0.01 * RIM ** 2)
    assert np.abs(spin - rigid).max() < 2e-3 * rigid[-1]
    # exudyn against ours at the same step: the spin to 2e-4 of its value, the disk's whirl (≈ 1 µm) to 2 %
    assert np.abs(spin - ours.probes["spin"]).max() < 2e-4 * rigid[-1]
    whirl = np.abs(ours.probes["disk"]).max()
    assert 1e-7 < whirl < 1e-5
    assert np.linalg.norm(disk - ours.probes["disk"], axis=1).max() < 0.02 * whirl


def test_torque_switches_off_after_T_and_the_mean_axes_frame_gives_the_same_motion():
    """Past T the spin stays at its level; with the mean axes as exudyn's frame the disk and spin barely change.

    The level: ours (mid-point loads) gains the impulse τT exactly; exudyn's generalized-α evaluates the
    load at the step's end and its velocity update weights the jump of the load by ½, so its spin falls short
    by τΔt/(2J) (here 2.5 %), an O(Δt) error of the step load, not of the model."""
    T, end = 0.02, 0.04
    run = peer_reduced.reduced_rotor(dt=DT, t_end=end, torque=TORQUE, T=T)
    t, disk, _ = run()
    after = t > T + 1e-9
    J = J_AXIAL + 0.01 * RIM ** 2
    level = TORQUE * T / J
    assert np.abs(run.stats["spin"][after] - (level - TORQUE * DT / (2 * J))).max() < 2e-3 * level
    ours = sf.simulate(run.data["scene"], t_end=end, dt=DT, scheme="energy-momentum", record_every=1)
    assert np.abs(ours.probes["spin"][after] - level).max() < 2e-3 * level
    mean = peer_reduced.reduced_rotor(dt=DT, t_end=end, torque=TORQUE, T=T, frame="mean axes")
    t2, disk2, _ = mean()
    assert np.array_equal(t, t2)
    assert np.linalg.norm(disk2 - disk, axis=1).max() < 0.01 * np.abs(disk).max()
    assert np.abs(mean.stats["spin"] - run.stats["spin"]).max() < 1e-4 * level
