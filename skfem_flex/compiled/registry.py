r"""Compiled units, made on first use: what is compiled, when, and what the user is told.

Every kernel (a scheme's step, a solver, an element family) is a ``numba.cfunc`` with the one
signature of :mod:`.abi`, cached on disk; the loop and its helpers are ``numba.njit`` functions with a
fixed signature. :func:`compiled_kernel` and :func:`compiled_function` make them when first needed:

* from the cache when it holds them (milliseconds, nothing said);
* otherwise compiled — said on the ``skfem_flex`` logger before it starts ("compiling the
  floating-frame beam family (first use on this machine) …") and when it ends, with its time; the time
  is added to :func:`compile_seconds`, which runs report apart from their run time.

A compile runs in a worker thread while the caller waits in short slices, so that Ctrl-C is answered
at once (``KeyboardInterrupt`` is raised in the caller; the worker, a daemon thread, dies with the
process).
"""
from __future__ import annotations

import contextlib
import importlib
import logging
import os
import sys
import threading
import time
from dataclasses import dataclass
from types import SimpleNamespace

from numba.core.ccallback import CFunc

from ..numerics.newton import set_compile_hook
from .abi import KERNEL_SIGNATURE

__all__ = ["compiled_kernel", "compiled_function", "compile_seconds", "compiled_names", "set_interrupt_check",
           "interruptible", "planning", "is_cached", "count_compiled", "Unit", "LOGGER"]

#: the package's logger for compile notices (INFO; ``logging.getLogger("skfem_flex").setLevel(logging.WARNING)``
#: or ``SKFEM_FLEX_QUIET=1`` silences it)
LOGGER = logging.getLogger("skfem_flex")

_KERNELS = {}
_PLAN = [None]
_INTERRUPT = [None]
_FUNCTIONS = {}
_SECONDS = [0.0]
_NAMES = []


@dataclass(frozen=True)
class Unit:
    """One compiled unit, named so that another process can make it (:mod:`.ahead`).

    ``kind`` is "kernel" (a ``numba.cfunc`` of :data:`~.abi.KERNEL_SIGNATURE` made from the plain function
    ``module.name``, with numba's reference counting when ``nrt``) or "function" (the ``numba.njit``
    function ``module.name`` for the argument types ``argtypes``); ``what`` names it in notices."""

    kind: str
    module: str
    name: str
    what: str
    nrt: bool = False
    argtypes: tuple = ()

    def target(self):
        """The plain function (kernel) or the dispatcher (function) the unit is made from."""
        return getattr(importlib.import_module(self.module), self.name)

    def make(self):
        """Load the unit from the cache, or compile it (with notices)."""
        if self.kind == "kernel":
            return compiled_kernel(self.target(), self.what, self.nrt)
        return compiled_function(self.target(), self.argtypes, self.what)


@contextlib.contextmanager
def planning():
    """Inside ``with planning() as units:``, :func:`compiled_kernel` compiles nothing: it appends the
    :class:`Unit` it would make to ``units`` and returns a stand-in whose ``address`` is 0."""
    units = []
    _PLAN[0] = units
    try:
        yield units
    finally:
        _PLAN[0] = None


def is_cached(unit):
    """Whether ``unit`` is made already in this process or in the cache; a unit found in the cache is
    loaded now (the later :func:`compiled_kernel` or :func:`compiled_function` finds it made)."""
    if unit.kind == "kernel":
        key = (unit.module, unit.name)
        if key not in _KERNELS:
            res = _new_cfunc(unit.target(), unit.nrt)
            if _load_cached_kernel(res) is None:
                return False
            res.compile()                   # loads the entry just found
            _KERNELS[key] = res
        return True
    dispatcher, argtypes = unit.target(), tuple(unit.argtypes)
    if (dispatcher, argtypes) not in _FUNCTIONS and argtypes not in dispatcher.overloads:
        if _load_cached_function(dispatcher, argtypes) is None:
            return False
        dispatcher.compile(argtypes)        # loads the entry just found
        _FUNCTIONS[(dispatcher, argtypes)] = True
    return True


def count_compiled(names, seconds):
    """Count ``names`` (compiled elsewhere for this process, :mod:`.ahead`) and ``seconds`` of waiting for
    them in :func:`compiled_names` and :func:`compile_seconds`."""
    _NAMES.extend(names)
    _SECONDS[0] += seconds


def compile_seconds():
    """Seconds spent compiling in this process so far."""
    return _SECONDS[0]


