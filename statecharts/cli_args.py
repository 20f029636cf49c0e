"""What every ``motionchart`` subcommand shares on its command line: argument types and exit codes.

Exit codes (the documented table): 0 ok, 1 a finding or invalid input, 2 a usage error.
A command with an outcome of its own adds codes above these (``check``: 3 incomplete).

Example::

    >>> positive_seconds("2.5")
    2.5
    >>> positive_int("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a positive integer, got '0'
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import Protocol, TextIO

EXIT_OK, EXIT_FINDING, EXIT_USAGE = 0, 1, 2

#: the longest time-out or time limit a command accepts (about eleven days)
MAX_SECONDS = 1e6


def positive_int(text: str) -> int:
    """An argparse type: a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """An argparse type: a number of seconds above 0 and below :data:`MAX_SECONDS`."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not 0 < value < MAX_SECONDS:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


class Located(Protocol):
    """An error that carries located diagnostics (``InputError``, ``ModelError``, ...)."""

    @property
    def diagnostics(self) -> Iterable[object]: ...


def input_error(exc: Located, stream: TextIO | None = None) -> int:
    """Print every located diagnostic of a bad input, one a line; the exit code for it."""
    out = stream or sys.stderr
    for d in exc.diagnostics:
        print(d, file=out)
    return EXIT_FINDING
