"""Files written atomically: a reader, or a run killed at any moment, sees the old file or the new one.

Every file the package writes (VTK frames and collections, results, checkpoints, summaries) goes
through :func:`write_atomically`: the content is written under a temporary name beside the target,
``.NAME.PID.tmp``, and renamed onto it with one ``os.replace``. On any failure (a full disk, an
interrupt) the temporary file is removed and the error propagates, so nothing half-written and no
``.tmp`` file is left behind.
"""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["temporary_name", "write_atomically", "write_text_atomically"]


def temporary_name(path):
    """The temporary file name used while ``path`` is written: ``.NAME.PID.tmp`` beside it."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def write_atomically(path, write):
    """Call ``write(tmp)`` with a temporary path beside ``path``, then rename it onto ``path``.

    Returns ``path`` (a Path).
    """
    path = Path(path)
    tmp = temporary_name(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)          # a full disk leaves no temporary file behind
        raise
    return path


def write_text_atomically(path, text):
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return write_atomically(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
