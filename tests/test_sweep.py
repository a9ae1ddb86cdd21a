"""Parameter sweeps on a local Dask cluster: bit-for-bit equality with serial runs, faults, resume, kernels
compiled once per machine, the command line's bar, table and study options."""
import json
import logging
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import xarray as xr
from distributed import Client, LocalCluster

import skfem_flex as sf
from skfem_flex.schemes import NewtonSettings
from skfem_flex.apps.sweep import local_cluster, open_sweep, plan, probe_extremes

from helpers import PACKAGE_PARENT, package_env

GRID = {"omega": [4.0, 6.0, 8.0, 10.0], "n_elements": [2, 3, 4, 6]}


@pytest.fixture(scope="module")
def client():
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def _same(case, res):
    """Every stored history of a case equals the serial Result exactly."""
    n = int(case.n_times)
    pairs = [(case.t, res.t), (case.probe_tip, res.probes["tip"]), (case.q, res.q), (case.v, res.v),
             (case.kinetic, res.kinetic), (case.potential, res.potential), (case.external_work, res.external_work),
             (case.energy_balance_error, res.energy_balance_error), (case.newton_iterations, res.newton_iterations),
             (case.constraint_residual, res.constraint_residual)]
    for a, b in pairs:
        a = a.values
        own = a[tuple(slice(0, m) for m in b.shape)]     # the rest is NaN padding (other meshes are larger)
        if not (np.array_equal(own, b) and np.isnan(a).sum() == a.size - b.size):
            return False
    return n == len(res.t) and int(case.steps) == res.steps


def test_sixteen_cases_on_two_workers_equal_serial_runs_bit_for_bit(client, tmp_path):
    record = ("probes", "energy", "residuals", "newton", "state")
    ds = sf.sweep("spin_up_beam", vary=GRID, t_end=1.0, dt=0.01, record=record, store=tmp_path / "s",
                  client=client)
    assert ds.sizes["case"] == 16 and ds.attrs["computed"] == 16 and ds.attrs["skipped"] == 0
    assert set(ds.status.values) == {"completed"}
    assert len(set(ds.worker.values)) == 2          # the cases really were spread over both workers
    # grid order: itertools.product, last name fastest
    assert list(ds.omega.values) == [w for w in GRID["omega"] for _ in GRID["n_elements"]]
    assert list(ds.n_elements.values) == GRID["n_elements"] * 4
    for i in range(16):
        case = ds.isel(case=i)
        res = sf.simulate(sf.scenes.spin_up_beam(omega=float(case.omega), n_elements=int(case.n_elements)), 1.0, 0.01)
        assert _same(case, res), f"case {i} differs from the serial run"
    # the store holds the same numbers; each case opens with plain xarray
    stored = open_sweep(tmp_path / "s")
    assert stored.sizes["case"] == 16
    xr.testing.assert_identical(stored.drop_attrs(), ds.drop_attrs())
    one = xr.open_dataset(tmp_path / "s" / f"{ds.case.values[5]}.nc", engine="scipy")
    assert np.array_equal(one.probe_tip.values, ds.probe_tip.values[5]) and one.status.item() == "completed"
    # same plan again: nothing is computed
    again = sf.sweep("spin_up_beam", vary=GRID, t_end=1.0, dt=0.01, record=record, store=tmp_path / "s",
                     client=client)
    assert (again.attrs["computed"], again.attrs["skipped"]) == (0, 16)
    # another setting is another case: dt enters the key
    other = sf.sweep("spin_up_beam", vary={"omega": [4.0]}, t_end=1.0, dt=0.02, record=record,
                     store=tmp_path / "s", client="serial")
    assert other.attrs["computed"] == 1 and len(open_sweep(tmp_path / "s").case) == 17


