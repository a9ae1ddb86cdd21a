"""Every script in examples/ runs to its end at the reduced size of its quick mode.

Each example reads ``SKFEM_FLEX_EXAMPLE_QUICK=1`` (its docstring says what it shrinks). The examples
that compute physical results run here as ``__main__`` (runpy, with the script's folder first on
``sys.path``, as ``python examples/X.py`` does), so that one physical fact of each is checked against its
reference: an analytic value, a conservation law, a published value. The benchmark and profiling
scripts, which start processes and clusters of their own, run as subprocesses and must exit with 0.
"""
import math
import re
import runpy
import subprocess
import sys
import numpy as np
import pytest
from scipy.special import beta

from helpers import ROOT, package_env

EXAMPLES = ROOT / "examples"
QUICK_ENV = {"SKFEM_FLEX_EXAMPLE_QUICK": "1", "MPLBACKEND": "Agg"}


def run_example(name, monkeypatch, *args):
    """Run ``examples/NAME.py ARGS`` as ``__main__`` in quick mode in this process; returns its globals."""
    path = EXAMPLES / f"{name}.py"
    for key, value in QUICK_ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.setattr(sys, "argv", [str(path), *map(str, args)])
    monkeypatch.syspath_prepend(str(EXAMPLES))
    try:
        return runpy.run_path(str(path), run_name="__main__")
    except SystemExit as exc:
        assert exc.code in (None, 0), f"{name}.py exited with {exc.code!r}"
        return {}


def run_script(name, *args):
    """Run ``python examples/NAME.py ARGS`` in quick mode in a subprocess (this checkout's package first);
    returns its standard output after checking that it exited with 0."""
    env = package_env(**QUICK_ENV)
    proc = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), *map(str, args)], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, f"{name}.py exited with {proc.returncode}:\n{proc.stderr[-4000:]}"
    return proc.stdout


def energy_scale(res):
    return np.max(np.abs(res.kinetic) + np.abs(res.potential))


# ------------------------------------------------------------------ benchmark and profiling scripts
# (first: the longest tests, so that the two xdist workers share the rest)
def test_benchmark(tmp_path):
    """All four tables (time loop, start-up, catalogue, exudyn side by side or its absence) on tiny sizes."""
    run_script("benchmark", "--out", tmp_path)
    text = (tmp_path / "benchmark.md").read_text()
    assert "| spin-up, 64 P1 elements" in text and "| pendulum |" in text and "| flexible_pendulum |" in text
    assert "exudyn" in text


def test_benchmark_peers(tmp_path):
    """The side-by-side tables on their own, one problem (the rigid pendulum: the trapezoidal rule, generalized-α
    and energy-momentum at exudyn's step, energy-momentum at a larger one): with exudyn its rows, our error
    against the exact elliptic motion between 1e-6 and 1e-2 m; without it, the one line that says so."""
    out = run_script("benchmark_peers", "--only", "rigid pendulum", "--out", tmp_path)
    text = (tmp_path / "side_by_side.md").read_text()
    assert text in out
    try:
        import exudyn  # noqa: F401
    except ImportError:
        assert text.strip() == 'exudyn is not installed (pip install ".[bench]"): no side-by-side table.'
        return
    rows = [line for line in text.splitlines() if line.startswith("| rigid pendulum |")]
    assert len(rows) == 4 and "reduced rotor" not in text
    for row in rows:
        error = float(row.split("|")[-3])
        assert 1e-6 < error < 1e-2, row


def test_benchmark_limits(tmp_path):
    run_script("benchmark_limits", "--out", tmp_path)
    text = (tmp_path / "benchmark_limits.md").read_text()
    assert "| spin_up_beam | 10 |" in text and "failed" not in text


def test_peer_exudyn():
    pytest.importorskip("exudyn")
    assert run_script("peer_exudyn").count("exudyn") == 3


def test_profile_step():
    """The profile names the run's families, storage and solver, and times a compiled and a Python run."""
    out = run_script("profile_step")
    assert "families: floating-frame bodies, gravity, point constraints" in out
    assert "compile and start-up" in out and "Newton iterations per step" in out
    fast, slow = (float(x) for x in re.findall(r"run: +([0-9.]+) µs per step", out))
    assert 0 < fast < slow


