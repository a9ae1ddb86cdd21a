"""Memory a request needs, checked against the memory available before anything is allocated.

A mesh of 10⁷ elements or a run of 10¹² recorded steps used to be started and then killed by
the operating system minutes later without a word. :func:`check_fits` compares an estimate
with the memory available to this process (the least of the system's free memory, the
container's cgroup limit and the process's address-space limit, :func:`available_memory`)
and raises :class:`MemoryError` with a sentence naming the request instead.
"""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["available_memory", "check_fits", "InsufficientMemoryError", "BYTES_PER_ELEMENT"]


class InsufficientMemoryError(MemoryError, ValueError):
    """A request that cannot fit in the memory available (raised before allocating it).

    Also a ValueError: it is bad input, reported like any other (exit status 2 in the CLI)."""

#: peak memory per beam element of a run (bytes): measured by ``examples/benchmark.py --memory``
#: (peak RSS of one step of the spin-up and flexible pendulum beams at 10³–10⁵ elements grows by
#: about 10 kB per element); the estimate takes twice that as a margin
BYTES_PER_ELEMENT = 20_000


def available_memory():
    """Bytes of memory available to a new allocation of this process, or None if unknown.

    The least of what is known of:

    - the system: ``MemAvailable`` of ``/proc/meminfo`` on Linux (else the free physical pages);
    - the memory cgroup (containers, batch schedulers): the limit minus the usage of the process's
      cgroup and of each of its ancestors — cgroup v2 ``memory.max`` − ``memory.current``, cgroup v1
      ``memory.limit_in_bytes`` − ``memory.usage_in_bytes``, under ``/sys/fs/cgroup``; ``max`` (or
      v1's page-rounded 2⁶³) is no limit, and the inactive file cache of ``memory.stat`` counts as
      free (the kernel reclaims it before it kills);
    - the process's address-space limit (``ulimit -v``, ``resource.RLIMIT_AS`` soft limit) when
      finite, minus the process's current virtual size (``/proc/self/statm``). Where that size is
      not known (no ``/proc``) the limit minus the peak resident size
      (``getrusage().ru_maxrss``) is used instead: an *estimate*, too generous by the address
      space the process has reserved but not touched.
    """
    known = [x for x in (_system_available(), _cgroup_available(), _rlimit_available()) if x is not None]
    return max(min(known), 0) if known else None


def _system_available():
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


#: where the cgroup hierarchies are mounted (a module constant so that tests can point it elsewhere)
CGROUP_ROOT = Path("/sys/fs/cgroup")
#: (hierarchy below CGROUP_ROOT, limit file, usage file, controller named in /proc/self/cgroup)
_CGROUP_FILES = (("", "memory.max", "memory.current", ""),                               # v2 (unified)
                 ("unified", "memory.max", "memory.current", ""),                        # v2 beside v1
                 ("memory", "memory.limit_in_bytes", "memory.usage_in_bytes", "memory"))  # v1


def _read_text(path):
    """The stripped text of a small file, or None if it cannot be read."""
    try:
        with open(path, encoding="ascii") as fh:
            return fh.read().strip()
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def _own_cgroups():
    """{controller: path} from /proc/self/cgroup ("" for the cgroup v2 line ``0::/path``)."""
    out = {}
    for line in (_read_text("/proc/self/cgroup") or "").splitlines():
        parts = line.split(":", 2)
        if len(parts) == 3:
            for controller in parts[1].split(",") if parts[1] else [""]:
                out[controller] = parts[2]
    return out


def _inactive_file(directory):
    """Bytes of inactive file cache in the cgroup ``directory`` (reclaimable), 0 if not reported."""
    stats = {}
    for line in (_read_text(directory / "memory.stat") or "").splitlines():
        key, _, value = line.partition(" ")
        stats[key] = value
    for key in ("total_inactive_file", "inactive_file"):         # v1 hierarchical first, then v2/v1 local
        if stats.get(key, "").isdigit():
            return int(stats[key])
    return 0


def _cgroup_available():
    """Least limit − usage over the process's memory cgroup and its ancestors, or None if no limit is set."""
    own = _own_cgroups()
    best = None
    for hierarchy, limit_file, usage_file, controller in _CGROUP_FILES:
        base = CGROUP_ROOT / hierarchy if hierarchy else CGROUP_ROOT
        # the process's own group and its ancestors (inside a cgroup namespace the mount's root is
        # the own group: then only the root is there to read)
        rel = own.get(controller, "/").strip("/")
        parts = rel.split("/") if rel else []
        for depth in range(len(parts), -1, -1):
            directory = base.joinpath(*parts[:depth])
            limit, usage = _read_text(directory / limit_file), _read_text(directory / usage_file)
            if limit is None or usage is None or not limit.isdigit() or not usage.isdigit():
                continue                                         # absent, unreadable or "max": no limit here
            left = int(limit) - max(int(usage) - _inactive_file(directory), 0)
            best = left if best is None else min(best, left)
    return best


def _rlimit_available():
    """RLIMIT_AS soft limit minus the process's virtual size (or peak RSS as an estimate), None if unlimited."""
    try:
        import resource
    except ImportError:                                          # not on Windows
        return None
    try:
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    except (OSError, ValueError, AttributeError):
        return None
    if soft == resource.RLIM_INFINITY or soft < 0:
        return None
    return soft - _process_size()


def _process_size():
    """Bytes of address space the process uses: VmSize from /proc/self/statm, else the peak RSS."""
    statm = _read_text("/proc/self/statm")
    try:
        return int(statm.split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, IndexError, ValueError, OSError):
        pass
    try:
        import resource
        import sys
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak if sys.platform == "darwin" else peak * 1024       # bytes on macOS, kB elsewhere
    except (ImportError, OSError, AttributeError):
        return 0


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
