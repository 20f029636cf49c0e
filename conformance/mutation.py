"""Mutation score of the conformance suite: how many faulty specs the vectors tell apart.

Pipeline position: IR -> **conformance.mutation** (mutants) -> the reference adapter
(:class:`conformance.adapter.ReferenceAdapter`, in process, plus a sample through a
``motionchart adapter --mutant ID`` child process) -> :func:`conformance.runner`'s
worker, one vector after another until one fails -> ``motionchart mutate --score``.

Mutants (one change each, deterministic order, stable ids):

* ``drop_guard C:T`` -- transition T of chart C loses its guard;
* ``swap_target C:T->S`` -- transition T goes to leaf state S (the next leaf after its
  target in document order);
* ``err I.K`` / ``exerr I.K`` -- check or abort K of instruction I reports ERR + 1 /
  EXERR + 1;
* ``reorder I.K<->L`` -- adjacent checks K and L of instruction I are swapped;
* ``timer ... +1`` / ``-1`` -- an action assigning a timer or update counter of a chart
  gets one more / one less;
* ``flip ...`` -- an action assigning a boolean constant (a status bit of a chart or a
  MOTION_INSTRUCTION bit of an execution table) assigns the other value.

Only elements that the suite's vectors can reach are mutated: the charts and
instructions that some vector uses.  A mutant is *killed* when some vector fails
(a wrong observation, or the adapter reporting an error) on it.  A mutant that
survives is either listed in ``equivalent_mutants.yaml`` with the reason it cannot be
told apart by any run, or reported as a vector the suite lacks.
"""

from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from statecharts import ir
from statecharts.expr import Assignment, parse_assignment

EQUIVALENTS_FILE = Path(__file__).resolve().parent / "equivalent_mutants.yaml"


@dataclass(frozen=True, slots=True)
class Mutant:
    id: str
    kind: str
    chart: str | None
    instruction: str | None
    build: Callable[[ir.Spec], ir.Spec] = field(compare=False, repr=False)


# --------------------------------------------------------------------------- building blocks


def _replace_chart(spec: ir.Spec, chart: ir.Chart) -> ir.Spec:
    return dataclasses.replace(spec, charts=tuple(chart if c.id == chart.id else c for c in spec.charts))


def _replace_instruction(spec: ir.Spec, ins: ir.Instruction) -> ir.Spec:
    return dataclasses.replace(spec, instructions=tuple(ins if i.id == ins.id else i for i in spec.instructions))


def _with_transition(spec: ir.Spec, cid: str, tid: str, **changes: Any) -> ir.Spec:
    chart = spec.chart(cid)
    ts = tuple(dataclasses.replace(t, **changes) if t.id == tid else t for t in chart.transitions)
    return _replace_chart(spec, dataclasses.replace(chart, transitions=ts))


def _assign(a: Assignment, text: str) -> Assignment:
    return parse_assignment(text)


_BOOL = re.compile(r"^\s*(?P<t>[A-Za-z_][A-Za-z0-9_.]*)\s*=\s*(?P<v>true|false|True|False)\s*$")
_TIMER = re.compile(r"(Timer|Updates)$")


def _flipped(a: Assignment) -> Assignment | None:
    m = _BOOL.match(a.text)
    if not m:
        return None
    new = "false" if m["v"].lower() == "true" else "true"
    return parse_assignment(f"{m['t']} = {new}")


def _shifted(a: Assignment, delta: int) -> Assignment | None:
    if not _TIMER.search(a.target.split(".")[-1]) or "+=" in a.text or "-=" in a.text:
        return None
    rhs = a.text.split("=", 1)[1].strip()
    sign = "+" if delta > 0 else "-"
    try:
        return parse_assignment(f"{a.target} = ({rhs}) {sign} {abs(delta)}")
    except Exception:
        return None


def _action_sites(chart: ir.Chart) -> Iterator[tuple[str, str, int, Assignment]]:
    """(where, element id, index, assignment) of every action of the chart, in document order."""
    for s in chart.states:
        for i, a in enumerate(s.entry):
            yield "entry", s.id, i, a
        for i, a in enumerate(s.exit):
            yield "exit", s.id, i, a
    for t in chart.transitions:
        for i, a in enumerate(t.actions):
            yield "transition", t.id, i, a
    for e in chart.events:
        for i, a in enumerate(e.actions):
            yield "event", e.name, i, a


