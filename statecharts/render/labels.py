"""Text shared by every renderer: state titles, transition labels, wrapping, spec paths.

Pipeline position: IR -> **labels** -> the DOT, Mermaid, flowchart and Markdown
renderers.  Each renderer formats the same facts the same way (``Servo Control (2)``,
``event [guard] / action``), so a diagram, its Mermaid twin and the reference page
read alike.  Nothing here looks at a particular chart: everything is derived from the
IR records.
"""

from __future__ import annotations

import functools
import os
import textwrap
from collections.abc import Iterable
from pathlib import Path

from statecharts import ir
from statecharts.expr import Assignment

#: Width, in characters, at which guards and actions are wrapped in diagrams.
WRAP = 34


def state_title(state: ir.State) -> str:
    """``Servo Control (2)``: the state's name and, if it has one, its documented value."""
    if state.value is None:
        return state.name
    return f"{state.name} ({state.value})"


def error_tags(owner: ir.Instruction | ir.AddOnInstruction) -> tuple[str, str, str]:
    """The flag and the two code members a failing check of ``owner`` sets: ``ER``,
    ``ERR`` and ``EXERR`` of the MOTION_INSTRUCTION tag; an add-on instruction's own
    status tag has them under a prefix (``Sts_ER``, ``Sts_ERR``, ``Sts_EXERR``)."""
    if isinstance(owner, ir.AddOnInstruction):
        names = {m.name for m in owner.status}
        for n in sorted(names):
            prefix = n.removesuffix("ERR")
            if n != prefix and not prefix.endswith("EX") and f"{prefix}ER" in names:
                return f"{prefix}ER", n, f"{prefix}EXERR"
    return "ER", "ERR", "EXERR"


def wrap(text: str, width: int = WRAP) -> list[str]:
    """Break ``text`` into lines at spaces (never inside a word or a quoted string)."""
    words = _tokens(text)
    lines: list[str] = []
    line = ""
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}" if line else w
    if line:
        lines.append(line)
    return lines or [""]


def _tokens(text: str) -> list[str]:
    """Split at spaces outside quotes, so ``'Stop Motion'`` stays on one line."""
    out: list[str] = []
    cur = ""
    quote: str | None = None
    for ch in " ".join(text.split()):
        if quote:
            cur += ch
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
            cur += ch
        elif ch == " ":
            if cur:
                out.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        out.append(cur)
    return out


def paragraph(text: str, width: int = 40) -> list[str]:
    """Wrap prose (descriptions) for a diagram box."""
    return textwrap.wrap(" ".join(text.split()), width) or [""]


def guard_text(t: ir.Transition) -> str | None:
    return None if t.guard is None else f"[{t.guard.text}]"


def actions_text(actions: Iterable[Assignment]) -> list[str]:
    return [a.text for a in actions]


def transition_lines(t: ir.Transition, width: int = WRAP) -> list[str]:
    """The UML label of a transition, wrapped: ``event``, ``[guard]``, ``/ action`` lines."""
    lines: list[str] = []
    if t.event:
        lines.append(t.event)
    if t.guard is not None:
        lines.extend(wrap(f"[{t.guard.text}]", width))
    for a in t.actions:
        lines.extend(wrap(f"/ {a.text}", width))
    return lines


def transition_text(t: ir.Transition) -> str:
    """The UML label on one line: ``event [guard] / a; b``."""
    parts = []
    if t.event:
        parts.append(t.event)
    if t.guard is not None:
        parts.append(f"[{t.guard.text}]")
    if t.actions:
        parts.append("/ " + "; ".join(a.text for a in t.actions))
    return " ".join(parts)


def transition_kind(chart: ir.Chart, t: ir.Transition) -> str:
    """``request``, ``environment``, ``clock`` (the event's kind) or ``automatic`` (eventless)."""
    if t.event is None:
        return "automatic"
    for e in chart.events:
        if e.name == t.event:
            return e.kind
    return "request"


def internal_transitions(chart: ir.Chart, state_id: str) -> list[ir.Transition]:
    """Targetless transitions of ``state_id``: drawn inside the state, as UML does."""
    return [t for t in chart.transitions if t.source == state_id and t.target is None]


def children(chart: ir.Chart, state_id: str | None) -> list[ir.State]:
    """Child states in spec order (top-level states for ``None``)."""
    return [s for s in chart.states if s.parent == state_id]


def is_container(state: ir.State) -> bool:
    return state.kind in (ir.StateKind.COMPOUND, ir.StateKind.PARALLEL)


def spec_root(spec: ir.Spec) -> Path | None:
    """The directory the spec's files were read from (their common parent)."""
    if not spec.files:
        return None
    return _common_parent(tuple(spec.files), os.getcwd())


@functools.lru_cache(maxsize=64)
def _common_parent(files: tuple[str, ...], cwd: str) -> Path:
    """The common parent of ``files``, relative ones read from ``cwd`` (part of the key)."""
    paths = [(Path(cwd) / f).resolve() for f in files]
    common = paths[0].parent
    while not all(common == p.parent or common in p.parents for p in paths):
        common = common.parent
    return common


def spec_path(spec: ir.Spec, file: str) -> str:
    """A spec file's path as the docs show it: ``spec/charts/axis_noncip.yaml``.

    Never absolute: the bundled spec is called ``spec/`` whether it is read from a
    checkout or from an installed wheel, so generated artefacts are byte-identical.
    """
    from statecharts.loader import bundled_spec_dir

    root = spec_root(spec)
    p = Path(file).resolve()
    if root is None:
        return p.name
    try:
        rel = p.relative_to(root).as_posix()
    except ValueError:
        return p.name
    try:
        bundled = root == bundled_spec_dir().resolve()
    except (OSError, ModuleNotFoundError):  # pragma: no cover - package data missing
        bundled = False
    prefix = "spec" if bundled else root.name
    return f"{prefix}/{rel}"


def where(spec: ir.Spec, location: ir.Location) -> str:
    """``spec/charts/axis_noncip.yaml:77``."""
    return f"{spec_path(spec, location.file)}:{location.line}"
