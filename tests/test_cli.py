"""Issue 7: the skfem-flex command (run, list, bad input, failed runs)."""
import json
import subprocess

import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.apps import cli
from skfem_flex.io.output import read_pvd
from skfem_flex.scenes import CATALOGUE, register

from helpers import command, package_env

PNG = b"\x89PNG\r\n\x1a\n"


def run_process(args, cwd, timeout=120):
    env = package_env()
    env.pop("DISPLAY", None)
    return subprocess.run(command() + args, cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)


def check_outputs(out, name):
    summary = json.loads((out / "summary.json").read_text())
    listed = read_pvd(out / f"{name}.pvd")
    assert listed and all(p.exists() for _, p in listed)
    assert sorted(p.name for p in out.glob(f"{name}_*.vtu")) == [p.name for _, p in listed]
    for png in out.glob("*.png"):
        assert png.read_bytes()[:8] == PNG
    assert (out / "energy.png").exists() and (out / "snapshots.png").exists()
    return summary, listed


def test_run_without_arguments_runs_the_default_scene(tmp_path):
    if cli.DEFAULT_SCENE not in CATALOGUE:
        pytest.skip(f"default scene {cli.DEFAULT_SCENE!r} is not in the catalogue yet")
    proc = run_process(["run"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "results" / cli.DEFAULT_SCENE
    summary, _ = check_outputs(out, cli.DEFAULT_SCENE)
    assert summary["completed"] and summary["scene"] == cli.DEFAULT_SCENE
    assert str(out.resolve()) in proc.stdout


def test_run_pendulum_with_settings(tmp_path):
    proc = run_process(["run", "pendulum", "--set", "length=0.7", "--dt", "0.01", "--t-end", "1", "--out", "o"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    out = tmp_path / "o"
    summary, listed = check_outputs(out, "pendulum")
    assert summary["parameters"]["length"] == 0.7
    assert summary["dt"] == 0.01 and summary["steps"] == round(summary["t_end"] / 0.01)
    assert summary["completed"] and summary["error"] is None
    assert summary["max_constraint_residual"] < 1e-10
    assert summary["energy"]["relative_balance_error"] < 1e-10
    assert summary["newton"]["total_iterations"] > 0
    assert len(listed) == summary["steps"] + 1
    res = sf.Result.load(out / "result.npz")
    # the bob hangs at distance 0.7 from the pivot
    np.testing.assert_allclose(np.hypot(res.q[:, 0], res.q[:, 1]), 0.7, rtol=1e-12)
    assert (out / "probes.csv").read_text().startswith("t,position[0],position[1]")
    assert str(out.resolve()) in proc.stdout and "pendulum.pvd" in proc.stdout


@pytest.mark.parametrize("args, message", [
    (["run", "no_such_scene"], "unknown scene 'no_such_scene'"),
    (["run", "pendulum", "--set", "colour=red"], "has no parameter 'colour'"),
    (["run", "pendulum", "--set", "length=abc"], "length needs a number"),
    (["run", "pendulum", "--set", "length"], "expects key=value"),
    (["run", "pendulum", "--set", "length=-1"], "length"),
    (["run", "pendulum", "--dt", "0"], "--dt must be a positive"),
    (["run", "pendulum", "--dt", "-0.01"], "--dt must be a positive"),
    (["run", "pendulum", "--dt", "fast"], "--dt"),
    (["run", "pendulum", "--t-end", "nan"], "--t-end"),
    (["run", "pendulum", "--every", "0"], "--every"),
    (["run", "pendulum", "--integrator", "euler"], "--integrator"),
    (["run", "pendulum", "--unknown-flag"], "unrecognized arguments"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_input_exits_2_with_one_line(args, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("skfem-flex: error:"), err
    assert message in err
    assert not (tmp_path / "results").exists()


def test_unwritable_out_exits_2(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    for out in (blocker, blocker / "sub"):
        assert cli.main(["run", "pendulum", "--out", str(out), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--out" in err, err


def test_bad_input_in_a_process_has_no_traceback(tmp_path):
    proc = run_process(["run", "pendulum", "--dt", "0"], tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "Traceback" not in proc.stderr
    assert "dt" in proc.stderr


def test_failed_run_exits_1_and_keeps_its_outputs(tmp_path, capsys):
    # V = ½ u³ is unbounded below: the mass escapes to −∞ and Newton gives up
    out = tmp_path / "escape"
    rc = cli.main(["run", "spring_mass", "--set", "exponent=1.5", "--t-end", "100", "--dt", "0.1",
                   "--out", str(out), "--quiet"])
    assert rc == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Newton" in err and "Traceback" not in err
    summary, listed = check_outputs(out, "spring_mass")
    assert summary["completed"] is False and "Newton" in summary["error"]
    assert 0 < summary["steps"] < 1000
    res = sf.Result.load(out / "result.npz")
    assert not res.completed
    assert listed[-1][0] == pytest.approx(res.t[-1])


def test_scene_defaults_every_and_no_vtk(tmp_path, capsys):
    def tiny_pendulum(length=0.5, damped=False, label="x", count=3):
        return sf.scenes.pendulum(length=length)

    register(t_end=0.05, dt=0.01, length="m")(tiny_pendulum)
    try:
        assert tiny_pendulum.defaults == {"t_end": 0.05, "dt": 0.01}
        assert cli.main(["run", "tiny_pendulum", "--out", str(tmp_path / "a"), "--every", "2", "--quiet",
                         "--set", "damped=yes", "count=4.0", "label=abc"]) == 0
        assert capsys.readouterr().out == ""
        summary = json.loads((tmp_path / "a" / "summary.json").read_text())
        assert summary["t_end"] == 0.05 and summary["steps"] == 5
        # steps 0, 2, 4 and the last one
        assert len(read_pvd(tmp_path / "a" / "tiny_pendulum.pvd")) == 4
        assert cli.main(["run", "tiny_pendulum", "--out", str(tmp_path / "b"), "--no-vtk", "--quiet"]) == 0
        assert not list((tmp_path / "b").glob("*.vtu")) and (tmp_path / "b" / "summary.json").exists()
    finally:
        CATALOGUE.pop("tiny_pendulum", None)


def test_convert_setting_uses_the_type_of_the_default():
    assert cli.convert_setting("a", "0.7", 0.5) == 0.7
    assert cli.convert_setting("n", "8", 4) == 8 and isinstance(cli.convert_setting("n", "8.0", 4), int)
    assert cli.convert_setting("b", "false", True) is False and cli.convert_setting("b", "1", False) is True
    assert cli.convert_setting("s", "exact", "linear") == "exact"
    for text, default in [("1.5", 4), ("maybe", True), ("inf", 1.0)]:
        with pytest.raises(cli.UsageError):
            cli.convert_setting("x", text, default)


def test_list_shows_scenes_parameters_defaults_and_units(capsys):
    assert cli.main(["list"]) == 0
    out = capsys.readouterr().out
    assert "pendulum" in out and "spring_mass" in out
    lines = out.splitlines()
    start = lines.index("pendulum")
    line = next(ln for ln in lines[start:] if ln.strip().startswith("length"))
    assert "0.5" in line and line.rstrip().endswith("m")


def test_parser_has_subcommands():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert {"run", "list"} <= set(sub.choices)


# ---------------------------------------------------------------- first-hour surprises
def _one_error_line(capsys):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("skfem-flex: error:"), err
    assert "internal error" not in err and "please report" not in err
    return err


@pytest.mark.parametrize("mesh, why", [("/nonexistent.msh", "does not exist"),
                                       (".", "is a directory"),
                                       ("summary.txt", "is not a mesh meshio can read")])
def test_a_missing_or_unreadable_mesh_file_is_bad_input_naming_the_file(mesh, why, capsys, tmp_path, monkeypatch):
    """slider_crank takes a mesh file (``mesh``, for the plane-stress rod)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "summary.txt").write_text("not a mesh\n")
    assert cli.main(["run", "slider_crank", "--set", "body=plane-stress", f"mesh={mesh}", "--quiet"]) == 2
    err = _one_error_line(capsys)
    assert f"mesh file {mesh!r} {why}" in err


def test_resume_to_a_time_the_run_already_passed_is_refused(capsys, tmp_path):
    out = tmp_path / "o"
    assert cli.main(["run", "spring_mass", "--t-end", "1.1", "--dt", "0.1", "--out", str(out), "--quiet"]) == 0
    assert cli.main(["run", "--resume", str(out), "--t-end", "0.5", "--quiet"]) == 2
    err = _one_error_line(capsys)
    assert "already reached t = 1.1 s" in err and "--t-end must be beyond it" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["t_end"] == 1.1 and summary["t_reached"] == pytest.approx(1.1)     # untouched
    # beyond it, the run goes on
    assert cli.main(["run", "--resume", str(out), "--t-end", "1.5", "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["t_reached"] == pytest.approx(1.5)


@pytest.mark.parametrize("argv, wrong", [
    (["campbell", "rotating_beam", "--vary", "omega=0,fast"], "--vary omega=fast: omega needs a number"),
    (["campbell", "rotating_beam", "--vary", "omega=0:4:many"], "--vary omega=many: omega needs an integer"),
    (["sweep", "spring_mass", "--vary", "m=1,heavy"], "--vary m=heavy: m needs a number"),
])
def test_errors_of_vary_values_name_vary(argv, wrong, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == 2
    err = _one_error_line(capsys)
    assert wrong in err and "--set" not in err


def test_the_report_says_the_step_the_run_took(capsys, tmp_path):
    """A run shorter than its step takes one step of t_end (the last step lands on t_end)."""
    assert cli.main(["run", "spring_mass", "--t-end", "0.01", "--dt", "0.5", "--out", str(tmp_path / "a"),
                     "--no-vtk"]) == 0
    out = capsys.readouterr().out
    assert "spring_mass: 1 step of 0.01 s to t = 0.01 s" in out
    assert cli.main(["run", "spring_mass", "--t-end", "1.05", "--dt", "0.1", "--out", str(tmp_path / "b"),
                     "--no-vtk"]) == 0
    assert "spring_mass: 11 steps of 0.1 s (the last one 0.05 s) to t = 1.05 s" in capsys.readouterr().out


def test_the_summary_names_the_code_path_and_the_compile_time(capsys, tmp_path):
    """Which path ran is never silent: summary.json holds ``run_path`` (loop, solver, storage, the elements
    that ran through Python) and the run's compile time, and the printed report names them."""
    out = tmp_path / "o"
    assert cli.main(["run", "pendulum", "--t-end", "0.05", "--dt", "0.01", "--out", str(out), "--no-vtk"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    path = summary["run_path"]
    assert path["loop"] == "compiled" and path["python_elements"] == []
    assert isinstance(path["solver"], str) and path["solver"] and path["storage"] in ("dense", "sparse")
    assert isinstance(summary["compile_time_s"], float) and summary["compile_time_s"] >= 0.0
    assert f"{path['solver']} solver" in printed and "compiled loop" in printed, printed
    assert f"of which {summary['compile_time_s']:.2f} s compiling" in printed, printed


def test_probe_plots_label_their_units():
    from skfem_flex.io.plots import plot_probes, probe_units

    scene = sf.scenes.pendulum()
    assert probe_units(scene) == {"position": "m"}            # a PointProbe: a position
    assert probe_units(sf.scenes.rotating_beam()) == {"tip": "m"}
    assert probe_units(sf.scenes.spring_mass()) == {"u": "SI"}  # a plain function: SI, nothing more known
    result = sf.simulate(scene, 0.02, 0.01)
    fig = plot_probes(result, units=probe_units(scene))
    assert fig.axes[0].get_ylabel() == "position (m)"


def test_no_plots_writes_everything_but_the_plots(tmp_path):
    out = tmp_path / "o"
    assert cli.main(["run", "pendulum", "--t-end", "0.05", "--out", str(out), "--no-vtk", "--no-plots", "--quiet"]) == 0
    assert (out / "summary.json").exists() and (out / "result.npz").exists()
    assert not list(out.glob("*.png"))
