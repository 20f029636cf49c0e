"""Structural fuzzing of every input format: a clean, located error or success, nothing else.

Hypothesis strategies mutate the *parsed* bundled inputs (the spec files, the scenarios
under ``scenarios/`` and ``examples/``, the system and property files): delete a key,
change a value's type, duplicate a list element, swap a reference for another name of
the same file, inject huge or non-finite numbers, add eventless cycles to a chart,
replace a string by a hostile expression.  Each mutant goes through the public entry
points (:func:`statecharts.loader.load_spec_documents`,
:func:`statecharts.scenario.load_scenario_document` and ``run_scenario``,
:func:`checker.system.load_system`, :func:`checker.properties.load_properties`) in
this process, under a watchdog (``SIGPROF``: :data:`TIME_LIMIT` CPU-seconds per input,
so a loaded machine does not make an input look hung).
The outcome of each is classified:

* **clean error**: an :class:`~statecharts.diagnostics.InputError` (or the checker's
  ``ModelError``) whose every diagnostic names a file and a line;
* **success**: the input loaded (and, for a scenario or a spec that loaded, ran);
* **other**: any other exception, an error without a location, or the time limit
  (each is printed with the mutation that caused it).

Run as a program it prints the figures ``make deep`` quotes::

    python tests/fuzzing.py --specs 10000 --scenarios 10000 [--memory-gib 1]

``--memory-gib`` caps the address space of the process (``resource.RLIMIT_AS``) at that
much above what it uses after loading, so an input that needs more fails with
``MemoryError`` and counts as "other".  ``tests/test_fuzz.py`` runs a small sample of
the same harness under ``make test``.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import math
import os
import signal
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from checker.model import ModelError
from checker.properties import load_properties, properties_dir
from checker.system import load_system, systems_dir
from statecharts import ir
from statecharts.diagnostics import InputError
from statecharts.loader import load_spec_documents, plain_data, read_document, spec_files
from statecharts.scenario import load_scenario_document, run_scenario, scenario_files

#: CPU-seconds one input may take (load and run) before it counts as a hang.
TIME_LIMIT = 10.0

HOSTILE_EXPRESSIONS = (
    "__import__('os').system('true')", "().__class__.__bases__[0].__subclasses__()", "lambda: 1",
    "[x for x in (1, 2)]", "f'{ServoFault}'", "(y := 1)", "'a' * 10**6", "max([0] * 1000000)",
    "'ab' * 9999 + 'ab' * 9999", "9" * 5000, "1 / 0", "x" * 3000, "(" * 200 + "1" + ")" * 200,
    "𝐒ervoFault", "ＳervoFault", "True", "not True", "ServoFault ** 99", "open('/etc/passwd')",
    "ServoFault.__class__", "1e308 * 1e308 > 0", "-(2**70)", "'%s' % 1", "a if b else",
)
HUGE_NUMBERS: tuple[object, ...] = (
    2**70, -(2**65), 2**31, -(2**31) - 1, 10**400, 1e308, -1e308, math.nan, math.inf, -math.inf, 0, -1,
)


# --------------------------------------------------------------------------- the corpus


def _spec_documents() -> dict[str, Any]:
    docs: dict[str, Any] = {}
    for p in spec_files():
        if p.suffix == ".json" or p.parent.name in ("schema", "systems", "properties"):
            continue
        docs[str(p)] = plain_data(read_document(p, []))
    return docs


def _scenario_documents() -> dict[str, Any]:
    docs: dict[str, Any] = {}
    roots = [ROOT / "scenarios", ROOT / "examples"]
    for p in scenario_files([r for r in roots if r.is_dir()]):
        tree = read_document(p, [])
        if isinstance(tree, dict) and str(tree.get("format", "")).startswith("motionchart-") and "scenario" in str(tree.get("format")):
            docs[str(p)] = plain_data(tree)
    return docs


def _checker_documents(directory: Path) -> dict[str, Any]:
    return {str(p): plain_data(read_document(p, [])) for p in sorted(directory.glob("*.yaml"))}


@dataclass
class Corpus:
    spec_docs: dict[str, Any]
    scenario_docs: dict[str, Any]
    system_docs: dict[str, Any]
    property_docs: dict[str, Any]
    spec: ir.Spec
    probe: Any  # a short bundled scenario, run on every spec mutant that loads


def load_corpus() -> Corpus:
    spec_docs = _spec_documents()
    spec = load_spec_documents(spec_docs)
    scenarios = _scenario_documents()
    probe_name = next(k for k in sorted(scenarios) if k.endswith("exec_rung_false_clears_en.yaml"))
    corpus = Corpus(spec_docs, scenarios, _checker_documents(systems_dir()), _checker_documents(properties_dir()),
                    spec, scenarios[probe_name])
    # warm the caches (the add-on instruction world, the program readers) so that the
    # first input of each kind is not charged with loading them
    for name in sorted(scenarios):
        fmt = str(scenarios[name].get("format", ""))
        if "aoi" in fmt or isinstance(scenarios[name].get("setup", {}).get("program"), (str, dict)):
            with contextlib.suppress(InputError):
                run_scenario(load_scenario_document(name, scenarios[name], spec), spec, keep_rows=False)
    return corpus


# --------------------------------------------------------------------------- mutations


def _paths(tree: Any) -> list[tuple[Any, ...]]:
    """Every node path of a plain tree (iteratively)."""
    out: list[tuple[Any, ...]] = []
    stack: list[tuple[Any, tuple[Any, ...]]] = [(tree, ())]
    while stack:
        node, parts = stack.pop()
        out.append(parts)
        if isinstance(node, dict):
            stack.extend((v, (*parts, k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, (*parts, i)) for i, v in enumerate(node))
    return out


def _strings(tree: Any) -> list[str]:
    out: list[str] = []
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, str):
            out.append(node)
        elif isinstance(node, dict):
            out.extend(k for k in node if isinstance(k, str))
            stack.extend(node.values())
        elif isinstance(node, list):
            stack.extend(node)
    return out


def _get(tree: Any, parts: tuple[Any, ...]) -> Any:
    for p in parts:
        tree = tree[p]
    return tree


OPERATIONS = ("delete", "retype", "duplicate", "swap", "huge", "hostile", "cycle")


def _replacement(draw: st.DrawFn, old: Any, strings: list[str]) -> Any:
    return draw(st.sampled_from([
        None, True, 0, -1, 1.5, "", "x", [], {}, [old], {"x": old}, str(old)[:50],
        *HUGE_NUMBERS[:3], draw(st.sampled_from(strings)) if strings else "y",
    ]))


@st.composite
def mutated(draw: st.DrawFn, tree: Any, *, charts: bool = False) -> tuple[Any, list[str]]:
    """A copy of ``tree`` with one to three structural mutations, and what they were."""
    tree = copy.deepcopy(tree)
    strings = sorted(set(_strings(tree)))[:400]
    done: list[str] = []
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(tree)
        op = draw(st.sampled_from(OPERATIONS))
        if op == "cycle":
            chart = tree.get("chart") if isinstance(tree, dict) else None
            if not (charts and isinstance(chart, dict) and isinstance(chart.get("states"), list)
                    and isinstance(chart.get("transitions"), list)):
                op = "retype"
            else:
                ids = [s.get("id") for s in chart["states"] if isinstance(s, dict)] or ["X"]
                a, b = draw(st.sampled_from(ids)), draw(st.sampled_from(ids))
                guard = draw(st.sampled_from(["True", "not ServoFault", "ServoFault or not ServoFault", "1 == 1"]))
                new = [{"id": "fz1", "from": a, "to": b, "guard": guard, "priority": -9, "source": "MC tests/fuzzing.py"},
                       {"id": "fz2", "from": b, "to": a, "guard": guard, "priority": -9, "source": "MC tests/fuzzing.py"}]
                if draw(st.booleans()):
                    new = [{"id": "fz3", "from": a, "guard": guard, "priority": -9, "source": "MC tests/fuzzing.py",
                            "actions": [draw(st.sampled_from(["ServoFault = not ServoFault", "Moving = not Moving",
                                                              "TestTimer = TestTimer + 1"]))]}]
                chart["transitions"].extend(new)
                done.append(f"cycle {a}<->{b} guard {guard!r}")
                continue
        parts = draw(st.sampled_from(paths))
        if not parts:
            if op in ("retype", "huge"):
                tree = _replacement(draw, tree, strings)
                done.append(f"root -> {tree!r:.60}")
            continue
        parent, key = _get(tree, parts[:-1]), parts[-1]
        old = parent[key]
        if op == "delete":
            del parent[key]
        elif op == "duplicate":
            if isinstance(parent, list):
                parent.insert(key, copy.deepcopy(old))
            elif isinstance(old, list) and old:
                old.append(copy.deepcopy(old[draw(st.integers(0, len(old) - 1))]))
        elif op == "retype":
            parent[key] = _replacement(draw, old, strings)
        elif op == "swap":
            parent[key] = draw(st.sampled_from(strings)) if strings else "y"
        elif op == "huge":
            parent[key] = draw(st.sampled_from(HUGE_NUMBERS))
        elif op == "hostile":
            parent[key] = draw(st.sampled_from(HOSTILE_EXPRESSIONS))
        done.append(f"{op} at {'.'.join(map(str, parts))}")
    return tree, done


# --------------------------------------------------------------------------- running one input


class _Timeout(BaseException):
    """The watchdog fired: the input used more than TIME_LIMIT CPU-seconds."""


@dataclass
class Tally:
    kind: str
    tried: int = 0
    clean: int = 0
    successes: int = 0
    others: list[str] = field(default_factory=list)
    slowest: tuple[float, str] = (0.0, "")

    def line(self) -> str:
        return (f"{self.kind}: tried {self.tried}, clean errors {self.clean}, successes {self.successes}, "
                f"other exceptions {len(self.others)}, slowest case {self.slowest[0]:.2f} s ({self.slowest[1]})")


def _alarm(_signum: int, _frame: FrameType | None) -> None:
    raise _Timeout()


def _located(exc: InputError | ModelError) -> bool:
    ds = exc.diagnostics
    return bool(ds) and all(d.file and d.line >= 1 and d.message for d in ds)


def classify(tally: Tally, what: str, run: Callable[[], object]) -> None:
    """Run one input under the watchdog and count its outcome."""
    tally.tried += 1
    previous = signal.signal(signal.SIGPROF, _alarm)
    start = time.perf_counter()
    signal.setitimer(signal.ITIMER_PROF, TIME_LIMIT)
    outcome = ""
    try:
        run()
        tally.successes += 1
    except (InputError, ModelError) as exc:
        if _located(exc):
            tally.clean += 1
        else:
            outcome = f"unlocated {type(exc).__name__}: {str(exc)[:200]!r}"
    except _Timeout:
        outcome = f"over {TIME_LIMIT} CPU-s"
    except Exception as exc:
        outcome = f"{type(exc).__name__}: {str(exc)[:300]}"
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)
    elapsed = time.perf_counter() - start
    if elapsed > tally.slowest[0]:
        tally.slowest = (elapsed, what[:160])
    if outcome:
        tally.others.append(f"{what}: {outcome}")


def _spec_case(corpus: Corpus, name: str, doc: Any) -> Callable[[], object]:
    def run() -> object:
        docs = dict(corpus.spec_docs)
        docs[name] = doc
        spec = load_spec_documents(docs)
        scenario = load_scenario_document("probe.yaml", corpus.probe, spec)
        return run_scenario(scenario, spec, keep_rows=False)
    return run


def _scenario_case(corpus: Corpus, name: str, doc: Any) -> Callable[[], object]:
    def run() -> object:
        scenario = load_scenario_document(name, doc, corpus.spec)
        return run_scenario(scenario, corpus.spec, keep_rows=False)
    return run


def _file_case(corpus: Corpus, name: str, doc: Any, kind: str, scratch: Path) -> Callable[[], object]:
    def run() -> object:
        path = scratch / Path(name).name
        try:
            text = json.dumps(doc, allow_nan=True)
        except (ValueError, TypeError):
            text = "null"
        path.write_text(text, encoding="utf-8")  # JSON is YAML: the file's own reader parses it
        if kind == "system":
            return load_system(path, corpus.spec)
        return load_properties(corpus.spec, [path])
    return run


# --------------------------------------------------------------------------- driving hypothesis


def _settings(count: int, seed_note: str) -> settings:
    return settings(max_examples=count, deadline=None, database=None, derandomize=True,
                    phases=[Phase.generate], suppress_health_check=list(HealthCheck))


def fuzz(corpus: Corpus, kind: str, count: int, *, progress: bool = False) -> Tally:
    """Feed ``count`` mutants of one kind of input (spec, scenario, system, properties)."""
    tally = Tally(kind)
    docs = {"spec": corpus.spec_docs, "scenario": corpus.scenario_docs, "system": corpus.system_docs,
            "properties": corpus.property_docs}[kind]
    names = sorted(docs)
    scratch = Path(tempfile.mkdtemp(prefix="motionchart-fuzz-"))
    started = time.monotonic()

    @_settings(count, kind)
    @given(st.data())
    def one(data: st.DataObject) -> None:
        name = data.draw(st.sampled_from(names), label="file")
        doc, done = data.draw(mutated(docs[name], charts=kind == "spec"), label="mutation")
        what = f"{Path(name).name}: {'; '.join(done)}"
        if kind == "spec":
            case = _spec_case(corpus, name, doc)
        elif kind == "scenario":
            case = _scenario_case(corpus, name, doc)
        else:
            case = _file_case(corpus, name, doc, kind, scratch)
        classify(tally, what, case)
        if progress and tally.tried % 500 == 0:
            rate = tally.tried / max(1e-9, time.monotonic() - started)
            print(f"  {kind}: {tally.tried}/{count} ({rate:.0f}/s)", file=sys.stderr, flush=True)

    one()
    for p in scratch.iterdir():
        p.unlink()
    scratch.rmdir()
    return tally


def _cap_memory(gib: float) -> None:
    import resource

    with open("/proc/self/status", encoding="ascii") as fh:
        vm = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmSize:"))
    limit = vm + int(gib * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--specs", type=int, default=200)
    parser.add_argument("--scenarios", type=int, default=200)
    parser.add_argument("--systems", type=int, default=0)
    parser.add_argument("--properties", type=int, default=0)
    parser.add_argument("--memory-gib", type=float, default=1.0, help="address space allowed above the baseline")
    parser.add_argument("--show", type=int, default=20, help="print at most this many other exceptions")
    args = parser.parse_args(argv)
    started = time.monotonic()
    corpus = load_corpus()
    if args.memory_gib > 0 and os.path.exists("/proc/self/status"):
        _cap_memory(args.memory_gib)
    print(f"corpus: {len(corpus.spec_docs)} spec files, {len(corpus.scenario_docs)} scenarios, "
          f"{len(corpus.system_docs)} systems, {len(corpus.property_docs)} property files; "
          f"time bound {TIME_LIMIT:g} CPU-s and memory bound {args.memory_gib:g} GiB per input", flush=True)
    others = 0
    for kind, count in (("spec", args.specs), ("scenario", args.scenarios), ("system", args.systems),
                        ("properties", args.properties)):
        if count <= 0:
            continue
        tally = fuzz(corpus, kind, count, progress=True)
        print(tally.line(), flush=True)
        for o in tally.others[: args.show]:
            print(f"  OTHER {o}", flush=True)
        others += len(tally.others)
    print(f"fuzzing done in {time.monotonic() - started:.0f} s; other exceptions: {others}", flush=True)
    return 1 if others else 0


if __name__ == "__main__":
    raise SystemExit(main())
