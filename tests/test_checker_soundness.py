"""Soundness of the checker's abstractions: every engine run is a path of the checker.

A run of the *engine* (python-statemachine axes, no abstraction at all) is driven by
inputs of the checker's alphabet (one change per scan, within the system's live-call
bound).  After every scan the engine's state is mapped through the abstraction (the
clock phase, collapsed variables left out, dead operands reset, idle tags retired,
axes sorted under symmetry) and must be one of the checker's successors of the
previous abstract state.  This is what makes "holds" mean something: no engine
behaviour is missing from the search.  The same run on the checker's own back-end
(the IR interpreter, concrete) must give the same observations scan by scan.
"""

from __future__ import annotations

import dataclasses

import pytest
from conftest import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from checker.compile import FastAxis
from checker.model import Model
from checker.properties import load_properties
from checker.search import Codec
from checker.system import SystemDef, bundled_systems, load_system
from statecharts import ir
from statecharts.engine import AxisInstance

#: The systems the soundness run explores: every bundled one, ``two_axes`` and a slave
#: axis geared to a master axis, listed after it and before it (below).
SYSTEMS = ("cip", "motion", "noncip", "noncip_pairs", "two_axes", "geared", "geared_master_first")
#: The bundled systems with add-on instruction tags: explored with fewer runs (every step of
#: the check scans each of the checker's choices on the whole system).
ADD_ON_SYSTEMS = ("aoi",)


def _systems(spec: ir.Spec) -> dict[str, SystemDef]:
    out = {name: load_system(path, spec) for name, path in bundled_systems().items() if name not in ADD_ON_SYSTEMS}
    # two interchangeable axes with a small program, to exercise symmetry reduction
    base = out["noncip"]
    g = dataclasses.replace(base.groups[0], count=2, program=("MSO", "MDO", "MASD", "MAFR"))
    out["two_axes"] = dataclasses.replace(base, name="two_axes", groups=(g,), max_live_calls=1)
    # a slave axis whose MAG reads its bound master axis (a conformance system), and the
    # same with the master listed first (the core then expands states on the interpreter)
    from pathlib import Path
    geared = load_system(Path(__file__).resolve().parents[1] / "conformance" / "systems" / "mag_virtual.yaml", spec)
    out["geared"] = geared
    out["geared_master_first"] = dataclasses.replace(geared, name="geared_master_first",
                                                     groups=tuple(reversed(geared.groups)))
    return out


@pytest.fixture(scope="module")
def models(spec: ir.Spec) -> dict[str, Model]:
    props = load_properties(spec)
    return {name: Model(spec, sd, props) for name, sd in _systems(spec).items()}


def _abstract(model: Model, codec: Codec, snapshot: tuple[object, ...], monitors: list[tuple[int, ...]],
              budget: int | None = None) -> tuple[bytes, list[tuple[int, ...]]]:
    """alpha(concrete state): load it exactly, update the monitors, extract, encode.  ``budget``:
    the changes the run has left (the checker's own count, no state of the engine)."""
    model.system.restore(snapshot)
    model.monitor_values = list(monitors)
    model.budget = budget
    model.evaluate()
    return codec.encode(model.extract()), list(model.monitor_values)


def _successors(model: Model, codec: Codec, code: bytes) -> set[bytes]:
    flat = codec.decode(code)
    model.load(flat)
    out = set()
    for choice in model.enabled():
        model.load(flat)
        succ, _bad, _good, _facts = model.step(choice)
        out.add(codec.encode(succ))
    return out


def _offered(model: Model, snapshot: tuple[object, ...], budget: int | None = None) -> list[int]:
    """The checker's choices in a concrete state (not its canonical representative:
    under symmetry the two may name the axes differently)."""
    model.system.restore(snapshot)
    model.budget = budget
    return [c.index for c in model.enabled()]


def test_every_bundled_system_is_explored() -> None:
    assert set(bundled_systems()) | {"two_axes", "geared", "geared_master_first"} == set(SYSTEMS) | set(ADD_ON_SYSTEMS)


