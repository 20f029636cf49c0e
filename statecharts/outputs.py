"""Safe output: every file is written whole or not at all.

Pipeline position: below every writer (counterexamples, GraphML, generated artefacts;
:func:`replace_folder` for whole output folders such as ``docs`` and ``generate``).
:func:`atomic_write_bytes` writes to a temporary file in the target's directory and
renames it over the target, so a reader (or an interrupted run) never sees half a
file, and the temporary file is removed whatever happens, Ctrl-C included.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")


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


def replace_folder(out_dir: Path | str, fill: Callable[[Path], T]) -> T:
    """Update the folder ``out_dir`` as a whole: either it stays as it was or it is complete.

    The current folder is copied into a staging folder beside it (copies, not links:
    a writer may write a file in place), ``fill(staging)`` writes and prunes there, and the staging
    folder then takes the place of the old one by two renames made with SIGINT held
    back.  An interruption or an error before that leaves ``out_dir`` untouched and no
    staging folder behind.  Folders that cannot be renamed (the current directory or
    one of its ancestors, a mount point) are filled in place.
    """
    out = Path(out_dir)
    try:
        resolved = out.resolve()
        in_place = resolved == Path.cwd() or resolved in Path.cwd().parents or os.path.ismount(resolved)
    except OSError:
        in_place = True
    if in_place:
        return fill(out)
    parent = resolved.parent
    parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{resolved.name}.new-", dir=parent))
    old = parent / f".{resolved.name}.old-{os.getpid()}"
    try:
        if resolved.is_dir():
            shutil.copytree(resolved, staging, dirs_exist_ok=True, symlinks=True)
        result = fill(staging)
        with _sigint_held():
            if resolved.is_dir():
                os.rename(resolved, old)
                try:
                    os.rename(staging, resolved)
                except OSError:
                    os.rename(old, resolved)
                    raise
            else:
                os.rename(staging, resolved)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        shutil.rmtree(old, ignore_errors=True)
    return result


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """Hold SIGINT (Ctrl-C) back for the few system calls that swap two folders."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
