"""Interrupted, killed and resumed runs of ``skfem-flex run`` (issue: nothing lost, nothing silent).

A real ``skfem-flex run`` subprocess is stopped with SIGINT, SIGTERM and SIGKILL at random
moments of its time loop. Afterwards the output directory must hold collections that parse
and list only complete frames, no temporary files, and histories that ``Result.load`` reads
(``result.npz`` after SIGINT/SIGTERM, ``checkpoint.npz`` after SIGKILL); ``run --resume``
must then finish the run with exactly the histories of an uninterrupted run.
"""
import json
import os
import random
import signal
import subprocess
import sys
import time
from unittest import mock

import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.apps.cli import main
from skfem_flex.io.output import read_pvd

from helpers import default_sigint, package_env

SCENE, T_END, DT = "pendulum", 10.0, 0.01


@pytest.fixture(scope="module")
def reference():
    """The uninterrupted run (every step recorded, as the CLI records), on the Python path as the runs below."""
    return sf.simulate(sf.scenes.get(SCENE)(), T_END, DT, compiled=False)


def start_run(out):
    # the Python path polls signals after every step; the compiled one after every chunk, and the whole
    # pendulum run is one chunk of a few milliseconds, which no signal sent "during the loop" could hit
    env = package_env(SKFEM_FLEX_COMPILED="0")
    return subprocess.Popen([sys.executable, "-m", "skfem_flex", "run", SCENE, "--t-end", str(T_END), "--dt", str(DT),
                             "--out", str(out), "--quiet", "--every", "2", "--checkpoint-every", "0.2"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_sigint)


def wait_for_loop(proc, out, timeout=60.0):
    """Until the first frames are listed (the time loop runs), then a random moment later."""
    end = time.time() + timeout
    series = out / f"{SCENE}.vtu.series"
    while time.time() < end:
        assert proc.poll() is None, proc.stderr.read()
        try:
            if len(json.loads(series.read_text())["files"]) >= 3:
                break
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.02)
    time.sleep(random.uniform(0.0, 0.5))


def check_collections(out, unlisted_allowed, tmp_allowed=0, killed=False):
    """Both collections parse, agree, list increasing times of existing complete frames; no .tmp
    (after SIGKILL: the files that were being written, which the next run or resume removes).

    The two collections are renamed into place one after the other, so a SIGKILL between the two
    renames leaves one a few frames longer than the other: after a kill each must list a prefix of
    the frames written (the shorter a prefix of the longer), and each is checked on its own.
    """
    listed = read_pvd(out / f"{SCENE}.pvd")
    series = json.loads((out / f"{SCENE}.vtu.series").read_text())["files"]
    pvd_names, series_names = [p.name for _, p in listed], [e["name"] for e in series]
    if killed:
        shorter, longer = sorted((pvd_names, series_names), key=len)
        assert longer[:len(shorter)] == shorter
        assert len(series_names) >= 1 and all((out / name).exists() for name in series_names)
    else:
        assert pvd_names == series_names
    times = [t for t, _ in listed]
    assert times == sorted(times) and len(set(times)) == len(times)
    for _, p in listed:
        assert p.exists() and p.stat().st_size > 0
    on_disk = {p.name for p in out.glob(f"{SCENE}_*.vtu")}
    assert {p.name for _, p in listed} <= on_disk
    assert len(on_disk) - len(listed) <= unlisted_allowed
    if killed:                           # the series may lag the .pvd by the batch being listed
        assert len(on_disk) - len(series_names) <= 2 * unlisted_allowed
    assert len([p.name for p in out.iterdir() if p.name.endswith(".tmp")]) <= tmp_allowed
    return listed


def check_resume_equals_reference(out, reference):
    with mock.patch.dict(os.environ, SKFEM_FLEX_COMPILED="0"):
        assert main(["run", "--resume", str(out), "--quiet"]) == 0
    res = sf.Result.load(out / "result.npz")
    assert res.completed and len(res.t) == len(reference.t)
    for name in ("t", "q", "v", "lam", "total_energy", "external_work"):
        np.testing.assert_allclose(getattr(res, name), getattr(reference, name), rtol=1e-12, atol=1e-12,
                                   err_msg=name)
    assert json.loads((out / "summary.json").read_text())["completed"] is True
    listed = check_collections(out, unlisted_allowed=0)
    assert abs(listed[-1][0] - T_END) < 1e-9
    assert not (out / "checkpoint.npz").exists()