def test_a_failing_case_is_recorded_and_the_others_are_unaffected(client, tmp_path):
    no_newton = NewtonSettings(max_iterations=1)
    cases = [{"omega": 4.0}, {"n_elements": 0}, {"omega": 6.0, "newton": no_newton, "max_halvings": 0},
             {"omega": 6.0}, {"omega": 4.0, "dt": 0.05}]
    ds = sf.sweep("spin_up_beam", cases=cases, t_end=0.5, dt=0.01, store=tmp_path / "f", client=client)
    assert list(ds.status.values) == ["completed", "error", "failed", "completed", "completed"]
    assert "n_elements must be a positive integer, got 0" in str(ds.message.values[1])
    assert "ValueError" in str(ds.message.values[1]) and int(ds.n_times[1]) == 0
    assert "Newton" in str(ds.message.values[2]) or "converge" in str(ds.message.values[2]).lower()
    assert int(ds.n_times[2]) >= 1              # the history up to the failure is kept (here: the initial state)
    # cases with another step have fewer times: padded with NaN, their own length recorded
    assert int(ds.n_times[4]) == 11 and np.isnan(ds.t.values[4, 11:]).all() and "time" not in ds.coords
    for i, kw in ((0, {}), (3, {"omega": 6.0})):
        res = sf.simulate(sf.scenes.spin_up_beam(**kw), 0.5, 0.01)
        assert _same_without_state(ds.isel(case=i), res)
    short = sf.simulate(sf.scenes.spin_up_beam(), 0.5, 0.05)
    assert _same_without_state(ds.isel(case=4), short)
    # failures are stored like any case, with their status
    stored = open_sweep(tmp_path / "f")
    assert sorted(p.suffix for p in (tmp_path / "f").iterdir()) == [".json"] + [".nc"] * 5
    assert list(stored.status.values) == list(ds.status.values)
    ext = probe_extremes(ds, "tip")
    assert np.isnan(ext.values[1]).all() and np.all(np.abs(ext.values[0]) > 0)
    assert float(ext.values[0, 1]) == pytest.approx(ds.probe_tip.values[0, :, 1][
        np.nanargmax(np.abs(ds.probe_tip.values[0, :, 1]))])


def _same_without_state(case, res, probe="tip"):
    n = int(case.n_times)
    return n == len(res.t) and np.array_equal(case[f"probe_{probe}"].values[:n], res.probes[probe]) \
        and np.array_equal(case.total_energy.values[:n], res.total_energy)


def test_bad_plans_are_rejected_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="no parameter 'omegax'"):
        plan("spin_up_beam", vary={"omegax": [1.0]}, t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="unknown scene 'nope'"):
        plan("nope", vary={"omega": [1.0]}, t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="not both"):
        plan("spin_up_beam", vary={"omega": [1.0]}, cases=[{}], t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="give name="):
        plan(lambda: sf.scenes.pendulum(), t_end=1.0, dt=0.1)
    with pytest.raises(TypeError, match="unexpected option"):
        plan("pendulum", t_end=1.0, dt=0.1, progress=True)
    with pytest.raises(ValueError, match="integrator"):
        plan("pendulum", t_end=1.0, dt=0.1, integrator="euler")
    # an int for a float parameter is the same case as the float
    assert plan("spin_up_beam", vary={"omega": [4]}, t_end=1, dt=0.1)[0].key == \
        plan("spin_up_beam", vary={"omega": [4.0]}, t_end=1, dt=0.1)[0].key
    (tmp_path / "not_a_store").mkdir()
    with pytest.raises(ValueError, match="not a skfem_flex sweep store"):
        open_sweep(tmp_path / "not_a_store")


def test_worker_killed_mid_case_the_sweep_still_completes_every_case(client, tmp_path):
    # case 0 is slow (60 000 steps, over a second even on a fast machine), so the kill lands while it runs; the
    # others are short
    cases = [{"n_elements": 16, "t_end": 60.0}] + [{"omega": w} for w in (4.0, 5.0, 6.0, 7.0)]
    slow = plan("spin_up_beam", cases=cases, t_end=1.0, dt=1e-3)[0].task_name
    pids = client.run(os.getpid)
    out = {}
    runner = threading.Thread(target=lambda: out.update(ds=sf.sweep(
        "spin_up_beam", cases=cases, t_end=1.0, dt=1e-3, store=tmp_path / "k", client=client)))
    runner.start()
    victim, deadline = None, time.monotonic() + 30
    while victim is None and time.monotonic() < deadline:
        for addr, keys in client.processing().items():
            if slow in keys:
                victim = addr
        time.sleep(0.05)
    assert victim is not None, "the slow case never started"
    time.sleep(0.2)                               # well inside the slow case
    assert slow in client.processing()[victim], "the slow case finished before the kill"
    os.kill(pids[victim], signal.SIGKILL)
    runner.join(timeout=120)
    ds = out["ds"]
    assert list(ds.status.values) == ["completed"] * 5
    assert float(ds.t_reached[0]) == pytest.approx(60.0)
    # the slow case was finished by a worker process other than the one killed
    assert not str(ds.worker.values[0]).endswith(f":{pids[victim]}")
    assert len(open_sweep(tmp_path / "k").case) == 5


