"""Memory a request needs, checked against the memory available before anything is allocated.

A mesh of 10⁷ elements or a run of 10¹² recorded steps used to be started and then killed by
the operating system minutes later without a word. :func:`check_fits` compares an estimate
with the memory the system reports available and raises :class:`MemoryError` with a
sentence naming the request instead.
"""
from __future__ import annotations

import os

__all__ = ["available_memory", "check_fits", "InsufficientMemoryError", "BYTES_PER_ELEMENT"]


class InsufficientMemoryError(MemoryError, ValueError):
    """A request that cannot fit in the memory available (raised before allocating it).

    Also a ValueError: it is bad input, reported like any other (exit status 2 in the CLI)."""

#: peak memory per beam element of a run (bytes): measured by ``examples/benchmark.py --memory``
#: (peak RSS of one step of the spin-up and flexible pendulum beams at 10³–10⁵ elements grows by
#: about 10 kB per element); the estimate takes twice that as a margin
BYTES_PER_ELEMENT = 20_000


def available_memory():
    """Bytes of memory available to a new allocation (``MemAvailable`` on Linux), or None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_fits(n_bytes, what):
    """Raise InsufficientMemoryError if ``n_bytes`` (an estimate) exceed the memory available.

    Parameters
    ----------
    n_bytes : float
        Estimated peak memory of the request, bytes.
    what : str
        The request, in words, for the message (e.g. "a beam of 10000000 elements").
    """
    free = available_memory()
    if free is not None and n_bytes > free:
        raise InsufficientMemoryError(f"{what} needs about {_size(n_bytes)} of memory, but only {_size(free)} "
                          f"are available; make it smaller")


def _size(n):
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} PB"