def _replace_action(spec: ir.Spec, cid: str, where: str, elem: str, i: int, new: Assignment) -> ir.Spec:
    chart = spec.chart(cid)

    def sub(actions: tuple[Assignment, ...]) -> tuple[Assignment, ...]:
        return tuple(new if k == i else a for k, a in enumerate(actions))

    if where == "entry":
        chart = dataclasses.replace(chart, states=tuple(
            dataclasses.replace(s, entry=sub(s.entry)) if s.id == elem else s for s in chart.states))
    elif where == "exit":
        chart = dataclasses.replace(chart, states=tuple(
            dataclasses.replace(s, exit=sub(s.exit)) if s.id == elem else s for s in chart.states))
    elif where == "transition":
        chart = dataclasses.replace(chart, transitions=tuple(
            dataclasses.replace(t, actions=sub(t.actions)) if t.id == elem else t for t in chart.transitions))
    else:
        chart = dataclasses.replace(chart, events=tuple(
            dataclasses.replace(e, actions=sub(e.actions)) if e.name == elem else e for e in chart.events))
    return _replace_chart(spec, chart)


TABLE_PARTS = ("on_execute", "on_error", "on_accept", "on_done")


def _replace_table_action(spec: ir.Spec, iid: str, part: str, i: int, new: Assignment) -> ir.Spec:
    ins = spec.instruction(iid)
    table = ins.table
    if part.startswith("row:"):
        cond = part[4:]
        rows = tuple(dataclasses.replace(r, actions=tuple(new if k == i else a for k, a in enumerate(r.actions)))
                     if r.condition == cond else r for r in table.rows)
        table = dataclasses.replace(table, rows=rows)
    else:
        new_actions = tuple(new if k == i else a for k, a in enumerate(getattr(table, part)))
        if part == "on_execute":
            table = dataclasses.replace(table, on_execute=new_actions)
        elif part == "on_error":
            table = dataclasses.replace(table, on_error=new_actions)
        elif part == "on_accept":
            table = dataclasses.replace(table, on_accept=new_actions)
        else:
            table = dataclasses.replace(table, on_done=new_actions)
    return _replace_instruction(spec, dataclasses.replace(ins, table=table))


def _with_check(spec: ir.Spec, iid: str, cid: str, **changes: Any) -> ir.Spec:
    ins = spec.instruction(iid)

    def fix(cs: tuple[ir.Check, ...]) -> tuple[ir.Check, ...]:
        return tuple(dataclasses.replace(c, **changes) if c.id == cid else c for c in cs)

    return _replace_instruction(spec, dataclasses.replace(ins, checks=fix(ins.checks), aborts=fix(ins.aborts)))


def _swap_checks(spec: ir.Spec, iid: str, k: int) -> ir.Spec:
    ins = spec.instruction(iid)
    cs = list(ins.checks)
    cs[k], cs[k + 1] = cs[k + 1], cs[k]
    return _replace_instruction(spec, dataclasses.replace(ins, checks=tuple(cs)))


# --------------------------------------------------------------------------- the mutants


def mutants(spec: ir.Spec, charts: Sequence[str] | None = None, instructions: Sequence[str] | None = None) -> list[Mutant]:
    """Every mutant of ``spec`` in the given charts and instructions (default: all), in a fixed order."""
    out: list[Mutant] = []
    use_charts = [c for c in spec.charts if charts is None or c.id in charts]
    use_ins = [i for i in spec.instructions if instructions is None or i.id in instructions]
    for chart in use_charts:
        cid = chart.id
        leaves = [s.id for s in chart.leaf_states()]
        for t in chart.transitions:
            if t.guard is not None:
                out.append(Mutant(f"drop_guard {cid}:{t.id}", "drop_guard", cid, None,
                                  partial(_with_transition, cid=cid, tid=t.id, guard=None)))
            if t.target is not None and t.target in leaves and len(leaves) > 1:
                new = leaves[(leaves.index(t.target) + 1) % len(leaves)]
                out.append(Mutant(f"swap_target {cid}:{t.id}->{new}", "swap_target", cid, None,
                                  partial(_with_transition, cid=cid, tid=t.id, target=new)))
        for where, elem, i, a in _action_sites(chart):
            flipped = _flipped(a)
            if flipped is not None:
                out.append(Mutant(f"flip {cid}:{where}:{elem}[{i}] {a.text}", "flip_bit", cid, None,
                                  partial(_replace_action, cid=cid, where=where, elem=elem, i=i, new=flipped)))
            for delta in (1, -1):
                shifted = _shifted(a, delta)
                if shifted is not None:
                    out.append(Mutant(f"timer {cid}:{where}:{elem}[{i}] {a.text} {delta:+d}", "timer", cid, None,
                                      partial(_replace_action, cid=cid, where=where, elem=elem, i=i, new=shifted)))
    for ins in use_ins:
        iid = ins.id
        for chk in (*ins.checks, *ins.aborts):
            out.append(Mutant(f"err {iid}.{chk.id} {chk.err}->{chk.err + 1}", "error_code", None, iid,
                              partial(_with_check, iid=iid, cid=chk.id, err=chk.err + 1)))
            if chk.exerr:
                out.append(Mutant(f"exerr {iid}.{chk.id} {chk.exerr}->{chk.exerr + 1}", "exerr", None, iid,
                                  partial(_with_check, iid=iid, cid=chk.id, exerr=chk.exerr + 1)))
        for k in range(len(ins.checks) - 1):
            first, second = ins.checks[k], ins.checks[k + 1]
            out.append(Mutant(f"reorder {iid}.{first.id}<->{second.id}", "reorder", None, iid,
                              partial(_swap_checks, iid=iid, k=k)))
        table = ins.table
        parts: list[tuple[str, tuple[Assignment, ...]]] = [(p, getattr(table, p)) for p in TABLE_PARTS]
        parts += [(f"row:{r.condition}", r.actions) for r in table.rows]
        for part, actions in parts:
            for i, a in enumerate(actions):
                flipped = _flipped(a)
                if flipped is not None:
                    out.append(Mutant(f"flip {iid}:{part}[{i}] {a.text}", "flip_bit", None, iid,
                                      partial(_replace_table_action, iid=iid, part=part, i=i, new=flipped)))
    return out


