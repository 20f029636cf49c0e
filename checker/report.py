"""Verdicts, statistics, coverage and graph analyses of a search, as one record.

Pipeline position: :mod:`checker.search` + :mod:`checker.coverage` + :mod:`checker.counterexample`
-> **checker.report** -> :mod:`checker.check_cli` (text and ``--json``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from checker import coverage as cov
from checker.counterexample import Trace, replay, table_text, write_scenario
from checker.properties import Property
from checker.search import SearchResult
from statecharts.outputs import atomic_write_with

if TYPE_CHECKING:
    import networkx as nx


@dataclass
class PropertyVerdict:
    prop: Property
    holds: bool | None  # None: undecided (the search was incomplete)
    detail: str
    depth: int | None = None
    trace: Trace | None = None
    scenario: Path | None = None
    kind_of_trace: str = "violation"

    def as_dict(self) -> dict[str, object]:
        ce: dict[str, object] | None = None
        if self.trace is not None and self.kind_of_trace != "witness":
            ce = {"scans": len(self.trace.steps), "steps": [s.choice.label() for s in self.trace.steps],
                  "scenario": str(self.scenario) if self.scenario else None}
        out: dict[str, object] = {"name": self.prop.name, "kind": self.prop.kind, "holds": self.holds,
                                  "detail": self.detail, "counterexample": ce, "source": self.prop.source}
        if self.trace is not None and self.kind_of_trace == "witness":
            out["witness"] = {"scans": len(self.trace.steps), "steps": [s.choice.label() for s in self.trace.steps]}
        return out


@dataclass
class Report:
    result: SearchResult
    verdicts: list[PropertyVerdict]
    coverage: dict[str, cov.CoverageTable]
    explained: dict[str, dict[str, str]] = field(default_factory=dict)
    graph: dict[str, object] | None = None

    @property
    def exit_code(self) -> int:
        if any(v.holds is False for v in self.verdicts):
            return 1
        if not self.result.complete or any(v.holds is None for v in self.verdicts):
            return 3
        return 0

    def as_dict(self) -> dict[str, object]:
        r = self.result
        m = r.model
        coverage: dict[str, object] = {}
        for name, t in self.coverage.items():
            if name == "error_codes":
                coverage[name] = {"reached": list(t.reached), "unreached": list(t.unreached),
                                  "explained": self.explained.get(name, {}), "total": t.total}
            else:
                coverage[name] = {"reached": len(t.reached), "total": t.total, "unreached": list(t.unreached)}
        out: dict[str, object] = {
            "system": m.sysdef.name,
            "axes": len(m.axes),
            "tags": len(m.tags),
            "initial_states": len(r.initial_assignment),
            "complete": r.complete,
            "stop_reason": r.stop_reason,
            "verdict": {0: "holds", 1: "violated", 3: "incomplete"}[self.exit_code],
            "states": r.states,
            "transitions": r.transitions,
            "depth": r.depth,
            "seconds": round(r.seconds, 3),
            "states_per_second": round(r.states_per_second, 1),
            "peak_memory_mb": round(r.peak_rss_kb / 1024, 1),
            "choices": len(m.choices),
            "symmetric_axis_groups": [[m.axes[a].name for a in g] for g in m.symmetric_groups],
            "abstractions": abstraction_notes(r),
            "properties": [v.as_dict() for v in self.verdicts],
            "coverage": coverage,
        }
        if self.graph is not None:
            out["graph"] = self.graph
        return out


def abstraction_notes(r: SearchResult) -> list[str]:
    m = r.model
    sd = m.sysdef
    notes = ["one input change per scan (rung up with operands, rung down, one environment event, prescan, nothing)"]
    if sd.max_live_calls is not None:
        notes.append(f"at most {sd.max_live_calls} instruction call(s) live per axis")
    if sd.collapse:
        notes.append(f"collapsed (outside the cone of influence): {', '.join(sd.collapse)}")
    notes.append("operands of a tag with its rung low and nothing pending or queued are reset")
    if sd.retire_idle_tags:
        notes.append("idle tags are stored with their initial values (tag properties hold over each call's lifetime)")
    if m.symmetric_groups:
        notes.append("symmetry reduction over interchangeable axes")
    notes.extend(m.notes)
    return notes


def build_report(result: SearchResult, *, counterexamples: Path | None = None, graph: bool = False,
                 graphml: Path | None = None) -> Report:
    m = result.model
    verdicts: list[PropertyVerdict] = []
    explained: dict[str, dict[str, str]] = {}
    for p in m.properties:
        if p.kind in ("invariant", "response"):
            w = result.violations.get(p.name)
            if w is not None:
                trace = replay(result, p.name, w)
                v = PropertyVerdict(p, False, f"violated after {len(trace.steps)} scans", w.depth, trace)
            elif result.complete:
                v = PropertyVerdict(p, True, "holds in every reachable state")
            else:
                v = PropertyVerdict(p, None, "no violation found before the search stopped")
        elif p.kind == "reachable":
            w = result.reached.get(p.name)
            if w is not None:
                trace = replay(result, p.name, w, kind="witness")
                v = PropertyVerdict(p, True, f"reached after {len(trace.steps)} scans", w.depth, trace,
                                    kind_of_trace="witness")
            elif result.complete:
                v = PropertyVerdict(p, False, "no reachable state satisfies the goal")
            else:
                v = PropertyVerdict(p, None, "goal not reached before the search stopped")
        elif p.kind == "deadlock_free":
            if result.deadlocks:
                dead = min(result.deadlocks, key=lambda s: result.depth_of[s])
                trace = replay(result, p.name, None, end_state=dead, kind="deadlock")
                v = PropertyVerdict(p, False, f"{len(result.deadlocks)} state(s) without a successor other than "
                                              f"themselves; the nearest after {len(trace.steps)} scans",
                                    result.depth_of[dead], trace, kind_of_trace="deadlock")
            elif result.complete:
                v = PropertyVerdict(p, True, "every reachable state has a successor other than itself")
            else:
                v = PropertyVerdict(p, None, "no deadlock found before the search stopped")
        else:
            cv = cov.cover_verdict(result, p)
            parts = []
            if cv.unexplained:
                parts.append(f"not reached: {', '.join(cv.unexplained)}")
            if cv.stale:
                parts.append(f"listed as unreachable but reached: {', '.join(cv.stale)}")
            if cv.unknown_items:
                parts.append(f"listed items that do not exist: {', '.join(cv.unknown_items)}")
            if cv.explained:
                parts.append(f"{len(cv.explained)} explained as impossible")
                explained.setdefault(p.cover or "", {}).update(dict(cv.explained))
            v = PropertyVerdict(p, cv.holds, "; ".join(parts) or "everything reached")
        verdicts.append(v)
    if counterexamples is not None:
        for v in verdicts:
            if v.trace is not None and v.kind_of_trace != "witness":
                v.scenario = write_scenario(result, v.trace, v.prop, counterexamples)
    tables = {name: cov.table(result, name) for name in ("states", "transitions", "error_codes", "cells")}
    report = Report(result, verdicts, tables, explained)
    if graph or graphml is not None:
        report.graph = graph_analyses(result, graphml)
    return report


def to_networkx(result: SearchResult) -> nx.DiGraph[int]:
    """The explored state graph as a ``networkx.DiGraph`` (needs ``keep_graph=True``)."""
    import networkx as nx

    if result.edges is None:
        raise ValueError("the search did not keep the graph; run explore(..., keep_graph=True)")
    g: nx.DiGraph[int] = nx.DiGraph()
    m = result.model
    for i in range(result.states):
        flat = result.state(i)
        label = []
        for ai, axis in enumerate(m.axes):
            part = flat[m.block_start[ai]]
            leaf = axis.c.leaf(part[0]).id
            live = [m.tags[t].instruction.id for t in m.tags_of_axis[ai]
                    if flat[m.block_start[ai] + 1 + m.tags_of_axis[ai].index(t)] != m.slots[t].retired]
            label.append(f"{axis.name}={leaf}" + (f"[{','.join(live)}]" if live else ""))
        g.add_node(i, label=" ".join(label), depth=int(result.depth_of[i]), initial=result.parent[i] < 0)
    e = result.edges
    for k in range(0, len(e), 2):
        g.add_edge(e[k], e[k + 1])
    return g


def graph_analyses(result: SearchResult, graphml: Path | None) -> dict[str, object]:
    import networkx as nx

    g = to_networkx(result)
    if graphml is not None:
        graphml.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_with(graphml, lambda tmp: nx.write_graphml(g, tmp))
    sccs = list(nx.strongly_connected_components(g))
    dead = [n for n in g if not any(s != n for s in g.successors(n))]
    initial = [n for n, d in g.nodes(data=True) if d["initial"]]
    lengths: dict[int, int] = {}
    for s in initial:
        for n, d in nx.single_source_shortest_path_length(g, s).items():
            lengths[n] = min(d, lengths.get(n, d))
    return {
        "nodes": g.number_of_nodes(),
        "edges": g.number_of_edges(),
        "strongly_connected_components": len(sccs),
        "largest_component": max((len(c) for c in sccs), default=0),
        "dead_ends": len(dead),
        "longest_shortest_path": max(lengths.values(), default=0),
        "graphml": str(graphml) if graphml else None,
    }


def text(report: Report) -> str:
    d = report.as_dict()
    lines = [
        f"system {d['system']}: {d['axes']} axis(es), {d['tags']} tags, {d['initial_states']} initial state(s)",
        f"  {d['states']:,} states, {d['transitions']:,} transitions, depth {d['depth']}, "
        f"{d['seconds']} s ({d['states_per_second']:,} states/s), peak memory {d['peak_memory_mb']} MB",
    ]
    m = report.result.model
    if m.add_ons:
        lines.append("  add-on instruction tags: " + ", ".join(f"{a.name} ({a.add_on.id})" for a in m.add_ons)
                     + (f"; at most {m.max_changes} change(s) per run" if m.max_changes is not None else ""))
    if not report.result.complete:
        lines.append(f"  INCOMPLETE: {report.result.stop_reason}")
    lines.append("properties:")
    for v in report.verdicts:
        mark = {True: "holds   ", False: "VIOLATED", None: "unknown "}[v.holds]
        lines.append(f"  {mark} {v.prop.name} ({v.prop.kind}): {v.detail}")
        if v.scenario is not None:
            lines.append(f"           counterexample: {v.scenario}")
    lines.append("coverage:")
    for name, t in report.coverage.items():
        extra = ""
        if name == "error_codes" and t.unreached:
            ex = report.explained.get("error_codes", {})
            extra = "; unreached: " + ", ".join(f"{i} ({'explained' if i in ex else 'UNEXPLAINED'})" for i in t.unreached)
        elif t.unreached and len(t.unreached) <= 8:
            extra = "; unreached: " + ", ".join(t.unreached)
        lines.append(f"  {name}: {len(t.reached)}/{t.total}{extra}")
    if report.graph is not None:
        g = report.graph
        lines.append(f"graph: {g['nodes']} nodes, {g['edges']} edges, {g['strongly_connected_components']} strongly "
                     f"connected components (largest {g['largest_component']}), {g['dead_ends']} dead ends"
                     + (f"; written to {g['graphml']}" if g.get("graphml") else ""))
    for v in report.verdicts:
        if v.trace is not None and v.holds is False:
            lines.append(f"\ncounterexample for {v.prop.name}:")
            lines.append(table_text(v.trace).rstrip("\n"))
    lines.append({0: "verdict: every property holds", 1: "verdict: VIOLATED",
                  3: "verdict: INCOMPLETE (raise --max-states / --max-seconds)"}[report.exit_code])
    return "\n".join(lines) + "\n"
