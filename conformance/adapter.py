"""The reference adapter: the project's own engine served over the conformance protocol.

Pipeline position: :mod:`conformance.session` -> **conformance.adapter** ->
``motionchart adapter`` (JSON Lines on stdin/stdout, ``docs/conformance.md``) and, in
process, :mod:`conformance.runner` and :mod:`conformance.mutation`.

:class:`ReferenceAdapter` answers one message at a time (:meth:`handle`), so the same
code serves a pipe and an in-process run.  Every answer is one JSON object; a request it
cannot serve gets an ``error`` answer with the reason, never a traceback.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from typing import IO, Any

from conformance.schemas import PROTOCOL
from conformance.session import Session, SetupError
from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.expr import EvalError


def _version() -> str:
    import importlib.metadata
    try:
        return importlib.metadata.version("motionchart")
    except importlib.metadata.PackageNotFoundError:
        return "0+unknown"


class ReferenceAdapter:
    """Answers protocol messages with the engine (or another axis back-end) on ``spec``."""

    def __init__(self, spec: ir.Spec, *, backend: Callable[..., Any] = AxisInstance, name: str = "motionchart") -> None:
        self.spec = spec
        self.backend = backend
        self.name = name
        self.session: Session | None = None

    def supports(self) -> dict[str, Any]:
        families = [c.id for c in self.spec.charts if any(c.id in i.charts for i in self.spec.instructions)]
        return {
            "axis_families": families,
            "instructions": list(self.spec.mnemonics()),
            "observables": {"*": ["*"]},
            "features": ["prescan", "events", "operands"],
        }

    def handle(self, msg: Any) -> dict[str, Any] | None:
        """The answer to one message; None after ``bye`` (then the adapter exits)."""
        if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
            return {"type": "error", "message": "expected a JSON object with a string `type`"}
        kind = msg["type"]
        try:
            if kind == "hello":
                if msg.get("protocol") != PROTOCOL:
                    return {"type": "error", "message": f"unsupported protocol {msg.get('protocol')!r}; this adapter speaks {PROTOCOL}"}
                return {"type": "hello", "protocol": PROTOCOL,
                        "implementation": {"name": self.name, "version": _version()}, "supports": self.supports()}
            if kind == "reset":
                self.session = Session(self.spec, msg["setup"], backend=self.backend)
                return {"type": "ready", "observations": self.session.observe()}
            if kind == "scan":
                if self.session is None:
                    return {"type": "error", "message": "scan before reset"}
                obs = self.session.scan(msg["inputs"])
                return {"type": "observations", "index": msg.get("index", 0), "observations": obs}
            if kind == "bye":
                return None
        except (SetupError, EvalError, KeyError, TypeError, ValueError, AttributeError) as exc:
            detail = f"missing field {exc}" if isinstance(exc, KeyError) else str(exc)
            return {"type": "error", "message": f"{kind}: {detail}"}
        except RuntimeError as exc:  # the engine refused to go on (e.g. an eventless loop of a mutant)
            return {"type": "error", "message": f"{kind}: {type(exc).__name__}: {exc}"}
        return {"type": "error", "message": f"unknown message type {kind!r}"}


def serve(spec: ir.Spec, stdin: IO[str] | None = None, stdout: IO[str] | None = None) -> int:
    """Read JSON Lines from ``stdin`` until ``bye`` or end of input, answer each on ``stdout``."""
    inp = stdin or sys.stdin
    out = stdout or sys.stdout
    adapter = ReferenceAdapter(spec)
    for line in inp:
        line = line.strip()
        if not line:
            continue
        try:
            msg = json.loads(line)
        except (json.JSONDecodeError, RecursionError) as exc:
            answer: dict[str, Any] | None = {"type": "error", "message": f"not JSON: {exc}"}
        else:
            answer = adapter.handle(msg)
        if answer is None:
            out.write(json.dumps({"type": "bye"}) + "\n")
            out.flush()
            return 0
        out.write(json.dumps(answer, allow_nan=True, separators=(",", ":")) + "\n")
        out.flush()
    return 0
