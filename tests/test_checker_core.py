"""The compiled checker core against the interpreter back-end of the search.

Two implementations of the same transition system: :func:`checker.search.explore_interpreted`
loads a whole :class:`statecharts.scan.System` of IR-interpreted axes for every step,
:func:`checker.search.explore` composes memoised pieces over integer vectors
(:mod:`checker.core`).  They must build the same state graph: the same numbers of
states and transitions, the same depth, the same verdicts (each property violated or
reached at the same least depth), the same deadlocks and the same coverage -- on random
small systems drawn from the spec, on samples cut from every bundled system (here) and on
every bundled system in full (``make deep``, ``test_bundled_systems_agree``, marked
``deep``: the interpreter needs minutes for them).
"""

from __future__ import annotations

import pytest
from conftest import sampled
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from checker.model import Model, ModelError
from checker.properties import load_properties
from checker.search import SearchResult, explore, explore_interpreted, stored_bytes, witness_run
from checker.system import SystemDef, bundled_systems, load_system
from motionchart.strategies import checking_systems
from statecharts import ir

#: random systems larger than this are skipped (the interpreter explores them slowly)
LIMIT = 2000


def _same(a: SearchResult, b: SearchResult) -> None:
    ga, gb = _graph(a), _graph(b)
    for key in ga:
        assert ga[key] == gb[key], f"{key}: compiled {ga[key]!r} != interpreted {gb[key]!r}"


def _graph(r: SearchResult) -> dict[str, object]:
    cov = r.coverage
    return {
        "states": r.states, "transitions": r.transitions, "depth": r.depth, "complete": r.complete,
        "violated": {k: w.depth for k, w in r.violations.items()},
        "reached": {k: w.depth for k, w in r.reached.items()},
        "deadlocks": len(r.deadlocks),
        "configs": cov.configs, "fired": cov.fired, "executed": cov.executed, "errors": cov.errors,
        "values": cov.values, "checks": cov.checks,
    }


@pytest.fixture(scope="module")
def base(spec: ir.Spec) -> SystemDef:
    return load_system(bundled_systems()["noncip"], spec)


@settings(suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much], max_examples=10)
@given(data=st.data())
def test_random_small_systems_agree(spec: ir.Spec, base: SystemDef, data: st.DataObject) -> None:
    sysdef = data.draw(checking_systems(spec, base), label="system")
    props = load_properties(spec)
    try:
        compiled = explore(Model(spec, sysdef, props), progress=False, max_states=LIMIT)
    except ModelError:
        assume(False)
        return
    assume(compiled.complete)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False)
    _same(compiled, interpreted)


@pytest.mark.parametrize("program", sampled(["MSO", "MSO MAFR"], fast={"MSO"}))
def test_two_interchangeable_axes_agree(spec: ir.Spec, base: SystemDef, program: str) -> None:
    """(make test: MSO only, about 5,000 states; make deep: MSO and MAFR, about 11,000.)"""
    import dataclasses

    g = dataclasses.replace(base.groups[0], count=2, program=tuple(program.split()),
                            configurations=base.groups[0].configurations[:1])
    sysdef = dataclasses.replace(base, name="two_axes", groups=(g,), max_live_calls=1)
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False)
    assert compiled.complete and compiled.states > 20
    _same(compiled, interpreted)


def test_coverage_witnesses_are_shortest_runs(spec: ir.Spec, base: SystemDef) -> None:
    """The core credits every coverage item to a step of least depth: the same items
    as the interpreter back-end, with runs of the same length, and the run replays on
    the engine showing the item."""
    import dataclasses

    g = dataclasses.replace(base.groups[0], program=("MSO", "MDO", "MAFR"), configurations=base.groups[0].configurations[:2])
    sysdef = dataclasses.replace(base, name="witnesses", groups=(g,), max_live_calls=1)
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False, witnesses=True)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False, witnesses=True)
    assert set(compiled.coverage.first) == set(interpreted.coverage.first)
    kinds = {item[0] for item in compiled.coverage.first}
    assert kinds == {"transition", "cell", "error", "check"}
    for item in compiled.coverage.first:
        run = witness_run(compiled, item)
        assert len(run.choices) == len(witness_run(interpreted, item).choices), item
        assert run.states[0] in compiled.initial_assignment and len(run.states) == len(run.choices)
        # the run, scan by scan on the model's System: its last scan shows the item
        model = compiled.model
        model.initial(model.assignments[run.assignment])
        for c in run.choices:
            facts = model.step(model.choices[c])[3]
        shown = {("transition", *f) for f in facts.fired} | {("cell", *f) for f in facts.executed}
        shown |= {("error", *f) for f in facts.errors} | {("check", *f) for f in facts.checks}
        assert item in shown, (item, run)
    with pytest.raises(KeyError):
        witness_run(compiled, ("transition", "AxisNonCIP", "no_such_transition"))


