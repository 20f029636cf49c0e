"""The conformance runner: drive an implementation through every vector and give a verdict per vector.

Pipeline position: vectors (:mod:`conformance.vectors`) + an adapter (any program that
speaks the protocol of ``docs/conformance.md`` on stdin/stdout) -> **conformance.runner**
-> ``motionchart conform``: verdicts, a summary, JSON and JUnit XML.

Verdicts: ``pass``; ``fail`` (the first scan and field that differ, expected vs actual);
``error`` (the adapter answered with an error, broke the protocol, printed something
that is not a JSON object, answered too much, or exited); ``timeout`` (no answer within
the per-message time-out, or the vector took longer than the per-vector time-out);
``skipped`` (the vector needs an axis family, instruction, event or feature the adapter
did not declare in ``hello``).  With a known-failures file a listed vector that fails,
errs or times out is ``xfail`` (expected) and one that passes is ``xpass``, which is
unexpected, as with pytest's ``xfail_strict``.

Robustness: the adapter runs as a child process whose output is read through a
bounded, non-blocking line reader (a line longer than ``max_line`` bytes is an error,
so a flood cannot exhaust memory); stderr is drained into a bounded tail; after an
error or a time-out the adapter is killed and started again for the next vector; if it
cannot even answer ``hello`` twice in a row, the remaining vectors are errors without
further attempts.  Every path ends in bounded time.
"""

from __future__ import annotations

import contextlib
import fnmatch
import json
import math
import os
import selectors
import shlex
import subprocess
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from conformance.schemas import PROTOCOL
from statecharts.diagnostics import Diagnostic, InputError

DEFAULT_MESSAGE_TIMEOUT = 10.0
DEFAULT_VECTOR_TIMEOUT = 120.0
DEFAULT_STARTUP_TIMEOUT = 60.0
DEFAULT_MAX_LINE = 4 * 1024 * 1024
STDERR_TAIL = 4096
#: how long the reason of an exit waits for the adapter's last words on stderr, seconds
STDERR_GRACE = 2.0


class ProtocolError(Exception):
    """The adapter broke the protocol (the vector is an error)."""


class AdapterTimeout(Exception):
    """No answer in time."""


class AdapterExited(Exception):
    """The adapter process ended."""


# --------------------------------------------------------------------------- transports


class Transport:
    """Sends one message and returns the one answer (a dict)."""

    def request(self, msg: Mapping[str, Any], timeout: float) -> dict[str, Any]:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def describe_exit(self) -> str:
        return ""


