"""Where compiled (Numba) code is cached, and when a cached function counts as stale.

The package's kernels are ``numba.njit(cache=True)`` functions. Numba keys
each cached function to the content of its *own* source file. A compiled
function that calls a kernel in another file (the compiled time loop calls
the floating-frame kernels) inlines that callee into its machine code, so
after an edit of the callee numba would keep loading the old caller: it
computes with the old code or crashes.

This module makes the stamp of every cached function of the package the
hash of *all* the package's Python sources (and the numba version): any edit
of any file of the package invalidates every cached kernel of the package,
and the next process compiles afresh, with no cache to clear by hand. Code
outside the package keeps numba's own rule.

Where the cache lives is numba's choice, in numba's order: ``NUMBA_CACHE_DIR``
when set; else the ``__pycache__`` folder beside the source when it is
writable; else the user's cache folder (``~/.cache/numba``, or under
``XDG_CACHE_HOME``), so a read-only installation compiles once per user,
not once per run.

Importing :mod:`skfem_flex` registers the locators below (in front of
numba's) before any kernel module is imported.
"""
from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import numba
from numba.core import caching as _caching

__all__ = ["PACKAGE_DIR", "source_stamp", "install"]

#: the folder of the installed package
PACKAGE_DIR = Path(__file__).resolve().parent.parent


@functools.lru_cache(maxsize=None)
def source_stamp():
    """SHA-256 (hex) of every ``*.py`` file of the package and of the numba version.

    Computed once per process: an edit takes effect in the next process,
    as it does for Python code itself.
    """
    digest = hashlib.sha256(numba.__version__.encode())
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE_DIR).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def _inside_package(py_file):
    try:
        Path(py_file).resolve().relative_to(PACKAGE_DIR)
    except (ValueError, OSError):
        return False
    return True


class _PackageStamp:
    """Mixin: applies to the package's own files only, stamped by :func:`source_stamp`."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _inside_package(py_file):
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return source_stamp()


class UserProvidedLocator(_PackageStamp, _caching.UserProvidedCacheLocator):
    """``NUMBA_CACHE_DIR``, when the user set it."""


class InTreeLocator(_PackageStamp, _caching.InTreeCacheLocator):
    """The ``__pycache__`` folder beside the source, when writable."""


class UserWideLocator(_PackageStamp, _caching.UserWideCacheLocator):
    """The user's cache folder: read-only installations."""


_LOCATORS = (UserProvidedLocator, InTreeLocator, UserWideLocator)


def install():
    """Put the package's locators in front of numba's (idempotent)."""
    impl = getattr(_caching, "CacheImpl", None) or getattr(_caching, "_CacheImpl")   # renamed in numba 0.59
    classes = impl._locator_classes
    if classes[:len(_LOCATORS)] != list(_LOCATORS):
        classes[:] = list(_LOCATORS) + [c for c in classes if c not in _LOCATORS]


install()