# --------------------------------------------------------------------------- scoring


@dataclass
class MutantResult:
    mutant: Mutant
    killed: bool
    by: str = ""  # the vector that killed it
    detail: str = ""
    equivalent: str = ""  # reason, for a listed equivalent survivor
    via: str = "in-process"


@dataclass
class Score:
    results: list[MutantResult]
    seconds: float
    vectors: int

    @property
    def killed(self) -> int:
        return sum(r.killed for r in self.results)

    @property
    def equivalent(self) -> list[MutantResult]:
        return [r for r in self.results if not r.killed and r.equivalent]

    @property
    def missing(self) -> list[MutantResult]:
        return [r for r in self.results if not r.killed and not r.equivalent]

    @property
    def score(self) -> float:
        n = len(self.results) - len(self.equivalent)
        return self.killed / n if n else 1.0

    def by_kind(self) -> dict[str, tuple[int, int]]:
        out: dict[str, list[int]] = {}
        for r in self.results:
            k = out.setdefault(r.mutant.kind, [0, 0])
            k[0] += r.killed
            k[1] += 1
        return {k: (v[0], v[1]) for k, v in out.items()}

    def text(self) -> str:
        lines = [f"mutants: {len(self.results)} built, {self.killed} killed, {len(self.equivalent)} equivalent, "
                 f"{len(self.missing)} survived ({self.vectors} vectors, {self.seconds:.1f} s)"]
        for kind, (k, n) in sorted(self.by_kind().items()):
            lines.append(f"  {kind:<12} {k:>4}/{n:<4} killed")
        sub = [r for r in self.results if r.via != "in-process"]
        if sub:
            lines.append(f"  through a `motionchart adapter` child process: {sum(r.killed for r in sub)}/{len(sub)} killed")
        for r in self.equivalent:
            lines.append(f"  equivalent: {r.mutant.id}: {r.equivalent}")
        for r in self.missing:
            lines.append(f"  SURVIVED (a vector is missing): {r.mutant.id}")
        lines.append(f"mutation score: {self.score:.1%} of {len(self.results) - len(self.equivalent)} "
                     f"non-equivalent mutants killed")
        return "\n".join(lines) + "\n"

    def as_dict(self) -> dict[str, Any]:
        return {
            "mutants": len(self.results), "killed": self.killed, "equivalent": len(self.equivalent),
            "survived": len(self.missing), "score": self.score, "seconds": round(self.seconds, 3),
            "by_kind": {k: {"killed": a, "total": b} for k, (a, b) in self.by_kind().items()},
            "results": [{"id": r.mutant.id, "kind": r.mutant.kind, "killed": r.killed, "by": r.by,
                         "detail": r.detail, "equivalent": r.equivalent, "via": r.via} for r in self.results],
        }


def load_equivalents(path: Path = EQUIVALENTS_FILE) -> dict[str, str]:
    """Mutant id -> the reason it is equivalent (``equivalent_mutants.yaml``)."""
    if not path.is_file():
        return {}
    from statecharts.diagnostics import Diagnostic, InputError
    from statecharts.loader import plain_data, read_yaml
    errors: list[Diagnostic] = []
    tree = read_yaml(path, errors, what="equivalent mutants")
    if errors:
        raise InputError(errors)
    doc = plain_data(tree) if tree is not None else {}
    out: dict[str, str] = {}
    for entry in doc.get("equivalent", []):
        out[str(entry["mutant"])] = " ".join(str(entry["reason"]).split())
    return out


