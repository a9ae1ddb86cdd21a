r"""Compiling a run's missing units on two processes at once.

A first run compiles each unit it needs (the scheme's step, the solver, one kernel per element family,
the loop's entry points; :class:`~.registry.Unit`) that the cache does not hold. Numba compiles one
function at a time per process, so on a machine with two or more cores :func:`compile_units` starts one
helper process (``python -m skfem_flex.compiled.ahead``) and both pull units from one list, largest
first: each takes the next unit that neither has claimed (an ``O_EXCL`` file per unit) and compiles it
into the shared cache. When the list is done and the helper has exited, the caller loads everything
from the cache in milliseconds. The wall time of a cold start falls by up to half.

Nothing depends on the helper: when it cannot start, fails or dies, what it did not write is compiled
in this process when first needed, as with one process. Ctrl-C while waiting for it stops the helper
and raises :class:`~skfem_flex.errors.Interrupted`.

``SKFEM_FLEX_COMPILE_PROCESSES=1`` compiles in this process only.
"""
from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

from . import registry
from .registry import LOGGER

__all__ = ["compile_units", "processes", "Compiled", "PACKAGE_PARENT", "package_environment"]

#: the folder that holds this skfem_flex (the helper's working directory and first entry of its path)
PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def package_environment(**extra):
    """This process's environment (with ``extra``) and :data:`PACKAGE_PARENT` first on ``PYTHONPATH``: a
    Python process started with it runs this same package, and finds its compiled kernels in the same
    cache, even where its working directory holds another copy (``-m`` and ``-c`` put that first)."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = os.pathsep.join([PACKAGE_PARENT] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    return env


def processes():
    """How many processes compile at once: 2 when this process may use two or more cores, else 1;
    ``SKFEM_FLEX_COMPILE_PROCESSES`` (1 or 2) overrides.

    Raises
    ------
    ValueError
        If ``SKFEM_FLEX_COMPILE_PROCESSES`` is set to something else than 1 or 2.
    """
    text = os.environ.get("SKFEM_FLEX_COMPILE_PROCESSES", "").strip()
    if text:
        if text not in ("1", "2"):
            raise ValueError(f"SKFEM_FLEX_COMPILE_PROCESSES must be 1 or 2, got {text!r}")
        return int(text)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:              # not on Linux
        cores = os.cpu_count() or 1
    return 2 if cores >= 2 else 1


def _claim(folder, i, who):
    """True when this process is the first to claim unit i."""
    try:
        fd = os.open(os.path.join(folder, f"{i}.claim"), os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    os.write(fd, who.encode())
    os.close(fd)
    return True


def _work(folder, units, who, parent=None):
    """Make every unit of ``units`` that this process claims first (the helper stops when the process
    ``parent`` that started it is gone)."""
    for i, unit in enumerate(units):
        if parent is not None and os.getppid() != parent:
            return
        if _claim(folder, i, who):
            unit.make()


class Compiled(NamedTuple):
    """What :func:`compile_units` compiled: the units' names (``what``) made in this process and in the
    helper, and the wall time (s)."""
    here: tuple
    helper: tuple
    seconds: float


def compile_units(units):
    """Make ``units`` (:class:`~.registry.Unit`, largest first), the ones the cache lacks on two processes
    when :func:`processes` allows; returns :class:`Compiled`."""
    start = time.perf_counter()
    todo = [unit for unit in dict.fromkeys(units) if not registry.is_cached(unit)]
    if len(todo) < 2 or processes() < 2:
        for unit in todo:
            unit.make()
        return Compiled(tuple(unit.what for unit in todo), (), time.perf_counter() - start)
    start = time.perf_counter()
    before = registry.compile_seconds()
    with tempfile.TemporaryDirectory(prefix="skfem_flex_compile_") as folder:
        with open(os.path.join(folder, "units.pickle"), "wb") as f:
            pickle.dump(todo, f)
        helper = _start_helper(folder)
        LOGGER.info("compiling %d units on 2 processes (first use on this machine, cached afterwards) ...",
                    len(todo))
        try:
            _work(folder, todo, "main")
            if helper is not None:
                registry.interruptible(helper.wait, "units in the helper process")
        finally:
            if helper is not None and helper.poll() is None:
                helper.kill()
                helper.wait()
        if helper is not None and helper.returncode != 0:
            LOGGER.warning("the helper compile process stopped with exit code %s; what it did not finish is "
                           "compiled here", helper.returncode)
        claimed = [_claimed_by(folder, i) for i in range(len(todo))]
    theirs = tuple(unit.what for unit, who in zip(todo, claimed) if who == "helper")
    waited = time.perf_counter() - start - (registry.compile_seconds() - before)
    registry.count_compiled(theirs, max(waited, 0.0))
    seconds = time.perf_counter() - start
    LOGGER.info("compiled %d units in %.1f s", len(todo), seconds)
    return Compiled(tuple(unit.what for unit, who in zip(todo, claimed) if who == "main"), theirs, seconds)


def _claimed_by(folder, i):
    try:
        with open(os.path.join(folder, f"{i}.claim")) as f:
            return f.read()
    except OSError:
        return ""


def _start_helper(folder):
    env = package_environment(SKFEM_FLEX_QUIET="1", SKFEM_FLEX_COMPILE_PROCESSES="1")
    try:
        return subprocess.Popen([sys.executable, "-m", "skfem_flex.compiled.ahead", folder,
                                 str(os.getpid())], env=env, cwd=PACKAGE_PARENT,
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError as exc:
        LOGGER.warning("could not start a helper compile process (%s); compiling in this process only", exc)
        return None


def _helper_main(folder, parent):
    with open(os.path.join(folder, "units.pickle"), "rb") as f:
        units = pickle.load(f)
    _work(folder, units, "helper", parent)


if __name__ == "__main__":
    _helper_main(sys.argv[1], int(sys.argv[2]))
