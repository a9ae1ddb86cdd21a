"""Parameter sweeps: many runs of one model as Dask tasks, results as an xarray Dataset in Zarr.

A *case* is one call of :func:`~skfem_flex.run.simulate.simulate` on a scene built
from a factory with some parameters, under some run settings (end time,
step, integrator, ...). :func:`sweep` expands a grid (``vary``) or a list
(``cases``) into cases, runs each case as one task on a Dask cluster (a local
cluster of worker processes it starts itself, or any cluster a
``dask.distributed.Client`` points at), and collects the results into one
:class:`xarray.Dataset` with dimensions ``case`` and ``time``.

Store (``store=PATH``, a directory) in one of two layouts, chosen by the name:

* ``PATH`` ending in ``.zarr``: a Zarr (format 2) group, one child group
  ``PATH/<key>/`` per finished case; the whole store opens with
  ``xarray.open_datatree(PATH, engine="zarr")``;
* any other name: ``PATH/<key>.nc``, one netCDF file per finished case
  (``xarray.open_dataset``); about ten times faster to write and read than a
  Zarr group of the same case, which matters for many short cases.

Either way a marker (``.zattrs`` or ``sweep-store.json``) says it is a
sweep store, and the driver writes a finished case into
``PATH.parent/.PATH.name.partial/`` and then renames it into ``PATH`` with a
single ``rename(2)``, atomic on a POSIX file system: a reader (or a rerun)
sees either the whole case or none of it, whatever moment the driver is
killed at (SIGKILL included), so the store opens with xarray at every
moment. Only the driver writes, so workers need no shared file system.
:func:`open_sweep` joins the cases into one Dataset.

A case's *key* is a SHA-256 hash of (scene name, parameters, settings,
recorded groups, measure names); with ``resume=True`` a case whose key is
already in the store is read back instead of run, so a killed sweep restarts
where it stopped, and changing any setting (``dt``, ``t_end``,
``integrator``, ``rho_inf``, ...) makes new cases instead of reusing old ones.

Cases of different lengths (another ``dt`` or ``t_end``, or a run that stopped
early) share the ``time`` dimension as the index of the recorded step: shorter
cases are padded with NaN, ``n_times`` holds each case's own length and the
variable ``t`` (case, time) its times. When every case has the same times they
also become the ``time`` coordinate. Other dimensions that differ between
cases (``q_dof`` of meshes with more or fewer elements) are padded the same way.

The package's rooms: :mod:`~skfem_flex.apps.sweep.cases` (the plan: cases and their keys),
:mod:`~skfem_flex.apps.sweep.task` (one case as a Dask task), :mod:`~skfem_flex.apps.sweep.budget`
(the wall-clock budget of a case), :mod:`~skfem_flex.apps.sweep.store` (the store on disk,
:func:`open_sweep`, the Dataset of the cases), :mod:`~skfem_flex.apps.sweep.runner` (running the cases
serially or on Dask, with the warm-up) and :mod:`~skfem_flex.apps.sweep.cluster` (the local cluster,
:func:`connect`, the refusal of a script without ``if __name__ == "__main__":``).
"""
from __future__ import annotations

from .budget import BudgetExceeded, WallClockBudget
from .cases import DEFAULT_RECORD, RECORD_GROUPS, RUN_SETTINGS, SIMULATE_OPTIONS, CaseSpec, plan
from .cluster import LOCAL_CLUSTER_CONFIG, UnguardedScriptError, connect, local_cluster
from .runner import run_cases
from .store import open_sweep, probe_extremes
from .task import STATUSES, run_case

__all__ = ["sweep", "plan", "run_cases", "open_sweep", "probe_extremes", "local_cluster", "connect", "CaseSpec",
           "BudgetExceeded", "WallClockBudget", "RUN_SETTINGS", "RECORD_GROUPS", "DEFAULT_RECORD", "STATUSES",
           "LOCAL_CLUSTER_CONFIG", "UnguardedScriptError", "SIMULATE_OPTIONS", "run_case"]


