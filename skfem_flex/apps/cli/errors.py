"""How a command ends when something goes wrong: one clear line on stderr (no traceback) and an exit status.

:func:`exit_status` runs a command and turns what it raises into that line and status: bad input
(:class:`UsageError`) 2; an output that cannot be written (:class:`OutputWriteError`) 1; Ctrl-C 130 and
SIGTERM (:class:`Terminated`) 143; numbers beyond double precision and a failed solve outside the time loop
(:class:`~skfem_flex.errors.ConvergenceError`, :class:`~skfem_flex.errors.DivergenceError`) 1; anything else an "internal error"
line, 1 (``SKFEM_FLEX_DEBUG=1`` shows the traceback). Python warnings print as one line too
(:func:`one_line_warning`).
"""
from __future__ import annotations

import os
import sys

from ...errors import ConvergenceError, DivergenceError

__all__ = ["UsageError", "OutputWriteError", "Terminated", "raise_terminated", "exit_status", "one_line",
           "one_line_warning", "EXIT_STOPPED", "EXIT_DIVERGED", "EXIT_SIGNAL"]

#: exit status of ``run`` per way of stopping (besides 0 = completed and 2 = bad input)
EXIT_STOPPED, EXIT_DIVERGED = 1, 3
#: exit status after SIGINT and SIGTERM (128 + signal number, the shell's convention)
EXIT_SIGNAL = {2: 130, 15: 143}


class UsageError(Exception):
    """Bad command-line input: reported in one line, exit status 2."""


class OutputWriteError(Exception):
    """Writing an output file failed (disk full, permissions): one line, exit status 1."""

    def __init__(self, exc):
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        super().__init__(f"cannot write the outputs: {exc.strerror or one_line(exc)}{where}")


class Terminated(BaseException):
    """SIGTERM outside the time loop (the loop itself stops gracefully on it)."""


def raise_terminated(signum, frame):
    """SIGTERM handler of the command: raise :class:`Terminated`."""
    raise Terminated()


def one_line(text):
    """``text`` (an exception's message) on one line: runs of white space, newlines included, as one space."""
    return " ".join(str(text).split())


def one_line_warning(message, category, filename, lineno, file=None, line=None):
    """``warnings.showwarning`` of the command: Python warnings (ours, numpy's, matplotlib's) as one line
    like the command's own, with no source echo."""
    kind = "" if category is UserWarning else f"{category.__name__}: "
    try:
        print(f"skfem-flex: warning: {kind}{one_line(message)}", file=sys.stderr if file is None else file)
    except OSError:
        pass


def exit_status(command):
    """``command()``'s exit status; whatever it raises becomes one line on stderr and the status that says it."""
    try:
        return command()
    except UsageError as exc:
        print(f"skfem-flex: error: {exc}", file=sys.stderr)
        return 2
    except OutputWriteError as exc:
        print(f"skfem-flex: error: {exc}", file=sys.stderr)
        return EXIT_STOPPED
    except BrokenPipeError:
        # the reader of stdout went away (``skfem-flex list | head``): not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 0
    except KeyboardInterrupt:
        print("skfem-flex: interrupted; outputs written so far are kept", file=sys.stderr)
        return EXIT_SIGNAL[2]
    except Terminated:
        print("skfem-flex: terminated; outputs written so far are kept", file=sys.stderr)
        return EXIT_SIGNAL[15]
    except (ArithmeticError, MemoryError, RecursionError) as exc:
        # numbers beyond double precision deep inside a computation: one line, not a traceback
        print(f"skfem-flex: error: {type(exc).__name__}: {one_line(exc)}", file=sys.stderr)
        return EXIT_STOPPED
    except (ConvergenceError, DivergenceError) as exc:
        # a solve outside the time loop (a steady spin, a static equilibrium, a scene's set-up) that the settings
        # made impossible: the message says where and why
        print(f"skfem-flex: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_STOPPED
    except Exception as exc:
        if os.environ.get("SKFEM_FLEX_DEBUG"):
            raise
        print(f"skfem-flex: internal error: {type(exc).__name__}: {one_line(exc)} (please report it; "
              f"SKFEM_FLEX_DEBUG=1 shows the traceback)", file=sys.stderr)
        return EXIT_STOPPED
