"""The JSON Schema, the loader and the IR agree on every key of the spec language.

* Each node kind's keys are one constant of :mod:`statecharts.loader` (``NODE_KEYS``);
  each equals the ``properties`` of the same node in ``spec/schema/spec.schema.json``,
  and every object node of the schema belongs to some kind.
* Loading the bundled spec reads exactly those keys (the loader's ``Node`` refuses an
  undeclared key; here every read is recorded).
* Every key lands in a field of the IR record built from it, or is listed below with
  the reason it does not.
* The schema files are what ``tools/write_schemas.py`` writes, and they ship as
  package data.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import tomllib
from collections.abc import Iterator
from fnmatch import fnmatch
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from statecharts import ir, loader
from statecharts.loader import NODE_KEYS, load_spec

PROJECT = Path(__file__).resolve().parents[1]
SCHEMA_DIR = PROJECT / "spec" / "schema"
SCHEMA: dict[str, Any] = json.loads((SCHEMA_DIR / "spec.schema.json").read_text(encoding="utf-8"))
FIX = "python tools/write_schemas.py"

#: Where each node kind sits in the schema (JSON pointers); a kind may appear twice.
SCHEMA_NODES: dict[str, tuple[str, ...]] = {
    "file": ("",),
    "chart": ("/properties/chart",),
    "state": ("/$defs/state",),
    "transition": ("/properties/chart/properties/transitions/items",),
    "variable": ("/properties/chart/properties/variables/items", "/properties/tag_type/properties/internal/items",
                 "/properties/add_on_instruction/properties/local_tags/items"),
    "value": ("/properties/chart/properties/variables/items/properties/values/items",
              "/properties/tag_type/properties/internal/items/properties/values/items",
              "/properties/add_on_instruction/properties/local_tags/items/properties/values/items"),
    "event": ("/properties/chart/properties/events/items",),
    "instruction": ("/properties/instruction",),
    "operand": ("/properties/instruction/properties/operands/items",),
    "check": ("/properties/instruction/properties/checks/items", "/properties/add_on_instruction/properties/checks/items"),
    "abort": ("/properties/instruction/properties/aborts/items",),
    "request": ("/properties/instruction/properties/request",),
    "done": ("/properties/instruction/properties/done",),
    "process": ("/properties/instruction/properties/process",),
    "execution_table": ("/properties/execution_tables/items",),
    "table_row": ("/properties/execution_tables/items/properties/rows/items",),
    "table_block": tuple(f"/properties/execution_tables/items/properties/{k}"
                         for k in ("on_execute", "on_error", "on_accept", "on_done", "on_complete", "on_end")),
    "tag_type": ("/properties/tag_type",),
    "wrong_axis_family": ("/properties/tag_type/properties/wrong_axis_family",),
    "tag_member": ("/properties/tag_type/properties/members/items",),
    "interpretation": ("/properties/interpretations/items",),
    "error": ("/properties/errors/items",),
    "extended_error": ("/properties/extended_errors/items",),
    "chart_parameter": ("/properties/chart/properties/parameters/items",),
    "add_on_instruction": ("/properties/add_on_instruction",),
    "execution": ("/properties/add_on_instruction/properties/execution",),
    "addon_parameter": ("/properties/add_on_instruction/properties/parameters/items",),
    "status_member": ("/properties/add_on_instruction/properties/status/items",),
    "addon_error": ("/properties/add_on_instruction/properties/errors/items",),
    "recovery": ("/properties/add_on_instruction/properties/recovery",),
    "recovery_state": ("/properties/add_on_instruction/properties/recovery/properties/states/items",),
    "recovery_call": ("/properties/add_on_instruction/properties/recovery/properties/states/items/properties/call",),
    "recovery_transition": ("/properties/add_on_instruction/properties/recovery/properties/transitions/items",),
    "on_done": ("/properties/add_on_instruction/properties/on_done/items",),
    "scan_rule": ("/properties/add_on_instruction/properties/rung_false", "/properties/add_on_instruction/properties/prescan"),
    "world": ("/properties/add_on_instruction/properties/world",),
    "world_object": ("/properties/add_on_instruction/properties/world/properties/objects/items",),
    "fact": ("/properties/add_on_instruction/properties/world/properties/objects/items/properties/facts/items",),
    "fact_set": ("/properties/add_on_instruction/properties/world/properties/objects/items/properties/facts/items/properties/set/items",),
}


def at(pointer: str) -> dict[str, Any]:
    node: Any = SCHEMA
    for part in filter(None, pointer.split("/")):
        node = node[part]
    assert isinstance(node, dict)
    return node


def object_nodes(node: Any, pointer: str = "") -> Iterator[str]:
    """JSON pointers of every schema node that declares properties."""
    if isinstance(node, dict):
        if "properties" in node and node.get("type") == "object":
            yield pointer
        for k, v in node.items():
            if k == "properties":
                for name, sub in v.items():
                    yield from object_nodes(sub, f"{pointer}/properties/{name}")
            elif isinstance(v, (dict, list)):
                yield from object_nodes(v, f"{pointer}/{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from object_nodes(v, f"{pointer}/{i}")


# --------------------------------------------------------------------------- schema == loader


def test_every_kind_has_a_schema_node() -> None:
    assert set(SCHEMA_NODES) == set(NODE_KEYS)


@pytest.mark.parametrize("kind", sorted(NODE_KEYS))
def test_loader_keys_equal_schema_properties(kind: str) -> None:
    for pointer in SCHEMA_NODES[kind]:
        schema_keys = set(at(pointer)["properties"])
        loader_keys = set(NODE_KEYS[kind])
        assert schema_keys == loader_keys, (
            f"{kind} at {pointer or '/'}: only in the schema {sorted(schema_keys - loader_keys)}, "
            f"only in the loader {sorted(loader_keys - schema_keys)}")
        assert at(pointer).get("additionalProperties") is False, f"{pointer}: unknown keys must be refused"


def test_every_schema_object_is_a_known_kind() -> None:
    covered = {p for pointers in SCHEMA_NODES.values() for p in pointers}
    assert set(object_nodes(SCHEMA)) == covered


def test_loader_constants_are_module_frozensets() -> None:
    for kind, keys in NODE_KEYS.items():
        assert isinstance(keys, frozenset)
        assert getattr(loader, f"{kind.upper()}_KEYS") is keys


def test_loading_reads_exactly_the_declared_keys(monkeypatch: pytest.MonkeyPatch) -> None:
    reads: dict[str, set[str]] = {kind: set() for kind in NODE_KEYS}
    real_declared = loader.Node._declared

    def record(self: loader.Node, key: str) -> None:
        real_declared(self, key)  # an undeclared key fails here
        reads[self.kind].add(key)

    monkeypatch.setattr(loader.Node, "_declared", record)
    loader.forget_trees()  # a spec built earlier in this process would be returned unread
    load_spec()
    unread = {kind: sorted(NODE_KEYS[kind] - keys) for kind, keys in reads.items() if NODE_KEYS[kind] - keys}
    assert not unread, f"keys the schema accepts but the loader never reads: {unread}"


def test_undeclared_key_is_refused() -> None:
    node = loader.Node({"id": "x", "zz": 1}, "chart")
    assert node["id"] == "x"
    with pytest.raises(AssertionError, match="'zz' of a chart"):
        node.get("zz")


# --------------------------------------------------------------------------- loader == IR

_PROV = {"source": "provenance", "interpretation": "provenance"}
#: kind -> (IR record, key -> field where the names differ)
IR_RECORDS: dict[str, tuple[type, dict[str, str]]] = {
    "chart": (ir.Chart, {**_PROV, "initial": "root_initial"}),
    "state": (ir.State, {**_PROV, "history": "history_type", "states": "children"}),
    "transition": (ir.Transition, {**_PROV, "from": "source", "to": "target", "guard": "guard"}),
    "variable": (ir.Variable, {**_PROV, "range": "domain"}),
    "value": (ir.DocumentedValue, _PROV),
    "event": (ir.Event, _PROV),
    "instruction": (ir.Instruction, {**_PROV, "execution_table": "table", "done": "done_when"}),
    "operand": (ir.Operand, _PROV),
    "check": (ir.Check, _PROV),
    "abort": (ir.Check, {**_PROV, "when": "fails_when"}),
    "request": (ir.Request, {}),
    "done": (ir.Instruction, {"when": "done_when", "source": "done_provenance", "interpretation": "done_provenance"}),
    "process": (ir.Process, _PROV),
    "execution_table": (ir.ExecutionTable, _PROV),
    "table_row": (ir.TableRow, _PROV),
    "tag_type": (ir.TagType, _PROV),
    "wrong_axis_family": (ir.Check, _PROV),
    "tag_member": (ir.TagMember, _PROV),
    "interpretation": (ir.Interpretation, {}),
    "error": (ir.ErrorCode, _PROV),
    "extended_error": (ir.ExtendedError, _PROV),
    "chart_parameter": (ir.ChartParameter, _PROV),
    "add_on_instruction": (ir.AddOnInstruction, _PROV),
    "execution": (ir.Execution, _PROV),
    "addon_parameter": (ir.AddOnParameter, _PROV),
    "status_member": (ir.StatusMember, _PROV),
    "addon_error": (ir.AddOnError, _PROV),
    "recovery": (ir.Recovery, _PROV),
    "recovery_state": (ir.RecoveryState, _PROV),
    "recovery_call": (ir.RecoveryCall, {}),
    "recovery_transition": (ir.RecoveryTransition, {**_PROV, "from": "source", "to": "target"}),
    "on_done": (ir.OnDone, _PROV),
    "scan_rule": (ir.ScanRule, _PROV),
    "world": (ir.World, _PROV),
    "world_object": (ir.WorldObject, _PROV),
    "fact": (ir.Fact, _PROV),
    "fact_set": (ir.FactSet, {}),
}
#: (kind, key) pairs that do not reach the IR, each with the reason.
NOT_IN_IR: dict[tuple[str, str], str] = {
    ("file", k): "a file is a container; its sections become Spec fields" for k in NODE_KEYS["file"]
} | {
    ("table_block", "actions"): "become ExecutionTable.on_execute/on_error/on_accept/on_done/on_complete/on_end",
    ("operand", "role"): "the master operand's name becomes Instruction.master_operand",
    ("table_block", "source"): "the IR keeps no provenance for the four action blocks of a table",
    ("table_block", "interpretation"): "checked to exist, not kept (as source)",
}


@pytest.mark.parametrize("kind", sorted(NODE_KEYS))
def test_every_key_reaches_the_ir(kind: str) -> None:
    missing = []
    for key in sorted(NODE_KEYS[kind]):
        if (kind, key) in NOT_IN_IR:
            continue
        record, renames = IR_RECORDS[kind]
        fields = {f.name for f in dataclasses.fields(record)}
        if renames.get(key, key) not in fields:
            missing.append(f"{key} -> {record.__name__}.{renames.get(key, key)}")
    assert not missing, f"{kind}: keys with no IR field: {missing}"


def test_not_in_ir_list_has_no_stale_entries() -> None:
    for kind, key in NOT_IN_IR:
        assert key in NODE_KEYS[kind], (kind, key)


# --------------------------------------------------------------------------- generated schema files


def _write_schemas_module() -> Any:
    path = PROJECT / "tools" / "write_schemas.py"
    spec = importlib.util.spec_from_file_location("_write_schemas_under_test", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # its writing code is under `if __name__ == "__main__"`
    return module


def test_schema_files_are_up_to_date() -> None:
    module = _write_schemas_module()
    names = set(module.SCHEMAS)
    on_disk = {p.name for p in SCHEMA_DIR.glob("*.json")}
    assert names == on_disk, f"spec/schema/ holds {sorted(on_disk)}, tools/write_schemas.py writes {sorted(names)}; run: {FIX}"
    for name, doc in sorted(module.SCHEMAS.items()):
        expected = module.render(doc)
        actual = (SCHEMA_DIR / name).read_text(encoding="utf-8")
        assert actual == expected, f"spec/schema/{name} is stale; regenerate it with: {FIX}"


@pytest.mark.parametrize("name", ["spec.schema.json", "scenario.schema.json"])
def test_schemas_are_valid_draft_2020_12(name: str) -> None:
    jsonschema.Draft202012Validator.check_schema(json.loads((SCHEMA_DIR / name).read_text(encoding="utf-8")))


# --------------------------------------------------------------------------- package data


def test_schema_ships_as_package_data() -> None:
    schema = resources.files("motionchart_spec") / "schema" / "spec.schema.json"
    assert schema.is_file()
    assert json.loads(schema.read_text(encoding="utf-8")) == SCHEMA
    assert (resources.files("motionchart_spec") / "schema" / "scenario.schema.json").is_file()
    assert loader.spec_schema() == SCHEMA


def test_every_spec_file_matches_a_package_data_pattern() -> None:
    """A YAML file in a deeper folder than pyproject's patterns reach would be left
    out of the wheel while every test here (which reads the checkout) still passed."""
    config = tomllib.loads((PROJECT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = config["tool"]["setuptools"]["package-data"]["motionchart_spec"]
    spec_root = PROJECT / "spec"
    files = [p.relative_to(spec_root).as_posix() for p in spec_root.rglob("*")
             if p.is_file() and p.suffix in (".yaml", ".yml", ".json") and "__pycache__" not in p.parts]
    unmatched = [f for f in files if not any(fnmatch(f, pat) and f.count("/") == pat.count("/") for pat in patterns)]
    assert not unmatched, f"not shipped in the wheel (package-data patterns {patterns}): {unmatched}"
