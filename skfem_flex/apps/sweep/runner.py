"""Running a plan's cases: :func:`run_cases`, one after another in this process (``"serial"``) or as
Dask tasks, with the warm-up that compiles each kernel once per machine before the cases start."""
from __future__ import annotations

import dataclasses
import math

from .cluster import connect, leave_if_spawned
from .store import clean_partial, combine, open_store, write_case
from .task import case_dataset, one_line, run_case

__all__ = ["run_cases"]


def run_cases(specs, store=None, client=None, resume=True, n_workers=None, progress=False, on_case=None):
    """Run cases (from :func:`~skfem_flex.apps.sweep.plan`) on Dask and return their Dataset; see
    :func:`~skfem_flex.apps.sweep.sweep`.

    ``on_case(spec, ds)``, if given, is called in the driver with each case's
    Dataset as it finishes (cases read from the store first).
    """
    import xarray as xr  # noqa: F401  (fail here, not on a worker, when xarray is missing)

    if client is None:
        leave_if_spawned()          # a worker of this very sweep, importing an unguarded script
    specs = list(specs)
    keys = [s.key for s in specs]
    seen = {}
    for s, k in zip(specs, keys):
        if k in seen:
            raise ValueError(f"cases {seen[k]} and {s.index} of the plan are the same run (key {k})")
        seen[k] = s.index
    root, layout = open_store(store, create=True) if store is not None else (None, None)
    results = {}
    if root is not None:
        clean_partial(root)
        if resume:
            stored = set(layout.keys(root))
            for s, k in zip(specs, keys):
                if k in stored:
                    results[k] = layout.read(layout.path(root, k))
                    if on_case is not None:
                        on_case(s, results[k])
    skipped = len(results)
    todo = [s for s, k in zip(specs, keys) if k not in results]
    by_key = {k: s for s, k in zip(specs, keys)}
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(specs), initial=skipped, unit="case", desc="sweep", dynamic_ncols=True)

    def finished(ds):
        if root is not None and ds["status"].item() != "lost":
            write_case(root, layout, ds)
        results[ds.attrs["key"]] = ds
        if on_case is not None:
            on_case(by_key[ds.attrs["key"]], ds)
        if bar is not None:
            bar.set_postfix_str(f"last: {ds['status'].item()}", refresh=False)
            bar.update(1)
    try:
        if todo and isinstance(client, str) and client == "serial":
            for s in todo:
                finished(run_case(s))
        elif todo:
            _run_on_dask(todo, client, n_workers, finished)
    finally:
        if bar is not None:
            bar.close()
    out = combine([results[k] for k in keys],
                  attrs={"store": str(root) if root is not None else "", "computed": len(todo), "skipped": skipped})
    return out


def _run_on_dask(specs, client, n_workers, finished):
    from distributed import as_completed

    with connect(client, n_workers) as client:
        _warm_up(client, specs)
        futures = {client.submit(run_case, s, key=s.task_name, pure=False): s for s in specs}
        for fut in as_completed(futures):
            s = futures.pop(fut)
            try:
                ds = fut.result()
            except Exception as exc:     # KilledWorker and the like: the case is lost, not failed
                ds = case_dataset(s, "lost", f"{type(exc).__name__}: {one_line(exc)}", None, math.nan, {})
            fut.release()
            finished(ds)


def _kernel_set(spec):
    """What decides which compiled units a case needs: the build key of its scene under its scheme
    (:func:`skfem_flex.compiled.pack.build_key`: families, storage, solver), read from the packed scene
    itself. A case whose scene cannot be built gets a key of its own (it fails in its task, not here)."""
    from ... import scenes
    from ...compiled.pack import build_key

    try:
        factory = scenes.get(spec.scene) if isinstance(spec.scene, str) else spec.scene
        return build_key(factory(**spec.params), spec.settings["integrator"],
                         python_only=spec.settings.get("compiled") is False)
    except Exception as exc:          # reported by the case itself
        return ("unbuilt", spec.task_name, type(exc).__name__)


def _warm_worker(specs, first, dask_worker=None):
    """The warm-up on one worker (``client.run``; unpickling this function imported the package there).
    The first worker of a machine runs the one-step ``specs`` one after another; the others import what
    a case needs meanwhile, and no kernel (they would compile it at the same time). Nothing comes back."""
    if dask_worker is not None and dask_worker.address in first:
        for spec in specs:               # one step each: compiles what is not cached, loads the rest
            run_case(spec)
    else:
        import xarray  # noqa: F401


def _warm_up(client, specs):
    """Before the cases start, run one step of one case per kernel set (:func:`_kernel_set`) on one worker
    per machine, one after another, so that every Numba kernel the sweep needs is compiled once per machine
    (into numba's on-disk cache) rather than by every worker at once; the other workers of the machine
    then load it from the cache. Machines with a single worker need no warm-up."""
    hosts = {}
    for addr, info in client.scheduler_info(n_workers=-1)["workers"].items():
        hosts.setdefault(info.get("host", addr), []).append(addr)
    first = [addrs[0] for addrs in hosts.values() if len(addrs) > 1]
    if not first:
        return
    shorts = {}
    for spec in specs:
        shorts.setdefault(_kernel_set(spec), dataclasses.replace(
            spec, settings={**spec.settings, "t_end": spec.settings["dt"]}, measures={}))
    try:
        client.run(_warm_worker, list(shorts.values()), first)
    except Exception:                # only a warm-up: the cases themselves report any failure
        pass
