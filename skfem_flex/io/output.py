"""Output sinks: the deformed system as a VTK time series, written during the run.

:class:`VTKSeries` is what :func:`skfem_flex.run.simulate` calls at every recorded
step (``simulate(scene, ..., output=[VTKSeries(out_dir, name, every=10)])``).
It merges every body's :class:`~skfem_flex.bodies.base.BodyGeometry` into one
unstructured grid per output step (points in 3-D with z = 0), writes it as a
``.vtu`` with meshio, and keeps two collection files that list every step
written so far with its time:

* ``NAME.pvd``, the ParaView collection (``<DataSet timestep=.. file=../>``);
* ``NAME.vtu.series``, the JSON series ParaView also opens directly.

"Nothing lost": each ``.vtu`` and each collection file is first written to a
temporary name in the same directory and then renamed over its final name
(``os.replace``, atomic on POSIX), and a step enters the collections only
after its ``.vtu`` is in place, so a reader or a killed run only ever sees
collections that parse and name complete files. Writing N steps costs O(N)
up to a logarithm: every step's entries are formatted once and kept, and the
collections are rewritten (a join and one write) only when the steps not yet
listed reach 1/256 of those listed, or a second has passed, and always at
:meth:`VTKSeries.close`; a killed run therefore lists every step up to at
most max(1, N/256) steps, or one second, before the kill. If a write fails
(disk full), the steps not listed are removed, no temporary file is left and
the ``OSError`` is raised.

Arrays in every file (the same set at every step, so ParaView can colour by
them throughout):

point data
    ``displacement`` (global, m; a body that gives none gets the motion of its
    geometry points since the first call of :meth:`VTKSeries.write`, the
    initial state of the run), ``velocity`` (m/s),
    ``angle`` (cross-section or body angle, rad), plus any other point array a
    body supplies. Vectors have three components (z = 0).
cell data
    ``body_id`` (index of the body in ``scene.bodies``), ``axial_force`` N (N),
    ``shear_force`` Q (N), ``bending_moment`` M (N m),
    ``strain_energy_density`` (J/m), plus any other cell array a body supplies.

A body that does not provide an array (a point mass has no bending moment)
gets zeros there, never NaN.
"""
from __future__ import annotations

import json
import math
import re
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .files import write_atomically, write_text_atomically

__all__ = ["VTKSeries", "merge_geometry", "read_pvd", "POINT_ARRAYS", "CELL_ARRAYS"]

#: point arrays every written file carries (name -> number of components; 3 = vector)
POINT_ARRAYS = {"displacement": 3, "velocity": 3, "angle": 1}
#: the collections are rewritten once the steps not listed reach 1/LISTING_FRACTION of the listed ones ...
LISTING_FRACTION = 256
#: ... or this many seconds after the last rewrite (and always when the series closes)
LISTING_SECONDS = 1.0
#: cell arrays every written file carries (besides ``body_id``)
CELL_ARRAYS = {"axial_force": 1, "shear_force": 1, "bending_moment": 1, "strain_energy_density": 1}


def _as_components(arr, n_rows, what):
    """``arr`` as float (n_rows,) or (n_rows, k); 2-component vectors get z = 0."""
    a = np.asarray(arr, dtype=float)
    if a.ndim == 0:
        a = np.full(n_rows, float(a))
    if a.shape[0] != n_rows:
        raise ValueError(f"{what} has {a.shape[0]} rows, expected {n_rows}")
    if a.ndim == 2 and a.shape[1] == 1:
        a = a[:, 0]
    if a.ndim == 2 and a.shape[1] == 2:
        a = np.column_stack([a, np.zeros(n_rows)])
    return a.reshape(n_rows, -1) if a.ndim > 2 else a


def _trailing(a):
    return a.shape[1:]