def relevant(vectors: Sequence[Mapping[str, Any]], m: Mutant, spec: ir.Spec) -> list[Mapping[str, Any]]:
    """The vectors that can observe the mutated element (its chart, or its instruction on its charts)."""
    out = []
    for v in vectors:
        families = set(v["requires"]["axis_families"])
        if m.chart is not None and m.chart in families:
            out.append(v)
        elif m.instruction is not None:
            ins = spec.instruction(m.instruction)
            if ins.mnemonic in v["requires"]["instructions"] and families & set(ins.charts):
                out.append(v)
    # short vectors first: a mutant is usually killed by the first one that reaches it
    return sorted(out, key=lambda v: (len(v["scans"]), v["id"]))


def try_mutant(m: Mutant, spec: ir.Spec, vectors: Sequence[Mapping[str, Any]],
               transport: Callable[[ir.Spec], Any]) -> MutantResult:
    from conformance import runner
    mutated = m.build(spec)
    worker = runner.Worker(lambda: transport(mutated), message_timeout=60.0, vector_timeout=600.0)
    try:
        for v in relevant(vectors, m, spec):
            verdict = worker.run(v)
            if verdict.verdict in ("fail", "error", "timeout"):
                return MutantResult(m, True, v["id"], verdict.detail)
    finally:
        worker.close()
    return MutantResult(m, False)


class BaselineError(RuntimeError):
    """The unmutated spec fails some vector on the back-end the mutants are served with:
    a kill there would say nothing about the mutant."""


def baseline(spec: ir.Spec, vectors: Sequence[Mapping[str, Any]]) -> None:
    """Every vector passes on the unmutated spec served as the mutants are (the checker's
    interpreter in process); raise :class:`BaselineError` naming those that do not."""
    from conformance import runner
    worker = runner.Worker(lambda: in_process(spec), message_timeout=60.0, vector_timeout=600.0)
    bad = []
    try:
        for v in vectors:
            verdict = worker.run(v)
            if verdict.verdict != "pass":
                bad.append(f"{v['id']}: {verdict.detail}")
    finally:
        worker.close()
    if bad:
        raise BaselineError("the unmutated spec does not pass every vector on the checker's interpreter, so the "
                            "interpreter and the engine disagree: " + "; ".join(bad[:5])
                            + (f" (and {len(bad) - 5} more)" if len(bad) > 5 else ""))


def in_process(mutated: ir.Spec) -> Any:
    from checker.compile import FastAxis
    from conformance.adapter import ReferenceAdapter
    from conformance.runner import InProcessTransport
    return InProcessTransport(ReferenceAdapter(mutated, backend=FastAxis))