class ProcessTransport(Transport):
    """An adapter child process speaking JSON Lines, read with a bounded line reader."""

    def __init__(self, command: str, *, max_line: int = DEFAULT_MAX_LINE, cwd: str | None = None) -> None:
        self.command = command
        self.max_line = max_line
        argv = shlex.split(command)
        if not argv:
            raise ValueError("empty adapter command")
        self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     cwd=cwd, start_new_session=True)
        assert self.proc.stdout is not None and self.proc.stderr is not None
        self.fd = self.proc.stdout.fileno()
        os.set_blocking(self.fd, False)
        self.buf = bytearray()
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.fd, selectors.EVENT_READ)
        self.stderr_tail = bytearray()
        self._drain = threading.Thread(target=self._drain_stderr, daemon=True)
        self._drain.start()

    def _drain_stderr(self) -> None:
        assert self.proc.stderr is not None
        try:
            while True:
                chunk = self.proc.stderr.read1(65536) if hasattr(self.proc.stderr, "read1") else self.proc.stderr.read(65536)
                if not chunk:
                    return
                self.stderr_tail += chunk
                if len(self.stderr_tail) > STDERR_TAIL:
                    del self.stderr_tail[:-STDERR_TAIL]
        except (OSError, ValueError):
            return

    def _send(self, msg: Mapping[str, Any]) -> None:
        assert self.proc.stdin is not None
        data = (json.dumps(msg, separators=(",", ":"), allow_nan=False) + "\n").encode()
        try:
            self.proc.stdin.write(data)
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError, ValueError):
            self._reap()
            raise AdapterExited(self.describe_exit() or "the adapter closed its input") from None

    def _line(self, deadline: float) -> bytes:
        while True:
            nl = self.buf.find(b"\n")
            if nl >= 0:
                line = bytes(self.buf[:nl])
                del self.buf[:nl + 1]
                if len(line) > self.max_line:
                    raise ProtocolError(f"answer longer than {self.max_line:,} bytes")
                return line
            if len(self.buf) > self.max_line:
                raise ProtocolError(f"answer longer than {self.max_line:,} bytes without a line end")
            left = deadline - time.monotonic()
            if left <= 0:
                raise AdapterTimeout("no answer")
            if not self.sel.select(timeout=left):
                continue
            try:
                chunk = os.read(self.fd, 1 << 16)
            except BlockingIOError:
                continue
            except OSError:
                chunk = b""
            if not chunk:
                if self.buf:
                    line = bytes(self.buf)
                    self.buf.clear()
                    return line
                self._reap()
                raise AdapterExited(self.describe_exit())
            self.buf += chunk

    def _reap(self) -> None:
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=1.0)

    def describe_exit(self) -> str:
        code = self.proc.poll()
        if code is not None:
            # the process is gone: its last words reach the tail when the drain reads the
            # pipe's end (bounded: a child of the adapter may hold the pipe open)
            self._drain.join(timeout=STDERR_GRACE)
        tail = bytes(self.stderr_tail).decode("utf-8", "replace").strip().splitlines()[-3:]
        what = "the adapter exited" if code is None or code >= 0 else f"the adapter was killed by signal {-code}"
        if code is not None and code >= 0:
            what += f" with status {code}"
        if tail:
            what += "; its last words on stderr: " + " | ".join(t[:200] for t in tail)
        return what

    def request(self, msg: Mapping[str, Any], timeout: float) -> dict[str, Any]:
        self._send(msg)
        deadline = time.monotonic() + timeout
        while True:
            line = self._line(deadline).strip()
            if not line:
                continue
            try:
                answer = json.loads(line)
            except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
                raise ProtocolError(f"answer is not JSON: {line[:80]!r}") from None
            if not isinstance(answer, dict) or not isinstance(answer.get("type"), str):
                raise ProtocolError(f"answer is not a JSON object with a `type`: {line[:80]!r}")
            return answer

    def close(self, graceful: bool = True) -> None:
        if graceful and self.proc.poll() is None:
            try:
                self._send({"type": "bye"})
                self.proc.wait(timeout=1.0)
            except (AdapterExited, subprocess.TimeoutExpired):
                pass
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, 9)
            except (ProcessLookupError, PermissionError):
                self.proc.kill()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(timeout=5.0)
        self.sel.close()
        for stream in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            try:
                if stream is not None:
                    stream.close()
            except OSError:
                pass
        self._drain.join(timeout=1.0)


class InProcessTransport(Transport):
    """An object with ``handle(message) -> answer`` (the reference adapter), with JSON round trips."""

    def __init__(self, adapter: Any) -> None:
        self.adapter = adapter

    def request(self, msg: Mapping[str, Any], timeout: float) -> dict[str, Any]:
        answer = self.adapter.handle(json.loads(json.dumps(msg)))
        if answer is None:
            return {"type": "bye"}
        result: dict[str, Any] = json.loads(json.dumps(answer))
        return result


# --------------------------------------------------------------------------- verdicts