def check_stopped_by_signal(proc, out, reference, status):
    """SIGINT/SIGTERM: exit status, one line, histories and summary of the steps done, series complete."""
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    assert "Traceback" not in err and "interrupted at t = " in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False and summary["stopped"].startswith("interrupted at t = ")
    res = sf.Result.load(out / "result.npz")
    assert not res.completed and 0 < res.t[-1] < T_END
    n = len(res.t)
    # the histories so far are those of the uninterrupted run
    np.testing.assert_allclose(res.q, reference.q[:n], rtol=1e-12, atol=1e-12)
    probes = np.loadtxt(out / "probes.csv", delimiter=",", skiprows=1)
    assert probes.shape[0] == n
    check_collections(out, unlisted_allowed=0)


def check_killed(proc, out, reference):
    """SIGKILL: no summary, at most the frame in flight unlisted, the checkpoint holds the steps so far."""
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert not (out / "summary.json").exists()
    # the frame, a collection and the checkpoint in flight may be left as temporary files (resume removes
    # them); the collections list every frame up to at most N/256 frames before the kill
    n_frames = len(list(out.glob(f"{SCENE}_*.vtu")))
    check_collections(out, unlisted_allowed=max(1, n_frames // 256) + 1, tmp_allowed=3, killed=True)
    res = sf.Result.load(out / "checkpoint.npz")
    n = len(res.t)
    assert n >= 2 and res.final_state is not None
    np.testing.assert_allclose(res.q, reference.q[:n], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("trial", range(1))
def test_sigint_sigterm_sigkill_at_random_moments_then_resume(tmp_path, reference, trial):
    """Three runs at once, stopped by SIGINT, SIGTERM and SIGKILL at random moments of their loops;
    each keeps what the issue asks for, and ``run --resume`` then gives the uninterrupted result."""
    runs = {sig: (tmp_path / sig.name, start_run(tmp_path / sig.name))
            for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)}
    for sig, (out, proc) in runs.items():
        wait_for_loop(proc, out)
        if sig == signal.SIGKILL:
            time.sleep(0.3)                  # at least one checkpoint interval into the loop
        proc.send_signal(sig)
    for sig, (out, proc) in runs.items():
        if sig == signal.SIGKILL:
            check_killed(proc, out, reference)
        else:
            check_stopped_by_signal(proc, out, reference, 130 if sig == signal.SIGINT else 143)
        check_resume_equals_reference(out, reference)


def test_python_resume_equals_uninterrupted_generalized_alpha(tmp_path):
    """simulate(..., resume=...) carries what generalized-α needs (accelerations) across the break."""
    scene = sf.scenes.get("double_pendulum")
    full = sf.simulate(scene(), 0.06, 0.002, integrator="generalized-alpha", rho_inf=0.8)
    first = sf.simulate(scene(), 0.03, 0.002, integrator="generalized-alpha", rho_inf=0.8)
    path = first.save(tmp_path / "first.npz")
    rest = sf.simulate(scene(), 0.06, 0.002, integrator="generalized-alpha", rho_inf=0.8, resume=path)
    assert len(rest.t) == len(full.t)
    np.testing.assert_allclose(rest.q, full.q, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(rest.v, full.v, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="generalized-alpha"):
        sf.simulate(scene(), 0.06, 0.002, resume=path)
    with pytest.raises(ValueError, match="dt"):
        sf.simulate(scene(), 0.06, 0.001, integrator="generalized-alpha", rho_inf=0.8, resume=path)


def test_python_resume_of_the_compiled_loop_extends_a_finished_run():
    """The compiled spin-up loop resumed from a finished 3 s run (extended to 6 s) follows the
    uninterrupted 6 s run to round-off (chunk boundaries move; the arithmetic is the same)."""
    make = sf.scenes.spin_up_beam
    full = sf.simulate(make(), 6.0, 0.02)
    rest = sf.simulate(make(), 6.0, 0.02, resume=sf.simulate(make(), 3.0, 0.02))
    assert rest.completed and len(rest.t) == len(full.t)
    np.testing.assert_allclose(rest.q, full.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(rest.total_energy - rest.external_work, full.total_energy - full.external_work,
                               rtol=0, atol=1e-8)
