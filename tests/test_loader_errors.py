"""Bad spec input: every mistake is a located SpecError, never a traceback, never executed.

Each test copies the bundled spec to a temporary directory and breaks one file in one
way (through a ruamel round trip, so the rest of the file stays as written), then
asserts the diagnostics: which file, which line (found by searching the written text
for a marker unique to the change), which node path, and what was expected.  The
edits look the elements up by their role (a compound state, a transition with an
event...) rather than by name, so the tests survive additions to the bundled spec.

The last part is a hypothesis fuzz test: random damage to the spec files' text must
give a SpecError or a loaded spec, and nothing else.
"""

from __future__ import annotations

import functools
import io
import json
import os
import shutil
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from conftest import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from ruamel.yaml import YAML
from ruamel.yaml.comments import CommentedMap

from statecharts import loader
from statecharts.diagnostics import Diagnostic, SpecError
from statecharts.loader import MAX_YAML_DEPTH, MAX_YAML_NODES, bundled_spec_dir, load_spec, spec_files

BUNDLED = bundled_spec_dir()
CHART_FILE = "charts/axis_noncip.yaml"
INSTRUCTION_FILE = "instructions/MSO.yaml"
INTERPRETATIONS_FILE = "interpretations.yaml"
ERRORS_FILE = "errors.yaml"

_RT = YAML(typ="rt")
_RT.width = 100_000  # never fold long lines: markers must stay on one line
_RT.preserve_quotes = True

# --------------------------------------------------------------------------- helpers

_PRISTINE = {p.read_bytes() for p in spec_files()}
_PARSED: dict[bytes, Any] = {}  # the loader only reads the trees, so sharing them is safe


@contextmanager
def _parse_cache() -> Iterator[None]:
    """Reuse the parse of the spec files a test leaves alone (ruamel is slow).

    Only files identical to a bundled one are cached, by their exact bytes; an edited
    file is always parsed, so every test runs the real read_yaml on the damaged text.
    """
    real = loader.read_yaml

    def cached(path: Path, errors: list[Diagnostic], *, what: str = "file") -> Any:
        try:
            data = path.read_bytes()
        except OSError:
            data = b""
        if data not in _PRISTINE:
            return real(path, errors, what=what)
        if data not in _PARSED:
            _PARSED[data] = real(path, errors, what=what)
        return _PARSED[data]

    loader.read_yaml = cached
    try:
        yield
    finally:
        loader.read_yaml = real


@pytest.fixture(autouse=True, scope="module")
def _reuse_parses_of_untouched_files() -> Iterator[None]:
    with _parse_cache():
        yield


