"""The command's argument parser class and the types of its numeric options.

:class:`Parser` reports a parse error as a :class:`~skfem_flex.apps.cli.errors.UsageError` (one line,
exit status 2) instead of argparse's usage text and exit.
"""
from __future__ import annotations

import argparse
import math

from .errors import UsageError

__all__ = ["Parser", "positive_int", "positive_number", "number"]


class Parser(argparse.ArgumentParser):
    """argparse parser whose errors are one line (raised as UsageError, reported by
    :func:`~skfem_flex.apps.cli.main`)."""

    def error(self, message):
        raise UsageError(f"{message} (see '{self.prog} --help')")


def positive_int(text):
    """``type=`` of an option taking a positive integer."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return n


def positive_number(text):
    """``type=`` of an option taking a positive finite number."""
    x = number(text)
    if not math.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return x


def number(text):
    """``type=`` of an option taking a number."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
