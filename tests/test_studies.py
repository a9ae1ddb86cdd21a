"""Studies (issue 8) on tiny settings: references, work–precision rows, stability matrix, tables."""
import math

import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.apps import studies


def test_oscillator_period_references():
    # linear: 2π sqrt(m/k); quartic: Γ(1/4)√π / Γ(3/4) (issue 3's formula) for m = k = u0 = 1
    assert studies.oscillator_period(1.0, m=2.0, k=8.0) == pytest.approx(2 * math.pi * 0.5, rel=1e-14)
    assert studies.oscillator_period(2.0) == pytest.approx(
        math.gamma(0.25) * math.sqrt(math.pi) / math.gamma(0.75), rel=1e-12)
    # direct quadrature of T = 4 ∫ du / sqrt(1 − u⁴) for the quartic case
    from scipy.integrate import quad
    val, _ = quad(lambda s: 1.0 / math.sqrt(1.0 - s ** 4), 0.0, 1.0, limit=200)
    assert studies.oscillator_period(2.0) == pytest.approx(4.0 * val, rel=1e-8)
    with pytest.raises(ValueError, match="even"):
        studies.oscillator_period(1.5)


def test_pendulum_period_small_amplitude_limit():
    assert studies.pendulum_period(1.0, 1e-4, 9.81) == pytest.approx(2 * math.pi * math.sqrt(1 / 9.81), rel=1e-8)
    with pytest.raises(ValueError, match="over the top"):
        studies.pendulum_period(0.5, 5.0, 9.81)


def test_upward_crossings_of_a_sine():
    t = np.linspace(0, 10, 101)
    tc = studies.upward_crossings(t, np.sin(2 * t - 0.3), 2 * np.cos(2 * t - 0.3))
    exact = (0.3 + 2 * np.pi * np.arange(4)) / 2
    np.testing.assert_allclose(tc, exact[: tc.size], atol=1e-5)


def test_work_precision_rows_and_rate(tmp_path):
    case = studies.WORK_PRECISION_CASES["spring_mass"]()
    period = studies.oscillator_period(2.0)
    rows = studies.work_precision(case, schemes=["energy-momentum"], dts=[period / 20, period / 40])
    assert [r.scheme for r in rows] == ["energy-momentum"] * 2
    assert all(r.wall_time > 0 and r.steps > 0 and r.message == "" for r in rows)
    rate = math.log2(rows[0].error / rows[1].error)
    assert abs(rate - 2.0) < 0.15
    png = studies.plot_work_precision(rows, tmp_path / "wp.png")
    assert png.stat().st_size > 1000
    csv_path, md_path = studies.write_table(rows, tmp_path / "wp")
    assert md_path.read_text().count("\n") == 4
    assert "energy-momentum" in csv_path.read_text()


def test_stability_matrix_reports_failures_as_rows(monkeypatch):
    monkeypatch.setitem(studies.STABILITY_CASES, "escaping cubic",
                        lambda: studies.StabilityCase(lambda: sf.scenes.spring_mass(exponent=1.5), 100.0, 0.05))
    rows = studies.stability(cases=["quartic_T4", "escaping cubic"], schemes=["energy-momentum", "trapezoidal"],
                             quick=True)
    assert len(rows) == 4
    quartic = [r for r in rows if r.case == "quartic_T4"]
    em = [r for r in quartic if r.scheme == "energy-momentum"][0]
    assert em.bounded and em.max_energy_error < 1e-12
    escaping = [r for r in rows if r.case == "escaping cubic"]
    for r in escaping:
        assert not r.completed and not r.bounded
        assert "t = " in r.message and np.isfinite(r.t_reached) and r.t_reached > 1.0
    with pytest.raises(ValueError, match="no stability case"):
        studies.stability(cases=["nope"])


