"""Located user errors: one record per problem, all of a file reported in one pass.

Every error a user can cause (a spec, a scenario, a vector) becomes a
:class:`Diagnostic` with the file, 1-based line and column, the node path inside the
document and what was expected.  :class:`InputError` carries a tuple of them; the CLI
prints them one per line as ``file:line:col: node-path: message`` and exits 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True, order=True)
class Diagnostic:
    file: str
    line: int
    column: int
    path: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}"
        return f"{where}: {self.path}: {self.message}" if self.path else f"{where}: {self.message}"

    def as_dict(self) -> dict[str, object]:
        """The record for ``--json`` output."""
        return {"file": self.file, "line": self.line, "column": self.column, "path": self.path,
                "message": self.message}


class InputError(ValueError):
    """A user-supplied file is wrong; ``diagnostics`` says where and why."""

    def __init__(self, diagnostics: list[Diagnostic] | tuple[Diagnostic, ...]) -> None:
        self.diagnostics = tuple(sorted(set(diagnostics)))
        super().__init__("\n".join(str(d) for d in self.diagnostics))


class SpecError(InputError):
    """The specification is malformed."""


class ScenarioError(InputError):
    """A scenario or conformance vector is malformed."""


def node_path(parts: tuple[Any, ...] | list[Any]) -> str:
    """Render a document path like ``chart.states[2].entry[0]``."""
    out = ""
    for p in parts:
        if isinstance(p, int):
            out += f"[{p}]"
        else:
            out += f".{p}" if out else str(p)
    return out


def locate(root: Any, parts: tuple[Any, ...] | list[Any], *, key: bool = False) -> tuple[int, int]:
    """1-based (line, column) of the node at ``parts`` in a ruamel round-trip tree.

    With ``key=True`` and a mapping key as the last part, the position of the key
    itself (for "unknown key" errors) rather than of its value.  Falls back to the
    nearest located ancestor when a node carries no position (plain scalars do not;
    their parent mapping or sequence does), and to line 1 for trees without
    positions (JSON).
    """
    line, col = 1, 1
    node = root
    last = len(parts) - 1
    for n, p in enumerate(parts):
        lc = getattr(node, "lc", None)
        try:
            if lc is not None:
                if isinstance(p, int) and isinstance(node, list):
                    pos = lc.item(p)
                elif not isinstance(node, dict) or p not in node:
                    pos = None
                elif key and n == last:
                    pos = lc.key(p)
                else:
                    pos = lc.value(p)
                if pos is not None:
                    line, col = pos[0] + 1, pos[1] + 1
            node = node[p]
        except (KeyError, IndexError, TypeError, AttributeError):
            break
    return line, col
