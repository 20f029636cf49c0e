"""The SCXML export runs on python-statemachine's own SCXML reader exactly as the engine runs the IR.

Property: for each chart, the exported document is loaded with
``statemachine.io.load(text, format="scxml")`` (the reader's default, restricted
expression evaluator), and it and :class:`statecharts.engine.AxisInstance` are given
the same random initial values of the chart's input variables (those no action writes)
and the same random event sequence.  After every event the active configurations and
every chart variable must be equal.  Environment events' drive-model assignments are
applied to both before the event is sent, as :mod:`statecharts.scan` does.

Two independent encodings are compared (our SCXML text through the library's XML
reader and evaluator; our IR through the engine's dict definition and compiled
closures), so this is not the spec checked against itself.

Charts: every chart of the bundled spec, and ``tests/snapshots/demo_every_construct.yaml``,
a fixture using parallel regions, shallow and deep history, a final state, eventless
and targetless transitions and every rewritten expression form.

Strict expected failures (each turns into a failure the day it starts passing):

* the engine gives a history pseudo-state no default transition, so entering one that
  was never visited leaves python-statemachine with an empty configuration, where SCXML
  (and our export) takes the default: the parent's initial state.  The same comparison
  with the engine built *with* those defaults passes;
* two limitations of python-statemachine 3.2.2's reader that the exporter works around,
  pinned here so the workarounds can go when the reader lifts them: no ``in`` operator
  in its restricted evaluator, and a class from ``load()`` initialises its datamodel
  only for its first instance (so every comparison loads a fresh class).
"""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree as ET

import pytest
from conftest import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from statemachine.io import load

from statecharts import ir
from statecharts.engine import AxisInstance
from statecharts.expr import parse_assignment, parse_expression
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.render.scxml import ScxmlUnsupported, chart_scxml, translate_assignment, translate_guard

FIXTURE = Path(__file__).parent / "snapshots" / "demo_every_construct.yaml"
SCXML_NS = "{http://www.w3.org/2005/07/scxml}"
MAX_EVENTS = 25
#: Real values tried for unbounded real inputs: inside, on and beyond the clamps.
REALS = (-150.0, -10.0, -5.0, -0.5, 0.0, 0.5, 2.5, 10.0, 50.0)

_SPEC_WITH_FIXTURE: ir.Spec | None = None


def spec_with_fixture() -> ir.Spec:
    global _SPEC_WITH_FIXTURE
    if _SPEC_WITH_FIXTURE is None:
        _SPEC_WITH_FIXTURE = load_spec([bundled_spec_dir(), FIXTURE])
    return _SPEC_WITH_FIXTURE


def input_variables(chart: ir.Chart) -> list[ir.Variable]:
    """Variables no entry, exit or transition action writes: free to start anywhere."""
    written = {a.target for s in chart.states for a in (*s.entry, *s.exit)}
    written |= {a.target for t in chart.transitions for a in t.actions}
    return [v for v in chart.variables if v.name not in written]


def initial_values(chart: ir.Chart) -> st.SearchStrategy[dict[str, object]]:
    fields: dict[str, st.SearchStrategy[object]] = {}
    for v in input_variables(chart):
        if v.domain is not None:
            fields[v.name] = st.sampled_from(list(v.domain))
        elif v.type == "real":
            fields[v.name] = st.sampled_from(REALS)
    return st.fixed_dictionaries(fields)


def run_both(chart: ir.Chart, init: dict[str, object], events: list[str]) -> None:
    axis = AxisInstance(chart, "A", variables=init)
    # a fresh class per run: the reader initialises the datamodel of its first instance only
    sm = load(chart_scxml(chart, initial=init), format="scxml")()
    by_name = {e.name: e for e in chart.events}

    def agree(step: str) -> None:
        ours = set(axis.active)
        theirs = {str(v) for v in sm.configuration_values}
        assert ours == theirs, f"after {step}: engine {sorted(ours)} != SCXML {sorted(theirs)}"
        for v in chart.variables:
            a, b = axis.env[v.name], getattr(sm.model, v.name, "<missing>")
            # a bool must stay a bool (``True == 1``): the rewrites of and/or depend on it
            same = a == b and isinstance(a, bool) == isinstance(b, bool)
            assert same, f"after {step}: {v.name} engine {a!r} != SCXML {b!r}"

    agree("start")
    for i, ev in enumerate(events):
        axis.apply_event_actions(ev)
        for a in by_name[ev].actions:
            env = {v.name: getattr(sm.model, v.name) for v in chart.variables}
            setattr(sm.model, a.target, a.value(env))
        axis.send(ev)
        sm.send(ev)
        agree(f"event {i + 1} {ev!r} of {events}")


def event_sequences(chart: ir.Chart) -> st.SearchStrategy[list[str]]:
    return st.lists(st.sampled_from([e.name for e in chart.events]), max_size=MAX_EVENTS)


_SETTINGS = settings(max_examples=examples(40))  # make deep: the deep profile's count


# --------------------------------------------------------------------------- the property


@pytest.mark.parametrize("chart_id", [c.id for c in load_spec().charts])
def test_bundled_chart_scxml_behaves_like_engine(chart_id: str) -> None:
    chart = load_spec().chart(chart_id)

    @_SETTINGS
    @given(init=initial_values(chart), events=event_sequences(chart))
    def prop(init: dict[str, object], events: list[str]) -> None:
        run_both(chart, init, events)

    prop()


