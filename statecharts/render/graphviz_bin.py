"""Find a Graphviz layout program and run it: DOT text -> SVG or PNG bytes.

Pipeline position: DOT text (:mod:`statecharts.render.dot`,
:mod:`statecharts.render.flowchart`) -> **graphviz_bin** -> ``*.svg`` / ``*.png``.

Two programs are accepted, in this order: Graphviz's own ``dot`` (Debian's
``graphviz`` package; what ``make install`` installs as root) and ``graphviz-pure``
(a static binary from PyPI, no root needed; ``make install`` falls back to it).  Each
is looked for on ``PATH`` and in the directory of the running interpreter
(``.venv/bin`` when the command runs from the project's virtual environment without
it being activated).  When neither is there, :class:`GraphvizNotFoundError` says so
and how to install one; text artefacts (DOT, Mermaid) never need either.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

#: Programs tried, in order.
PROGRAMS = ("dot", "graphviz-pure")
#: Output formats this module renders.
FORMATS = ("svg", "png", "pdf")
#: Seconds a single rendering may take before it is abandoned.
TIMEOUT = 60


class RenderError(RuntimeError):
    """The layout program failed (bad DOT, crash, time-out)."""


class GraphvizNotFoundError(RenderError):
    """Neither ``dot`` nor ``graphviz-pure`` could be found."""

    def __init__(self, searched: list[str]) -> None:
        self.searched = searched
        super().__init__(
            "cannot render SVG/PNG: neither `dot` (Graphviz) nor `graphviz-pure` was found "
            f"(looked in PATH and {', '.join(searched) or 'nowhere else'}). Install one: "
            "`sudo apt-get install graphviz`, or `pip install graphviz-pure` in the project's "
            "virtual environment (`make install` does either). DOT and Mermaid output need neither."
        )


def _candidate_dirs() -> list[str]:
    dirs = []
    exe_dir = Path(sys.executable).parent
    dirs.append(str(exe_dir))
    prefix_bin = Path(sys.prefix) / "bin"
    if str(prefix_bin) not in dirs:
        dirs.append(str(prefix_bin))
    return dirs


def find_program() -> str:
    """Path of the first layout program found; GraphvizNotFoundError if none."""
    extra = _candidate_dirs()
    for name in PROGRAMS:
        found = shutil.which(name)
        if found:
            return found
        for d in extra:
            found = shutil.which(name, path=d)
            if found:
                return found
    raise GraphvizNotFoundError(extra)


def available() -> bool:
    try:
        find_program()
    except GraphvizNotFoundError:
        return False
    return True


def render(source: str, fmt: str, program: str | None = None) -> bytes:
    """Lay out DOT ``source`` and return the ``fmt`` (``svg``, ``png`` or ``pdf``) bytes."""
    if fmt not in FORMATS:
        raise ValueError(f"unsupported format {fmt!r}; expected one of: {', '.join(FORMATS)}")
    prog = program or find_program()
    env = dict(os.environ)
    env.setdefault("LC_ALL", "C.UTF-8")
    try:
        proc = subprocess.run(
            [prog, f"-T{fmt}"], input=source.encode("utf-8"), capture_output=True,
            timeout=TIMEOUT, check=False, env=env,
        )
    except subprocess.TimeoutExpired:
        raise RenderError(f"{Path(prog).name} did not finish within {TIMEOUT} s") from None
    except OSError as exc:
        raise RenderError(f"cannot run {prog}: {exc.strerror or exc}") from None
    if proc.returncode != 0 or not proc.stdout:
        err = proc.stderr.decode("utf-8", "replace").strip()
        raise RenderError(f"{Path(prog).name} -T{fmt} failed (exit {proc.returncode}): {err}")
    return proc.stdout