@dataclass
class Verdict:
    id: str
    verdict: str  # pass | fail | error | timeout | skipped | xfail | xpass
    detail: str = ""
    scan: int | None = None
    label: str = ""
    object: str | None = None
    field: str | None = None
    expected: Any = None
    actual: Any = None
    seconds: float = 0.0
    reason: str = ""  # known-failure reason

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"id": self.id, "verdict": self.verdict, "detail": self.detail,
                               "seconds": round(self.seconds, 3)}
        if self.scan is not None or self.object is not None:
            out.update({"scan": self.scan, "label": self.label, "object": self.object, "field": self.field,
                        "expected": self.expected, "actual": self.actual})
        if self.reason:
            out["known_failure"] = self.reason
        return out

    def line(self) -> str:
        head = {"pass": "PASS", "fail": "FAIL", "error": "ERROR", "timeout": "TIMEOUT", "skipped": "SKIP",
                "xfail": "XFAIL", "xpass": "XPASS"}[self.verdict]
        text = f"{head} {self.id}"
        if self.detail:
            text += f": {self.detail}"
        if self.reason and self.verdict in ("xfail", "xpass"):
            text += f" [known failure: {self.reason}]"
        return text


UNEXPECTED = ("fail", "error", "timeout", "xpass")


def _same(expected: object, actual: object) -> bool:
    if isinstance(expected, bool) or isinstance(actual, bool):
        return type(expected) is type(actual) and expected == actual
    if isinstance(expected, (int, float)) and isinstance(actual, (int, float)):
        e, a = float(expected), float(actual)
        if math.isnan(e) or math.isnan(a):
            return math.isnan(e) and math.isnan(a)
        return abs(e - a) <= 1e-9 * max(1.0, abs(e))
    return expected == actual


def _spell(value: object) -> str:
    return json.dumps(value)


class Supports:
    """What an adapter declared in ``hello``."""

    def __init__(self, doc: Mapping[str, Any]) -> None:
        self.families = set(doc.get("axis_families", []))
        self.instructions = set(doc.get("instructions", []))
        self.observables: dict[str, set[str]] = {k: set(v) for k, v in dict(doc.get("observables", {})).items()}
        self.events = {k: set(v) for k, v in dict(doc.get("events", {})).items()} if "events" in doc else None
        self.features = set(doc.get("features", [])) if "features" in doc else None

    def unsupported(self, vector: Mapping[str, Any]) -> list[str]:
        req = vector["requires"]
        out = [f"axis family {f}" for f in req["axis_families"] if f not in self.families]
        out += [f"instruction {i}" for i in req["instructions"] if i not in self.instructions]
        if self.events is not None:
            for e in req["events"]:
                fam, ev = e.split(".", 1)
                if fam in self.events and ev not in self.events[fam]:
                    out.append(f"event {e}")
        if self.features is not None:
            out += [f"feature {f}" for f in req["features"] if f not in self.features]
        return out

    def compared(self, kind: str, fld: str) -> bool:
        for key in (kind, "*"):
            fields = self.observables.get(key)
            if fields is not None and ("*" in fields or fld in fields):
                return True
        return False


def first_difference(vector: Mapping[str, Any], supports: Supports, scan: int | None,
                     expected: Mapping[str, Mapping[str, object]], actual: Any) -> Verdict | None:
    """The first expected field (in the vector's order) the actual observations do not match."""
    kinds = {p["tag"]: "tag" for p in vector["setup"]["program"]}
    kinds.update({a["name"]: a["family"] for a in vector["setup"]["axes"]})
    label = "" if scan is None else vector["scans"][scan].get("label", "")
    if not isinstance(actual, dict):
        return Verdict(vector["id"], "error", "observations are not a JSON object", scan=scan, label=label)
    for obj, fields in expected.items():
        kind = kinds.get(obj, "tag")
        for fld, value in fields.items():
            if not supports.compared(kind, fld):
                continue
            got = actual.get(obj)
            have = isinstance(got, dict) and fld in got
            seen = got[fld] if isinstance(got, dict) and have else None
            if not have or not _same(value, seen):
                where = "before the first scan" if scan is None else f"scan {scan}" + (f" ({label})" if label else "")
                shown = _spell(seen) if have else "nothing (field missing)"
                return Verdict(vector["id"], "fail", f"{where}: {obj}.{fld} expected {_spell(value)}, got {shown}",
                               scan=scan, label=label, object=obj, field=fld, expected=value,
                               actual=seen)
    return None


# --------------------------------------------------------------------------- one adapter