def merge_geometry(geometries, point_names=None, cell_names=None):
    """Merge several bodies' geometries into one meshio mesh.

    Parameters
    ----------
    geometries : sequence of BodyGeometry
        One per body, in body order; the body id is the position in this sequence.
    point_names, cell_names : dict of str to tuple, optional
        Array names with their trailing shapes that must be present (filled
        with zeros where a body gives none). Arrays some body supplies are
        added to these dicts in place, so passing the same dicts on every
        step keeps the array set stable over a series.

    Returns
    -------
    meshio.Mesh
        Points (n, 3) with z = 0, one cell block per (cell type, nodes per
        cell) over all bodies, cell data ``body_id`` and the union of the
        bodies' arrays.

    Raises
    ------
    ValueError
        If a body's arrays do not match its point or cell counts, or two bodies
        give the same array with different shapes.
    """
    import meshio

    point_names = {k: ((3,) if n == 3 else ()) for k, n in POINT_ARRAYS.items()} if point_names is None \
        else point_names
    cell_names = {k: ((3,) if n == 3 else ()) for k, n in CELL_ARRAYS.items()} if cell_names is None \
        else cell_names
    # normalise every body's arrays and learn the union of names and shapes
    bodies = []
    for bid, g in enumerate(geometries):
        pts = np.asarray(g.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] not in (1, 2, 3):
            raise ValueError(f"body {bid}: geometry points must have shape (n, 2), got {pts.shape}")
        p3 = np.zeros((pts.shape[0], 3))
        p3[:, : pts.shape[1]] = pts
        pdata = {k: _as_components(v, len(p3), f"body {bid}: point array {k!r}") for k, v in g.point_data.items()}
        blocks = []
        for j, (ctype, conn) in enumerate(g.cells):
            conn = np.asarray(conn, dtype=np.int64)
            if conn.ndim == 1:
                conn = conn[:, None]
            cd = {}
            for k, per_block in g.cell_data.items():
                cd[k] = _as_components(per_block[j], len(conn), f"body {bid}: cell array {k!r}")
            blocks.append((str(ctype), conn, cd))
        for names, arrays in [(point_names, pdata.items())] + [(cell_names, b[2].items()) for b in blocks]:
            for k, a in arrays:
                if k not in names:
                    names[k] = _trailing(a)
                elif names[k] != _trailing(a):
                    raise ValueError(f"body {bid}: array {k!r} has shape {_trailing(a)} per entry, "
                                     f"another body gives {names[k]}")
        bodies.append((p3, pdata, blocks))

    points, point_data = [], {k: [] for k in point_names}
    grouped = {}                       # (type, nodes per cell) -> [conn], {name: [arrays]}
    offset = 0
    for bid, (p3, pdata, blocks) in enumerate(bodies):
        points.append(p3)
        for k, shape in point_names.items():
            point_data[k].append(pdata[k] if k in pdata else np.zeros((len(p3),) + shape))
        for ctype, conn, cd in blocks:
            key = (ctype, conn.shape[1])
            if key not in grouped:
                grouped[key] = ([], {k: [] for k in cell_names}, [])
            conns, cdata, ids = grouped[key]
            conns.append(conn + offset)
            ids.append(np.full(len(conn), bid, dtype=np.int32))
            for k, shape in cell_names.items():
                cdata[k].append(cd[k] if k in cd else np.zeros((len(conn),) + shape))
        offset += len(p3)

    cells, cell_data = [], {"body_id": []}
    cell_data.update({k: [] for k in cell_names})
    for (ctype, _), (conns, cdata, ids) in grouped.items():
        cells.append((ctype, np.concatenate(conns)))
        cell_data["body_id"].append(np.concatenate(ids))
        for k in cell_names:
            cell_data[k].append(np.concatenate(cdata[k]))
    return meshio.Mesh(np.concatenate(points) if points else np.zeros((0, 3)), cells,
                       point_data={k: np.concatenate(v) for k, v in point_data.items()},
                       cell_data=cell_data)