@pytest.fixture
def spec_dir(tmp_path: Path) -> Path:
    """A private copy of the bundled spec's YAML files."""
    d = tmp_path / "spec"
    shutil.copytree(BUNDLED, d, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema", "*.json"))
    return d


def edit(spec_dir: Path, rel: str, change: Callable[[Any], None]) -> Path:
    """Load ``rel`` as a round-trip tree, let ``change`` modify it, write it back."""
    path = spec_dir / rel
    tree = _RT.load(path.read_text(encoding="utf-8"))
    change(tree)
    buf = io.StringIO()
    _RT.dump(tree, buf)
    path.write_text(buf.getvalue(), encoding="utf-8")
    return path


def flow(**items: Any) -> CommentedMap:
    """A mapping written on one line (``{a: 1, b: 2}``), so its marker names its line."""
    m = CommentedMap()
    for k, v in items.items():
        if k == "source" and isinstance(v, str):
            v = f"MC spec/{v}"  # a resolvable citation (spec/sources.yaml) that still holds the marker
        m[k.rstrip("_")] = v  # from_ -> from
    m.fa.set_flow_style()
    return m


def line_of(path: Path, marker: str) -> int:
    lines = [i for i, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if marker in text]
    assert len(lines) == 1, f"marker {marker!r} found on lines {lines} of {path}"
    return lines[0]


def errors_of(paths: list[Path] | Path) -> tuple[Diagnostic, ...]:
    with pytest.raises(SpecError) as info:
        load_spec(paths if isinstance(paths, list) else [paths])
    diags = info.value.diagnostics
    assert diags, "a SpecError must carry diagnostics"
    return diags


def only_error(spec_dir: Path, path: Path, line: int, *fragments: str, node_path: str | None = None) -> Diagnostic:
    """Exactly one diagnostic, in ``path`` at ``line``, whose message holds every fragment."""
    diags = errors_of(spec_dir)
    assert len(diags) == 1, "\n".join(map(str, diags))
    d = diags[0]
    assert d.file == str(path)
    assert d.line == line, str(d)
    for frag in fragments:
        assert frag in d.message, str(d)
    if node_path is not None:
        assert d.path == node_path, str(d)
    assert str(d).startswith(f"{path}:{line}:")
    return d


def chart_of(tree: Any) -> Any:
    return tree["chart"]


def all_states(states: Any) -> Iterator[Any]:
    for s in states:
        yield s
        yield from all_states(s.get("states", []))


def event_transition(chart: Any) -> tuple[int, Any]:
    """A transition with an event and a target, no guard and no priority."""
    for i, t in enumerate(chart["transitions"]):
        if "event" in t and "to" in t and "guard" not in t and "priority" not in t:
            return i, t
    raise AssertionError("the bundled chart has no plain event transition")


def some_event(chart: Any) -> str:
    return str(chart["events"][0]["name"])


def leaf_id(chart: Any) -> str:
    return next(str(s["id"]) for s in all_states(chart["states"]) if "states" not in s)


def bool_variable(chart: Any) -> str:
    return next(str(v["name"]) for v in chart["variables"] if v["type"] == "bool")


# --------------------------------------------------------------------------- the baseline


def test_bundled_spec_loads() -> None:
    spec = load_spec()
    assert spec.charts and spec.instructions


def test_round_tripped_copy_loads(spec_dir: Path) -> None:
    """The edit helper alone changes nothing that matters: the copy still loads."""
    for path in spec_dir.rglob("*.yaml"):
        edit(spec_dir, str(path.relative_to(spec_dir)), lambda tree: None)
    assert load_spec([spec_dir]).files


# --------------------------------------------------------------------------- YAML and schema


def test_yaml_syntax_error(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    k = next(i for i, text in enumerate(lines) if text.startswith("  name:"))
    lines[k] = "  name: [Motion Servo On\n"  # unclosed flow sequence
    path.write_text("".join(lines), encoding="utf-8")
    d = only_error(spec_dir, path, k + 2, "YAML syntax error")  # found where the next key starts
    assert d.column > 1


def test_schema_unknown_key(spec_dir: Path) -> None:
    path = edit(spec_dir, INSTRUCTION_FILE, lambda t: t["instruction"]["checks"][0].insert(1, "zz_bogus", 1))
    only_error(spec_dir, path, line_of(path, "zz_bogus"), "unknown key 'zz_bogus'", "expected one of:", "fails_when",
               node_path="instruction.checks[0].zz_bogus")


def test_schema_wrong_type(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        t["instruction"]["checks"][0]["err"] = "zz_eight"

    path = edit(spec_dir, INSTRUCTION_FILE, change)
    only_error(spec_dir, path, line_of(path, "zz_eight"), "expected an integer", "'zz_eight'",
               node_path="instruction.checks[0].err")


def test_schema_missing_source(spec_dir: Path) -> None:
    marker: list[str] = []

    def change(t: Any) -> None:
        state = next(s for s in all_states(chart_of(t)["states"]) if "states" not in s)
        del state["source"]
        marker.append(str(state["id"]))

    path = edit(spec_dir, CHART_FILE, change)
    d = only_error(spec_dir, path, line_of(path, f"id: {marker[0]}"), "missing required key 'source'")
    assert d.path.startswith("chart.states[")


def test_schema_errors_of_one_file_come_together(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        checks = t["instruction"]["checks"]
        checks[0].insert(1, "zz_bogus", 1)
        checks[1]["err"] = "zz_eight"
        checks.append(flow(id="zz_nosource", fails_when="False", err=8))

    path = edit(spec_dir, INSTRUCTION_FILE, change)
    diags = errors_of(spec_dir)
    assert [d.line for d in diags] == sorted(line_of(path, m) for m in ("zz_bogus", "zz_eight", "zz_nosource"))
    assert {d.file for d in diags} == {str(path)}


def test_file_that_is_not_a_mapping(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    path.write_text("- just\n- a list\n", encoding="utf-8")
    only_error(spec_dir, path, 1, "expected a mapping", node_path="(document)")


def test_empty_file(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    path.write_text("# nothing here\n", encoding="utf-8")
    only_error(spec_dir, path, 1, "empty file", "format: motionchart-spec/1")


def test_nodes_of_the_wrong_kind(spec_dir: Path) -> None:
    """Lists where mappings belong and the other way round are schema errors, not crashes."""
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append("zz_not_a_mapping")
        c["variables"] = {"zz_not_a_list": 1}

    path = edit(spec_dir, CHART_FILE, change)
    diags = errors_of(spec_dir)
    assert {d.line for d in diags} == {line_of(path, "zz_not_a_mapping"), line_of(path, "zz_not_a_list")}
    assert all("expected a" in d.message for d in diags)


def test_ids_that_are_not_names(spec_dir: Path) -> None:
    """Numbers, lists and mappings where a name belongs are schema errors at their node."""
    def change(t: Any) -> None:
        c = chart_of(t)
        c["states"].append(flow(id=12345, source="zz_int_id"))
        c["transitions"].append(flow(id=["zz_list_id"], from_=leaf_id(c), event=some_event(c), source="t"))
        c["events"].append(flow(name={"zz": "map"}, kind="environment", source="zz_map_name"))

    path = edit(spec_dir, CHART_FILE, change)
    diags = errors_of(spec_dir)
    assert [d.line for d in diags] == sorted(line_of(path, m) for m in ("zz_int_id", "zz_list_id", "zz_map_name"))
    assert all(d.message.startswith("expected a string, got ") for d in diags), "\n".join(map(str, diags))


def test_files_of_other_formats_are_left_alone(spec_dir: Path) -> None:
    """A model-checker file beside the spec is not a spec file, but what it cites counts."""
    def change(t: Any) -> None:
        t["interpretations"].append(flow(id="INT-997", title="zz", confidence="I", text="zz", evidence=["MC spec/zz"]))

    edit(spec_dir, INTERPRETATIONS_FILE, change)
    (spec_dir / "zz_properties.yaml").write_text(
        "format: motionchart-properties/1\nproperties:\n  - {name: p, kind: cover, interpretation: INT-997}\n",
        encoding="utf-8")
    spec = load_spec([spec_dir])
    assert str(spec_dir / "zz_properties.yaml") not in spec.files
    future = spec_dir / "zz_future.yaml"
    future.write_text("format: motionchart-spec/2\nerrors: []\n", encoding="utf-8")
    d = only_error(spec_dir, future, 1, "expected 'motionchart-spec/1', got 'motionchart-spec/2'", node_path="format")
    assert d.column == 9


# --------------------------------------------------------------------------- semantic checks of a chart


def test_unknown_target_state(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_t", from_=leaf_id(c), event=some_event(c), to="ZzNowhere", source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    d = only_error(spec_dir, path, line_of(path, "ZzNowhere"), "unknown target state 'ZzNowhere'", "states:")
    assert d.path.endswith(".to")


def test_unknown_source_state(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_t", from_="ZzNowhere", event=some_event(c), to=leaf_id(c), source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    d = only_error(spec_dir, path, line_of(path, "ZzNowhere"), "unknown source state 'ZzNowhere'")
    assert d.path.endswith(".from")


def test_guard_with_unknown_variable(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_t", from_=leaf_id(c), event=some_event(c), guard="ZzUnknownVar > 0",
                                     to=leaf_id(c), source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    d = only_error(spec_dir, path, line_of(path, "ZzUnknownVar"), "unknown variable 'ZzUnknownVar'")
    assert d.path.endswith(".guard")


def test_unknown_event(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_t", from_=leaf_id(c), event="zz_no_event", to=leaf_id(c), source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, "zz_no_event"), "unknown event 'zz_no_event'", "chart.events")


def test_duplicate_state_id(spec_dir: Path) -> None:
    dup: list[str] = []

    def change(t: Any) -> None:
        c = chart_of(t)
        dup.append(leaf_id(c))
        c["states"].append(flow(id=dup[0], name="zz_dup_state", source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, "zz_dup_state"), f"duplicate state id '{dup[0]}'")


def test_duplicate_transition_id(spec_dir: Path) -> None:
    dup: list[str] = []

    def change(t: Any) -> None:
        c = chart_of(t)
        _, tr = event_transition(c)
        dup.append(str(tr["id"]))
        c["transitions"].append(flow(id=dup[0], from_=tr["from"], event=tr["event"], to=tr["to"], priority=7,
                                     source="zz_dup_transition"))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, "zz_dup_transition"), f"duplicate transition '{dup[0]}'")


def test_unreachable_state(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c.setdefault("initial", c["states"][0]["id"])
        c["states"].append(flow(id="ZzOrphan", source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, "ZzOrphan"), "'ZzOrphan' is unreachable")


def test_compound_state_without_initial(spec_dir: Path) -> None:
    compound: list[str] = []

    def change(t: Any) -> None:
        state = next(s for s in all_states(chart_of(t)["states"]) if "states" in s and "initial" in s)
        del state["initial"]
        compound.append(str(state["id"]))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, f"id: {compound[0]}"), "must name its initial child")


def _overlap_pair(guard_a: str | None, guard_b: str | None, priority_b: int | None) -> Callable[[Any], None]:
    """Add a copy of a plain event transition; optionally guard both and prioritise the copy."""
    def change(t: Any) -> None:
        c = chart_of(t)
        _i, tr = event_transition(c)
        b = bool_variable(c)
        if guard_a is not None:
            tr["guard"] = guard_a.format(b=b)
        extra = {"id": "zz_overlap", "from_": tr["from"], "event": tr["event"], "to": tr["to"], "source": "test"}
        if guard_b is not None:
            extra["guard"] = guard_b.format(b=b)
        if priority_b is not None:
            extra["priority"] = priority_b
        c["transitions"].append(flow(**extra))

    return change


def test_overlapping_guards_with_equal_priority(spec_dir: Path) -> None:
    path = edit(spec_dir, CHART_FILE, _overlap_pair("{b}", "{b} or not {b}", None))
    only_error(spec_dir, path, line_of(path, "zz_overlap"), "'zz_overlap'", "can both be enabled", "priority")


def test_unguarded_pair_with_equal_priority(spec_dir: Path) -> None:
    path = edit(spec_dir, CHART_FILE, _overlap_pair(None, None, None))
    only_error(spec_dir, path, line_of(path, "zz_overlap"), "can both be enabled (always)")


@pytest.mark.parametrize(
    ("guard_a", "guard_b", "priority_b"),
    [(None, None, 1), ("{b}", "{b}", 1), ("{b}", "not {b}", None)],
    ids=["different-priority", "overlapping-guards-different-priority", "disjoint-guards"],
)
def test_same_pair_accepted(spec_dir: Path, guard_a: str | None, guard_b: str | None, priority_b: int | None) -> None:
    edit(spec_dir, CHART_FILE, _overlap_pair(guard_a, guard_b, priority_b))
    spec = load_spec([spec_dir])
    assert any(t.id == "zz_overlap" for c in spec.charts for t in c.transitions)


def test_three_errors_of_a_chart_in_one_pass(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_a", from_=leaf_id(c), event=some_event(c), to="ZzNowhere", source="t"))
        c["transitions"].append(flow(id="zz_b", from_=leaf_id(c), event="zz_no_event", to=leaf_id(c), source="t"))
        c["transitions"].append(flow(id="zz_c", from_=leaf_id(c), guard="ZzUnknownVar", to=leaf_id(c), source="t"))

    path = edit(spec_dir, CHART_FILE, change)
    diags = errors_of(spec_dir)
    assert len(diags) == 3, "\n".join(map(str, diags))
    assert [d.line for d in diags] == [line_of(path, m) for m in ("zz_a", "zz_b", "zz_c")]
    assert [d.message.split(" '")[0] for d in diags] == ["unknown target state", "unknown event", "unknown variable"]


# --------------------------------------------------------------------------- references across files


def test_unknown_interpretation(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        assert "interpretation" not in t["instruction"]
        t["instruction"].insert(2, "interpretation", "INT-999")

    path = edit(spec_dir, INSTRUCTION_FILE, change)
    only_error(spec_dir, path, line_of(path, "INT-999"), "unknown interpretation 'INT-999'",
               node_path="instruction.interpretation")


def test_unused_interpretation(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        t["interpretations"].append(flow(id="INT-998", title="zz", confidence="I", text="zz", evidence=["MC spec/zz"]))

    path = edit(spec_dir, INTERPRETATIONS_FILE, change)
    only_error(spec_dir, path, line_of(path, "INT-998"), "INT-998 is not used")


def test_check_with_error_code_not_in_catalog(spec_dir: Path) -> None:
    catalog = {int(e["code"]) for e in _RT.load((spec_dir / ERRORS_FILE).read_text(encoding="utf-8"))["errors"]}
    code = max(catalog) + 1000

    def change(t: Any) -> None:
        t["instruction"]["checks"].append(flow(id="zz_code", fails_when="False", err=code, source="test"))

    path = edit(spec_dir, INSTRUCTION_FILE, change)
    only_error(spec_dir, path, line_of(path, "zz_code"), f"error code {code} is not in the error catalog")


def test_errors_of_several_files_without_cascade(spec_dir: Path) -> None:
    """A broken instruction file does not make its interpretations 'unused' or its
    extended errors 'unknown': only the real problems are reported, all in one pass."""
    broken = spec_dir / INSTRUCTION_FILE
    broken.write_text(broken.read_text(encoding="utf-8").replace("\n  name:", "\n  name: [", 1), encoding="utf-8")

    def change(t: Any) -> None:
        c = chart_of(t)
        c["transitions"].append(flow(id="zz_t", from_=leaf_id(c), event=some_event(c), to="ZzNowhere", source="t"))

    chart = edit(spec_dir, CHART_FILE, change)
    diags = errors_of(spec_dir)
    assert len(diags) == 2, "\n".join(map(str, diags))
    assert {d.file for d in diags} == {str(broken), str(chart)}


# --------------------------------------------------------------------------- hostile expressions

HOSTILE = [
    "__import__('os').system('true')",
    "().__class__",
    "x.__class__",
    "lambda: 1",
    "[x for x in y]",
]


class _Executed(BaseException):
    """Raised by the patched os.system: a BaseException, so no ``except Exception`` hides it."""


@contextmanager
def _no_system() -> Iterator[None]:
    """Patch os.system to refuse (and record) any call; fail if one happened."""
    real = os.system
    calls: list[tuple[object, ...]] = []

    def refuse(*args: object) -> int:
        calls.append(args)
        raise _Executed(f"spec text was executed: os.system{args!r}")

    os.system = refuse
    try:
        yield
    finally:
        os.system = real
    assert not calls, f"spec text was executed: os.system calls {calls}"


@pytest.fixture
def no_system() -> Iterator[None]:
    """Fail loudly if anything tries to run a command."""
    with _no_system():
        yield


def _hostile_edit(where: str, text: str) -> tuple[str, Callable[[Any], None]]:
    if where == "guard":
        def change(t: Any) -> None:
            _, tr = event_transition(chart_of(t))
            tr["guard"] = text
        return CHART_FILE, change
    if where == "check":
        def change(t: Any) -> None:
            t["instruction"]["checks"][0]["fails_when"] = text
        return INSTRUCTION_FILE, change

    def change(t: Any) -> None:
        c = chart_of(t)
        _, tr = event_transition(c)
        real = next(str(v["name"]) for v in c["variables"] if v["type"] in ("int", "real"))
        tr["actions"] = [f"{real} = {text}"]
    return CHART_FILE, change


@pytest.mark.usefixtures("no_system")
@pytest.mark.parametrize("where", ["guard", "check", "action"])
@pytest.mark.parametrize("text", HOSTILE)
def test_hostile_expression_is_refused_not_run(spec_dir: Path, where: str, text: str) -> None:
    rel, change = _hostile_edit(where, text)
    path = edit(spec_dir, rel, change)
    d = only_error(spec_dir, path, line_of(path, text), "not allowed in a spec expression", text)
    assert d.path.endswith({"guard": ".guard", "check": ".fails_when", "action": ".actions[0]"}[where])


@pytest.mark.usefixtures("no_system")
def test_python_tags_are_not_constructed(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    text = path.read_text(encoding="utf-8").replace(
        "\n  name:", "\n  name: !!python/object/apply:os.system ['true']", 1)
    path.write_text(text, encoding="utf-8")
    diags = errors_of(spec_dir)
    assert {d.file for d in diags} == {str(path)}


# --------------------------------------------------------------------------- crashes found by the fuzz test


def test_non_string_keys(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace("\n  name:", "\n  2: one\n  true: yes\n  ? [a, b]\n  : c\n  name:", 1), encoding="utf-8")
    diags = errors_of(spec_dir)
    assert len(diags) == 3, "\n".join(map(str, diags))
    assert all("is not a string" in d.message and d.path == "instruction" for d in diags)
    first = line_of(path, "2: one")
    assert [d.line for d in diags] == [first, first + 1, first + 2]


def test_status_bits_with_a_numeric_key(spec_dir: Path) -> None:
    """Such a key passed the schema as text and then broke sorting in the loader."""
    def change(t: Any) -> None:
        t["instruction"]["status_bits"] = {1: True, "zz_bit": False}

    path = edit(spec_dir, INSTRUCTION_FILE, change)
    diags = errors_of(spec_dir)
    assert all(d.file == str(path) for d in diags)
    assert any("is not a string" in d.message for d in diags)


def test_alias_bomb(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    bomb = "zz0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"zz{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 9))
    path.write_text(path.read_text(encoding="utf-8") + bomb, encoding="utf-8")
    only_error(spec_dir, path, 1, f"more than {MAX_YAML_NODES} YAML nodes")


def test_recursive_alias(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    path.write_text(path.read_text(encoding="utf-8") + "zz_loop: &loop [1, *loop]\n", encoding="utf-8")
    diags = errors_of(spec_dir)
    assert {d.file for d in diags} == {str(path)}


def test_aliases_that_expand_to_valid_nodes_are_fine(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    text = path.read_text(encoding="utf-8")
    text = text.replace("axis_types: [", "axis_types: &types [", 1)
    path.write_text(text, encoding="utf-8")
    assert load_spec([spec_dir]).instructions


@pytest.mark.parametrize("depth", [MAX_YAML_DEPTH + 5, 5000])
def test_deep_nesting(spec_dir: Path, depth: int) -> None:
    path = spec_dir / INSTRUCTION_FILE
    path.write_text(path.read_text(encoding="utf-8") + "zz_deep: " + "[" * depth + "]" * depth + "\n", encoding="utf-8")
    d = only_error(spec_dir, path, line_of(path, "zz_deep"), "nesting")
    assert "deep" in d.message


def test_not_utf8(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    raw = path.read_bytes().replace(b"\n  name: ", b"\n  name: \xff\xfe", 1)
    path.write_bytes(raw)
    line = raw[: raw.index(b"\xff")].count(b"\n") + 1
    only_error(spec_dir, path, line, "not UTF-8")


def test_nul_and_control_characters(spec_dir: Path) -> None:
    path = spec_dir / INSTRUCTION_FILE
    path.write_text(path.read_text(encoding="utf-8").replace("\n  name: ", "\n  name: \x00\x07", 1), encoding="utf-8")
    diags = errors_of(spec_dir)
    assert {d.file for d in diags} == {str(path)}


def test_infinite_range(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["variables"].append(flow(name="ZzCounter", type="int", initial=0, range=[0, float("inf")], source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    diags = errors_of(spec_dir)
    assert len(diags) == 1 and "finite" in diags[0].message and diags[0].line == line_of(path, "ZzCounter")


def test_real_variable_with_text_initial_value(spec_dir: Path) -> None:
    def change(t: Any) -> None:
        c = chart_of(t)
        c["variables"].append(flow(name="ZzReal", type="real", initial="zz_text", source="test"))

    path = edit(spec_dir, CHART_FILE, change)
    only_error(spec_dir, path, line_of(path, "ZzReal"), "is not a number")


def test_integral_floats_are_read_as_integers(spec_dir: Path) -> None:
    """JSON Schema calls 1.0 an integer; the IR must still hold ints (bit shifts use them)."""
    def change(t: Any) -> None:
        for m in t["tag_type"]["members"]:
            if "bit" in m:
                m["bit"] = float(m["bit"])

    edit(spec_dir, "motion_instruction.yaml", change)
    spec = load_spec([spec_dir])
    assert all(isinstance(m.bit, int) for m in spec.tag_type.members if m.bit is not None)


def test_missing_path_and_empty_directory(tmp_path: Path) -> None:
    diags = errors_of(tmp_path / "nope.yaml")
    assert "cannot read" in diags[0].message
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "no spec files" in errors_of(empty)[0].message


# --------------------------------------------------------------------------- fuzz

_FILES = sorted(str(p.relative_to(BUNDLED)) for p in spec_files() if p.parent.name != "schema")
_TEXTS = {rel: (BUNDLED / rel).read_text(encoding="utf-8") for rel in _FILES}

_NASTY = [
    "", "~", "null", "[]", "{}", "-1", "1.0", "1e400", ".inf", ".nan", "true", "0x1F", "2001-01-01",
    "&a [*a]", "*undefined", "!!python/object/apply:os.system ['true']", "!!binary aGk=", "!!set {a}",
    "'", '"', "{", "[", "- x", "? [a]\n: b", "{1: 2}", "<<: *a", "|\n  text", "&x 1", "!tag x",
    "__import__('os').system('true')", "().__class__", "lambda: 1", "INT-999", "AxisReady", "servo_on",
]

_yaml_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.floats(allow_nan=True),
    st.text(max_size=20), st.sampled_from(_NASTY),
)
_yaml_values = st.recursive(
    _yaml_scalars,
    lambda kids: st.one_of(st.lists(kids, max_size=4), st.dictionaries(st.text(max_size=8), kids, max_size=4)),
    max_leaves=12,
)


def _render(value: Any) -> str:
    """Flow-style YAML text of a value (repr of a Python value is close enough to YAML)."""
    try:
        return json.dumps(value, allow_nan=True)
    except (TypeError, ValueError):
        return repr(value)


def _scalars_of(node: Any) -> Iterator[str]:
    if isinstance(node, dict):
        for v in node.values():
            yield from _scalars_of(v)
    elif isinstance(node, list):
        for v in node:
            yield from _scalars_of(v)
    elif isinstance(node, str):
        yield node


#: Every text scalar of the bundled spec (ids, names, events, expressions...): swapping
#: one for another keeps the YAML and often the schema valid and stresses the semantics.
@functools.cache
def _spec_strings() -> list[str]:
    """(Parsed when the fuzz test first draws one, not when the tests are collected.)"""
    return sorted({s for rel in _FILES for s in _scalars_of(_RT.load(_TEXTS[rel])) if len(s) < 120})


def _slots(node: Any, label: str, out: dict[str, list[tuple[Any, Any]]]) -> dict[str, list[tuple[Any, Any]]]:
    """Every (container, key-or-index) of a tree, grouped by a label such as
    ``range[]`` or ``status_bits`` (so that rare node kinds are drawn as often as common ones)."""
    if isinstance(node, dict):
        for k, v in node.items():
            out.setdefault(str(k), []).append((node, k))
            _slots(v, str(k), out)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out.setdefault(label + "[]", []).append((node, i))
            _slots(v, label + "[]", out)
    return out


_RETYPED = st.one_of(
    st.sampled_from([float("inf"), float("-inf"), float("nan"), 1.0, 31.0, -1, 2**64, True, None, "", "zz"]),
    st.integers(), st.floats(),
)


def _tree_mutation(draw: st.DrawFn, rel: str) -> bytes:
    """Structural damage through a round trip: the result is YAML, often schema-valid."""
    tree = _RT.load(_TEXTS[rel])
    for _ in range(draw(st.integers(1, 3))):
        groups = _slots(tree, "", {})
        if not groups:
            break
        group = groups[draw(st.sampled_from(sorted(groups)))]
        container, key = group[draw(st.integers(0, len(group) - 1))]
        op = draw(st.sampled_from(["reuse_string", "reuse_string", "retype", "value", "delete", "duplicate", "swap",
                                   "int_key"]))
        if op == "reuse_string":
            container[key] = draw(st.sampled_from(_spec_strings()))
        elif op == "retype":
            container[key] = draw(_RETYPED)
        elif op == "value":
            container[key] = draw(_yaml_values)
        elif op == "delete":
            del container[key]
        elif op == "duplicate" and isinstance(container, list):
            container.insert(key, container[key])
        elif op == "swap" and isinstance(container, list):
            other = draw(st.integers(0, len(container) - 1))
            container[key], container[other] = container[other], container[key]
        elif op == "int_key" and isinstance(container, dict):
            container[draw(st.one_of(st.integers(), st.booleans(), st.none()))] = container.pop(key)
    buf = io.StringIO()
    try:
        _RT.dump(tree, buf)
    except Exception:
        return _TEXTS[rel].encode("utf-8")[: len(_TEXTS[rel]) // 2]
    return buf.getvalue().encode("utf-8", "surrogatepass")


@st.composite
def _mutations(draw: st.DrawFn) -> tuple[str, bytes]:
    rel = draw(st.sampled_from(_FILES))
    if draw(st.booleans()):
        return rel, _tree_mutation(draw, rel)
    lines = _TEXTS[rel].splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            lines = ["\n"]
        i = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(
            ["delete", "duplicate", "swap", "scalar", "indent", "insert", "truncate", "bytes", "nasty_line"]))
        if op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "scalar":
            line = lines[i]
            cut = line.find(": ")
            if cut < 0:
                cut = max(line.find("- "), 0)
            new = draw(st.one_of(st.sampled_from(_NASTY), st.text(max_size=12), _yaml_values.map(_render)))
            lines[i] = line[: cut + 2] + new + "\n"
        elif op == "indent":
            change = draw(st.sampled_from(["  ", " ", "\t", "-"]))
            lines[i] = change + lines[i] if draw(st.booleans()) else lines[i][len(change):]
        elif op == "insert":
            indent = " " * draw(st.sampled_from([0, 2, 4, 6]))
            key = draw(st.sampled_from(["zz", "id", "source", "states", "chart", "- id", "-", "format"]))
            lines.insert(i, f"{indent}{key}: {_render(draw(_yaml_values))}\n")
        elif op == "nasty_line":
            lines.insert(i, draw(st.sampled_from(_NASTY)) + "\n")
        elif op == "truncate":
            lines = lines[:i]
            if lines and draw(st.booleans()):
                lines[-1] = lines[-1][: draw(st.integers(0, len(lines[-1])))]
    data = "".join(lines).encode("utf-8", "surrogatepass")
    if draw(st.booleans()) and draw(st.booleans()):  # now and then, raw bytes
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    return rel, data


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("fuzz") / "spec"
    shutil.copytree(BUNDLED, d, ignore=shutil.ignore_patterns("__pycache__", "*.py", "schema", "*.json"))
    return d


@settings(suppress_health_check=[HealthCheck.data_too_large],  # whole spec files are drawn
          max_examples=examples(40))  # make deep: 2000, and tests/fuzzing.py 10,000 specs
@given(mutation=_mutations())
def test_fuzz_damaged_spec_raises_only_spec_error(fuzz_dir: Path, mutation: tuple[str, bytes]) -> None:
    rel, data = mutation
    path = fuzz_dir / rel
    original = (BUNDLED / rel).read_bytes()
    path.write_bytes(data)
    try:
        with _no_system():
            try:
                load_spec([fuzz_dir])
            except SpecError as exc:
                assert exc.diagnostics
                for d in exc.diagnostics:
                    assert d.line >= 1 and d.column >= 1 and d.message
                    assert d.file.startswith(str(fuzz_dir))
    finally:
        path.write_bytes(original)
