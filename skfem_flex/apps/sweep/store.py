"""The sweep store on disk and the Dataset of its cases: atomic writes, :func:`open_sweep`, the
concatenation along ``case`` (NaN-padded) and :func:`probe_extremes`.

Only the driver writes: a finished case is written under a temporary name in
``PATH.parent/.PATH.name.partial/`` and renamed into the store with one ``rename(2)``, so a reader
sees the whole case or none of it. See :mod:`skfem_flex.apps.sweep` for the two layouts.
"""
from __future__ import annotations

import itertools
import json
import math
import os
import shutil
from pathlib import Path

import numpy as np

from .cases import RUN_SETTINGS, SIMULATE_OPTIONS

__all__ = ["open_sweep", "probe_extremes", "open_store", "clean_partial", "write_case", "combine", "STORE_FORMAT"]

#: the format marker of a sweep store and of each case stored in it
STORE_FORMAT = "skfem_flex.apps.sweep/1"


def _partial_dir(root):
    return root.parent / f".{root.name}.partial"


class _Layout:
    """How one case is a file system entry: a netCDF file (``<key>.nc``) or a Zarr group (``<key>/``)."""

    def __init__(self, kind):
        self.kind = kind
        self.suffix = ".nc" if kind == "netcdf" else ""

    def write(self, ds, path):
        import dask

        # the Dataset is in memory: with a distributed Client as the default scheduler xarray would
        # take a cluster-wide lock per variable (a scheduler round trip each, ~0.4 s a case)
        with dask.config.set(scheduler="synchronous"):
            if self.kind == "netcdf":
                ds.to_netcdf(str(path), engine="scipy", format="NETCDF3_64BIT")
            else:
                ds.to_zarr(str(path), mode="w", zarr_format=2, consolidated=False)

    def read(self, path):
        import xarray as xr

        if self.kind == "netcdf":
            with xr.open_dataset(str(path), engine="scipy") as ds:
                return ds.load()
        with xr.open_zarr(str(path), consolidated=False) as ds:
            return ds.load()

    def keys(self, root):
        """Keys of the finished cases (temporary entries never live in the root)."""
        if self.kind == "netcdf":
            return sorted(p.name[:-3] for p in root.iterdir() if p.name.endswith(".nc") and p.is_file())
        return sorted(d.name for d in root.iterdir() if (d / ".zgroup").is_file())

    def path(self, root, key):
        return root / f"{key}{self.suffix}"


_MARKER = "sweep-store.json"     # the netCDF layout's root marker (the Zarr layout keeps it in .zattrs)


def open_store(path, create):
    """(root directory, layout); a missing store is created when ``create`` (Zarr if the name ends in .zarr)."""
    root = Path(path)
    if root.exists():
        marker = root / (".zattrs" if (root / ".zgroup").is_file() else _MARKER)
        try:
            fmt = json.loads(marker.read_text()).get("format")
        except (OSError, ValueError, AttributeError):
            fmt = None
        if not root.is_dir() or fmt != STORE_FORMAT:
            raise ValueError(f"{str(root)!r} exists but is not a skfem_flex sweep store (no {STORE_FORMAT!r} "
                             f"marker in it); choose another store path")
        return root, _Layout("zarr" if marker.name == ".zattrs" else "netcdf")
    if not create:
        raise FileNotFoundError(f"no sweep store at {str(root)!r}")
    kind = "zarr" if root.suffix == ".zarr" else "netcdf"
    root.parent.mkdir(parents=True, exist_ok=True)
    partial = _partial_dir(root)
    partial.mkdir(exist_ok=True)
    tmp = partial / f"root-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    if kind == "zarr":
        import zarr
        zarr.open_group(str(tmp), mode="w", zarr_format=2, attributes={"format": STORE_FORMAT})
    else:
        tmp.mkdir()
        (tmp / _MARKER).write_text(json.dumps({"format": STORE_FORMAT}) + "\n")
    try:
        os.rename(tmp, root)
    except OSError:                  # another driver created it first
        shutil.rmtree(tmp, ignore_errors=True)
        return open_store(path, create=False)
    return root, _Layout(kind)


def clean_partial(root):
    """Remove leftovers of drivers that died while writing (their process no longer exists)."""
    partial = _partial_dir(root)
    if not partial.is_dir():
        return
    for d in partial.iterdir():
        try:
            pid = int(d.name.split("-")[1])
            os.kill(pid, 0)
        except (IndexError, ValueError, ProcessLookupError):
            shutil.rmtree(d, ignore_errors=True) if d.is_dir() else d.unlink(missing_ok=True)
        except PermissionError:      # alive, another user's
            pass


_TEMP_NAMES = itertools.count()