class Worker:
    """One adapter (restarted as needed) running vectors one after another."""

    def __init__(self, factory: Callable[[], Transport], *, message_timeout: float, vector_timeout: float,
                 startup_timeout: float = DEFAULT_STARTUP_TIMEOUT) -> None:
        self.factory = factory
        self.startup_timeout = startup_timeout
        self.message_timeout = message_timeout
        self.vector_timeout = vector_timeout
        self.transport: Transport | None = None
        self.hello: dict[str, Any] | None = None
        self.supports: Supports | None = None
        self.failed_starts = 0
        self.start_problem = ""
        self.stopped = threading.Event()

    def _start(self) -> bool:
        if self.failed_starts >= 2:
            return False
        try:
            t = self.factory()
        except (OSError, ValueError) as exc:
            self.failed_starts = 2
            self.start_problem = f"the adapter cannot be started: {exc}"
            return False
        try:
            answer = t.request({"type": "hello", "protocol": PROTOCOL}, self.startup_timeout)
            if answer.get("type") != "hello" or answer.get("protocol") != PROTOCOL or not isinstance(answer.get("supports"), dict):
                raise ProtocolError(f"expected a hello answer with protocol {PROTOCOL} and `supports`, got {json.dumps(answer)[:120]}")
        except (ProtocolError, AdapterTimeout, AdapterExited) as exc:
            why = t.describe_exit() if isinstance(exc, AdapterExited) else str(exc)
            self._kill(t)
            self.failed_starts += 1
            self.start_problem = f"the adapter did not answer hello: {why or type(exc).__name__}"
            return False
        self.failed_starts = 0
        self.transport = t
        self.hello = answer
        self.supports = Supports(answer["supports"])
        return True

    def _kill(self, t: Transport) -> None:
        if isinstance(t, ProcessTransport):
            t.close(graceful=False)
        else:
            t.close()

    def restart(self) -> None:
        if self.transport is not None:
            self._kill(self.transport)
            self.transport = None

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()
            self.transport = None

    def ensure(self) -> bool:
        while self.transport is None:
            if not self._start() and self.failed_starts >= 2:
                return False
        return True

    def run(self, vector: Mapping[str, Any]) -> Verdict:
        start = time.monotonic()
        v = self._run(vector, start)
        v.seconds = time.monotonic() - start
        return v

    def _run(self, vector: Mapping[str, Any], start: float) -> Verdict:
        vid = vector["id"]
        if not self.ensure():
            return Verdict(vid, "error", self.start_problem)
        assert self.transport is not None and self.supports is not None
        missing = self.supports.unsupported(vector)
        if missing:
            return Verdict(vid, "skipped", f"unsupported: {', '.join(missing)}")
        deadline = start + self.vector_timeout
        scan: int | None = None

        def ask(msg: Mapping[str, Any], expect: str) -> dict[str, Any]:
            assert self.transport is not None
            left = deadline - time.monotonic()
            if left <= 0:
                raise AdapterTimeout(f"the vector took longer than {self.vector_timeout:g} s")
            per = min(self.message_timeout, left)
            try:
                answer = self.transport.request(msg, per)
            except AdapterTimeout:
                if per < self.message_timeout:
                    raise AdapterTimeout(f"the vector took longer than {self.vector_timeout:g} s") from None
                raise AdapterTimeout(f"no answer to {msg['type']} within {self.message_timeout:g} s") from None
            if answer.get("type") == "error":
                raise _AdapterSaid(str(answer.get("message", "")))
            if answer.get("type") != expect:
                raise ProtocolError(f"expected a {expect!r} answer to {msg['type']}, got {answer.get('type')!r}")
            if expect == "observations" and answer.get("index", msg.get("index")) != msg.get("index"):
                raise ProtocolError(f"answer for scan {answer.get('index')!r} to scan {msg.get('index')}")
            return answer

        try:
            ready = ask({"type": "reset", "vector": vid, "setup": vector["setup"]}, "ready")
            diff = first_difference(vector, self.supports, None, vector["initial"], ready.get("observations"))
            if diff is not None:
                return diff
            for k, entry in enumerate(vector["scans"]):
                scan = k
                answer = ask({"type": "scan", "index": k, "inputs": entry["inputs"]}, "observations")
                diff = first_difference(vector, self.supports, k, entry["expect"], answer.get("observations"))
                if diff is not None:
                    return diff
        except _AdapterSaid as exc:
            at = "reset" if scan is None else f"scan {scan}"
            return Verdict(vid, "error", f"the adapter answered an error at {at}: {str(exc)[:300]}", scan=scan)
        except AdapterTimeout as exc:
            self.restart()
            at = "reset" if scan is None else f"scan {scan}"
            return Verdict(vid, "timeout", f"{exc} (at {at}); the adapter was restarted", scan=scan)
        except ProtocolError as exc:
            self.restart()
            at = "reset" if scan is None else f"scan {scan}"
            return Verdict(vid, "error", f"protocol error at {at}: {exc}; the adapter was restarted", scan=scan)
        except AdapterExited as exc:
            t = self.transport
            why = (t.describe_exit() if t is not None else "") or str(exc) or "the adapter exited"
            self.restart()
            at = "reset" if scan is None else f"scan {scan}"
            return Verdict(vid, "error", f"{why} (at {at}); restarting it for the next vector", scan=scan)
        return Verdict(vid, "pass")


