"""A cache, across processes, of the parsed YAML trees of the bundled spec.

Parsing YAML with positions (ruamel's round-trip loader, pure Python) is most of what a
short command such as ``motionchart diagram`` spends its time on.  The trees of the
project's own files (the bundled spec, the bundled conformance systems, the scenarios
of a checkout) are therefore kept on disk, as JSON, keyed by the SHA-256 of the file's
bytes (and of the ruamel version and this format): a changed file simply misses, and any
file with the same bytes as a kept one (a copy of the spec, as a user makes to change
one file) is read from that entry.  Only the project's own files are stored.

What is kept is what the loader reads: mappings and sequences with their line/column
positions (``lc``), string keys, and scalars as plain ``str``/``int``/``float``/``bool``/
``None``.  Only trees that parsed cleanly are stored.  The cache is JSON, never code:
reading it cannot run anything, and an unreadable or malformed entry is a miss.

Location: ``$MOTIONCHART_CACHE_DIR``, else ``$XDG_CACHE_HOME/motionchart``, else
``~/.cache/motionchart``; ``MOTIONCHART_CACHE=0`` turns it off.  At most
:data:`MAX_ENTRIES` entries are kept (the oldest are removed).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import ruamel.yaml
from ruamel.yaml.comments import CommentedMap, CommentedSeq

FORMAT = "motionchart-tree/1"
MAX_ENTRIES = 1000
SUBDIR = "trees"


def cache_dir() -> Path | None:
    if os.environ.get("MOTIONCHART_CACHE", "1") in ("0", "false", "no", "off"):
        return None
    explicit = os.environ.get("MOTIONCHART_CACHE_DIR")
    if explicit:
        return Path(explicit) / SUBDIR
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "motionchart" / SUBDIR


def _key(raw: bytes) -> str:
    h = hashlib.sha256()
    h.update(f"{FORMAT}\0{ruamel.yaml.__version__}\0".encode())
    h.update(raw)
    return h.hexdigest()


def _encode(node: Any) -> Any:
    if isinstance(node, CommentedMap):
        items = list(node.items())
        data = node.lc.data or {}
        return {"m": [[str(k), _encode(v)] for k, v in items], "l": [node.lc.line, node.lc.col],
                "d": [list(data[k]) if k in data else None for k, _v in items]}
    if isinstance(node, CommentedSeq):
        data = node.lc.data or {}
        return {"s": [_encode(v) for v in node], "l": [node.lc.line, node.lc.col],
                "d": [list(data[i]) if i in data else None for i in range(len(node))]}
    if isinstance(node, bool) or node is None:
        return node
    if isinstance(node, int):
        return int(node)
    if isinstance(node, float):
        return float(node)
    if isinstance(node, str):
        return str(node)
    raise TypeError(type(node).__name__)


def _decode(node: Any) -> Any:
    if isinstance(node, dict):
        if "m" in node:
            m = CommentedMap()
            for (k, v), pos in zip(node["m"], node["d"], strict=True):
                m[k] = _decode(v)
                if pos is not None:
                    m.lc.add_kv_line_col(k, list(pos))
            m.lc.line, m.lc.col = node["l"]
            return m
        s = CommentedSeq(_decode(v) for v in node["s"])
        for i, pos in enumerate(node["d"]):
            if pos is not None:
                s.lc.add_idx_line_col(i, list(pos))
        s.lc.line, s.lc.col = node["l"]
        return s
    if isinstance(node, list):
        raise ValueError("bare list in a cached tree")
    return node


def load(raw: bytes) -> Any | None:
    """The cached tree of a file with these bytes, or None (no cache, a miss, a bad entry)."""
    folder = cache_dir()
    if folder is None:
        return None
    try:
        text = (folder / f"{_key(raw)}.json").read_text(encoding="utf-8")
        doc = json.loads(text)
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            return None
        return _decode(doc["tree"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def store(raw: bytes, tree: Any) -> None:
    """Keep the tree of a file that parsed cleanly (best effort: any failure is ignored)."""
    folder = cache_dir()
    if folder is None:
        return
    try:
        payload = json.dumps({"format": FORMAT, "tree": _encode(tree)}, separators=(",", ":"))
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".json")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(payload)
        os.replace(tmp, folder / f"{_key(raw)}.json")
        entries = sorted(folder.glob("*.json"), key=lambda p: p.stat().st_mtime)
        for old in entries[: max(len(entries) - MAX_ENTRIES, 0)]:
            with contextlib.suppress(OSError):
                old.unlink()
    except (OSError, TypeError, ValueError):
        return


# --------------------------------------------------------------------------- valid documents
#
# Checking a file against its JSON schema (pure-Python jsonschema) is the other large cost
# of loading the spec.  A document found valid is remembered as an empty file named by the
# SHA-256 of (this format, the jsonschema version, the schema, the document), all as
# canonical JSON: a marker holds no data, so reading one can only skip a check that was
# passed by exactly these bytes before.

VALID_SUBDIR = "valid"
MAX_VALID = 2000


@functools.cache
def _jsonschema_version() -> str:
    from importlib import metadata

    try:
        return metadata.version("jsonschema")
    except metadata.PackageNotFoundError:  # pragma: no cover - jsonschema is a dependency
        return ""


def _valid_marker(schema_text: str, document_text: str) -> Path | None:
    folder = cache_dir()
    if folder is None:
        return None
    h = hashlib.sha256()
    h.update(f"{FORMAT}\0{_jsonschema_version()}\0{len(schema_text)}\0".encode())
    h.update(schema_text.encode())
    h.update(b"\0")
    h.update(document_text.encode())
    return folder.parent / VALID_SUBDIR / h.hexdigest()


def known_valid(schema_text: str, document_text: str) -> bool:
    """Whether this document (canonical JSON) was found valid against this schema before."""
    marker = _valid_marker(schema_text, document_text)
    try:
        return marker is not None and marker.is_file()
    except OSError:
        return False


def remember_valid(schema_text: str, document_text: str) -> None:
    """Remember a document found valid (best effort: any failure is ignored)."""
    marker = _valid_marker(schema_text, document_text)
    if marker is None:
        return
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
        entries = list(marker.parent.iterdir())
        if len(entries) > MAX_VALID:
            entries.sort(key=lambda p: p.stat().st_mtime)
            for old in entries[: len(entries) - MAX_VALID]:
                with contextlib.suppress(OSError):
                    old.unlink()
    except OSError:
        return


__all__ = ["FORMAT", "MAX_ENTRIES", "MAX_VALID", "cache_dir", "known_valid", "load", "remember_valid", "store"]
