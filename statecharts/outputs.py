"""Safe output: every file is written whole or not at all.

Pipeline position: below every writer (counterexamples, GraphML, generated artefacts).
:func:`atomic_write_bytes` writes to a temporary file in the target's directory and
renames it over the target, so a reader (or an interrupted run) never sees half a
file, and the temporary file is removed whatever happens, Ctrl-C included.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path


@contextlib.contextmanager
def atomic_path(target: Path | str) -> Iterator[Path]:
    """A temporary path beside ``target``; renamed over it when the block ends normally."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.replace(tmp, target)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def atomic_write_bytes(target: Path | str, data: bytes) -> None:
    """Write ``data`` to ``target`` atomically (see :func:`atomic_path`)."""
    with atomic_path(target) as tmp, open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def atomic_write_text(target: Path | str, text: str) -> None:
    atomic_write_bytes(target, text.encode("utf-8"))


def atomic_write_with(target: Path | str, write: Callable[[Path], object]) -> None:
    """Let ``write(path)`` produce the file (a library writer), then rename it into place."""
    with atomic_path(target) as tmp:
        write(tmp)