def read_pvd(path):
    """[(time, file path)] listed by a ``.pvd`` collection, paths resolved next to it."""
    import xml.etree.ElementTree as ET

    path = Path(path)
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), path.parent / d.get("file")) for d in root.iter("DataSet")]


class VTKSeries:
    """Output sink writing the deformed system as a VTK time series.

    Parameters
    ----------
    directory : str or Path
        Created if missing. Files: ``NAME_000000.vtu``, ``NAME_000001.vtu``,
        ... (numbered in the order written), ``NAME.pvd`` and ``NAME.vtu.series``.
    name : str, optional
        Base name of the files; default ``scene.name`` at the first write.
    every : int, optional
        Write every n-th call of :meth:`write` (the first call, i.e. the
        initial state, is always written). Default 1 when ``times`` is not given.
    times : sequence of float, optional
        Output times, s: each is written at the first call with t ≥ time
        (to a relative tolerance of 1e-9 of the step). Not together with ``every``.
    clean : bool
        Remove ``NAME_*.vtu`` files (and temporary files) of an earlier series
        of the same name in ``directory`` before the first write (default True),
        so the directory holds exactly the series its ``.pvd`` lists.

    Notes
    -----
    With ``every``, the state of the last call is written by :meth:`close`
    if the selection skipped it, so the series ends at the last recorded
    state (also when a run stops on a ConvergenceError). With ``times``,
    exactly the requested times are written (those the run reaches).
    ``simulate`` calls :meth:`write` at every recorded step and :meth:`close`
    at the end. One sink serves one run.

    Attributes
    ----------
    written : list of (float, Path)
        (time, file) of every step written so far.
    """

    def __init__(self, directory, name=None, every=None, times=None, clean=True):
        if every is not None and times is not None:
            raise ValueError("give either every or times to VTKSeries, not both")
        if every is None and times is None:
            every = 1
        if every is not None:
            if isinstance(every, bool) or int(every) != every or int(every) < 1:
                raise ValueError(f"every must be an integer >= 1, got {every!r}")
            every = int(every)
        if times is not None:
            times = np.sort(np.asarray(times, dtype=float).ravel())
            if not np.all(np.isfinite(times)):
                raise ValueError(f"output times must be finite, got {times!r}")
        if name is not None and (not isinstance(name, str) or not re.fullmatch(r"[\w.+-]+", name)):
            raise ValueError(f"name must be a plain file name (letters, digits, _ . + -), got {name!r}")
        self.directory = Path(directory)
        self.name = name
        self.every = every
        self.times = times
        self.clean = clean
        self.written = []
        self._calls = 0
        self._next_time = 0
        self._pending = None
        self._closed = False
        self._started = False
        self._reference = None
        self._point_names = None
        self._cell_names = None
        self._failed = False
        self._pvd_lines, self._series_lines = [], []
        self._listed = 0
        self._last_listing = 0.0

    # ----------------------------------------------------------------- paths
    @property
    def pvd_path(self):
        """Path of the ``.pvd`` collection (None before the first write when no name was given)."""
        return None if self.name is None else self.directory / f"{self.name}.pvd"

    @property
    def series_path(self):
        """Path of the ``.vtu.series`` JSON file."""
        return None if self.name is None else self.directory / f"{self.name}.vtu.series"

    def _start(self, scene, q, v):
        """First write: name, directory, removal of an older series, reference geometry."""
        self._started = True
        if self.name is None:
            self.name = re.sub(r"[^\w.+-]", "_", str(scene.name)) or "scene"
        self.directory.mkdir(parents=True, exist_ok=True)
        # an empty collection first, so that no collection ever names a removed file
        self._write_collections()
        if self.clean:
            name = re.escape(self.name)
            pattern = re.compile(rf"^(\.?{name}_\d+\.vtu|\.{name}_\d+\.vtu\.\d+\.tmp"
                                 rf"|\.{name}\.(pvd|vtu\.series)\.\d+\.tmp)$")
            for p in self.directory.iterdir():
                if pattern.match(p.name):
                    p.unlink()
        self._init_arrays(scene, q, v)

    def _init_arrays(self, scene, q=None, v=None):
        """Reference geometry (for displacements) and the array set of the series."""
        if q is None:
            q, v = scene.initial_state()
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        self._reference = [np.asarray(b.geometry(q[scene.slice(b)], v[scene.slice(b)]).points, dtype=float)
                           for b in scene.bodies]
        self._point_names = {k: ((3,) if n == 3 else ()) for k, n in POINT_ARRAYS.items()}
        self._cell_names = {k: ((3,) if n == 3 else ()) for k, n in CELL_ARRAYS.items()}

    # ------------------------------------------------------------------ sink
    def _selected(self, t):
        if self.every is not None:
            return (self._calls - 1) % self.every == 0
        tol = 1e-9 * max(1.0, abs(t))
        hit = False
        while self._next_time < len(self.times) and t >= self.times[self._next_time] - tol:
            hit = True
            self._next_time += 1
        return hit

    def write(self, scene, t, q, v):
        """Called by ``simulate`` at every recorded step; writes the ones selected by ``every``/``times``."""
        if self._closed:
            raise RuntimeError("this VTKSeries is closed; make a new sink for each run")
        if not self._started:
            self._start(scene, q, v)
        self._calls += 1
        if self._selected(t):
            self._write_step(scene, t, q, v)
            self._pending = None
        else:
            self._pending = (scene, float(t), np.array(q, dtype=float), np.array(v, dtype=float))

    def close(self):
        """Write the last state if it was skipped, rewrite the collections whole, and finish.

        Safe to call twice; after a failed write (disk full) it only finishes."""
        if self._closed:
            return
        self._closed = True
        if self._failed or not self._started:
            return
        if self._pending is not None and self.every is not None:
            self._write_step(*self._pending)
            self._pending = None
        self._write_collections()

    def resume(self, scene, prior):
        """Continue the series of an earlier run that this one resumes (``simulate(..., resume=...)``).

        Keeps the steps the existing ``NAME.vtu.series`` (else ``NAME.pvd``) lists up to the
        earlier run's last time and removes this series' other ``.vtu`` files (steps written
        after the last checkpoint of a killed run); displacements keep the earlier run's
        initial state as reference, and ``every`` continues counting from its recorded steps.

        Parameters
        ----------
        scene : Scene
        prior : Result
            The earlier run's result (its ``t``, ``q`` and ``v`` histories).
        """
        if self._started:
            raise RuntimeError("resume() must come before the first write")
        if self.name is None:
            self.name = re.sub(r"[^\w.+-]", "_", str(scene.name)) or "scene"
        self.directory.mkdir(parents=True, exist_ok=True)
        t_last = float(prior.t[-1])
        listed = []
        try:
            listed = [(float(e["time"]), self.directory / e["name"])
                      for e in json.loads(self.series_path.read_text(encoding="utf-8"))["files"]]
        except (OSError, ValueError, KeyError, TypeError):
            try:
                listed = read_pvd(self.pvd_path)
            except (OSError, ValueError, SyntaxError):
                listed = []
        tol = 1e-9 * max(1.0, abs(t_last))
        kept = []
        for t, p in listed:
            if t > t_last + tol or not p.exists() or p.name != f"{self.name}_{len(kept):06d}.vtu":
                break
            kept.append((t, p))
        self.written = kept
        self._pvd_lines = [self._pvd_entry(t, p) for t, p in kept]
        self._series_lines = [self._series_entry(t, p) for t, p in kept]
        keep = {p.name for _, p in kept}
        name = re.escape(self.name)
        pattern = re.compile(rf"^(\.?{name}_\d+\.vtu|\.{name}_\d+\.vtu\.\d+\.tmp|\.{name}\.(pvd|vtu\.series)\.\d+\.tmp)$")
        for p in self.directory.iterdir():
            if pattern.match(p.name) and p.name not in keep:
                p.unlink()
        self._started = True
        self._calls = len(prior.t)
        if self.times is not None:
            self._next_time = int(np.searchsorted(self.times, t_last + tol, side="right"))
        self._init_arrays(scene, np.asarray(prior.q[0], dtype=float), np.asarray(prior.v[0], dtype=float))
        self._write_collections()

    def mesh(self, scene, q, v):
        """The merged meshio mesh of the scene at (q, v), as it would be written."""
        if self._reference is None:
            self._init_arrays(scene)
        geoms = []
        for b, ref in zip(scene.bodies, self._reference):
            sl = scene.slice(b)
            g = b.geometry(q[sl], v[sl])
            if "displacement" not in g.point_data:
                pts = np.asarray(g.points, dtype=float)
                disp = pts - ref if ref.shape == pts.shape else np.zeros_like(pts)
                g = type(g)(g.points, g.cells, dict(g.point_data, displacement=disp), g.cell_data)
            geoms.append(g)
        return merge_geometry(geoms, self._point_names, self._cell_names)

    def _write_step(self, scene, t, q, v):
        import meshio

        mesh = self.mesh(scene, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        index = len(self.written)
        final = self.directory / f"{self.name}_{index:06d}.vtu"
        try:
            write_atomically(final, lambda tmp: meshio.write(tmp, mesh, file_format="vtu"))
        except BaseException:
            self._drop_unlisted()
            raise
        self.written.append((float(t), final))
        self._pvd_lines.append(self._pvd_entry(float(t), final))
        self._series_lines.append(self._series_entry(float(t), final))
        pending = len(self.written) - self._listed
        if pending >= max(1, self._listed // LISTING_FRACTION) or \
                time.monotonic() - self._last_listing >= LISTING_SECONDS:
            self._write_collections()

    # ----------------------------------------------------------- collections
    _PVD_HEAD = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                 "  <Collection>\n")
    _PVD_TAIL = "  </Collection>\n</VTKFile>\n"
    _SERIES_HEAD = '{\n  "file-series-version": "1.0",\n  "files": [\n'
    _SERIES_TAIL = "\n  ]\n}\n"

    @staticmethod
    def _pvd_entry(t, p):
        return f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(p.name)}/>\n'

    @staticmethod
    def _series_entry(t, p):
        return f"    {json.dumps({'name': p.name, 'time': t if math.isfinite(t) else 0.0})}"

    def _drop_unlisted(self):
        """After a failed write: remove the steps the collections do not list yet; the sink is done."""
        self._failed = True
        for _, p in self.written[self._listed:]:
            p.unlink(missing_ok=True)
        del self.written[self._listed:], self._pvd_lines[self._listed:], self._series_lines[self._listed:]

    def _write_collections(self):
        """Both collections written whole (temporary file and rename) from the cached entries.

        On failure the steps not listed yet are removed (the collections on disk still list the
        earlier ones) and the OSError is raised."""
        pvd = self._PVD_HEAD + "".join(self._pvd_lines) + self._PVD_TAIL
        series = self._SERIES_HEAD + ",\n".join(self._series_lines) + self._SERIES_TAIL
        try:
            write_text_atomically(self.pvd_path, pvd)
            write_text_atomically(self.series_path, series)
        except BaseException:
            failed_after_pvd = self.pvd_path.exists() and len(read_pvd(self.pvd_path)) > self._listed
            self._drop_unlisted()
            if failed_after_pvd:           # the .pvd already listed them: put it back to the listed steps
                try:
                    write_text_atomically(self.pvd_path, self._PVD_HEAD + "".join(self._pvd_lines) + self._PVD_TAIL)
                except OSError:
                    pass
            raise
        self._listed = len(self.written)
        self._last_listing = time.monotonic()
