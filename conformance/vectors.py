"""Conformance vectors: self-contained JSON test cases other implementations run.

Pipeline position: scenarios (:mod:`statecharts.scenario`) and the model checker
(:mod:`checker.search`, :mod:`checker.counterexample`) -> **conformance.vectors** -> a
directory of ``*.json`` vectors plus ``manifest.json`` -> :mod:`conformance.runner`.

A vector (``format: motionchart-vector/1``, schema ``spec/schema/vector.schema.json``,
explained in ``docs/conformance.md``) holds a set-up (axes with their type, family,
start state and variables; the program of instruction calls with their operands), one
entry per scan (its inputs: every rung-condition-in, operand writes, environment
events, the prescan flag) with the observations expected after it, the sources, what
the implementation must support to run it and the coverage items it exercises.

Two kinds:

* ``scenario``: every hand-written scenario under ``scenarios/`` in the main format
  (each one must pass on the engine).  A scenario that calls an add-on instruction or
  sets up a device is listed in the manifest as left out: version 1 of the vector format
  carries programs of motion instruction calls on axes only.
* ``generated``: for every transition, documented error code, instruction x state
  cell and ordered-check boundary that the checker reaches on a bundled system, the
  shortest run that reaches it (the search is breadth first and records the first
  step that covered each item, :attr:`checker.search.Coverage.first`; the path is
  replayed with :func:`checker.counterexample.replay`).  Items with the same witness
  share a vector; vectors with the same set-up and inputs are merged.

The expected observations of every vector are computed on the python-statemachine
engine (the reference); what each vector covers is measured by running it again on the
checker's interpreter, so the manifest states coverage that was observed, not assumed.
Output is deterministic: the same spec and scenarios give byte-identical files.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from conformance.session import Covered, Session, error_item
from statecharts import ir
from statecharts.diagnostics import Diagnostic, ScenarioError

VECTOR_FORMAT = "motionchart-vector/1"
MANIFEST_FORMAT = "motionchart-vector-manifest/1"
SYSTEMS_DIR = Path(__file__).resolve().parent / "systems"
#: what the suite is generated from: the systems, and the charts none of them drives (data)
SUITE_FILE = SYSTEMS_DIR / "suite.yaml"


def suite_plan(path: Path = SUITE_FILE) -> tuple[tuple[str, ...], dict[str, str]]:
    """(systems: bundled names or files, charts no system drives -> reason) of ``suite.yaml``."""
    from checker.system import bundled_systems
    from statecharts.diagnostics import Diagnostic, InputError
    from statecharts.loader import plain_data, read_yaml
    errors: list[Diagnostic] = []
    tree = read_yaml(path, errors, what="vector suite plan")
    doc = plain_data(tree) if tree is not None and not errors else None
    if not isinstance(doc, dict) or not isinstance(doc.get("systems"), list) \
            or not isinstance(doc.get("not_driven", {}), dict):
        raise InputError(errors or [Diagnostic(str(path), 1, 1, "", "expected `systems:` (a list of names) "
                                               "and `not_driven:` (chart -> reason)")])
    bundled = bundled_systems()
    systems = tuple(str(n) if str(n) in bundled else str(SYSTEMS_DIR / f"{n}.yaml") for n in doc["systems"])
    not_driven = {str(k): " ".join(str(v).split()) for k, v in doc.get("not_driven", {}).items()}
    return systems, not_driven


DEFAULT_SYSTEMS, NOT_DRIVEN = suite_plan()
ADDON_LEFT_OUT = ("calls an add-on instruction or sets up a device (docs/aoi.md); version 1 of the vector format "
                  "carries programs of motion instruction calls on axes only")
LADDER_LEFT_OUT = ("runs a ladder program file (docs/programs.md); version 1 of the vector format carries "
                   "programs of motion instruction calls only")

ORDER_OF_KINDS = ("transitions", "error_codes", "cells", "checks", "orders", "refusals", "states")


@dataclass
class Suite:
    """Vectors (JSON documents), what was left out, and the coverage universe."""

    vectors: list[dict[str, Any]] = field(default_factory=list)
    left_out: list[dict[str, str]] = field(default_factory=list)
    universe: dict[str, list[str]] = field(default_factory=dict)
    explained: dict[str, dict[str, str]] = field(default_factory=dict)  # kind -> item -> reason
    systems: list[dict[str, object]] = field(default_factory=list)
    searched: list[_Searched] = field(default_factory=list)

    def covered(self) -> Covered:
        c = Covered()
        for v in self.vectors:
            for k in Covered.KINDS:
                getattr(c, k).update(v["covers"].get(k, []))
        return c

    def coverage(self) -> dict[str, dict[str, Any]]:
        got = self.covered()
        out: dict[str, dict[str, Any]] = {}
        for kind in ORDER_OF_KINDS:
            items = self.universe.get(kind, [])
            have = getattr(got, kind)
            reasons = self.explained.get(kind, {})
            missing = [i for i in items if i not in have]
            out[kind] = {
                "total": len(items),
                "covered": len(items) - len(missing),
                "explained": {i: reasons[i] for i in missing if i in reasons},
                "uncovered": [i for i in missing if i not in reasons],
            }
        return out


# --------------------------------------------------------------------------- helpers


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.@-]+", "-", text).strip("-")


def _universe(spec: ir.Spec) -> dict[str, list[str]]:
    from checker import coverage
    shim = SimpleNamespace(spec=spec)
    out = {k: coverage.universe(shim, k, whole_spec=True) for k in ("states", "transitions", "error_codes", "cells")}  # type: ignore[arg-type]  # whole_spec reads .spec only
    out["checks"] = [f"{ins.id}.{c.id}" for ins in spec.instructions for c in ins.checks]
    out["orders"] = [order_item(ins, k) for ins in spec.instructions for k in range(len(ins.checks) - 1)
                     if observable_order(ins, k)]
    from conformance.witness import refusal_universe
    out["refusals"] = refusal_universe(spec)
    return out


def order_item(ins: ir.Instruction, k: int) -> str:
    """The order of adjacent checks k and k+1: ``MSO.shutdown<faulted``."""
    return f"{ins.id}.{ins.checks[k].id}<{ins.checks[k + 1].id}"


def observable_order(ins: ir.Instruction, k: int) -> bool:
    """Whether swapping checks k and k+1 could be seen at all: not when both report the
    same ERR and EXERR (wherever both are evaluated the same code is reported, and where
    only one of them is evaluated their order does not matter)."""
    a, b = ins.checks[k], ins.checks[k + 1]
    return (a.err, a.exerr) != (b.err, b.exerr)


def _explanations(spec: ir.Spec, universe: Mapping[str, list[str]]) -> dict[str, dict[str, str]]:
    """Reasons, from the bundled property files, why a coverage item cannot be reached."""
    from checker.properties import load_properties
    out: dict[str, dict[str, str]] = {k: {} for k in ORDER_OF_KINDS}
    for p in load_properties(spec):
        if p.kind == "cover" and p.cover in out:
            for u in p.unreachable:
                out[p.cover].setdefault(u.item, " ".join(u.reason.split()))
    for kind in ("states", "transitions", "refusals"):
        for item in universe[kind]:
            chart = item.split(":", 1)[0]
            if chart in NOT_DRIVEN:
                out[kind].setdefault(item, f"chart {chart} is {NOT_DRIVEN[chart]}")
    # a check whose error code cannot be produced cannot be the first to fail either
    for ins in spec.instructions:
        for c in ins.checks:
            reason = out["error_codes"].get(error_item(ins.id, c.err, c.exerr))
            if reason is not None:
                out["checks"].setdefault(f"{ins.id}.{c.id}", reason)
    return out


def requirements(spec: ir.Spec, setup: Mapping[str, Any], scans: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """What an implementation must support to run a vector."""
    families = sorted({a["family"] for a in setup["axes"]})
    instructions = sorted({p["instruction"] for p in setup["program"]})
    events = sorted({f"{_family(setup, e['axis'])}.{e['event']}" for s in scans for e in s["inputs"].get("events", [])})
    features = []
    if any(s["inputs"].get("prescan") for s in scans):
        features.append("prescan")
    return {"axis_families": families, "instructions": instructions, "events": events, "features": features}


def _family(setup: Mapping[str, Any], axis: str) -> str:
    return str(next(a["family"] for a in setup["axes"] if a["name"] == axis))


def run_on_engine(spec: ir.Spec, setup: Mapping[str, Any], inputs: Sequence[Mapping[str, Any]]
                  ) -> tuple[dict[str, dict[str, object]], list[dict[str, dict[str, object]]]]:
    """Initial observations and the observations after each scan, on the reference engine."""
    s = Session(spec, setup)
    initial = s.observe()
    return initial, [s.scan(i) for i in inputs]


def measure_coverage(spec: ir.Spec, setup: Mapping[str, Any], inputs: Sequence[Mapping[str, Any]]) -> Covered:
    from conformance.witness import RecordingAxis
    s = Session(spec, setup, backend=RecordingAxis, record=True)
    for i in inputs:
        s.scan(i)
    return s.covered


def make_vector(spec: ir.Spec, *, vid: str, kind: str, name: str, description: str, sources: Sequence[str],
                setup: dict[str, Any], inputs: list[dict[str, Any]], labels: list[str],
                stated: Sequence[str] = (), origin: str = "", universe: Mapping[str, list[str]] | None = None,
                ) -> dict[str, Any]:
    initial, observed = run_on_engine(spec, setup, inputs)
    scans = []
    for k, (inp, obs) in enumerate(zip(inputs, observed)):
        entry: dict[str, Any] = {"index": k, "inputs": inp, "expect": obs}
        if labels[k]:
            entry["label"] = labels[k]
        scans.append(entry)
    covers = measure_coverage(spec, setup, inputs).as_dict(universe)
    if stated:
        covers["stated"] = list(stated)
    doc: dict[str, Any] = {
        "format": VECTOR_FORMAT, "id": vid, "kind": kind, "name": name,
        "description": description, "sources": list(sources), "origin": origin,
        "requires": requirements(spec, setup, scans), "covers": covers,
        "setup": setup, "initial": initial, "scans": scans,
    }
    return doc


def _inputs_key(v: Mapping[str, Any]) -> str:
    return json.dumps([v["setup"], [s["inputs"] for s in v["scans"]]], sort_keys=True)


# --------------------------------------------------------------------------- scenario vectors


def scenario_vectors(spec: ir.Spec, paths: Sequence[Path | str], suite: Suite,
                     progress: Callable[[str], None] | None = None) -> None:
    from statecharts.loader import read_document
    from statecharts.scenario import load_scenario, run_scenario, scenario_files
    files = scenario_files(paths)
    roots = [Path(p) for p in paths]
    for f in files:
        rel = _relative(f, roots)
        errors: list[Diagnostic] = []
        tree = read_document(f, errors, what="scenario")
        setup_node = tree.get("setup") if isinstance(tree, Mapping) else None
        if isinstance(setup_node, Mapping) and isinstance(setup_node.get("program"), (str, Mapping)):
            suite.left_out.append({"file": rel, "reason": LADDER_LEFT_OUT})
            continue
        add_ons = {a.id for a in spec.add_ons}
        if isinstance(setup_node, Mapping) and (setup_node.get("devices") or any(
                isinstance(p, Mapping) and p.get("instruction") in add_ons for p in setup_node.get("program") or ())):
            suite.left_out.append({"file": rel, "reason": ADDON_LEFT_OUT})
            continue
        scenario = load_scenario(f, spec)
        result = run_scenario(scenario, spec)
        if not result.passed:
            raise ScenarioError([Diagnostic(str(f), m.line, 1, f"steps[{m.step}]",
                                            f"the scenario fails on the engine ({m}); a vector must pass")
                                 for m in result.mismatches])
        setup = {
            "scan_ms": scenario.scan_ms, "coarse_update_ms": scenario.coarse_update_ms,
            "axes": [_axis_entry(a.name, a.axis_type, a.chart, a.state, dict(a.variables)) for a in scenario.axes],
            "program": [_program_entry(p.tag, p.instruction, p.axis, dict(p.operands), p.master)
                        for p in scenario.program],
        }
        rungs = {p.tag: False for p in scenario.program}
        inputs: list[dict[str, Any]] = []
        labels: list[str] = []
        for step in scenario.steps:
            for k in range(step.scans):
                si = step.inputs
                if k == 0:
                    rungs.update(si.rungs)
                entry: dict[str, Any] = {"rungs": dict(rungs)}
                if k == 0 and si.operands:
                    entry["operands"] = {t: dict(o) for t, o in si.operands.items()}
                if k == 0 and si.events:
                    entry["events"] = [{"axis": e.axis, "event": e.event} for e in si.events]
                if si.prescan:
                    entry["prescan"] = True
                inputs.append(entry)
                label = f"step {step.index + 1}" + (f": {step.name}" if step.name else "")
                labels.append(label if k == 0 else "")
        vid = "scenario-" + _slug(str(Path(rel).with_suffix("")).replace(os.sep, "-"))
        suite.vectors.append(make_vector(
            spec, vid=vid, kind="scenario", name=scenario.name, description=scenario.description,
            sources=scenario.sources, setup=setup, inputs=inputs, labels=labels, stated=scenario.covers,
            origin=f"scenarios/{rel}" if not Path(rel).is_absolute() else rel, universe=suite.universe))
        if progress:
            progress(f"scenario {rel}")


def _relative(f: Path, roots: Sequence[Path]) -> str:
    for r in roots:
        try:
            if r.is_dir():
                return f.resolve().relative_to(r.resolve()).as_posix()
        except ValueError:
            continue
    return f.name


def _axis_entry(name: str, axis_type: str, family: str, state: str | None, variables: dict[str, object]) -> dict[str, Any]:
    entry: dict[str, Any] = {"name": name, "type": axis_type, "family": family}
    if state is not None:
        entry["state"] = state
    entry["variables"] = dict(sorted(variables.items()))
    return entry


def _program_entry(tag: str, mnemonic: str, axis: str, operands: dict[str, object],
                   master: str | None = None) -> dict[str, Any]:
    entry: dict[str, Any] = {"tag": tag, "instruction": mnemonic, "axis": axis}
    if master is not None:
        entry["master"] = master
    entry["operands"] = dict(sorted(operands.items()))
    return entry


# --------------------------------------------------------------------------- generated vectors


KIND_OF_ITEM = {"transition": "transitions", "error": "error_codes", "cell": "cells", "check": "checks"}


def _item_text(item: tuple[object, ...]) -> tuple[str, str]:
    kind = item[0]
    if kind == "transition":
        return "transitions", f"{item[1]}:{item[2]}"
    if kind == "error":
        err, exerr = item[2], item[3]
        assert isinstance(err, int) and isinstance(exerr, int)
        return "error_codes", error_item(str(item[1]), err, exerr)
    if kind == "cell":
        return "cells", f"{item[1]}@{item[2]}"
    return "checks", f"{item[1]}.{item[2]}"


def _witness_search(search: Any) -> Callable[..., Any]:
    """The search that records the first step covering each item (``witnesses=True``)."""
    import inspect
    for name in ("explore", "explore_interpreted"):
        fn: Callable[..., Any] | None = getattr(search, name, None)
        if fn is not None and "witnesses" in inspect.signature(fn).parameters:
            return fn
    raise RuntimeError("no search of checker.search records coverage witnesses")


def generated_vectors(spec: ir.Spec, system: str | Path, suite: Suite,
                      progress: Callable[[str], None] | None = None, *, explore_fn: Callable[..., Any] | None = None,
                      ) -> None:
    """Shortest runs for every item the checker covers on ``system`` (a bundled name or a file)."""
    from checker import search
    from checker.counterexample import replay
    from checker.properties import load_properties
    from checker.system import bundled_systems, load_system
    from conformance.witness import WitnessModel, decode
    path = bundled_systems().get(str(system), Path(system))
    sysdef = load_system(path, spec)
    model = WitnessModel(spec, sysdef, load_properties(spec))
    if progress:
        progress(f"exploring system {sysdef.name}")
    result = (explore_fn or _witness_search(search))(model, progress=False, witnesses=True)
    suite.systems.append({"name": sysdef.name, "states": result.states, "transitions": result.transitions,
                          "complete": result.complete})
    if result.complete:
        events = {"tick"} | {c.event for c in model.choices if c.kind == "event" and c.event}
        events |= {t.instruction.request.event for t in model.tags if t.instruction.request is not None}
        suite.searched.append(_Searched(sysdef.name, frozenset(model.charts),
                                        frozenset(t.instruction.id for t in model.tags), frozenset(events)))
    # order the witnesses by the kind of item, then by the universe's order of items
    rank = {kind: {it: i for i, it in enumerate(items)} for kind, items in suite.universe.items()}
    items = []
    for item, where in result.coverage.first.items():
        kind, text = decode(item) or _item_text(item)
        if kind in rank and text not in rank[kind]:
            # outside the universe: an order of two checks that report the same code
            continue
        items.append((ORDER_OF_KINDS.index(kind), rank.get(kind, {}).get(text, 1 << 30), text, kind, where))
    items.sort()
    by_witness: dict[tuple[int, int], list[tuple[str, str]]] = {}
    for _k, _r, text, kind, where in items:
        by_witness.setdefault(where, []).append((kind, text))
    for (state, choice), found in by_witness.items():
        trace = replay(result, "", None, end_state=state)
        choices = [st.choice for st in trace.steps] + [model.choices[choice]]
        kind0, text0 = found[0]
        vid = f"{sysdef.name}-{_KIND_IN_ID[kind0]}-{_slug(text0.replace('/', '-').replace(':', '.').replace('<', '-before-'))}"
        what = "; ".join(f"{_KIND_IN_TEXT[k]} {t}" for k, t in found)
        v = _run_vector(spec, model, sysdef, suite, trace.assignment, choices, vid, what)
        missing = [t for k, t in found if t not in v["covers"][k]]
        if missing:
            # the search's abstraction lets it reach an item that the engine, replaying the
            # same inputs, does not: the system's abstraction is not exact for this item
            from checker.system import SystemError_

            raise SystemError_([Diagnostic(
                sysdef.file, 1, 1, "abstraction",
                f"vector {vid}: replayed on the engine, the run the search found does not cover "
                f"{', '.join(missing)}; the system's abstraction (collapsed variables, drive outcomes as "
                "inputs) is not exact for it: collapse fewer variables, or leave out the configuration "
                "or input that reaches it")])
        suite.vectors.append(v)
    if progress:
        progress(f"system {sysdef.name}: {result.states:,} states, {len(by_witness)} shortest runs")


_KIND_IN_ID = {"transitions": "transition", "error_codes": "error", "cells": "cell", "checks": "check",
               "orders": "order", "refusals": "refusal", "states": "state"}
_KIND_IN_TEXT = {"transitions": "transition", "error_codes": "error code", "cells": "cell", "checks": "check",
                 "orders": "check order", "refusals": "refused guard of", "states": "state"}


@dataclass(frozen=True)
class _Searched:
    """A system whose search was complete: what it could have shown."""

    name: str
    charts: frozenset[str]
    instructions: frozenset[str]
    events: frozenset[str]  # the events its axes can get: tick, environment events, requests


def _run_vector(spec: ir.Spec, model: Any, sysdef: Any, suite: Suite, assignment: Sequence[int],
                choices: Sequence[Any], vid: str, what: str) -> dict[str, Any]:
    """The vector of one run of the checker's model: its set-up, its inputs, the engine's observations."""
    program = [(tag, spec.instruction(m).mnemonic, axis) for tag, m, axis in model.program]
    # a call whose rung never rises never executes and changes nothing but its own
    # (all-false) tag: the vector leaves it out, so it needs only the instructions it runs
    used = {c.tag for c in choices if c.kind == "raise"}
    calls = [(t, m, a) for t, m, a in program if t in used]
    setup: dict[str, Any] = {
        "scan_ms": sysdef.scan_ms, "coarse_update_ms": sysdef.coarse_update_ms,
        "axes": [], "program": [_program_entry(t, m, a, {}, model.masters.get(t)) for t, m, a in calls],
    }
    for (name, g), ci in zip(model.axis_defs, assignment):
        variables = dict(g.variables)
        variables.update(dict(g.configurations[ci].variables))
        setup["axes"].append(_axis_entry(name, g.axis_type, g.chart, g.state, variables))
    rungs = {t: False for t, _m, _a in calls}
    inputs: list[dict[str, Any]] = []
    labels: list[str] = []
    for c in choices:
        entry: dict[str, Any] = {}
        if c.kind == "raise" and c.tag is not None:
            rungs[c.tag] = True
        elif c.kind == "drop" and c.tag is not None:
            rungs[c.tag] = False
        entry["rungs"] = dict(rungs)
        if c.kind == "raise" and c.operands:
            entry["operands"] = {c.tag: dict(c.operands)}
        if c.kind == "event" or c.drive:
            entry["events"] = [{"axis": e.axis, "event": e.event} for e in c.inputs.events]
        if c.kind == "prescan":
            entry["prescan"] = True
        inputs.append(entry)
        labels.append(c.label())
    cfg = ", ".join(g.configurations[ci].name for (_n, g), ci in zip(model.axis_defs, assignment))
    return make_vector(
        spec, vid=vid, kind="generated", name=f"shortest run to {what}",
        description=(f"A shortest run ({len(inputs)} scans) found by breadth-first search of system "
                     f"{sysdef.name} (configuration {cfg}) that covers: {what}."),
        sources=[f"systems/{Path(sysdef.file).name}"], setup=setup, inputs=inputs, labels=labels,
        origin=f"motionchart check --system {sysdef.name}", universe=suite.universe)


def _explain_unseen(spec: ir.Spec, suite: Suite) -> None:
    """Orders and refusals no vector covers, that the complete search of every system that
    runs the instruction (has an axis of the chart) never showed: explained with that."""
    got = suite.covered()
    instructions = {i.id: i for i in spec.instructions}
    for item in suite.universe.get("orders", []):
        if item in got.orders or item in suite.explained["orders"]:
            continue
        iid, pair = item.split(".", 1)
        first, second = pair.split("<")
        names = [s.name for s in suite.searched if iid in s.instructions]
        if not names:
            continue
        ins = instructions[iid]
        a = next(c for c in ins.checks if c.id == first)
        b = next(c for c in ins.checks if c.id == second)
        why = (f"the exhaustive search of system{'s' if len(names) > 1 else ''} {', '.join(names)} finds no "
               f"evaluation of {iid}'s checks (at {a.stage.value if a.stage is b.stage else 'the delivery'}) where "
               f"`{a.fails_when.text}` ({first}) fails first and `{b.fails_when.text}` ({second}) fails too")
        hint = _exclusive_states(spec, ins, a, b) or _stage_hint(a, b)
        suite.explained["orders"][item] = f"{hint}; {why}" if hint else why
    for item in suite.universe.get("refusals", []):
        if item in got.refusals or item in suite.explained["refusals"]:
            continue
        cid, tid = item.split(":", 1)
        t = next(x for x in spec.chart(cid).transitions if x.id == tid)
        # only a search in which the event can happen at all shows the guard is never false
        names = [s.name for s in suite.searched if cid in s.charts and t.event in s.events]
        if not names:
            continue
        suite.explained["refusals"][item] = (
            f"the exhaustive search of system{'s' if len(names) > 1 else ''} {', '.join(names)} never tries "
            f"transition {tid} on event {t.event} with its guard `{t.guard.text if t.guard else ''}` false")


def _stage_hint(a: ir.Check, b: ir.Check) -> str:
    """Why two checks of different stages rarely fail together: only at the delivery are
    both evaluated, and a failing execute-stage check errs the call before it is queued."""
    if a.stage is b.stage:
        return ""
    early = a if a.stage is ir.Stage.EXECUTE else b
    return (f"only at the delivery are both evaluated, and a call whose {early.id} check fails at its "
            f"execution errs there and is never delivered, so both fail only if `{early.fails_when.text}` "
            f"became true between the execution and the delivery")


def _exclusive_states(spec: ir.Spec, ins: ir.Instruction, a: ir.Check, b: ir.Check) -> str:
    """When the two checks fail only in two different leaf states of every chart of the
    instruction, that reason (the axis is in one leaf state at a time)."""
    pattern = re.compile(r"^'([A-Za-z0-9_]+)' in axis\.active$")
    ma, mb = pattern.match(a.fails_when.text.strip()), pattern.match(b.fails_when.text.strip())
    if not (ma and mb) or ma[1] == mb[1]:
        return ""
    for cid in ins.charts:
        leaves = {s.id for s in spec.chart(cid).leaf_states()}
        if ma[1] not in leaves or mb[1] not in leaves:
            return ""
    return f"{a.id} fails only in state {ma[1]} and {b.id} only in state {mb[1]}, and an axis is in one leaf state at a time"


# --------------------------------------------------------------------------- the suite


def build_suite(spec: ir.Spec, *, scenarios: Sequence[Path | str] = ("scenarios",),
                systems: Sequence[str | Path] = DEFAULT_SYSTEMS,
                progress: Callable[[str], None] | None = None) -> Suite:
    suite = Suite()
    suite.universe = _universe(spec)
    suite.explained = _explanations(spec, suite.universe)
    if scenarios:
        scenario_vectors(spec, scenarios, suite, progress)
    for system in systems:
        generated_vectors(spec, system, suite, progress)
    _explain_unseen(spec, suite)
    # de-duplicate: the same set-up and inputs give the same observations
    seen: dict[str, dict[str, Any]] = {}
    unique = []
    for v in suite.vectors:
        key = _inputs_key(v)
        first = seen.get(key)
        if first is None:
            seen[key] = v
            unique.append(v)
            continue
        first.setdefault("also", []).append(v["id"])
    ids: dict[str, int] = {}
    for v in unique:  # ids must be unique file names
        n = ids.get(v["id"], 0)
        ids[v["id"]] = n + 1
        if n:
            v["id"] = f"{v['id']}-{n + 1}"
    suite.vectors = unique
    return suite


def suite_digest(roots: Sequence[Path | str]) -> str:
    """A name for what a suite is generated from: the files under ``roots`` (the spec and
    the scenarios) and the source of the code that generates and runs it."""
    h = hashlib.sha256()
    code = [Path(__file__).resolve().parent.parent / d for d in ("statecharts", "checker", "conformance")]
    for root in [*map(Path, roots), *code]:
        if not root.is_dir():
            continue
        for p in sorted(root.rglob("*")):
            if p.is_file() and p.suffix in (".yaml", ".yml", ".json", ".py") and "__pycache__" not in p.parts:
                h.update(p.relative_to(root).as_posix().encode())
                h.update(p.read_bytes())
    return h.hexdigest()[:16]


def cached_suite(cache: Path, roots: Sequence[Path | str], build: Callable[[], Suite]) -> Path:
    """The suite directory ``cache/vectors-<digest>``, built with ``build`` the first time;
    concurrent callers (test workers, parallel runs) wait for the one that builds it."""
    import fcntl
    d = Path(cache) / f"vectors-{suite_digest(roots)}"
    if (d / "manifest.json").is_file():
        return d
    d.parent.mkdir(parents=True, exist_ok=True)
    with open(d.parent / f".{d.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if not (d / "manifest.json").is_file():
                write_suite(build(), d)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    return d


def manifest(suite: Suite) -> dict[str, Any]:
    return {
        "format": MANIFEST_FORMAT,
        "vector_format": VECTOR_FORMAT,
        "count": len(suite.vectors),
        "vectors": [{"id": v["id"], "file": f"{v['id']}.json", "kind": v["kind"], "name": v["name"],
                     "requires": v["requires"], "covers": {k: v["covers"][k] for k in ORDER_OF_KINDS}}
                    for v in suite.vectors],
        "left_out": suite.left_out,
        "systems": suite.systems,
        "coverage": suite.coverage(),
    }


def dumps(doc: Mapping[str, Any]) -> str:
    return json.dumps(doc, indent=1, sort_keys=True, ensure_ascii=False, allow_nan=False) + "\n"


def write_suite(suite: Suite, directory: Path) -> list[Path]:
    """Write every vector and the manifest; the directory ends with exactly these files.

    Files are written in a fresh sibling directory that then replaces ``directory``, so
    an interrupted run leaves the previous suite (or nothing) in place."""
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise NotADirectoryError(f"{directory} exists and is not a directory")
    if directory.is_dir() and any(directory.iterdir()) and not (directory / "manifest.json").is_file():
        raise FileExistsError(f"{directory} is not empty and holds no vector manifest; refusing to replace it")
    directory.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", dir=directory.parent))
    written = []
    try:
        for v in suite.vectors:
            p = tmp / f"{v['id']}.json"
            p.write_text(dumps(v), encoding="utf-8")
            written.append(directory / p.name)
        (tmp / "manifest.json").write_text(dumps(manifest(suite)), encoding="utf-8")
        os.chmod(tmp, 0o755)
        old = None
        if directory.exists():
            old = directory.with_name(f".{directory.name}.old-{os.getpid()}")
            directory.rename(old)
        tmp.rename(directory)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return written


def coverage_text(cov: Mapping[str, Mapping[str, Any]]) -> str:
    lines = []
    for kind in ORDER_OF_KINDS:
        c = cov[kind]
        lines.append(f"  {kind.replace('_', ' '):<12} {c['covered']:>4}/{c['total']:<4} covered, "
                     f"{len(c['explained'])} explained as not reachable, {len(c['uncovered'])} uncovered")
        for item in c["uncovered"]:
            lines.append(f"    uncovered: {item}")
    return "\n".join(lines) + "\n"


def iter_items(cov: Mapping[str, Iterable[str]]) -> Iterable[tuple[str, str]]:
    for k in ORDER_OF_KINDS:
        for it in cov.get(k, []):
            yield k, it


# --------------------------------------------------------------------------- reading vectors

#: a vector file larger than this is refused (the bundled ones are well under 1 MB)
MAX_VECTOR_BYTES = 64 * 1024 * 1024


def load_vector(path: Path | str) -> dict[str, Any]:
    """Read one vector file and check it against ``vector.schema.json`` and itself;
    raise :class:`ScenarioError` with every problem, located."""
    from conformance.schemas import VECTOR_SCHEMA
    from statecharts.inputs import read_input
    from statecharts.loader import read_yaml, schema_diagnostics
    path = Path(path)
    name = str(path)

    def fail(message: str, line: int = 1, col: int = 1, where: str = "") -> ScenarioError:
        return ScenarioError([Diagnostic(name, line, col, where, message)])

    read_errors: list[Diagnostic] = []
    raw = read_input(path, read_errors, what="vector", limit=MAX_VECTOR_BYTES)
    if raw is None:
        raise ScenarioError(read_errors)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise fail(f"vector is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise fail(f"JSON syntax error: {exc.msg}", exc.lineno, exc.colno) from None
    except RecursionError:
        raise fail("JSON nesting too deep to parse") from None
    except ValueError as exc:  # an integer too long to convert
        raise fail(f"JSON error: {exc}") from None
    problems = schema_diagnostics(name, doc, VECTOR_SCHEMA, "a vector")
    if problems:
        positioned = read_yaml(path, [], what="vector")
        if positioned is not None:
            problems = schema_diagnostics(name, positioned, VECTOR_SCHEMA, "a vector")
        raise ScenarioError(problems)
    errors: list[Diagnostic] = []
    tags = {p["tag"] for p in doc["setup"]["program"]}
    axes = {a["name"] for a in doc["setup"]["axes"]}
    for p in doc["setup"]["program"]:
        if p["axis"] not in axes:
            errors.append(Diagnostic(name, 1, 1, "setup.program", f"tag {p['tag']}: unknown axis {p['axis']!r}"))
    for k, s in enumerate(doc["scans"]):
        where = f"scans[{k}]"
        if s["index"] != k:
            errors.append(Diagnostic(name, 1, 1, f"{where}.index", f"expected index {k}, got {s['index']}"))
        for t in [*s["inputs"]["rungs"], *s["inputs"].get("operands", {})]:
            if t not in tags:
                errors.append(Diagnostic(name, 1, 1, f"{where}.inputs", f"unknown tag {t!r}; tags: {', '.join(sorted(tags))}"))
        for e in s["inputs"].get("events", []):
            if e["axis"] not in axes:
                errors.append(Diagnostic(name, 1, 1, f"{where}.inputs.events", f"unknown axis {e['axis']!r}"))
    if errors:
        raise ScenarioError(errors)
    return dict(doc)


def vector_files(directory: Path | str) -> list[Path]:
    d = Path(directory)
    if d.is_file():
        return [d]
    return sorted(p for p in d.glob("*.json") if p.name != "manifest.json")


def load_vectors(directory: Path | str) -> list[dict[str, Any]]:
    """Every vector of a suite directory (or one file), in file-name order; every problem of every file is reported."""
    out: list[dict[str, Any]] = []
    errors: list[Diagnostic] = []
    seen: dict[str, str] = {}
    for p in vector_files(directory):
        try:
            v = load_vector(p)
        except ScenarioError as exc:
            errors.extend(exc.diagnostics)
            continue
        if v["id"] in seen:
            errors.append(Diagnostic(str(p), 1, 1, "id", f"vector id {v['id']!r} is also the id of {seen[v['id']]}"))
            continue
        seen[v["id"]] = str(p)
        out.append(v)
    if errors:
        raise ScenarioError(errors)
    return out