def test_stability_budget_stops_slow_runs_and_keeps_the_history():
    rows = studies.stability(cases=["pendulum_1e5_steps"], schemes=["energy-momentum"], budget=0.5)
    row = rows[0]
    assert not row.completed and "wall-clock budget" in row.message
    assert 0.0 < row.t_reached < 1000.0 and row.max_energy_error < 1e-10


def test_study_command_writes_tables_and_plot(tmp_path):
    from skfem_flex.apps.cli import main
    assert main(["study", "stability", "--cases", "quartic_T4", "--schemes", "energy-momentum", "--quick",
                 "--quiet", "--out", str(tmp_path / "s")]) == 0
    for name in ("stability.md", "stability.csv", "stability.png"):
        assert (tmp_path / "s" / name).stat().st_size > 0
    assert main(["study", "work-precision", "spring_mass", "--schemes", "energy-momentum", "--quick", "--quiet",
                 "--out", str(tmp_path / "w")]) == 0
    assert "energy-momentum" in (tmp_path / "w" / "work_precision.md").read_text()
    assert main(["study", "work-precision", "nope", "--quiet", "--out", str(tmp_path / "x")]) == 2
    assert main(["study", "work-precision", "spring_mass", "--schemes", "energy-momentum", "--quick", "--quiet",
                 "--no-peer", "--out", str(tmp_path / "w2")]) == 0


def _tiny_flexible_pendulum():
    """The flexible-pendulum work–precision case cut to 0.25 s (reference run at Δt = 1.25e-4: 2 000 steps)."""
    import dataclasses
    return dataclasses.replace(studies.WORK_PRECISION_CASES["flexible_pendulum"](), t_end=0.25)


def test_work_precision_without_the_peer_has_only_our_rows(monkeypatch):
    from skfem_flex.apps import peer
    monkeypatch.setattr(peer, "peer_available", lambda: False)
    case = _tiny_flexible_pendulum()
    assert case.peer is not None and studies.WORK_PRECISION_CASES["spin_up_beam"]().peer is not None
    rows = studies.work_precision(case, schemes=["energy-momentum"], dts=[0.01, 0.005])
    assert [r.scheme for r in rows] == ["energy-momentum"] * 2 and rows.computed == 2
    assert all(np.isfinite(r.error) and r.message == "" for r in rows)
    assert rows[1].error < rows[0].error
    # cases without a peer model never ask for one
    monkeypatch.setattr(peer, "peer_available", lambda: pytest.fail("asked for the peer"))
    rows = studies.work_precision("spring_mass", schemes=["energy-momentum"], dts=[studies.oscillator_period(2.0) / 20])
    assert [r.scheme for r in rows] == ["energy-momentum"]


def test_work_precision_adds_the_peer_rows(tmp_path):
    pytest.importorskip("exudyn")
    rows = studies.work_precision(_tiny_flexible_pendulum(), schemes=["generalized-alpha"], dts=[0.01, 0.005],
                                  name="flexible_pendulum")
    assert [r.scheme for r in rows] == ["generalized-alpha"] * 2 + [studies.PEER_SCHEME] * 2
    peer_rows = rows[2:]
    assert [r.dt for r in peer_rows] == [0.01, 0.005] and [r.steps for r in peer_rows] == [25, 50]
    assert all(r.message == "" and np.isfinite(r.error) and r.wall_time > 0 for r in peer_rows)
    assert peer_rows[1].error < peer_rows[0].error
    # the same physical quantity: at equal Δt the two codes' errors are of one size
    for ours, theirs in zip(rows[:2], peer_rows):
        assert 0.5 < theirs.error / ours.error < 2.0
    assert rows.computed == 4
    # peer=False leaves it out; the plot draws it
    assert [r.scheme for r in studies.work_precision(_tiny_flexible_pendulum(), schemes=["generalized-alpha"],
                                                     dts=[0.01], peer=False)] == ["generalized-alpha"]
    assert studies.plot_work_precision(rows, tmp_path / "wp.png").stat().st_size > 1000