@pytest.mark.parametrize("name", ADD_ON_SYSTEMS)
@settings(max_examples=examples(6, 200))
@given(data=st.data())
def test_every_engine_run_of_an_add_on_system_is_a_path_of_the_checker(spec: ir.Spec, name: str,
                                                                         data: st.DataObject) -> None:
    model = Model(spec, load_system(bundled_systems()[name], spec), load_properties(spec))
    _engine_run_is_a_checker_path(model, data, max_scans=25)


@pytest.mark.parametrize("name", SYSTEMS)
@settings(max_examples=examples(40))  # make deep: the deep profile's count, and the long runs below
@given(data=st.data())
def test_every_engine_run_is_a_path_of_the_checker(models: dict[str, Model], name: str, data: st.DataObject) -> None:
    _engine_run_is_a_checker_path(models[name], data, max_scans=25)


@pytest.mark.deep
@pytest.mark.parametrize("name", SYSTEMS)
@given(data=st.data())
def test_every_long_engine_run_is_a_path_of_the_checker(models: dict[str, Model], name: str,
                                                        data: st.DataObject) -> None:
    _engine_run_is_a_checker_path(models[name], data, max_scans=120)


def _engine_run_is_a_checker_path(model: Model, data: st.DataObject, max_scans: int) -> None:
    codec = Codec(model)
    assignment = model.assignments[data.draw(st.integers(0, len(model.assignments) - 1), label="configuration")]
    engine = model.build_system(assignment, backend=AxisInstance)
    fast = model.build_system(assignment, backend=FastAxis)
    flat0, _bad, _good = model.initial(assignment)
    code = codec.encode(flat0)
    monitors = list(model.monitor_values)
    budget = model.budget
    assert _abstract(model, codec, engine.snapshot(), monitors, budget)[0] == code
    for step in range(data.draw(st.integers(1, max_scans), label="scans")):
        succs = _successors(model, codec, code)
        choice = model.choices[data.draw(st.sampled_from(_offered(model, engine.snapshot(), budget)),
                                         label=f"choice {step}")]
        if budget is not None and choice.index in model.counted:
            budget -= 1
        r_engine = engine.scan(choice.inputs)
        r_fast = fast.scan(choice.inputs)
        assert dict(r_engine.observations) == dict(r_fast.observations), f"scan {step}: back-ends differ"
        code, monitors = _abstract(model, codec, engine.snapshot(), monitors, budget)
        assert code in succs, (
            f"scan {step} ({choice.label()}): the engine's state, mapped through the abstraction, "
            "is not a successor in the checker")


def test_collapse_refuses_a_variable_that_control_reads(spec: ir.Spec) -> None:
    from checker.model import ModelError

    sd = dataclasses.replace(load_system(bundled_systems()["noncip"], spec), collapse=("EnableTimer",))
    with pytest.raises(ModelError, match="cannot collapse EnableTimer"):
        Model(spec, sd, load_properties(spec))


def test_idle_tags_of_the_state_instructions_may_retire(spec: ir.Spec) -> None:
    from checker.model import retirement_check

    for ins in spec.instructions:
        assert retirement_check(spec, ins) is None, ins.id


def test_retirement_is_refused_when_a_rise_reads_a_kept_bit(spec: ir.Spec) -> None:
    """A table whose rise does not execute but counts in ERR: an idle tag's ERR then matters."""
    from checker.model import retirement_check
    from statecharts.expr import parse_assignment

    ins = spec.instruction("MSO")
    rows = tuple(dataclasses.replace(r, execute=False, actions=(parse_assignment("EN = True"), parse_assignment("ERR = ERR + 1")))
                 if r.condition == "rung_true" else r for r in ins.table.rows)
    broken = dataclasses.replace(ins, table=dataclasses.replace(ins.table, rows=rows))
    assert retirement_check(spec, broken) is not None