class _AdapterSaid(Exception):
    pass


# --------------------------------------------------------------------------- known failures and selection


@dataclass(frozen=True)
class KnownFailure:
    pattern: str
    reason: str
    line: int


def load_known_failures(path: Path) -> list[KnownFailure]:
    """``vector-id-or-glob  reason`` per line; ``#`` starts a comment; a reason is required."""
    errors: list[Diagnostic] = []
    out: list[KnownFailure] = []
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError([Diagnostic(str(path), 1, 1, "", f"cannot read the known-failures file: {exc}")]) from None
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split(None, 1)
        if len(parts) < 2 or not parts[1].strip():
            errors.append(Diagnostic(str(path), n, 1, "", f"expected `VECTOR-ID REASON`, got {line!r} (a reason is required)"))
            continue
        out.append(KnownFailure(parts[0], parts[1].strip(), n))
    if errors:
        raise InputError(errors)
    return out


def _matches(pattern: str, vid: str) -> bool:
    if any(ch in pattern for ch in "*?["):
        return fnmatch.fnmatchcase(vid, pattern)
    return pattern == vid


def select(vectors: Sequence[Mapping[str, Any]], only: Sequence[str]) -> list[Mapping[str, Any]]:
    if not only:
        return list(vectors)
    out = []
    for v in vectors:
        if any(_matches(p, v["id"]) if any(ch in p for ch in "*?[") else p in v["id"] for p in only):
            out.append(v)
    return out


# --------------------------------------------------------------------------- the run


@dataclass
class RunResult:
    verdicts: list[Verdict]
    implementation: dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0
    problems: list[str] = field(default_factory=list)  # stale known failures and the like

    def counts(self) -> dict[str, int]:
        out = dict.fromkeys(("pass", "fail", "error", "timeout", "skipped", "xfail", "xpass"), 0)
        for v in self.verdicts:
            out[v.verdict] += 1
        return out

    @property
    def ok(self) -> bool:
        return not self.problems and not any(v.verdict in UNEXPECTED for v in self.verdicts)

    def summary(self) -> str:
        c = self.counts()
        parts = [f"{c['pass']} passed", f"{c['fail']} failed", f"{c['error']} errors", f"{c['timeout']} timed out",
                 f"{c['skipped']} skipped"]
        if c["xfail"] or c["xpass"]:
            parts += [f"{c['xfail']} known failures", f"{c['xpass']} unexpectedly passed"]
        return f"vectors: {len(self.verdicts)} run: " + ", ".join(parts) + f" in {self.seconds:.1f} s"

    def as_dict(self) -> dict[str, Any]:
        return {"implementation": self.implementation, "summary": self.counts(), "ok": self.ok,
                "seconds": round(self.seconds, 3), "problems": self.problems,
                "results": [v.as_dict() for v in self.verdicts]}


