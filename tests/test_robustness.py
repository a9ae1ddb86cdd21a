"""Bad and extreme input, divergence, full disks, damaged files, large meshes, long series.

Every case here was a traceback, a silent success or a misleading message before; each now
gets one line naming the value and an exit status that says what happened (0 done, 1 stopped
early, 2 bad input, 3 diverged).
"""
import errno
import json
import os
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skfem_flex as sf
from skfem_flex import scenes
from skfem_flex.apps import cli
from skfem_flex.compiled import registry
from skfem_flex.run import driver
from skfem_flex.io.output import VTKSeries, read_pvd

from helpers import default_sigint, package_env


#: --set values of the wrong type, sign and size (sizes kept where a run is rejected or short)
BAD_VALUES = ["", "abc", "nan", "inf", "-inf", "-1", "0", "-0.0", "1.5", "-2.5", "1e308", "-1e308", "1e-308",
              "1e-300", "1e9", "1e30", "-1e30", "true", "[1, 2]", "0x10", "1_000", " 3 ", "é"]
CATALOGUE = sorted(scenes.CATALOGUE)


def run_cli(capsys, argv):
    rc = cli.main(argv)
    err = capsys.readouterr().err
    return rc, err


#: hypothesis examples per catalogue scene: about SKFEM_FLEX_HYPOTHESIS_EXAMPLES (default 25) in all, at least
#: 2 a scene (the first example hypothesis draws is the simplest one)
EXAMPLES_PER_SCENE = max(2, -(-int(os.environ.get("SKFEM_FLEX_HYPOTHESIS_EXAMPLES", 25)) // len(CATALOGUE)))


@pytest.mark.parametrize("name", CATALOGUE)
@settings(max_examples=EXAMPLES_PER_SCENE, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_cli_survives_any_set_value(tmp_path, capsys, data, name):
    """Random wrong-typed/signed/sized --set values for every catalogue scene (each, every run): exit 0-3,
    never a traceback; stderr is one line of the CLI's own, plus one line per warning (no multi-line
    Python warning with its source echo)."""
    params = [p for p, _, _ in scenes.parameters(name)]
    key = data.draw(st.sampled_from(params), label="key")
    # integers small or far too large (a mid-sized mesh is a legitimate long run, not bad input)
    value = data.draw(st.sampled_from(BAD_VALUES) | st.floats(allow_nan=True).map(repr)
                      | st.integers(-10, 10).map(str) | st.integers(10**12, 10**30).map(str), label="value")
    defaults = getattr(scenes.get(name), "defaults", {}) or {}
    dt = defaults.get("dt", 0.01)
    rc, err = run_cli(capsys, ["run", name, "--set", f"{key}={value}", "--t-end", repr(2 * dt), "--out",
                               str(tmp_path / name), "--no-vtk", "--no-plots", "--quiet"])
    assert rc in (0, 1, 2, 3), err
    assert "Traceback" not in err and "internal error" not in err, err
    lines = err.strip().splitlines()
    assert all(line.startswith("skfem-flex: ") for line in lines), err
    assert len([line for line in lines if not line.startswith("skfem-flex: warning: ")]) <= 1, err
    if rc == 2:
        assert err.startswith("skfem-flex: error:") and len(lines) == 1, err


@pytest.mark.parametrize("argv, needle", [
    (["run", "pendulum", "--dt", "1e-300"], "steps"),
    (["run", "pendulum", "--t-end", "1e12"], "memory"),
    (["run", "pendulum", "--out", ""], "--out"),
    (["run", "pendulum", "--set", "length=1", "--set", "length=2"], "twice"),
    (["run", "spin_up_beam", "--set", "n_elements=100000000"], "memory"),
    (["run", "flexible_pendulum", "--set", "n_elements=1000000000"], "memory"),
    (["run", "slider_crank", "--set", "body=plane-stress", "--set", "n_elements=1000000000"], "memory"),
    (["run", "flexible_pendulum", "--set", "EA=1e13"], "EA"),
    (["run", "flexible_pendulum", "--set", "EI=1e-5"], "EI"),
    (["run", "flexible_pendulum", "--set", "length=1e300"], "length"),
    (["study", "stability", "--budget", "0"], "--budget"),
    (["study", "stability", "--budget", "-5"], "--budget"),
    (["run", "--resume", "/nonexistent/skfem-flex-run"], "--resume"),
])
def test_bad_cli_input_is_one_line_naming_it(tmp_path, capsys, argv, needle):
    if "--out" not in argv and argv[0] == "run" and "--resume" not in argv:
        argv = argv + ["--out", str(tmp_path / "o")]
    rc, err = run_cli(capsys, argv + ["--quiet"] if argv[0] == "run" else argv)
    assert rc == 2, err
    assert len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err, err


def test_a_solve_the_settings_make_impossible_is_one_line(tmp_path, capsys):
    """A steady spin at 1e308 rad/s (found by the test above): the solve before the run fails, and the command
    says where and why in one line with exit status 1, not an internal error."""
    rc, err = run_cli(capsys, ["run", "rotating_beam_3d", "--set", "omega=1e308", "--out", str(tmp_path / "o"),
                               "--no-vtk", "--no-plots", "--quiet"])
    lines = [line for line in err.strip().splitlines() if not line.startswith("skfem-flex: compil")]
    assert rc == 1 and len(lines) == 1, err
    assert lines[0].startswith("skfem-flex: error: steady spin") and "not finite" in lines[0], err


def test_list_into_a_closed_pipe_is_quiet():
    env = package_env()
    proc = subprocess.run(f"{sys.executable} -m skfem_flex list | head -1", shell=True, env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.stdout.strip() and "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr


def test_python_api_bad_input():
    with pytest.raises(TypeError, match="bodies"):
        sf.Scene(["beam"])
    with pytest.raises(TypeError, match="Scene"):
        sf.simulate("pendulum", 1.0, 0.1)
    with pytest.raises(ValueError, match="max_halvings"):
        sf.simulate(sf.scenes.pendulum(), 0.1, 0.01, max_halvings=-1)
    with pytest.raises(TypeError, match="output"):
        sf.simulate(sf.scenes.pendulum(), 0.1, 0.01, output=42)
    with pytest.raises(ValueError, match="steps"):
        sf.simulate(sf.scenes.pendulum(), 1e9, 1e-300)


def test_single_sink_without_a_list(tmp_path):
    res = sf.simulate(sf.scenes.pendulum(), 0.05, 0.01, output=VTKSeries(tmp_path, "p"))
    assert [t for t, _ in read_pvd(tmp_path / "p.pvd")] == pytest.approx(res.t)


def test_damaged_result_files_raise_value_error_naming_them(tmp_path):
    good = sf.simulate(sf.scenes.pendulum(), 0.05, 0.01).save(tmp_path / "good.npz")
    data = good.read_bytes()
    cases = {"empty.npz": b"", "text.npz": b"hello, not a result", "truncated.npz": data[: len(data) // 2],
             "flipped.npz": data[:200] + bytes(b ^ 0xFF for b in data[200:400]) + data[400:]}
    np.save(tmp_path / "array.npy", np.arange(3.0))
    np.savez(tmp_path / "other.npz", x=np.arange(3.0))
    paths = [tmp_path / "array.npy", tmp_path / "other.npz"]
    for fname, content in cases.items():
        (tmp_path / fname).write_bytes(content)
        paths.append(tmp_path / fname)
    for p in paths:
        with pytest.raises(ValueError) as info:
            sf.Result.load(p)
        msg = str(info.value)
        assert str(p) in msg and "pickle" not in msg, msg
    with pytest.raises(FileNotFoundError):
        sf.Result.load(tmp_path / "missing.npz")


def test_divergence_exits_3_and_keeps_outputs(tmp_path, capsys):
    """Linear-strain spin-up at ω = 10 rad/s (beyond its buckling speed): the coordinates explode."""
    out = tmp_path / "dv"
    rc, err = run_cli(capsys, ["run", "spin_up_beam", "--set", "omega=10", "strain=linear", "--out", str(out),
                               "--no-vtk", "--quiet"])
    assert rc == 3 and "diverged at t = " in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False and summary["stopped"].startswith("diverged at t = ")
    res = sf.Result.load(out / "result.npz")
    assert np.all(np.isfinite(res.q)) and res.t[-1] < 30.0


def test_divergence_guard_energy_rule():
    """A non-conservative scheme whose energy grows 10⁶ times beyond the scale of its first steps
    plus the work done is stopped; a run released from rest (T₀ + V₀ = 0) is not."""
    from skfem_flex.run.guard import DIVERGENCE_FACTOR, SCALE_RECORDS, DivergenceGuard
    scene = sf.scenes.pendulum()

    guard = DivergenceGuard(scene, np.array([0.5, 0.0]), [0.0], [0.0], [0.0])

    def record(t, kinetic, potential):
        guard.check_energy(t, kinetic, potential, 0.0)
    record(0.01, 1e-5, -1e-5 + 1e-17)                          # round-off from rest: no scale yet, no error
    for k in range(SCALE_RECORDS):
        record(0.02 + 0.01 * k, 2.0, -1.0)                     # the first steps set E_s = 3 J
    record(1.0, 0.9 * DIVERGENCE_FACTOR * 3.0, 0.0)             # below the bound
    with pytest.raises(sf.SimulationError, match="diverged at t = 2"):
        record(2.0, 1.1 * DIVERGENCE_FACTOR * 3.0, 0.0)


def test_energy_balance_warning(tmp_path, capsys):
    """Trapezoidal rule on the quartic oscillator at Δt ≈ T/2: ~70 % energy error, warned, still exit 0."""
    out = tmp_path / "tr"
    rc, err = run_cli(capsys, ["run", "spring_mass", "--integrator", "trapezoidal", "--dt", "3.7", "--t-end", "37",
                               "--out", str(out), "--no-vtk", "--quiet"])
    assert rc == 0 and "warning: energy balance error" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] and "energy balance error" in summary["warnings"][0]
    assert summary["rho_inf"] is None and "compile_time_s" in summary
    rc, err = run_cli(capsys, ["run", "spring_mass", "--dt", "3.7", "--t-end", "37", "--out", str(out),
                               "--no-vtk", "--quiet"])
    assert rc == 0 and "warning" not in err          # energy-momentum keeps the balance


@pytest.mark.parametrize("failing", ["vtu", "collection"])
def test_full_disk_is_one_line_without_tmp_or_unlisted_frames(tmp_path, capsys, monkeypatch, failing):
    """ENOSPC while writing the 6th frame (its .vtu, or its listing after the .pvd was written)."""
    import meshio
    from skfem_flex.io import output
    calls = {"n": 0}
    if failing == "vtu":
        real = meshio.write

        def write(path, *a, **k):
            calls["n"] += 1
            if calls["n"] == 6:
                Path(path).write_bytes(b"partial")
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
            return real(path, *a, **k)
        monkeypatch.setattr(meshio, "write", write)
    else:
        real = output.write_text_atomically

        def atomic_write_text(path, text):
            if str(path).endswith(".vtu.series"):
                calls["n"] += 1
                if calls["n"] == 7:              # the empty series at the start, then the 6th frame's listing
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
            return real(path, text)
        monkeypatch.setattr(output, "write_text_atomically", atomic_write_text)
    out = tmp_path / "full"
    rc, err = run_cli(capsys, ["run", "pendulum", "--t-end", "0.2", "--every", "1", "--out", str(out), "--quiet"])
    assert rc == 1 and "Traceback" not in err and "No space left on device" in err, err
    listed = read_pvd(out / "pendulum.pvd")
    series = json.loads((out / "pendulum.vtu.series").read_text())["files"]
    assert len(listed) == len(series) == 5
    assert sorted(p.name for p in out.glob("pendulum_*.vtu")) == [p.name for _, p in listed]
    assert not list(out.glob(".*tmp"))
    res = sf.Result.load(out / "result.npz")                 # histories up to the failure are kept
    assert not res.completed and len(res.t) == 5


def test_series_cost_is_linear_in_the_frames(tmp_path, monkeypatch):
    """Writing N frames writes O(N log N) bytes of collections, not O(N²): the collections are
    rewritten when the unlisted frames reach 1/256 of the listed ones (or after a second)."""
    from skfem_flex.io import output
    monkeypatch.setattr(output, "LISTING_SECONDS", 1e9)          # the count rule alone, deterministic
    written = {"bytes": 0, "calls": 0}
    real = output.write_text_atomically

    def counting(path, text):
        written["bytes"] += len(text)
        written["calls"] += 1
        return real(path, text)
    monkeypatch.setattr(output, "write_text_atomically", counting)
    scene = sf.scenes.pendulum()
    q, v = scene.initial_state()
    n = 4000
    sink = VTKSeries(tmp_path, "p")
    for k in range(n):
        sink.write(scene, 0.001 * k, q, v)
    sink.close()
    listed = read_pvd(tmp_path / "p.pvd")
    assert len(listed) == n and len(json.loads((tmp_path / "p.vtu.series").read_text())["files"]) == n
    per_entry = (tmp_path / "p.pvd").stat().st_size / n + (tmp_path / "p.vtu.series").stat().st_size / n
    # rewriting after every frame would write n²/2 entries (2000 n); the rule writes about 256 n (a
    # geometric series of collection sizes) plus the first 256 frames' rewrites, whatever n is
    assert written["bytes"] < 400 * n * per_entry, written
    # a rewrite per frame until 256 are listed, then batches growing with the listed count: about
    # 256 (1 + ln(n/256)) rewrites of each collection, against n for a rewrite per frame
    assert written["calls"] < 2 * 1.3 * 256 * (1 + np.log(n / 256))


def test_large_body_allocates_no_dense_n_by_n():
    """A pinned flexible pendulum above the small-system threshold (both integrator families): one
    step's peak Python memory stays far below one dense n × n matrix, and doubling the mesh about
    doubles it (it grew with n² before: 2.5 GB for 4 000 elements)."""
    # compile and import outside the count (a scene above the dense limit: its storage and solver are the
    # large ones' — compiling them holds ~10 MB of Python memory for a moment)
    small = sf.scenes.get("flexible_pendulum")(n_elements=60)
    for integrator in ("generalized-alpha", "energy-momentum"):
        sf.simulate(small, 0.002, 0.001, integrator=integrator)
    peaks = []
    # large enough that a dense n × n would dominate what is linear (the solver's index plans, ~6 kB
    # per element: at 300 elements that alone is a third of 8 n² bytes)
    for n_el in (600, 1200):
        scene = sf.scenes.get("flexible_pendulum")(n_elements=n_el)
        for integrator in ("generalized-alpha", "energy-momentum"):
            tracemalloc.start()
            sf.simulate(scene, 0.001, 0.001, integrator=integrator)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            assert peak < 0.25 * 8 * scene.n ** 2, (n_el, integrator, peak)
            peaks.append(peak)
    assert peaks[2] < 2.5 * peaks[0] and peaks[3] < 2.5 * peaks[1]


def test_memory_estimate_before_allocating(monkeypatch):
    from skfem_flex.numerics import resources
    monkeypatch.setattr(resources, "available_memory", lambda: 50e6)
    with pytest.raises(MemoryError, match="elements"):
        sf.scenes.get("spin_up_beam")(n_elements=100_000)


def test_compile_is_said_timed_apart_and_before_the_bar(monkeypatch):
    """A compile (here a slow unit wrapped around building the stepper, through the registry's own notice
    and clock): one line before and one after on the ``skfem_flex`` logger, its time in
    ``result.compile_time`` and not in ``wall_time``, and the progress bar opened only after it (no rate
    measured over the compile). A second, warm run says nothing."""
    import logging
    import time

    import tqdm

    events, lines = [], []

    class Bar:
        def __init__(self, total=None, initial=0, **kw):
            events.append(("open", initial, total))

        def update(self, n=1):
            events.append(("update", n))

        def reset(self, total=None):
            events.append(("reset", total))

        def set_postfix_str(self, s="", refresh=True):
            pass

        def close(self):
            events.append(("close",))

    class Lines(logging.Handler):
        def emit(self, record):
            lines.append(record.getMessage())

    real_stepper = driver.Stepper

    def slow_stepper(*args, **kw):
        def work():
            time.sleep(0.5)
            return real_stepper(*args, **kw)
        events.append(("compile",))
        return registry._compiling("a slow unit", work)

    handler = Lines()
    registry.LOGGER.addHandler(handler)
    level = registry.LOGGER.level
    registry.LOGGER.setLevel(logging.INFO)          # SKFEM_FLEX_QUIET may have set WARNING
    try:
        monkeypatch.setattr(tqdm, "tqdm", Bar)
        monkeypatch.setattr(driver, "Stepper", slow_stepper)
        res = sf.simulate(sf.scenes.get("spin_up_beam")(), 0.2, 0.02, progress=True)
        assert [m.split(" (")[0] for m in lines if "slow unit" in m][:1] == ["compiling a slow unit"], lines
        assert any(m.startswith("compiled a slow unit in ") for m in lines), lines
        assert res.compile_time >= 0.5 and res.wall_time < res.compile_time
        assert events[0] == ("compile",) and events[1] == ("open", 0, 10), events
        assert not any(e[0] == "reset" for e in events) and events[-1] == ("close",), events
        assert sum(e[1] for e in events if e[0] == "update") == res.steps == 10, events
        monkeypatch.setattr(driver, "Stepper", real_stepper)
        lines.clear()
        again = sf.simulate(sf.scenes.get("spin_up_beam")(), 0.2, 0.02)
        assert not any("compil" in m for m in lines) and again.compile_time == 0.0, lines
    finally:
        registry.LOGGER.removeHandler(handler)
        registry.LOGGER.setLevel(level)


def test_ctrl_c_during_a_cold_compile_stops_within_seconds(tmp_path):
    """An empty kernel cache: the first run says what it compiles; Ctrl-C (SIGINT) while it compiles
    ends the process within 5 s with exit status 130 and one line, not a traceback."""
    import signal
    import time

    import psutil

    # two compile processes: the helper (compiled/ahead.py) must go with the run
    env = package_env(NUMBA_CACHE_DIR=str(tmp_path), SKFEM_FLEX_QUIET="0", SKFEM_FLEX_COMPILE_PROCESSES="2")
    proc = subprocess.Popen([sys.executable, "-m", "skfem_flex.apps.cli", "run", "pendulum", "--t-end", "0.1"],
                            env=env, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                            cwd=str(tmp_path), preexec_fn=default_sigint)
    first = proc.stderr.readline()
    assert first.startswith("skfem-flex: compiling "), first
    time.sleep(0.5)
    helpers = psutil.Process(proc.pid).children(recursive=True)
    assert any("skfem_flex.compiled.ahead" in " ".join(h.cmdline()) for h in helpers), helpers
    proc.send_signal(signal.SIGINT)
    sent = time.perf_counter()
    try:
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert time.perf_counter() - sent <= 5.0
    assert proc.returncode == 130, (proc.returncode, err)
    gone, alive = psutil.wait_procs(helpers, timeout=5)
    assert not alive, alive
    assert "Traceback" not in err and "interrupted" in err, err


def test_divergence_is_caught_at_the_bodys_own_bound():
    """The spin-up with the linear axial strain (no geometric stiffening) diverges: its tip passes 1 m near
    t = 10 s. The floating beam's own bound (elastic coordinates ≤ 10 beam lengths) stops it at the first
    recorded state beyond 100 m, long before the run's end (it once ran to 30 s), keeping the history."""
    with pytest.raises(sf.DivergenceError, match="beyond the body's bound 100") as info:
        sf.simulate(sf.scenes.spin_up_beam(strain="linear"), 30.0, 1e-2)
    res = info.value.result
    tip = np.abs(res.probes["tip"][:, 1])
    assert 9.0 < res.t[np.argmax(tip > 1.0)] < 11.0 and res.t[-1] < 20.0
    assert np.abs(res.q[:-1, 3:]).max() <= 100.0 < np.abs(res.q[-1, 3:]).max()


@pytest.mark.parametrize("scheme", ["trapezoidal", "generalized-alpha"])
def test_an_energy_jump_is_refused_and_halved(scheme):
    """A hardening spring m ü = −k u⁷ (energy ½ exactly, conserved) stepped at Δt = 1 s, about a fifth of its
    period: the Newmark schemes' converged steps create energy in bulk (without the rule the trapezoidal
    run's energy rose to 2 J, 4× the exact value, in steps that tripled it). Such a step is refused and
    halved: the run completes with halvings and its energy stays below 2.2× the exact (1.0 J, against 2.0 J
    without the rule); with no halving allowed it stops naming the energy jump."""
    scene = sf.scenes.spring_mass(exponent=4.0)
    res = sf.simulate(scene, t_end=20.0, dt=1.0, integrator=scheme)
    assert res.completed and res.halvings >= 1
    assert res.total_energy.max() <= 2.2 * 0.5
    fine = sf.simulate(scene, t_end=20.0, dt=0.05, integrator=scheme)      # resolved: nothing refused
    assert fine.halvings == 0 and abs(fine.total_energy.max() - 0.5) < 0.01
    with pytest.raises(sf.ConvergenceError, match="energy rose by far more than the work"):
        sf.simulate(scene, t_end=20.0, dt=1.0, integrator=scheme, max_halvings=0)


def test_energy_jump_rule_counts_work_and_potential():
    """The rule (skfem_flex.compiled.acceptance.energy_jump): a fall under gravity turns potential into kinetic
    energy and a load's work into kinetic energy; neither is a jump, while kinetic energy tripled from
    nothing is, and round-off beside a large potential is not."""
    from skfem_flex.compiled.abi import CONTEXT
    from skfem_flex.compiled.acceptance import energy_jump
    from skfem_flex.compiled.tasks import REFUSAL_ENERGY, STATUS_REFUSED

    def jump(t0, v0, t1, v1, w):
        ctx = np.zeros(1, dtype=CONTEXT)
        out = energy_jump(ctx[0], t0, v0, t1, v1, w)
        assert out == (ctx[0]["status"] == STATUS_REFUSED) == (ctx[0]["refusal"] == REFUSAL_ENERGY)
        return out

    assert not jump(0.0, 10.0, 5.0, 5.0, 0.0)           # a fall: V → T
    assert not jump(1.0, 0.0, 3.0, 0.0, 2.0)            # work of a load
    assert not jump(1.0, 0.0, 0.9, 0.0, 0.0)            # dissipation
    assert jump(1.0, 0.0, 3.1, 0.0, 0.0)                # more than tripled from nothing
    assert not jump(1.0, 0.0, 2.9, 0.0, 0.0)            # not quite
    assert jump(1.0, 2.0, 4.0, 2.5, 0.0)                # +3.5 J where 5.5 J moved
    assert not jump(0.0, -1e6, 1e-10, -1e6 + 1e-9, 0.0)  # round-off at rest beside a large potential
