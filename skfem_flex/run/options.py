r"""The options of :func:`~skfem_flex.simulate`, grouped: what is recorded, how a run is kept safe, how it steps."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Recording", "Checkpointing", "Control", "finite_number", "count"]


def finite_number(name, x):
    """``x`` as a finite float, or TypeError/ValueError naming ``name``."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, got {type(x).__name__} {x!r:.40}")
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return x


def count(name, x, minimum):
    """``x`` as an int ≥ ``minimum``, or ValueError naming ``name``."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer, float)) or int(x) != x \
            or int(x) < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {x!r}")
    return int(x)


def _sinks(output):
    """The output sinks as a tuple; a single sink is accepted as well as a sequence of them."""
    if output is None:
        return ()
    if hasattr(output, "write") and hasattr(output, "close"):
        return (output,)
    try:
        sinks = tuple(output)
    except TypeError:
        raise TypeError(f"output must be a sink with write() and close() or a sequence of them, "
                        f"got {type(output).__name__}") from None
    for s in sinks:
        if not (callable(getattr(s, "write", None)) and callable(getattr(s, "close", None))):
            raise TypeError(f"output sinks need write(scene, t, q, v) and close() methods, got {type(s).__name__}")
    return sinks


@dataclass(frozen=True)
class Recording:
    """What a run keeps.

    Parameters
    ----------
    every : int
        Record every n-th step (the first and the last are always recorded).
    output : sink or sequence of sinks
        Objects with ``write(scene, t, q, v)`` and ``close()`` called at the recorded steps
        (e.g. :class:`~skfem_flex.VTKSeries`).
    progress : bool
        A progress bar on stderr for runs longer than a second.
    """

    every: int = 1
    output: tuple = field(default=())
    progress: bool = False

    def __post_init__(self):
        object.__setattr__(self, "every", count("record_every", self.every, 1))
        object.__setattr__(self, "output", _sinks(self.output))


@dataclass(frozen=True)
class Checkpointing:
    """Where and how often a run saves its histories and state, so that it can be read back and resumed
    after it was killed outright.

    Parameters
    ----------
    path : str or Path
        The file (:meth:`~skfem_flex.Result.save`, written atomically). It is written on this schedule,
        when the run is interrupted or stopped by an error, and at its end.
    every : float
        Wall-clock seconds between saves (> 0). After a save that took s seconds the next waits at
        least 20 s·s, so saving stays below about 5 % of the run.
    """

    path: object
    every: float = 5.0

    def __post_init__(self):
        every = finite_number("checkpoint_every", self.every)
        if every <= 0:
            raise ValueError(f"checkpoint_every must be a positive number of seconds, got {self.every!r}")
        object.__setattr__(self, "every", every)


@dataclass(frozen=True)
class Control:
    """How a run steps.

    Parameters
    ----------
    max_halvings : int
        A step whose Newton iteration fails (or that an element refuses) is split in two, recursively, at most
        this deep (≥ 0) before the run is given up.
    compiled : bool or None
        None (default): elements run compiled where they have a compiled form, the others through their own
        Python methods inside the same loop; True: the same, but an element without a compiled form is an
        error naming it; False: every element through its Python methods (the reference the compiled kernels
        are tested against). The environment variable ``SKFEM_FLEX_COMPILED=0`` makes False the default.
    handle_signals : bool
        While the run goes (in the main thread), Ctrl-C and SIGTERM end it after the current chunk of steps
        with :class:`~skfem_flex.Interrupted` (what was written is kept); a second one stops at once.
    """

    max_halvings: int = 8
    compiled: object = None
    handle_signals: bool = True

    def __post_init__(self):
        object.__setattr__(self, "max_halvings", count("max_halvings", self.max_halvings, 0))
        if self.compiled is None and os.environ.get("SKFEM_FLEX_COMPILED", "1").strip() == "0":
            object.__setattr__(self, "compiled", False)
        if self.compiled is not None and not isinstance(self.compiled, (bool, np.bool_)):
            raise ValueError(f"compiled must be True, False or None, got {self.compiled!r}")