#: The bundled systems whose samples are compared below: all but those with add-on instruction
#: tags, compared on a bound of their own (the next test; tests/test_checker_aoi.py explores them)
CORE_SYSTEMS = sorted(set(bundled_systems()) - {"aoi"})


def test_an_add_on_system_on_the_core_agrees_with_the_interpreter(spec: ir.Spec) -> None:
    """The add-on instruction system with no change (the first configurations; rungs, scans and
    prescans): the core numbers and stores the
    states (an add-on tag's part and the changes left follow the axis blocks) and expands
    them on the interpreter's step, so the two searches must find the same graph."""
    import dataclasses
    sysdef = dataclasses.replace(load_system(bundled_systems()["aoi"], spec), max_changes=0)
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False, witnesses=True)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False, witnesses=True)
    assert compiled.core is not None and compiled.complete and compiled.states > 100
    _same(compiled, interpreted)
    assert set(compiled.coverage.first) == set(interpreted.coverage.first)


def _sample(sysdef: SystemDef, part: str) -> SystemDef:
    """A small system cut from a bundled one: every configuration, the first (``head``)
    or last (``tail``) two instructions of each axis's program and four of its events."""
    import dataclasses

    def cut(items: tuple[str, ...], n: int) -> tuple[str, ...]:
        return items[:n] if part == "head" else items[-n:]

    groups = tuple(dataclasses.replace(g, program=cut(g.program, 2)) for g in sysdef.groups)
    env = cut(sysdef.environment, 4) if sysdef.environment is not None else None
    return dataclasses.replace(sysdef, name=f"{sysdef.name}_{part}", groups=groups, environment=env)


@pytest.mark.parametrize("part", ["head", "tail"])
@pytest.mark.parametrize("name", CORE_SYSTEMS)
def test_bundled_system_samples_agree(spec: ir.Spec, name: str, part: str) -> None:
    """The fast sample of the bundled-system comparison below: each bundled system cut
    down to two instructions and four events, with all its configurations, limits and
    abstractions."""
    sysdef = _sample(load_system(bundled_systems()[name], spec), part)
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False, witnesses=True)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False, witnesses=True)
    assert compiled.complete and compiled.states > 100
    _same(compiled, interpreted)
    assert set(compiled.coverage.first) == set(interpreted.coverage.first)


@pytest.mark.deep
@pytest.mark.parametrize("name", CORE_SYSTEMS)
def test_bundled_systems_agree(spec: ir.Spec, name: str) -> None:
    sysdef = load_system(bundled_systems()[name], spec)
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False)
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False)
    assert compiled.complete and interpreted.complete
    _same(compiled, interpreted)


def test_stored_state_is_compact(spec: ir.Spec, base: SystemDef) -> None:
    result = explore(Model(spec, base, load_properties(spec)), progress=False, max_states=20000)
    per_state = stored_bytes(result) / result.states
    assert per_state < 200, per_state


@pytest.mark.parametrize("order", ["slave_first", "master_first"])
def test_a_slave_and_its_master_axis_agree(spec: ir.Spec, order: str) -> None:
    """A call that reads a second axis (MAG's checks read its bound master): with the
    master after its slave the core memoises the slave's pieces per master core, with
    the master first it expands states on the interpreter; both build the interpreter's
    graph, coverage and witnesses."""
    import dataclasses
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "conformance" / "systems" / "mag_virtual.yaml"
    sysdef = dataclasses.replace(load_system(path, spec), prescan=False)
    if order == "master_first":
        sysdef = dataclasses.replace(sysdef, groups=tuple(reversed(sysdef.groups)))
    assert sysdef.groups[0].name == ("Slave" if order == "slave_first" else "Master")
    props = load_properties(spec)
    compiled = explore(Model(spec, sysdef, props), progress=False, witnesses=True)
    from checker.core import CompiledModel

    core = compiled.core
    assert isinstance(core, CompiledModel)
    assert (core._couple is None) == (order == "master_first")
    interpreted = explore_interpreted(Model(spec, sysdef, props), progress=False, witnesses=True)
    assert compiled.complete and compiled.states > 1000
    _same(compiled, interpreted)
    assert set(compiled.coverage.first) == set(interpreted.coverage.first)
    assert ("MAG_VIRTUAL", "master_homing") in compiled.coverage.checks