def write_case(root, layout, ds):
    """Write one case under a temporary name outside the root, then rename it into the root (atomic)."""
    key = ds.attrs["key"]
    partial = _partial_dir(root)
    partial.mkdir(exist_ok=True)
    tmp = partial / f"case-{os.getpid()}-{next(_TEMP_NAMES)}-{key}{layout.suffix}"
    layout.write(ds, tmp)
    final = layout.path(root, key)
    if final.exists():               # resume=False: replace the old case
        old = partial / f"old-{os.getpid()}-{next(_TEMP_NAMES)}-{key}{layout.suffix}"
        os.rename(final, old)
        os.rename(tmp, final)
        shutil.rmtree(old, ignore_errors=True) if old.is_dir() else old.unlink()
    else:
        os.rename(tmp, final)
    return final


def open_sweep(store):
    """All cases in a sweep store as one Dataset (dimensions ``case``, ``time``), in plan order.

    Safe to call while a sweep is writing: it sees the cases finished so far.
    The data are loaded into memory; for very large stores open the Zarr
    hierarchy lazily with ``xarray.open_datatree(store, engine="zarr")``.

    Raises
    ------
    FileNotFoundError
        No store at that path.
    ValueError
        The path is not a sweep store.
    """
    root, layout = open_store(store, create=False)
    cases = []
    for key in layout.keys(root):
        try:
            cases.append(layout.read(layout.path(root, key)))
        except FileNotFoundError:    # replaced by a resume=False rerun between listing and reading
            continue
    cases.sort(key=lambda ds: (ds.attrs.get("index", 0), ds.attrs["key"]))
    return combine(cases, attrs={"store": str(root)})


def _column(values):
    """One coordinate from per-case values (None = the case has no such parameter)."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present) and len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([math.nan if v is None else float(v) for v in values])
    return np.array(["" if v is None else str(v) for v in values])


def combine(cases, attrs=None):
    """Concatenate per-case Datasets along ``case`` (time padded with NaN, parameters as coordinates)."""
    import xarray as xr

    if not cases:
        return xr.Dataset(coords={"case": np.array([], dtype=str)}, attrs=dict(attrs or {}))
    # time (and any other dimension: q of different meshes) padded with NaN to the longest case
    size = {}
    for ds in cases:
        for d, n in ds.sizes.items():
            size[d] = max(size.get(d, 0), n)
    padded = []
    for ds in cases:
        short = {d: (0, size[d] - n) for d, n in ds.sizes.items() if n < size[d]}
        bare = (ds.pad(short) if short else ds).copy(deep=False)
        bare.attrs = {}              # (Dataset.drop_attrs rebuilds every variable: slow)
        padded.append(bare)
    out = xr.concat(padded, dim="case", join="outer", data_vars="all", coords="different", compat="equals")
    params = [json.loads(ds.attrs["parameters"]) for ds in cases]
    settings = [json.loads(ds.attrs["settings"]) for ds in cases]
    coords = {"case": [ds.attrs["key"] for ds in cases], "scene": _column([ds.attrs["scene"] for ds in cases]),
              "label": _column([ds.attrs.get("label", "") for ds in cases])}
    for k in RUN_SETTINGS + tuple(k for k in SIMULATE_OPTIONS if any(k in s for s in settings)):
        coords[k] = _column([s.get(k) for s in settings])
    for k in dict.fromkeys(k for p in params for k in p):
        coords[k] = _column([p.get(k) for p in params])
    out = out.assign_coords({k: ("case", v) if k != "case" else v for k, v in coords.items()})
    ts = [ds["t"].values for ds in cases]
    if all(len(t) == len(ts[0]) and np.array_equal(t, ts[0]) for t in ts):
        out = out.assign_coords(time=ts[0])
    out.attrs.update(attrs or {})
    out.attrs["settings"] = json.dumps(settings[0]) if all(s == settings[0] for s in settings) else ""
    return out


def probe_extremes(ds, probe):
    """The signed extreme (the value of largest magnitude over time) of a probe, per case and component.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep's Dataset.
    probe : str
        Probe name (the variable ``probe_<name>``).

    Returns
    -------
    xarray.DataArray
        Dimensions ``case`` and the probe's component dimension (if any);
        NaN for cases without a history.

    Raises
    ------
    ValueError
        When the Dataset has no such probe (the message lists the probes it has).
    """
    var = f"probe_{probe}".replace("/", "_")
    if var not in ds:
        have = [k[len("probe_"):] for k in ds.data_vars if k.startswith("probe_")]
        raise ValueError(f"the sweep recorded no probe {probe!r}; it has: {', '.join(have) or 'none'}")
    x = ds[var]
    where = abs(x).fillna(-1.0).argmax("time")
    return x.isel(time=where).where(ds["n_times"] > 0).drop_vars("time", errors="ignore")
