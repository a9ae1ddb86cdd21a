"""Issue 7: VTK time series (.vtu + .pvd + .vtu.series), Result save/load, probes CSV and plots."""
import dataclasses
import json
import signal
import subprocess
import sys
import textwrap
import time

import meshio
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.io.output import VTKSeries, read_pvd
from skfem_flex.io.plots import save_plots

from helpers import package_env


class Rod(sf.PointMass):
    """A point mass drawn as a 3-node polyline that gives only some arrays (exercises the padding)."""

    def geometry(self, q, v):
        pts = np.array([[q[0], q[1]], [q[0] + 0.1, q[1]], [q[0] + 0.2, q[1]]])
        return sf.BodyGeometry(pts, [("line", np.array([[0, 1], [1, 2]]))],
                               point_data={"velocity": np.tile(v, (3, 1)), "temperature": np.array([1.0, 2, 3])},
                               cell_data={"axial_force": [np.array([5.0, 6.0])]})


def two_body_scene():
    bodies = [sf.PointMass(1.0, [0.0, 0.0], [1.0, 0.0], name="ball"), Rod(2.0, [1.0, 1.0], [0.0, 1.0], name="rod")]
    return sf.Scene(bodies, forces=[sf.Gravity((0.0, -9.81))], name="two", probes={"ball": lambda s, t, q, v: q[:2]})


POINT_ARRAYS = {"displacement", "velocity", "angle", "temperature"}
CELL_ARRAYS = {"body_id", "axial_force", "shear_force", "bending_moment", "strain_energy_density"}


def test_series_files_pvd_and_readback(tmp_path):
    scene = two_body_scene()
    sink = VTKSeries(tmp_path, "run", every=3)
    res = sf.simulate(scene, t_end=0.1, dt=0.01, output=[sink])
    # calls at t = 0, 0.01, ..., 0.1: every 3rd from the first, plus the last one on close
    expected_idx = [0, 3, 6, 9, 10]
    files = sorted(tmp_path.glob("*.vtu"))
    assert len(files) == len(expected_idx)
    listed = read_pvd(tmp_path / "run.pvd")
    assert [p.name for _, p in listed] == [p.name for p in files]
    times = np.array([t for t, _ in listed])
    assert np.all(np.diff(times) > 0)
    np.testing.assert_array_equal(times, res.t[expected_idx])
    series = json.loads((tmp_path / "run.vtu.series").read_text())
    assert [(f["name"], f["time"]) for f in series["files"]] == [(p.name, t) for t, p in listed]

    vtk = pytest.importorskip("vtk")
    for (t, path), i in zip(listed, expected_idx):
        m = meshio.read(path)
        assert m.points.shape == (4, 3) and np.all(m.points[:, 2] == 0)
        assert sorted((c.type, len(c.data)) for c in m.cells) == [("line", 2), ("vertex", 1)]
        assert set(m.point_data) == POINT_ARRAYS
        assert set(m.cell_data) == CELL_ARRAYS
        for k, arr in m.point_data.items():
            assert np.all(np.isfinite(arr)), k
        # the point mass: displacement from its initial position, velocity, body 0
        q, v = res.q[i], res.v[i]
        np.testing.assert_allclose(m.points[0, :2], q[:2])
        np.testing.assert_allclose(m.point_data["displacement"][0, :2], q[:2] - [0.0, 0.0])
        np.testing.assert_allclose(m.point_data["displacement"][1:, :2], np.tile(q[2:] - [1.0, 1.0], (3, 1)))
        np.testing.assert_allclose(m.point_data["velocity"][1:, :2], np.tile(v[2:], (3, 1)))
        assert m.point_data["velocity"].shape == (4, 3)
        blocks = {c.type: j for j, c in enumerate(m.cells)}
        np.testing.assert_array_equal(m.cell_data["body_id"][blocks["vertex"]], [0])
        np.testing.assert_array_equal(m.cell_data["body_id"][blocks["line"]], [1, 1])
        np.testing.assert_array_equal(m.cell_data["axial_force"][blocks["line"]], [5.0, 6.0])
        np.testing.assert_array_equal(m.cell_data["axial_force"][blocks["vertex"]], [0.0])
        np.testing.assert_array_equal(m.point_data["temperature"], [0.0, 1.0, 2.0, 3.0])

        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(path))
        reader.Update()
        grid = reader.GetOutput()
        assert grid.GetNumberOfPoints() == 4
        assert grid.GetNumberOfCells() == 3
        pd, cd = grid.GetPointData(), grid.GetCellData()
        assert {pd.GetArrayName(j) for j in range(pd.GetNumberOfArrays())} == POINT_ARRAYS
        assert {cd.GetArrayName(j) for j in range(cd.GetNumberOfArrays())} == CELL_ARRAYS
        assert pd.GetArray("displacement").GetNumberOfComponents() == 3


def test_output_times_and_arguments(tmp_path):
    sink = VTKSeries(tmp_path, "sel", times=[0.025, 0.05, 0.2])
    sf.simulate(sf.scenes.pendulum(), t_end=0.1, dt=0.01, output=[sink])
    # the first recorded step at or after each requested time; 0.2 is never reached
    np.testing.assert_allclose([t for t, _ in read_pvd(tmp_path / "sel.pvd")], [0.03, 0.05], rtol=1e-12)
    assert len(list(tmp_path.glob("*.vtu"))) == 2
    with pytest.raises(ValueError, match="either every or times"):
        VTKSeries(tmp_path, every=2, times=[0.1])
    with pytest.raises(ValueError, match="every"):
        VTKSeries(tmp_path, every=0)
    with pytest.raises(RuntimeError, match="closed"):
        sink.write(sf.scenes.pendulum(), 0.0, np.zeros(2), np.zeros(2))


