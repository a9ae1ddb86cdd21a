"""Where a sweep's cases run: the local Dask cluster a sweep starts itself (:func:`local_cluster`),
:func:`connect` (a cluster for the length of a ``with`` block), and the refusal of a script that calls
a sweep outside ``if __name__ == "__main__":``.

The local cluster's worker processes are *spawned*: each starts a fresh interpreter that imports the
script's ``__main__`` module again. A sweep called at the top of an unguarded script then runs again in
every worker while it starts, and the worker cannot start processes of its own there. Such a worker
ends quietly (:func:`leave_if_spawned`), and the driver stops with one line saying where to put the
guard (:class:`UnguardedScriptError`) instead of Dask's pages of ``RuntimeError: Nanny failed to start``.
"""
from __future__ import annotations

import ast
import contextlib
import inspect
import logging
import multiprocessing
import os
import sys
import tokenize

import numpy as np

__all__ = ["local_cluster", "connect", "LOCAL_CLUSTER_CONFIG", "UnguardedScriptError", "leave_if_spawned"]

#: the guard a script needs around a sweep that starts a local cluster
GUARD = 'if __name__ == "__main__":'


class UnguardedScriptError(RuntimeError):
    """The running script calls a sweep (a local cluster) outside ``if __name__ == "__main__":``."""


def _default_workers():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _importing_main_in_a_child():
    """True while this process is a spawned child importing its parent's ``__main__`` (multiprocessing's
    own test before it refuses to start a process)."""
    return bool(getattr(multiprocessing.current_process(), "_inheriting", False))


def leave_if_spawned():
    """End this process quietly if it is a worker being spawned that imports an unguarded script.

    The script's sweep call runs again in such a worker, and could only fail there (a process cannot
    start processes while it imports ``__main__``), with a page of tracebacks per worker. The worker ends
    without a word instead (exit status 1), and the driver, whose cluster then fails to start, says what
    to do (:func:`local_cluster`). Anywhere else this does nothing.
    """
    if _importing_main_in_a_child():
        raise SystemExit(1)


def _is_main_guard(node):
    """``node`` is ``if __name__ == "__main__":`` (either way round)."""
    if not isinstance(node, ast.If):
        return False
    names = {n.id for n in ast.walk(node.test) if isinstance(n, ast.Name)}
    texts = {n.value for n in ast.walk(node.test) if isinstance(n, ast.Constant)}
    return "__name__" in names and "__main__" in texts


def _unguarded_call():
    """(script, line) of the running script's top-level statement that led here when it is not under
    ``if __name__ == "__main__":`` (spawned workers run it again), else None (no script: an interactive
    session, ``python -c``; or the call is guarded)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if path is None:
        return None
    frame = inspect.currentframe()
    while frame is not None and not (frame.f_code.co_name == "<module>" and frame.f_globals is vars(main)):
        frame = frame.f_back
    if frame is None:
        return None
    line = frame.f_lineno
    try:
        with tokenize.open(path) as fh:
            tree = ast.parse(fh.read())
    except (OSError, SyntaxError, ValueError):
        return None
    for node in tree.body:
        if node.lineno <= line <= (node.end_lineno or node.lineno):
            return None if _is_main_guard(node) else (path, line)
    return None


#: Dask settings of the local clusters a sweep starts itself (:func:`local_cluster`)
LOCAL_CLUSTER_CONFIG = {
    # the statistical profiler samples every thread's stack every 10 ms: several per cent of a GIL-bound time loop
    "distributed.worker.profile.enabled": False,
    # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536 (freed memory goes back to the system at
    # once). Setting it also stops glibc from adapting its mmap threshold, and the time loop's many
    # short-lived arrays then cost page faults: some 20 000-40 000 per spin-up case instead of a few hundred,
    # and about 10 % more CPU time per case with two workers at once. The workers of our clusters keep
    # glibc's defaults (a value set in the environment still wins: Dask's precedence).
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    # every process of the cluster (scheduler and nannies in the driver, each worker) measures its event
    # loop's delay every 20 ms, for diagnostics only: a few per cent of a core each, taken from the
    # workers on a machine with one core per worker
    "distributed.admin.tick.interval": "200ms",
}


def local_cluster(n_workers=None, **kwargs):
    """The local Dask cluster a sweep starts when no ``client`` is given (the caller closes it).

    ``n_workers`` worker processes (default one per core), one thread each,
    no dashboard, with :data:`LOCAL_CLUSTER_CONFIG`; ``kwargs`` go to
    ``distributed.LocalCluster`` (e.g. ``env={...}`` for the workers).
    Start a cluster that stays up for several sweeps with it
    (``Client(local_cluster(2))``) so that its workers run cases as fast as
    the sweep's own.

    Raises
    ------
    ValueError
        ``n_workers`` is not a positive integer.
    UnguardedScriptError
        The workers could not start because the running script calls this (a sweep) at its top level,
        outside ``if __name__ == "__main__":``: every worker imports the script again.
    """
    import dask
    from distributed import LocalCluster

    leave_if_spawned()
    n = _default_workers() if n_workers is None else n_workers
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n_workers must be a positive integer, got {n_workers!r}")
    options = {"threads_per_worker": 1, "processes": True, "dashboard_address": None,
               "silence_logs": logging.ERROR, **kwargs}
    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        try:
            return LocalCluster(n_workers=int(n), **options)
        except RuntimeError:                  # "Nanny failed to start": say why when the script is the cause
            where = _unguarded_call()
            if where is None:
                raise
    raise UnguardedScriptError(
        f"put the sweep at line {where[1]} of {where[0]}, and what uses its result, under '{GUARD}': its "
        f"worker processes run the script again from the top (or pass client=\"serial\" to run the cases in "
        f"this process)") from None


@contextlib.contextmanager
def connect(client=None, n_workers=None):
    """Where cases run, as :func:`run_cases` takes it, for the length of a ``with`` block.

    ``"serial"`` and a ``distributed.Client`` are yielded as they are; a
    scheduler address yields a Client connected to it; None starts
    :func:`local_cluster` (``n_workers``) and yields its Client. What was
    opened here is closed at the end of the block. Several sweeps (a study
    over several scenes) run on one cluster this way.

    Raises
    ------
    TypeError
        ``client`` is none of these.
    ValueError
        A bad ``n_workers``.
    """
    from distributed import Client

    if isinstance(client, str) and client == "serial":
        yield client
        return
    if client is not None and not isinstance(client, (str, Client)):
        raise TypeError(f"client must be None, 'serial', a scheduler address or a distributed.Client, "
                        f"got {client!r}")
    if isinstance(client, Client):
        yield client
        return
    with contextlib.ExitStack() as stack:
        if client is None:
            cluster = stack.enter_context(local_cluster(n_workers))
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(Client(client))
        yield client