def test_calibrate_dense_solve():
    """The calibration prints one row per size, LAPACK's time beside the model's (no timing is asserted)."""
    out = run_script("calibrate_dense_solve")
    rows = re.findall(r"^\| (\d+) \| ([0-9.]+) \| ([0-9.]+) \| ([0-9.]+) \|$", out, re.M)
    assert [int(r[0]) for r in rows] == [12, 20, 24, 28, 33, 40, 50, 64, 80, 100]
    assert all(float(v) > 0 for r in rows for v in r[1:])
    scenes = re.findall(r"^\| ([a-z_ ]+) \| (\d+) \| [a-zA-Z ()]+ \| [0-9.]+ \|", out, re.M)
    assert [name for name, _ in scenes] == ["reduced rotating beam", "spatial_slider_crank"]


def test_your_own_scene(monkeypatch, tmp_path):
    """The tutorial's scene (tests/test_your_own_scene.py checks its physics) runs to its end as a script."""
    run_example("your_own_scene", monkeypatch, tmp_path)


def test_sweep_benchmark(tmp_path):
    run_script("sweep_benchmark", "--out", tmp_path)
    assert "sweep, 2 workers, cluster already running" in (tmp_path / "sweep_benchmark.md").read_text()


# ------------------------------------------------------------------ examples with physical results
def test_cantilever(monkeypatch, tmp_path):
    """Tip deflection against Timoshenko theory: second order with reduced shear, locking with full shear."""
    example = run_example("cantilever", monkeypatch, tmp_path)
    np.testing.assert_allclose(example["observed_order"]["reduced"], 2.0, atol=0.05)
    assert np.all(np.abs(example["tip_error"]["reduced"][-1]) < 1e-4)
    assert np.all(np.abs(example["tip_error"]["full"][:, 1:]) > 0.4)  # locking when slender
    assert list(example["is_axial"]) == [False, False, True, False]
    assert "order" in example["convergence_table"]()
    assert (tmp_path / "cantilever_modes.png").exists()


def test_energy_conservation(monkeypatch, tmp_path):
    """V = ½ u³ (m = k = u0 = 1, v0 = 0) escapes to −∞ at t* = (B(1/3, 1/2) + B(1/3, 1/6))/3: both schemes stop
    within two steps before it, the trapezoidal rule with its energy blown up, the energy-conserving scheme
    with its energy kept; the quartic oscillator keeps its energy under the energy-conserving scheme."""
    example = run_example("energy_conservation", monkeypatch, tmp_path)
    t_escape = (beta(1 / 3, 1 / 2) + beta(1 / 3, 1 / 6)) / 3
    assert example["ESCAPE_TIME"] == pytest.approx(t_escape, rel=1e-8)
    runs, dt = example["spring_runs"], example["DT"]
    for scheme in ("trapezoidal", "energy-momentum"):
        res, msg = runs[(1.5, scheme)]
        assert msg and not res.completed
        assert t_escape - 2 * dt <= res.t[-1] <= t_escape
    trap, em = runs[(1.5, "trapezoidal")][0], runs[(1.5, "energy-momentum")][0]
    assert trap.total_energy[-1] > 1e3 * trap.total_energy[0]
    assert np.max(np.abs(em.total_energy - em.total_energy[0])) < 1e-6 * em.total_energy[0]
    quartic, msg = runs[(2.0, "energy-momentum")]
    assert msg == "" and np.ptp(quartic.total_energy) < 1e-12 * quartic.total_energy[0]
    assert (tmp_path / "spring_mass.png").exists() and (tmp_path / "pendulum.png").exists()


def test_double_pendulum(monkeypatch, tmp_path):
    """Energy-momentum: joints hold at position level, the energy balance to round-off."""
    example = run_example("double_pendulum", monkeypatch, tmp_path)
    res = example["runs"]["energy-momentum"]
    assert res.completed and np.max(res.constraint_residual) < 1e-12
    assert np.max(np.abs(res.energy_balance_error)) < 1e-10 * energy_scale(res)
    assert (tmp_path / "double_pendulum.png").exists()


def test_flexible_pendulum(monkeypatch, tmp_path):
    """The nearly rigid beam (EI = 1e4 N m²) swings as the rigid compound pendulum (scipy, tight tolerances)."""
    example = run_example("flexible_pendulum", monkeypatch, tmp_path)
    res = example["runs"][("EI = 1e4", "energy-momentum")]
    assert np.max(np.linalg.norm(res.probes["tip"] - example["rigid_tip"], axis=1)) < 1e-3
    assert np.max(np.abs(res.energy_balance_error)) < 1e-10 * example["E_REF"]
    assert (tmp_path / "flexible_pendulum_tip.png").exists()