def _cli(*args):
    env = package_env()
    return subprocess.Popen([sys.executable, "-m", "skfem_flex", "sweep", *args], env=env, cwd=PACKAGE_PARENT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)


def _finished(store):
    return sorted(d.name for d in store.iterdir() if d.is_dir() and not d.name.startswith(".")) \
        if store.exists() else []


def test_driver_killed_then_resume_computes_only_the_missing_cases(client, tmp_path):
    out = tmp_path / "run"
    store = out / "sweep.zarr"
    args = ["spin_up_beam", "--vary", "omega=4,5,6,7,8,9,10,11", "--t-end", "30", "--dt", "1e-3",
            "--format", "zarr", "--out", str(out), "--quiet"]
    proc = _cli(*args, "--workers", "1")        # its own local cluster, killed with it
    opened = 0
    try:
        deadline = time.monotonic() + 90
        # cases take about half a second each (30 000 steps; at 10 000 steps all eight were once done before
        # this loop saw two): kill as soon as two are in the store
        while len(_finished(store)) < 2 and time.monotonic() < deadline and proc.poll() is None:
            if store.exists():
                # the store opens with xarray at any moment while the sweep writes
                tree = xr.open_datatree(store, engine="zarr", consolidated=False)
                assert len(tree.children) <= len(open_sweep(store).case)
                opened += 1
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)      # the driver and the cluster it started
        proc.communicate()
    done = _finished(store)
    assert 2 <= len(done) < 8, f"{len(done)} cases were finished when the driver was killed"
    assert opened > 0
    # after the kill: opens with xarray, every case in it complete
    killed = open_sweep(store)
    assert set(killed.status.values) == {"completed"} and len(killed.case) == len(done)
    assert np.all(killed.n_times.values == 30001)
    before = {k: (store / k).stat().st_ino for k in done}
    # the rerun goes to a running cluster by its scheduler address
    proc = _cli(*args, "--resume", "--scheduler", client.scheduler.address)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    report = json.loads((out / "sweep.json").read_text())
    assert (report["computed"], report["skipped"], report["cases"]) == (8 - len(done), len(done), 8)
    assert {k: (store / k).stat().st_ino for k in done} == before    # the finished cases were not rewritten
    final = open_sweep(store)
    assert len(final.case) == 8 and set(final.status.values) == {"completed"}
    assert sorted(final.omega.values) == [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0]
    assert not any(p.name.startswith(".") for p in store.iterdir() if p.is_dir())
    assert (out / "extremes_tip.png").stat().st_size > 0 and (out / "summary.csv").exists()