def test_rerun_replaces_an_older_series(tmp_path):
    sf.simulate(sf.scenes.pendulum(), t_end=0.1, dt=0.01, output=[VTKSeries(tmp_path, "p")])
    assert len(list(tmp_path.glob("p_*.vtu"))) == 11
    sf.simulate(sf.scenes.pendulum(), t_end=0.03, dt=0.01, output=[VTKSeries(tmp_path, "p")])
    assert sorted(p.name for p in tmp_path.glob("p_*.vtu")) == [p.name for _, p in read_pvd(tmp_path / "p.pvd")]
    assert len(read_pvd(tmp_path / "p.pvd")) == 4


KILLED_RUN = textwrap.dedent("""
    import sys
    import skfem_flex as sf
    from skfem_flex.io.output import VTKSeries
    sf.simulate(sf.scenes.pendulum(), t_end=1e4, dt=1e-3, output=[VTKSeries(sys.argv[1], "killed")])
""")


def test_killed_run_leaves_a_valid_series(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", KILLED_RUN, str(tmp_path)], env=package_env())
    pvd = tmp_path / "killed.pvd"
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if pvd.exists() and len(read_pvd(pvd)) >= 30:     # always parses: it is replaced atomically
                break
            time.sleep(0.01)
        time.sleep(0.0137)                                   # land somewhere inside a later step
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before it was killed"
    listed = read_pvd(pvd)
    assert len(listed) >= 30
    times = [t for t, _ in listed]
    assert np.all(np.diff(times) > 0)
    on_disk = sorted(p.name for p in tmp_path.glob("killed_*.vtu"))
    names = [p.name for _, p in listed]
    # every listed file is complete; at most one finished file was not listed yet when the kill came
    assert set(names) <= set(on_disk) and len(on_disk) - len(names) <= 1
    for _, p in listed:
        assert meshio.read(p).points.shape == (1, 3)
    series = json.loads((tmp_path / "killed.vtu.series").read_text())
    assert len(series["files"]) in (len(names), len(names) - 1, len(names) + 1)


def assert_results_equal(a, b):
    for f in dataclasses.fields(sf.Result):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert isinstance(y, np.ndarray) and x.dtype == y.dtype and x.shape == y.shape, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        elif isinstance(x, dict):
            assert list(x) == list(y), f.name
            for k in x:
                if isinstance(x[k], np.ndarray) or isinstance(x[k], np.generic):
                    assert x[k].dtype == y[k].dtype
                    np.testing.assert_array_equal(x[k], y[k], err_msg=f"{f.name}[{k}]")
                else:                   # run_path: plain strings and lists
                    assert x[k] == y[k], (f.name, k, x[k], y[k])
        else:
            assert x == y and type(x) is type(y), (f.name, x, y)


def test_result_save_load_roundtrip(tmp_path):
    res = sf.simulate(sf.scenes.pendulum(), t_end=0.2, dt=0.01)
    path = res.save(tmp_path / "run.npz")
    assert_results_equal(res, sf.Result.load(path))
    # None fields, several dicts and a name without the suffix
    extra = {"reactions": {"rod": np.arange(6.0).reshape(3, 2)}} if "reactions" in \
        {f.name for f in dataclasses.fields(sf.Result)} else {}
    other = dataclasses.replace(res, linear_momentum=None, angular_momentum=None, completed=False,
                                probes={"a": np.array([1, 2, 3]), "b c/d": np.ones((3, 2, 2))}, **extra)
    path = other.save(tmp_path / "other")
    assert path.name == "other.npz"
    back = sf.Result.load(path)
    assert back.linear_momentum is None and back.angular_momentum is None
    assert_results_equal(other, back)
    with pytest.raises(ValueError, match="not a saved"):
        np.savez(tmp_path / "plain.npz", x=np.zeros(2))
        sf.Result.load(tmp_path / "plain.npz")


def test_probes_to_csv(tmp_path):
    res = sf.simulate(two_body_scene(), t_end=0.05, dt=0.01)
    path = res.probes_to_csv(tmp_path / "probes.csv")
    header = path.read_text().splitlines()[0]
    assert header == "t,ball[0],ball[1]"
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(data[:, 0], res.t)
    np.testing.assert_array_equal(data[:, 1:], res.probes["ball"])


def test_plots_without_display(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    scene = sf.scenes.pendulum()
    res = sf.simulate(scene, t_end=0.3, dt=0.01)
    files = save_plots(scene, res, tmp_path)
    assert set(files) == {"energy", "probes", "constraints", "snapshots"}
    for p in files.values():
        data = p.read_bytes()
        assert len(data) > 1000 and data[:8] == b"\x89PNG\r\n\x1a\n", p
    # a scene without constraints or probes: no constraint or probe plot
    free = sf.Scene([sf.PointMass(1.0, [0.0, 0.0], [1.0, 0.0])], name="free")
    files = save_plots(free, sf.simulate(free, t_end=0.05, dt=0.01), tmp_path / "free")
    assert set(files) == {"energy", "snapshots"}