def test_flying_beam(monkeypatch, tmp_path):
    """After the load (8 N along x for 2.5 s) the linear momentum is its impulse, (20, 0) N s, and energy and
    angular momentum stay constant under the energy-momentum scheme."""
    example = run_example("flying_beam", monkeypatch, tmp_path)
    res = example["energy_momentum"]
    after = res.t > 2.5 + 1e-9
    assert after.sum() >= 10
    np.testing.assert_allclose(res.linear_momentum[after], np.tile([8.0 * 2.5, 0.0], (after.sum(), 1)),
                               rtol=0, atol=1e-9 * 20.0)
    assert example["drift_after_load"](res, res.total_energy) < 1e-10
    assert example["drift_after_load"](res, res.angular_momentum) < 1e-10
    assert (tmp_path / "flying_beam_conservation.png").exists()


def test_free_beam(monkeypatch, tmp_path):
    """The tip pulse's impulse 2τF/π is the linear momentum after it (to the step's quadrature of the pulse)."""
    example = run_example("free_beam", monkeypatch, tmp_path)
    res = example["runs"]["energy-momentum"]
    after = res.t > example["DURATION"] + 1e-9
    impulse = 2 * example["DURATION"] * example["FORCE"] / math.pi
    assert res.linear_momentum[after][-1, 1] == pytest.approx(impulse, rel=0.01)
    assert np.ptp(res.total_energy[after]) < 1e-8 * res.total_energy[-1]
    assert (tmp_path / "free_beam.png").exists()


def test_heavy_top(monkeypatch, tmp_path):
    """Energy-momentum conserves the top's energy and vertical angular momentum at both steps, and with the
    quaternion its spin too; the Brüls top converges at second order towards the published Euler parameters
    under every scheme."""
    example = run_example("heavy_top", monkeypatch, tmp_path)
    for dt in example["TOP_STEPS"]:
        for rotation in example["ROTATIONS"]:
            energy, l3, spin, orth, _ = example["simo_wong"][(rotation, "energy-momentum", dt)]
            assert energy < 1e-10 and l3 < 1e-10 and orth < 1e-12
        assert example["simo_wong"][("quaternion", "energy-momentum", dt)][2] < 1e-10
    for name in example["SCHEMES"]:
        assert all(1.8 < o < 2.2 for o in example["orders"](name))
    assert (tmp_path / "heavy_top_convergence.png").exists()


def test_flexible_arm(monkeypatch):
    """The elbow hinge between two floating-frame beams' material points does no work under energy–momentum
    (the energy balance with the hub driver's work closes to round-off) and holds under every scheme; the
    forearm falls and swings."""
    results = run_example("flexible_arm", monkeypatch)["results"]
    assert results["energy-momentum"]["energy"] < 1e-11 and results["energy-momentum"]["work"] > 0.0
    for r in results.values():
        assert r["elbow"] < 1e-6 and r["lowest"] < -0.3 and not r["python"]


def test_spatial_mechanisms(monkeypatch, tmp_path):
    """Bricard and the spatial slider–crank meet the library's high-precision level (1e-3) under
    energy-momentum, which conserves their energy."""
    example = run_example("spatial_mechanisms", monkeypatch)
    err, energy, _ = example["bricard"]["energy-momentum"]
    assert err < 1e-4 and energy < 1e-9
    ex, eth, energy, _ = example["crank"]["energy-momentum"]
    assert ex < 1e-3 and eth < 1e-3 and energy < 1e-10


def test_spatial_beams(monkeypatch, tmp_path):
    """The flying beam in space keeps the pulse's impulse and, under energy-momentum alone, its energy and
    angular momentum; the frame's elbow moves out of its plane."""
    example = run_example("spatial_beams", monkeypatch)
    p, energy, L, _, _ = example["flying"]["energy-momentum"]
    assert p < 1e-10 * 50 and energy < 1e-10 and L < 1e-10
    assert example["flying"]["trapezoidal"][1] > 1e-6
    assert all(pk["elbow, first peak"][0] > 1.0 for pk in example["frame"].values())
    flap, lag, (lin, growth), flap_forms, lag_forms = example["campbell"][12.0]
    assert flap == pytest.approx(13.1702, rel=5e-3) and lag == pytest.approx(5.4270, rel=5e-3) and growth > 1.0
    assert flap_forms == pytest.approx(flap, rel=1e-3) and lag_forms == pytest.approx(lag, rel=1e-3)
    tips = {k: r.probes["tip"] for k, r in example["spin_up"].items()}
    assert np.abs(tips["floating"] - tips["exact"]).max() <= 1e-3 * np.abs(tips["exact"]).max()
    assert "flying beam" in example["summary"]() and "spin_up_3d" in example["summary"]()