def test_cli_sweep_rejects_bad_input_with_one_line_and_status_2(tmp_path, capsys):
    from skfem_flex.apps.cli import main

    for args, text in ((["nope", "--vary", "omega=1"], "unknown scene 'nope'"),
                       (["spin_up_beam", "--vary", "omegax=1"], "no parameter 'omegax'"),
                       (["spin_up_beam", "--vary", "n_elements=4.5"], "--vary n_elements=4.5"),
                       (["spin_up_beam", "--vary", "omega=1", "--set", "omega=2"], "both fixed"),
                       (["spin_up_beam"], "--vary")):
        assert main(["sweep", *args, "--out", str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err
        assert text in err and len(err.strip().splitlines()) == 1, err


def test_studies_run_their_cases_through_the_sweep_on_a_cluster_and_resume(client, tmp_path):
    from skfem_flex.apps import studies

    period = studies.oscillator_period(2.0)
    dts = [period / 20, period / 40]
    serial = studies.work_precision("spring_mass", schemes=["energy-momentum", "trapezoidal"], dts=dts)
    spread = studies.work_precision("spring_mass", schemes=["energy-momentum", "trapezoidal"], dts=dts,
                                    store=tmp_path / "wp", client=client)
    assert [(r.scheme, r.dt, r.steps, r.error) for r in spread] == [(r.scheme, r.dt, r.steps, r.error) for r in serial]
    again = studies.work_precision("spring_mass", schemes=["energy-momentum", "trapezoidal"], dts=dts,
                                   store=tmp_path / "wp", client=client)
    assert again == spread          # read back from the store: the same wall times, so nothing ran again
    assert len(open_sweep(tmp_path / "wp").case) == 4


def test_a_mixed_sweep_compiles_each_kernel_once_per_machine(tmp_path):
    # three schemes, two step kernels: trapezoidal and generalized-alpha share the Newmark step, energy-momentum
    # has its own; warming only the first case would leave the second kernel to both workers at once.
    cache, log = tmp_path / "numba-cache", tmp_path / "saves"
    cache.mkdir()
    log.mkdir()

    def log_compilations(log_dir):
        """In a worker: append (cache index, signature, index existed before) to a log at every save numba
        makes into its cache (one save per compilation)."""
        import json as _json
        import os as _os

        import numba
        from numba.core import caching

        save = caching.Cache.save_overload

        def logged(self, sig, data):
            index = self._cache_file._index_path
            existed = _os.path.exists(index)
            save(self, sig, data)
            with open(_os.path.join(log_dir, f"{_os.getpid()}.jsonl"), "a") as fh:
                fh.write(_json.dumps([_os.path.basename(index), str(sig), existed]) + "\n")
        caching.Cache.save_overload = logged
        return numba.config.CACHE_DIR

    # the mass on a nonlinear spring: the scene with the fewest compiled units (its small dense solver compiles in
    # a second where the beam's band solver takes seven)
    vary = {"integrator": ["trapezoidal", "generalized-alpha", "energy-momentum"], "u0": [1.0, 1.5]}
    # one compile process per worker: a helper (compiled/ahead.py) would compile outside the logged workers
    env = {"NUMBA_CACHE_DIR": str(cache), "SKFEM_FLEX_COMPILE_PROCESSES": "1"}
    with local_cluster(2, env=env) as cluster, Client(cluster) as c:
        assert set(c.run(log_compilations, str(log)).values()) == {str(cache)}
        ds = sf.sweep("spring_mass", vary=vary, t_end=0.5, dt=0.05, compiled=False, client=c)
    assert set(ds.status.values) == {"completed"} and len(set(ds.worker.values)) == 2
    saves = [json.loads(line) for f in log.iterdir() for line in f.read_text().splitlines()]
    indexes = sorted(p.name for p in cache.rglob("*.nbi"))
    assert any("energy_momentum" in name for name in indexes) and any("newmark" in n for n in indexes), indexes
    # every kernel was compiled for each of its signatures once on this machine, and its index created once
    per_signature = {}
    for index, sig, _ in saves:
        per_signature[index, sig] = per_signature.get((index, sig), 0) + 1
    assert {k: n for k, n in per_signature.items() if n != 1} == {}
    assert sorted(index for index, _, existed in saves if not existed) == indexes
    for i in range(ds.sizes["case"]):
        case = ds.isel(case=i)
        res = sf.simulate(sf.scenes.spring_mass(u0=float(case.u0)), 0.5, 0.05,
                          integrator=str(case.integrator.item()), compiled=False)
        assert _same_without_state(case, res, probe="u"), f"case {i} differs from the serial run"


def test_build_key_follows_what_is_compiled():
    """Cases share a build key when they compile the same units: numbers that change values only (a speed)
    keep it; a size that switches the Newton matrix to sparse storage, a scheme or the Python path change it."""
    from skfem_flex.compiled.pack import build_key

    small = build_key(sf.scenes.spin_up_beam(n_elements=4, omega=4.0), "energy-momentum")
    assert build_key(sf.scenes.spin_up_beam(n_elements=4, omega=6.0), "energy-momentum") == small
    assert build_key(sf.scenes.spin_up_beam(n_elements=4), "trapezoidal") != small
    assert build_key(sf.scenes.spin_up_beam(n_elements=4), "energy-momentum", python_only=True) != small
    large = build_key(sf.scenes.spin_up_beam(n_elements=400), "energy-momentum")
    assert large[1] == small[1] and large[2:] != small[2:]          # same families, other storage/solver


def test_cli_sweep_shows_a_progress_bar_and_a_summary_table(client, tmp_path, capsys):
    from skfem_flex.apps.cli import main

    out = tmp_path / "bar"
    assert main(["sweep", "spin_up_beam", "--vary", "omega=4,6", "--t-end", "0.05", "--dt", "0.01",
                 "--scheduler", client.scheduler.address, "--out", str(out)]) == 0
    captured = capsys.readouterr()
    header = captured.out.splitlines()[0].split()
    assert header[:6] == ["omega", "status", "steps", "wall_time", "newton_per_step", "max_energy_balance_error"]
    assert "tip extreme[0]" in captured.out.splitlines()[0] and header[-1] == "message"
    assert sum(line.split()[:2] in (["4", "completed"], ["6", "completed"]) for line in captured.out.splitlines()) == 2
    assert "2 cases: 2 computed, 0 read from the store" in captured.out
    # tqdm's bar over cases, on stderr, finished
    assert re.search(r"sweep: 100%\|.*\| 2/2 \[.*(case/s|s/case)", captured.err), captured.err


def test_cli_study_on_a_cluster_with_a_store_and_a_rerun_that_computes_nothing(client, tmp_path, capsys):
    from skfem_flex.apps.cli import main

    store = tmp_path / "runs"
    args = ["study", "stability", "--cases", "quartic_T4", "pendulum_near_upright",
            "--schemes", "energy-momentum", "trapezoidal", "--quick", "--store", str(store)]
    assert main([*args, "--scheduler", client.scheduler.address, "--out", str(tmp_path / "a")]) == 0
    first = capsys.readouterr().out
    assert "4 runs: 4 computed, 0 read from the store" in first
    assert len(open_sweep(store).case) == 4
    written = {p.name: p.stat().st_mtime_ns for p in store.iterdir()}
    # the rerun (in this process, the default) reads every run back: same table, wall times included
    assert main([*args, "--out", str(tmp_path / "b")]) == 0
    again = capsys.readouterr().out
    assert "4 runs: 0 computed, 4 read from the store" in again
    table = (tmp_path / "a" / "stability.md").read_text()
    assert (tmp_path / "b" / "stability.md").read_text() == table and table in first and table in again
    assert {p.name: p.stat().st_mtime_ns for p in store.iterdir()} == written
    # --no-resume runs them again and replaces them in the store
    assert main([*args, "--no-resume", "--quiet", "--out", str(tmp_path / "c")]) == 0
    assert len(open_sweep(store).case) == 4 and all(
        p.stat().st_mtime_ns != written[p.name] for p in store.iterdir() if p.suffix == ".nc")
    # --workers and --scheduler exclude each other, as for sweep
    assert main(["study", "stability", "--workers", "2", "--scheduler", "tcp://x:1", "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err
    assert "not allowed with argument" in err and len(err.strip().splitlines()) == 1


UNGUARDED = '''import skfem_flex as sf

ds = sf.sweep("pendulum", vary={"length": [0.5, 0.7]}, t_end=0.03, dt=0.01, n_workers=2)
print(ds.status.values)
'''


def test_a_sweep_in_a_script_without_the_main_guard_stops_with_one_clear_line(tmp_path):
    """The README's snippet saved as a script without ``if __name__ == "__main__":`` and run as
    ``python script.py``: the local cluster's workers import the script again. The workers end quietly and
    the driver stops with one line naming the line to put under the guard, not pages of
    ``RuntimeError: Nanny failed to start``."""
    script = tmp_path / "script.py"
    script.write_text(UNGUARDED)
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1 and proc.stdout == "", (proc.stdout, proc.stderr)
    said = [line for line in proc.stderr.splitlines() if "if __name__ ==" in line]
    assert len(said) == 1, proc.stderr
    assert said[0].startswith("skfem_flex.apps.sweep.cluster.UnguardedScriptError: put the sweep at line 3 of ")
    assert "script.py" in said[0] and "client=\"serial\"" in said[0]
    assert "Nanny" not in proc.stderr and "RuntimeError" not in proc.stderr and "bootstrapping" not in proc.stderr