def run(vectors: Sequence[Mapping[str, Any]], factory: Callable[[], Transport], *, jobs: int = 1,
        known: Sequence[KnownFailure] = (), message_timeout: float = DEFAULT_MESSAGE_TIMEOUT,
        vector_timeout: float = DEFAULT_VECTOR_TIMEOUT, startup_timeout: float = DEFAULT_STARTUP_TIMEOUT,
        on_verdict: Callable[[Verdict], None] | None = None,
        all_ids: Iterable[str] | None = None) -> RunResult:
    """Run every vector; ``jobs`` adapters work in parallel, each on the next vector free."""
    t0 = time.monotonic()
    problems = []
    ids = list(all_ids) if all_ids is not None else [v["id"] for v in vectors]
    for k in known:
        if not any(_matches(k.pattern, i) for i in ids):
            problems.append(f"known failure {k.pattern!r} (line {k.line}) names no vector of the suite")
    results: list[Verdict | None] = [None] * len(vectors)
    lock = threading.Lock()
    next_index = [0]
    implementation: dict[str, Any] = {}

    def work() -> None:
        w = Worker(factory, message_timeout=message_timeout, vector_timeout=vector_timeout,
                   startup_timeout=startup_timeout)
        try:
            while True:
                with lock:
                    i = next_index[0]
                    if i >= len(vectors):
                        return
                    next_index[0] += 1
                v = w.run(vectors[i])
                if w.hello is not None and not implementation:
                    implementation.update(w.hello.get("implementation") or {})
                kf = next((k for k in known if _matches(k.pattern, v.id)), None)
                if kf is not None:
                    v.reason = kf.reason
                    if v.verdict in ("fail", "error", "timeout"):
                        v.detail = f"{v.verdict}: {v.detail}"
                        v.verdict = "xfail"
                    elif v.verdict == "pass":
                        v.verdict = "xpass"
                        v.detail = "listed as a known failure but passed; remove it from the list"
                with lock:
                    results[i] = v
                    if on_verdict is not None:
                        on_verdict(v)
        finally:
            w.close()

    threads = [threading.Thread(target=work, daemon=True) for _ in range(max(1, jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    done = [r for r in results if r is not None]
    return RunResult(done, implementation, time.monotonic() - t0, problems)


def junit_xml(result: RunResult, vectors: Sequence[Mapping[str, Any]], name: str = "motionchart-conformance") -> bytes:
    """JUnit XML (one testcase per vector) that CI systems show as test results."""
    import xml.etree.ElementTree as ET
    kinds = {v["id"]: v.get("kind", "vector") for v in vectors}
    c = result.counts()
    suite = ET.Element("testsuite", {
        "name": name, "tests": str(len(result.verdicts)), "failures": str(c["fail"]),
        "errors": str(c["error"] + c["timeout"] + c["xpass"]), "skipped": str(c["skipped"] + c["xfail"]),
        "time": f"{result.seconds:.3f}"})
    for v in result.verdicts:
        case = ET.SubElement(suite, "testcase", {"classname": f"conformance.{kinds.get(v.id, 'vector')}",
                                                 "name": v.id, "time": f"{v.seconds:.3f}"})
        if v.verdict == "fail":
            ET.SubElement(case, "failure", {"message": v.detail[:500], "type": "mismatch"}).text = v.detail
        elif v.verdict in ("error", "timeout", "xpass"):
            ET.SubElement(case, "error", {"message": v.detail[:500], "type": v.verdict}).text = v.detail
        elif v.verdict in ("skipped", "xfail"):
            msg = v.detail if v.verdict == "skipped" else f"known failure: {v.reason} ({v.detail})"
            ET.SubElement(case, "skipped", {"message": msg[:500]})
    root = ET.Element("testsuites")
    root.append(suite)
    data: bytes = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    return data