def test_spatial_solid(monkeypatch, tmp_path):
    """The reduced steel bar: more modes, smaller frequency errors; the spin-up closes its energy balance with
    the driver's work and writes the mesh with its stresses."""
    example = run_example("spatial_solid", monkeypatch, tmp_path)
    errors = [np.abs(err).max() for err, _ in example["reduction"].values()]
    assert errors[-1] < errors[0] and np.abs(list(example["reduction"].values())[-1][0][:4]).max() <= 1e-3
    res = example["result"]
    assert res.relative_energy_error(np.max(np.abs(res.external_work))) <= 1e-9
    assert example["von_mises"] > 1e6 and (tmp_path / "solid.pvd").exists()
    flap, lag = example["spinning"]["green-lagrange", 3.0]
    assert flap == pytest.approx(4.7973, rel=2e-2) and lag == pytest.approx(3.7435, rel=2e-2)


def test_bracket(monkeypatch, tmp_path):
    """The bracket read from its gmsh file: the reduced body's static load-face displacement is the full
    mesh's (a static interface load is the reduction's exact case), stresses are written."""
    example = run_example("bracket", monkeypatch, tmp_path)
    reduced, full = example["reduced"], example["full"]
    assert np.abs(reduced - full).max() <= 1e-8 * np.abs(full).max() and np.abs(full).max() > 1e-6
    assert example["von_mises"].max() > 1e6 and (tmp_path / "bracket.pvd").exists()
    assert set(example["mesh"].boundaries) >= {"bolts", "load"}


def test_render_vtk(monkeypatch, tmp_path):
    """The picture of the bracket's stresses: rendered off screen from the VTK series the bracket example writes;
    the field the renderer reads back from the .vtu spans the example's own von Mises range (1e-6)."""
    pytest.importorskip("vtk")
    example = run_example("bracket", monkeypatch, tmp_path)
    render = run_example("render_vtk", monkeypatch, tmp_path / "bracket.pvd", "von_mises", tmp_path / "b.png",
                         "--warp", 50)                           # the command of the docs' picture
    lo, hi = render["field_range"](render["last_file"](tmp_path / "bracket.pvd"), "von_mises")
    assert hi == pytest.approx(example["von_mises"].max(), rel=1e-6)
    assert lo == pytest.approx(example["von_mises"].min(), rel=1e-6)
    assert (tmp_path / "b.png").stat().st_size > 10_000