def sample(ms: Sequence[Mutant], n: int) -> list[Mutant]:
    """``n`` mutants spread evenly over the list (every kind represented when n allows)."""
    if n >= len(ms):
        return list(ms)
    by_kind: dict[str, list[Mutant]] = {}
    for m in ms:
        by_kind.setdefault(m.kind, []).append(m)
    picked: list[Mutant] = []
    kinds = sorted(by_kind)
    i = 0
    while len(picked) < n:
        for k in kinds:
            group = by_kind[k]
            idx = i * max(1, len(group) // max(1, n // len(kinds) + 1))
            if idx < len(group) and group[idx] not in picked and len(picked) < n:
                picked.append(group[idx])
        i += 1
        if i > len(ms):
            break
    return [m for m in ms if m in picked]


def order_equivalence(spec: ir.Spec, m: Mutant, explained_orders: Mapping[str, str]) -> str:
    """Why a reorder mutant cannot be told apart, or "": the two checks report the same
    codes, or the exhaustive search of every system that runs the instruction found no
    evaluation where both fail (as the vector generator reports it in the manifest)."""
    if m.kind != "reorder" or m.instruction is None:
        return ""
    from conformance.vectors import observable_order, order_item
    ins = spec.instruction(m.instruction)
    a_id, b_id = m.id.split(" ", 1)[1].split(".", 1)[1].split("<->")
    k = next(i for i, c in enumerate(ins.checks) if c.id == a_id)
    if not observable_order(ins, k):
        c = ins.checks[k]
        return f"{a_id} and {b_id} both report ERR {c.err}, EXERR {c.exerr}; their order cannot be seen"
    reason = explained_orders.get(order_item(ins, k))
    # only an exhaustive search is a proof; runs that were tried are not
    if not reason or "exhaustive search" not in reason:
        return ""
    return f"the two checks never fail together: {reason}"


def guard_equivalence(m: Mutant, explained_refusals: Mapping[str, str]) -> str:
    """Why a dropped guard of a transition on an event cannot be told apart, or "": the
    exhaustive search never tries the transition with its guard false."""
    if m.kind != "drop_guard":
        return ""
    reason = explained_refusals.get(m.id.split(" ", 1)[1])
    if not reason or "exhaustive search" not in reason:
        return ""
    return f"the guard is never false where the transition is tried: {reason}"


def score(spec: ir.Spec, vectors: Sequence[Mapping[str, Any]], *, sample_size: int | None = None,
          subprocess_sample: int = 0, progress: Callable[[str], None] | None = None,
          equivalents: Mapping[str, str] | None = None, explained_orders: Mapping[str, str] | None = None,
          explained_refusals: Mapping[str, str] | None = None,
          **kwargs: Any) -> Score:
    """Build the mutants of what the vectors use, serve each through the reference adapter, score."""
    if "sample" in kwargs:
        sample_size = kwargs.pop("sample")
    explained_orders = explained_orders or {}
    t0 = time.monotonic()
    families = {f for v in vectors for f in v["requires"]["axis_families"]}
    mnemonics = {i for v in vectors for i in v["requires"]["instructions"]}
    ins_ids = [i.id for i in spec.instructions if i.mnemonic in mnemonics and families & set(i.charts)]
    baseline(spec, vectors)
    ms = mutants(spec, charts=sorted(families), instructions=ins_ids)
    if sample_size is not None:
        ms = sample(ms, sample_size)
    eq = load_equivalents() if equivalents is None else dict(equivalents)
    eq.update({m.id: why for m in ms if m.id not in eq and (why := order_equivalence(spec, m, explained_orders))})
    eq.update({m.id: why for m in ms if m.id not in eq and (why := guard_equivalence(m, explained_refusals or {}))})
    results: list[MutantResult] = []
    for n, m in enumerate(ms, 1):
        r = try_mutant(m, spec, vectors, in_process)
        if not r.killed:
            r.equivalent = eq.get(m.id, "")
        results.append(r)
        if progress and (n % 25 == 0 or n == len(ms)):
            progress(f"{n}/{len(ms)} mutants, {sum(x.killed for x in results)} killed")
    if subprocess_sample:
        import sys

        from conformance.runner import ProcessTransport
        # mutants killed by a wrong observation (not by the adapter refusing the mutant)
        killed = [r for r in results if r.killed and " expected " in r.detail][:subprocess_sample]
        for r in killed:
            cmd = f"{sys.executable} -m checker adapter --mutant {_quote(r.mutant.id)}"
            def child(_spec: ir.Spec, cmd: str = cmd) -> Any:
                return ProcessTransport(cmd)

            again = try_mutant(r.mutant, spec, [v for v in vectors if v["id"] == r.by], child)
            results.append(MutantResult(r.mutant, again.killed, again.by, again.detail, via="subprocess"))
            if progress:
                progress(f"subprocess: {r.mutant.id}: {'killed' if again.killed else 'NOT killed'}")
    sub = [r for r in results if r.via == "subprocess"]
    main = [r for r in results if r.via != "subprocess"]
    return _SubScore(main, time.monotonic() - t0, len(vectors), sub)


def _quote(text: str) -> str:
    import shlex
    return shlex.quote(text)


class _SubScore(Score):
    """The score over the in-process mutants, with the subprocess re-runs shown beside it."""

    def __init__(self, results: list[MutantResult], seconds: float, vectors: int, sub: list[MutantResult]) -> None:
        super().__init__(results, seconds, vectors)
        self.sub = sub

    def text(self) -> str:
        base = super().text()
        if not self.sub:
            return base
        lines = base.splitlines()
        extra = (f"  the same vectors through a `motionchart adapter --mutant` child process: "
                 f"{sum(r.killed for r in self.sub)}/{len(self.sub)} killed again")
        return "\n".join([*lines[:-1], extra, lines[-1]]) + "\n"

    def as_dict(self) -> dict[str, Any]:
        d = super().as_dict()
        d["subprocess"] = [{"id": r.mutant.id, "killed": r.killed, "by": r.by} for r in self.sub]
        return d


def find(spec: ir.Spec, mutant_id: str) -> Mutant:
    for m in mutants(spec):
        if m.id == mutant_id:
            return m
    raise KeyError(mutant_id)