def sweep(scene, vary=None, cases=None, *, t_end=None, dt=None, integrator="energy-momentum", record=DEFAULT_RECORD,
          store=None, client=None, resume=True, fixed=None, record_every=1, budget=None, measures=None, name=None,
          n_workers=None, progress=False, **options):
    """Run a scene over a grid or list of parameters, one Dask task per case.

    Each case calls ``simulate(factory(**params), t_end, dt, integrator=...,
    record_every=..., **options)`` exactly as a serial call would, so the
    numbers are the same bit for bit.

    Parameters
    ----------
    scene : str or callable
        Catalogue name (``skfem-flex list``) or a factory returning a Scene
        (it must pickle; a lambda needs ``name``).
    vary : dict of str to list, optional
        Grid: every combination of the values (``itertools.product``, last
        name fastest). Names are factory parameters, the run settings
        ``t_end``, ``dt``, ``integrator`` or the simulate options (below).
    cases : list of dict, optional
        Explicit cases instead of a grid (same names as ``vary``).
    t_end, dt : float, optional
        End time and step, s, for cases that do not set them (default: the
        scene's registered defaults).
    integrator : str
        ``"energy-momentum"``, ``"trapezoidal"`` or ``"generalized-alpha"``.
    record : sequence of str
        Time series stored per case: groups of :data:`RECORD_GROUPS`
        (``"state"`` adds q and v, which can be large).
    store : path, optional
        Directory of the store: a Zarr hierarchy if the name ends in
        ``.zarr``, else one netCDF file per case (see the module notes).
        None keeps the results in memory only.
    client : None, "serial", str or distributed.Client
        None: start a local cluster of ``n_workers`` worker processes
        (:func:`local_cluster`: one thread each, default one per core) and
        close it at the end. A Client or a scheduler address: run on that
        cluster. ``"serial"``: run the cases one after another in this
        process (same code path). On a cluster, one worker per machine first
        runs one step of one case per scene, integrator, compiled-or-not and
        non-numeric parameters, so that the Numba kernels are compiled once
        per machine.
    resume : bool
        Read cases already in the store instead of running them; False
        recomputes and replaces them.
    fixed : dict, optional
        Parameters given to every case.
    record_every : int
        As in ``simulate``.
    budget : float, optional
        Wall-clock seconds one case may spend in its time loop; then it is
        stopped with status ``"stopped"`` and its history kept.
    measures : dict of str to callable, optional
        ``name -> fn(result) -> float`` evaluated on the worker; stored per case.
    name : str, optional
        Scene name for the key and the store (needed for lambdas).
    n_workers : int, optional
        Worker processes of the local cluster (client=None only).
    progress : bool
        tqdm progress bar over cases on stderr.
    **options
        ``rho_inf``, ``newton``, ``max_halvings``, ``project``, ``compiled``:
        passed to ``simulate`` (and part of the key).

    Returns
    -------
    xarray.Dataset
        Dimensions ``case`` (coordinate: the case key) and ``time`` (step
        index; times when all cases share them). Coordinates along ``case``:
        ``scene``, ``label``, ``t_end``, ``dt``, ``integrator`` and every
        parameter given. Per case and time: ``t`` (s), ``probe_<name>``,
        ``kinetic``, ``potential``, ``total_energy``, ``external_work``,
        ``energy_balance_error`` (J), ``constraint_residual``,
        ``velocity_constraint_residual``, ``newton_iterations`` (NaN past
        ``n_times``). Per case: ``status`` (:data:`STATUSES`), ``message``,
        ``wall_time`` (time loop, s), ``run_time`` (simulate call, s),
        ``steps``, ``halvings``, ``newton_total``, ``newton_per_step``,
        ``t_reached``, ``n_times``, ``max_energy_balance_error`` (J),
        ``relative_energy_error``, ``max_constraint_residual``, ``worker``
        and the measures. ``attrs``: ``computed`` and ``skipped`` (read from
        the store) case counts, ``store``.

    Raises
    ------
    ValueError, TypeError
        For a bad plan (see :func:`plan`) before anything runs. Cases that
        fail are not errors: they are rows with their status and message.
    UnguardedScriptError
        A script calls the sweep (with a local cluster) outside
        ``if __name__ == "__main__":``: the worker processes import the
        script again and cannot start (see :func:`local_cluster`).
    """
    specs = plan(scene, vary, cases, fixed=fixed, t_end=t_end, dt=dt, integrator=integrator, record=record,
                 record_every=record_every, budget=budget, measures=measures, name=name, **options)
    return run_cases(specs, store=store, client=client, resume=resume, n_workers=n_workers, progress=progress)