def test_render_paraview(monkeypatch, tmp_path):
    """The ParaView picture of the bracket's stresses (ParaView's ``pvbatch``, off screen; skipped where ParaView is
    not installed): the field range ParaView read from the series is the example's von Mises
    range (1e-5), and the picture is written."""
    import shutil
    pvbatch = shutil.which("pvbatch")
    if pvbatch is None:
        pytest.skip("ParaView (pvbatch) is not installed")
    example = run_example("bracket", monkeypatch, tmp_path)
    # started with this Python, the script runs itself again under pvbatch (the docs' command)
    proc = subprocess.run([sys.executable, str(EXAMPLES / "render_paraview.py"), str(tmp_path / "bracket.pvd"),
                           "von_mises", str(tmp_path / "p.png"), "--warp", "50"], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lo, hi = (float(x) for x in re.search(r"von_mises: (\S+) to (\S+);", proc.stdout).groups())
    assert hi == pytest.approx(example["von_mises"].max(), rel=1e-5)
    assert lo == pytest.approx(example["von_mises"].min(), rel=1e-5)
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_meshed_rod(monkeypatch, tmp_path):
    """The coarse rod's slider–crank: joints hold and the energy balance closes; finite stresses are written."""
    example = run_example("meshed_rod", monkeypatch, tmp_path)
    res, vm = example["res"], example["vm"]
    assert res.completed and np.max(res.constraint_residual) <= 1e-10
    assert res.relative_energy_error() <= 1e-9
    assert np.all(np.isfinite(vm)) and vm.max() > 0
    assert (tmp_path / "meshed_rod.pvd").exists() and (tmp_path / "meshed_rod.png").exists()


def test_modes(monkeypatch, tmp_path):
    """The hanging bar stretches by ρA g L²/(2EA); its first frequency is the rigid rod's; the cantilever under
    M = 2πEI/L closes into a circle."""
    example = run_example("modes", monkeypatch, tmp_path)
    assert example["stretch"] == pytest.approx(1.0 * 9.81 * 1.0 / (2 * 1e9), rel=1e-6)
    rigid_rod = math.sqrt(9.81 / 2 / (1.0 / 3 + 1e-4))
    assert example["pendulum_modes"].omega[0] == pytest.approx(rigid_rod, rel=1e-4)
    assert all(gap < 1e-10 for *_, gap in example["roll_up"])
    assert (tmp_path / "campbell.png").exists()


def test_rotating_beam(monkeypatch, tmp_path):
    """The first in-plane frequency against the literature's flapwise values less the centrifugal softening."""
    example = run_example("rotating_beam", monkeypatch, tmp_path)
    flapwise = np.array([3.5160, 3.6816, 4.1373, 4.7973, 5.5850, 6.4495, 7.3604, 8.2996, 9.2568, 10.2257,
                         11.2023, 12.1843, 13.1702])
    lam = example["LAMBDAS"]
    literature = np.sqrt(flapwise[lam.astype(int)] ** 2 - lam ** 2)
    np.testing.assert_allclose(example["ffr"], literature, rtol=2e-3)
    assert example["southwell"] == pytest.approx(1.193, abs=0.005)
    assert (tmp_path / "rotating_beam.png").exists()


def test_slider_crank(monkeypatch, tmp_path):
    """Slider position and rod angle at t = 0.1 s against the published reference (Simeon's test set)."""
    from skfem_flex.scenes.mechanisms import SIMEON_REFERENCE

    example = run_example("slider_crank", monkeypatch, tmp_path)
    res = example["published"][("green-lagrange", 4, 1e-4)]
    assert res.probes["slider"][-1] == pytest.approx(SIMEON_REFERENCE["slider"], abs=1e-6)
    assert res.probes["rod_angle"][-1] == pytest.approx(SIMEON_REFERENCE["rod_angle"], abs=1e-6)
    em = example["revolution"]["energy-momentum"]
    assert np.max(np.abs(em.energy_balance_error)) < 1e-10 * energy_scale(em)
    assert (tmp_path / "slider_crank_revolution.png").exists()


def test_spin_up(monkeypatch, tmp_path):
    """Simo & Vu-Quoc's spin-up, ω_s = 4 rad/s: the tip dips to −0.40 m near 6.95 s with the Green–Lagrange
    strain; at ω_s = 10 rad/s the linear strain, without centrifugal stiffening, diverges."""
    example = run_example("spin_up", monkeypatch, tmp_path)
    runs = example["runs"]
    w_min, t_min = example["tip_minimum"](runs[(4.0, "green-lagrange")])
    assert w_min == pytest.approx(-0.40, abs=0.005) and t_min == pytest.approx(6.95, abs=0.02)
    assert np.abs(runs[(10.0, "green-lagrange")].probes["tip"][:, 1]).max() < 1.0
    assert np.abs(runs[(10.0, "linear")].probes["tip"][:, 1]).max() > 10.0
    assert (tmp_path / "spin_up.png").exists()


def test_very_flexible_pendulum(monkeypatch, tmp_path):
    """The soft pendulum's energy balance closes to round-off on every mesh."""
    example = run_example("very_flexible_pendulum", monkeypatch, tmp_path)
    for res in example["runs"].values():
        assert res.completed and res.relative_energy_error() < 1e-10
    assert (tmp_path / "very_flexible_pendulum.png").exists()


def test_reduction_scaling(tmp_path):
    """The reduction's time and memory table (1e3 and 3e3 nodes in quick mode): the sizes' rows, and the first
    clamped–clamped bending frequency of the P1 bar falling towards the beam's as the mesh refines (P1 tetrahedra
    are too stiff; Euler–Bernoulli 4.730² √(EI/(ρA L⁴)) = 3340 rad/s, shear lowers it by a few per cent)."""
    run_script("reduction_scaling", tmp_path)
    rows = [line.split("|")[1:-1] for line in (tmp_path / "reduction_scaling.md").read_text().splitlines()[2:]]
    assert len(rows) == 2
    f = [float(r[-1]) for r in rows]
    beam = 4.730 ** 2 * math.sqrt(2.1e11 * 0.1 ** 4 / 12 / (7850.0 * 0.1 ** 2))
    assert f[1] < f[0] and 0.93 < f[1] / beam < 1.1
    assert all(float(r[3]) > 0 and float(r[5]) > 0 and r[4].strip() in ("SuperLU", "PARDISO") for r in rows)


def test_every_example_has_a_test():
    tested = {name[len("test_"):] for name in globals() if name.startswith("test_")}
    assert {p.stem for p in EXAMPLES.glob("*.py")} <= tested