def set_interrupt_check(check):
    """While a compile runs, ``check()`` is polled every 0.1 s; when it returns a signal number the wait ends
    with :class:`~skfem_flex.errors.Interrupted` (None: no check)."""
    _INTERRUPT[0] = check


def compiled_names():
    """What this process compiled (not loaded from the cache), in order."""
    return tuple(_NAMES)


def interruptible(work, what):
    """Run ``work()`` in a daemon thread, waiting in slices of 0.1 s (Ctrl-C reaches the caller at once)."""
    box = {}

    def target():
        try:
            box["value"] = work()
        except BaseException as exc:      # handed to the caller
            box["error"] = exc
    thread = threading.Thread(target=target, name=f"compile {what}", daemon=True)
    thread.start()
    while thread.is_alive():
        thread.join(0.1)
        check = _INTERRUPT[0]
        signum = check() if check is not None else None
        if signum is not None:
            import signal
            from ..errors import Interrupted
            LOGGER.info("interrupted while compiling %s; stopping", what)
            raise Interrupted(f"interrupted by {signal.Signals(signum).name} while compiling {what}", signal=signum)
    if "error" in box:
        raise box["error"]
    return box.get("value")


def _compiling(what, work):
    """Say that ``what`` is being compiled, do it, say how long it took."""
    LOGGER.info("compiling %s (first use on this machine, cached afterwards) ...", what)
    start = time.perf_counter()
    value = interruptible(work, what)
    seconds = time.perf_counter() - start
    _SECONDS[0] += seconds
    _NAMES.append(what)
    LOGGER.info("compiled %s in %.1f s", what, seconds)
    return value


def _new_cfunc(pyfunc, nrt):
    res = CFunc(pyfunc, (KERNEL_SIGNATURE.args, KERNEL_SIGNATURE.return_type), locals={},
                options={} if nrt else {"_nrt": False})
    res.enable_caching()
    return res


def _load_cached_kernel(res):
    try:
        return res._cache.load_overload(res._sig, res._targetdescr.target_context)
    except Exception:                   # an unreadable cache entry: compile
        return None


def _load_cached_function(dispatcher, argtypes):
    try:
        return dispatcher._cache.load_overload(tuple(argtypes), dispatcher.targetctx)
    except Exception:                   # an unreadable cache entry: compile
        return None


def compiled_kernel(pyfunc, what, nrt=False):
    """The kernel compiled from ``pyfunc`` (signature :data:`~.abi.KERNEL_SIGNATURE`), from the cache or
    compiled now. ``what`` names it in notices ("the energy-momentum step"). ``nrt``: the kernel allocates
    (numba's reference-counted memory); without it no array a kernel passes on is reference counted, which
    is most of a small scene's cost otherwise."""
    key = (pyfunc.__module__, pyfunc.__qualname__)
    if _PLAN[0] is not None:
        _PLAN[0].append(Unit("kernel", pyfunc.__module__, pyfunc.__qualname__, what, nrt))
        return SimpleNamespace(address=0)
    hit = _KERNELS.get(key)
    if hit is not None:
        return hit
    res = _new_cfunc(pyfunc, nrt)
    if _load_cached_kernel(res) is None:
        _compiling(what, res.compile)
    else:
        res.compile()                   # loads the entry just found
    _KERNELS[key] = res
    return res


def compiled_function(dispatcher, argtypes, what):
    """``dispatcher`` (a ``numba.njit`` function) compiled for the argument types ``argtypes`` (a tuple of
    numba types) or loaded from the cache, with a notice when it compiles."""
    key = (dispatcher, tuple(argtypes))
    if key in _FUNCTIONS or tuple(argtypes) in dispatcher.overloads:
        return dispatcher
    if _load_cached_function(dispatcher, argtypes) is None:
        _compiling(what, lambda: dispatcher.compile(tuple(argtypes)))
    else:
        dispatcher.compile(tuple(argtypes))
    _FUNCTIONS[key] = True
    return dispatcher


set_compile_hook(compiled_function)


def _default_handler():
    if any(getattr(h, "_skfem_flex", False) for h in LOGGER.handlers):
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("skfem-flex: %(message)s"))
    handler._skfem_flex = True
    LOGGER.addHandler(handler)
    if LOGGER.level == logging.NOTSET:
        quiet = os.environ.get("SKFEM_FLEX_QUIET", "").strip() not in ("", "0")
        LOGGER.setLevel(logging.WARNING if quiet else logging.INFO)
    LOGGER.propagate = False


_default_handler()
