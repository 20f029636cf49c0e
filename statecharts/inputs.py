"""Safe reading of input files: regular files only, bounded size, every failure located.

Pipeline position: below every reader.  :func:`read_input` is the one place where a
user-named file is opened (:func:`statecharts.loader.read_document` parses what it
returns as YAML or JSON).  It opens without blocking and looks at what it opened before
reading: a FIFO, a character device such as ``/dev/zero``, a socket or a directory is
refused with a message that says what it is, so no input can block or fill memory;
a regular file larger than :data:`MAX_INPUT_BYTES` is refused without being read in full.
Names that the system refuses (empty, too long, a symlink loop, missing) become a
:class:`~statecharts.diagnostics.Diagnostic` at line 1 of that name.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from statecharts.diagnostics import Diagnostic

#: Largest input file accepted, in bytes (the largest bundled spec file is about 80 kB).
MAX_INPUT_BYTES = 2_000_000
#: Longest file name shown in a message (longer ones are shortened in the middle).
_SHOWN_NAME = 200

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def shown_name(path: Path | str) -> str:
    """A file name fit for a message (a name of thousands of characters is shortened)."""
    name = str(path)
    if len(name) <= _SHOWN_NAME:
        return name
    half = _SHOWN_NAME // 2 - 2
    return f"{name[:half]}...{name[-half:]}"


def path_problem(text: str) -> str | None:
    """Why a path argument cannot name a file at all (empty, NUL byte), or None."""
    if not text:
        return "empty path"
    if "\0" in text:
        return "path contains a NUL character"
    return None


def _kind(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def read_input(path: Path | str, errors: list[Diagnostic], *, what: str = "file",
               limit: int = MAX_INPUT_BYTES) -> bytes | None:
    """The bytes of a regular file of at most ``limit`` bytes; else a diagnostic and None."""
    name = shown_name(path)
    problem = path_problem(str(path))
    if problem is not None:
        errors.append(Diagnostic(name or "(empty path)", 1, 1, "", f"cannot read {what}: {problem}"))
        return None
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        reason = exc.strerror or str(exc)
        if exc.errno == errno.ELOOP:
            reason = "a loop of symbolic links"
        errors.append(Diagnostic(name, 1, 1, "", f"cannot read {what}: {reason}"))
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            errors.append(Diagnostic(name, 1, 1, "", (
                f"cannot read {what}: it is {_kind(info.st_mode)}, not a regular file")))
            return None
        if info.st_size > limit:
            errors.append(Diagnostic(name, 1, 1, "", f"{what} is larger than {limit} bytes ({info.st_size} bytes)"))
            return None
        chunks: list[bytes] = []
        size = 0
        while True:
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                break
            size += len(chunk)
            if size > limit:  # the file grew while it was read
                errors.append(Diagnostic(name, 1, 1, "", f"{what} is larger than {limit} bytes"))
                return None
            chunks.append(chunk)
        return b"".join(chunks)
    except OSError as exc:
        errors.append(Diagnostic(name, 1, 1, "", f"cannot read {what}: {exc.strerror or exc}"))
        return None
    finally:
        os.close(fd)


def path_argument_problem(text: str) -> str | None:
    """Why a path given on the command line names nothing usable, or None when it exists.

    Never raises: an over-long name, a symlink loop or a NUL byte become words.
    """
    problem = path_problem(text)
    if problem is not None:
        return problem
    try:
        os.stat(text)
    except OSError as exc:
        if exc.errno == errno.ENOENT:
            return "no such file or directory"
        if exc.errno == errno.ELOOP:
            return "a loop of symbolic links"
        return (exc.strerror or str(exc)).lower()
    except ValueError as exc:
        return str(exc)
    return None


def output_path_problem(text: str, *, directory: bool = False) -> str | None:
    """Why an output path cannot be written (checked before long work starts), or None.

    The parent must be an existing, writable directory (or, for ``directory=True``, the
    path itself may be one or be creatable there); an existing path of the wrong kind is
    refused.
    """
    problem = path_problem(text)
    if problem is not None:
        return problem
    try:
        path = Path(text)
        if path.exists():
            if directory and not path.is_dir():
                return "exists and is not a directory"
            if not directory and path.is_dir():
                return "is a directory"
            target = path if directory else path.parent
        else:
            target = path.parent
            while not target.exists() and target != target.parent:
                target = target.parent
        if not target.is_dir():
            return f"{shown_name(target)} is not a directory"
        if not os.access(target, os.W_OK | os.X_OK):
            return f"{shown_name(target)} is not writable"
    except OSError as exc:
        return (exc.strerror or str(exc)).lower()
    return None
