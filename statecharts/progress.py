"""A one-line progress display for commands that take more than a second.

On a terminal (standard error is a TTY and ``CI`` is not set) a :class:`Progress` keeps
one status line up to date on standard error -- ``motionchart generate: rendering
diagrams/AxisCIP.svg (3/34)`` -- and erases it when the work is done.  Anywhere else
(a pipe, a file, a CI log) it writes nothing at all, so output that is captured or
compared stays exactly as before.

>>> import io
>>> p = Progress("motionchart docs", stream=io.StringIO())  # not a terminal: silent
>>> p.enabled
False
>>> p.update("tracing scenarios", 1, 80); p.close()
"""

from __future__ import annotations

import os
import sys
import time
from typing import TextIO

#: Seconds between two redraws of the line (a redraw costs a write to the terminal).
REFRESH = 0.1


def wanted(stream: TextIO) -> bool:
    """Whether progress is shown on ``stream``: a terminal, and not under CI."""
    try:
        tty = stream.isatty()
    except (AttributeError, ValueError):  # closed or not a real stream
        return False
    return tty and os.environ.get("CI", "").lower() not in ("true", "1")


class Progress:
    """The status line of one command (see the module docstring)."""

    def __init__(self, prefix: str, *, stream: TextIO | None = None, enabled: bool | None = None) -> None:
        self.prefix = prefix
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = wanted(self.stream) if enabled is None else enabled
        self._shown = 0
        self._last = 0.0

    def update(self, what: str, done: int | None = None, total: int | None = None) -> None:
        """Show ``what`` (with ``done/total`` when given); redrawn at most every :data:`REFRESH` s,
        except for the first and the last step."""
        if not self.enabled:
            return
        now = time.monotonic()
        last_step = done is not None and total is not None and done >= total
        if self._shown and not last_step and now - self._last < REFRESH:
            return
        self._last = now
        count = f" ({done}/{total})" if done is not None and total is not None else ""
        line = f"{self.prefix}: {what}{count}"
        width = _width(self.stream)
        if len(line) > width - 1:
            line = line[: max(width - 2, 10)] + "…"
        pad = " " * max(self._shown - len(line), 0)
        try:
            self.stream.write("\r" + line + pad)
            self.stream.flush()
        except (OSError, ValueError):
            self.enabled = False
            return
        self._shown = len(line)

    def clear(self) -> None:
        """Erase the line (before other output goes to the same terminal)."""
        if self.enabled and self._shown:
            try:
                self.stream.write("\r" + " " * self._shown + "\r")
                self.stream.flush()
            except (OSError, ValueError):
                self.enabled = False
            self._shown = 0

    def close(self) -> None:
        self.clear()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _width(stream: TextIO) -> int:
    try:
        columns = os.get_terminal_size(stream.fileno()).columns
    except (OSError, ValueError, AttributeError):
        return 80
    return columns if columns > 20 else 80  # a terminal that reports no size


__all__ = ["REFRESH", "Progress", "wanted"]