def test_fixture_scxml_behaves_like_engine() -> None:
    chart = spec_with_fixture().chart("DemoEveryConstruct")

    @_SETTINGS
    @given(init=initial_values(chart), events=event_sequences(chart))
    def prop(init: dict[str, object], events: list[str]) -> None:
        run_both(chart, init, events)

    prop()


def test_fixture_history_resume_from_the_start() -> None:
    """A never-visited history enters the region's initial state, in the export as in the engine."""
    chart = spec_with_fixture().chart("DemoEveryConstruct")
    sm = load(chart_scxml(chart), format="scxml")()
    sm.send("resume")  # Mode is 'A': to the deep history of Lamp, never visited
    assert {str(v) for v in sm.configuration_values} == {"Running", "Motor", "MotorOff", "Lamp", "Dark"}


# --------------------------------------------------------------------------- the document


def test_document_is_scxml_with_every_construct() -> None:
    chart = spec_with_fixture().chart("DemoEveryConstruct")
    root = ET.fromstring(chart_scxml(chart))
    assert root.tag == f"{SCXML_NS}scxml" and root.get("version") == "1.0"
    data = [d.get("id") for d in root.iter(f"{SCXML_NS}data")]
    assert set(data) >= {v.name for v in chart.variables}
    tags = {el.tag.removeprefix(SCXML_NS) for el in root.iter()}
    assert {"state", "parallel", "history", "final", "transition", "assign", "onentry", "onexit", "if", "else"} <= tags
    histories = {h.get("id"): h.get("type") for h in root.iter(f"{SCXML_NS}history")}
    assert histories == {"MotorHist": "shallow", "LampHist": "deep"}
    for h in root.iter(f"{SCXML_NS}history"):
        assert len(h.findall(f"{SCXML_NS}transition")) == 1  # the default history transition
    eventless = [t for t in root.iter(f"{SCXML_NS}transition") if t.get("event") is None and t.get("cond")]
    assert eventless, "eventless transitions keep their cond and have no event"


def test_generated_file_loads_by_path(tmp_path: Path) -> None:
    chart = load_spec().chart("AxisNonCIP")
    path = tmp_path / "AxisNonCIP.scxml"
    path.write_text(chart_scxml(chart), encoding="utf-8")
    sm = load(str(path), format="scxml")()
    sm.send("servo_on")
    # Servo Control is state value 2 of the non-CIP axis (domain-facts §3a)
    assert {str(v) for v in sm.configuration_values} == {"Operating", "ServoControl"}
    assert sm.model.ServoActionStatus is True and sm.model.DriveEnableStatus is True


def test_export_is_deterministic() -> None:
    chart = load_spec().chart("AxisNonCIP")
    assert chart_scxml(chart) == chart_scxml(chart)


# --------------------------------------------------------------------------- expression rewrites


def test_membership_becomes_comparisons() -> None:
    assert translate_guard(parse_expression("Mode in ('B', 'C')")) == "Mode == 'B' or Mode == 'C'"
    assert translate_guard(parse_expression("Mode not in ('B', 'C')")) == "Mode != 'B' and Mode != 'C'"
    assert translate_guard(parse_expression("Mode in ()")) == "False"


def test_min_max_become_conditional_assigns() -> None:
    lines = translate_assignment(parse_assignment("Y = max(-L, min(L, X))"))
    text = "\n".join(lines)
    assert "max" not in text and "min" not in text
    assert text.count("<if ") == 3 and text.count("<assign ") == 4


def test_boolean_value_is_a_bool() -> None:
    (line,) = translate_assignment(parse_assignment("Busy = Count > 2 and Flag"))
    assert 'expr="not not (Count &gt; 2 and Flag)"' in line


@pytest.mark.parametrize("text, what", [
    ("Mode in Modes", "membership"),
    ("axis.Moving", "dotted name"),
    ("Mode == 'true'", "true/false/null"),
    ("state == 1", "reserved"),
])
def test_untranslatable_guards_are_refused(text: str, what: str) -> None:
    with pytest.raises(ScxmlUnsupported) as info:
        translate_guard(parse_expression(text), "C", "guard")
    assert what in str(info.value)


# --------------------------------------------------------------------------- reader limitations


_MEMBERSHIP_DOC = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="a">
<datamodel><data id="x" expr="'B'"/></datamodel>
<state id="a"><transition event="go" cond="x in ('B', 'C')" target="b"/></state><state id="b"/></scxml>"""


@pytest.mark.xfail(strict=True, raises=KeyError,
                   reason="python-statemachine 3.2.2's restricted evaluator has no 'in' operator; "
                          "the exporter rewrites membership into == / != comparisons")
def test_reader_evaluates_membership() -> None:
    sm = load(_MEMBERSHIP_DOC, format="scxml")()
    sm.send("go")
    assert {str(v) for v in sm.configuration_values} == {"b"}


@pytest.mark.xfail(strict=True, reason="python-statemachine 3.2.2 runs a loaded class's <datamodel> for its "
                                       "first instance only; the property test loads a class per run")
def test_reader_initialises_every_instance() -> None:
    cls = load(_MEMBERSHIP_DOC, format="scxml")
    cls()
    assert cls().model.x == "B"
