"""Project rules that ruff and mypy do not check (run by ``make lint``).

* A ``# type: ignore[code]`` or ``# noqa: CODE`` comment names its codes and gives a
  one-line reason as a further comment on the same line::

      value = f(x)  # type: ignore[arg-type]  # f is untyped upstream

  A ``type: ignore`` in a file mypy does not check (see ``[tool.mypy] files``) is dead
  and is refused too.
* No module uses another module's private names: no ``from m import _name`` and no
  ``m._name`` on an imported project module. A helper two modules share is public in
  one of them.

Usage: ``python tools/lint_rules.py [ROOT]``; prints ``file:line: problem`` for each
finding and exits 1 when there is one.
"""

from __future__ import annotations

import ast
import io
import re
import sys
import tokenize
import tomllib
from collections.abc import Iterator
from pathlib import Path

#: Top-level folders that hold no project source.
SKIPPED = {".git", ".venv", "build", "generated", "node_modules", ".mypy_cache", ".ruff_cache", ".pytest_cache",
           ".hypothesis", ".bench", ".deep"}
#: Top-level packages and folders of the project: ``m._name`` on one of their modules is refused.
PROJECT = {"statecharts", "checker", "conformance", "motionchart", "motionchart_spec", "tests", "tools",
           "benchmarks", "examples"}

_TYPE_IGNORE = re.compile(r"#\s*type:\s*ignore(?P<codes>\[[^\]]*\])?(?P<rest>.*)$")
_NOQA = re.compile(r"#\s*noqa(?P<codes>:\s*[A-Z]+[0-9]+(?:\s*,\s*[A-Z]+[0-9]+)*)?(?P<rest>.*)$", re.IGNORECASE)
#: The reason: a further ``#`` comment of a few characters at least.
_REASON = re.compile(r"^\s*#\s*\w\S*(\s+\S+)*\s*$")


def python_files(root: Path) -> Iterator[Path]:
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        if rel.parts[0] in SKIPPED or rel.parts[0].endswith(".egg-info") or "__pycache__" in rel.parts:
            continue
        yield path


def type_checked(root: Path) -> list[str]:
    """The files and folders ``[tool.mypy] files`` names (relative to ``root``)."""
    config = root / "pyproject.toml"
    if not config.is_file():
        return []
    with config.open("rb") as f:
        files = tomllib.load(f).get("tool", {}).get("mypy", {}).get("files", [])
    return [str(x).rstrip("/") for x in ([files] if isinstance(files, str) else files)]


def _comments(text: str) -> Iterator[tuple[int, str]]:
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.COMMENT:
                yield tok.start[0], tok.string
    except (tokenize.TokenError, SyntaxError):
        return


def pragma_problems(rel: str, text: str, *, checked: bool) -> list[str]:
    """``type: ignore`` and ``noqa`` comments of one file without codes or a reason."""
    out = []
    for line, comment in _comments(text):
        m = _TYPE_IGNORE.search(comment)
        if m is not None:
            if not checked:
                out.append(f"{rel}:{line}: `type: ignore` in a file mypy does not check; remove it")
            elif not m["codes"]:
                out.append(f"{rel}:{line}: `type: ignore` without error codes; write `# type: ignore[code]  # reason`")
            elif not _REASON.match(m["rest"]):
                out.append(f"{rel}:{line}: `type: ignore{m['codes']}` without a reason; add `  # why` on the same line")
            continue
        m = _NOQA.search(comment)
        if m is not None:
            if not m["codes"]:
                out.append(f"{rel}:{line}: `noqa` without rule codes; write `# noqa: CODE  # reason`")
            elif not _REASON.match(m["rest"]):
                out.append(f"{rel}:{line}: `noqa{m['codes']}` without a reason; add `  # why` on the same line")
    return out


def _is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_use_problems(rel: str, text: str, project: set[str] = PROJECT) -> list[str]:
    """Uses of another module's private names in one file."""
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return []  # ruff reports the syntax error
    out = []
    modules: set[str] = set()  # local names bound to project modules
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in project:
                    modules.add(a.asname or a.name.split(".")[0])
                if any(_is_private(p) for p in a.name.split(".")[1:]):
                    out.append(f"{rel}:{node.lineno}: `import {a.name}` imports a private module")
        elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
            source = "." * node.level + (node.module or "")
            for a in node.names:
                if _is_private(a.name):
                    out.append(f"{rel}:{node.lineno}: `from {source} import {a.name}` uses a private name of "
                               f"another module; make it public in one module")
                elif node.level == 0 and (node.module or "").split(".")[0] in project:
                    modules.add(a.asname or a.name)  # may be a module (`from statecharts import loader`)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and _is_private(node.attr) and isinstance(node.value, ast.Name)
                and node.value.id in modules):
            out.append(f"{rel}:{node.lineno}: `{node.value.id}.{node.attr}` uses a private name of another module; "
                       f"make it public in one module")
    return out


def problems(root: Path) -> list[str]:
    checked = type_checked(root)
    out = []
    for path in python_files(root):
        rel = path.relative_to(root).as_posix()
        text = path.read_text(encoding="utf-8", errors="replace")
        is_checked = any(rel == c or rel.startswith(c + "/") for c in checked)
        out += pragma_problems(rel, text, checked=is_checked)
        out += private_use_problems(rel, text)
    return out


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    root = Path(args[0]) if args else Path(__file__).resolve().parents[1]
    found = problems(root)
    for p in found:
        print(p)
    if found:
        print(f"{len(found)} finding(s) of tools/lint_rules.py (see its docstring for the rules)")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
