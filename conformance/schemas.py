"""JSON Schemas of the conformance formats: vectors, the manifest and each protocol message.

``tools/write_schemas.py`` writes them to ``spec/schema/vector*.schema.json``; a test
regenerates them in memory and compares, so the files cannot go stale.
"""

from __future__ import annotations

from typing import Any

PROTOCOL = "motionchart-conformance/1"

NAME = {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"}
SCALAR = {"type": ["boolean", "integer", "number", "string"]}
OBSERVATIONS = {
    "type": "object",
    "description": "Object name (a tag or an axis) -> field -> value.",
    "additionalProperties": {"type": "object", "additionalProperties": SCALAR},
}
NAME_LIST = {"type": "array", "items": {"type": "string"}, "uniqueItems": True}

AXIS = {
    "type": "object", "additionalProperties": False,
    "required": ["name", "type", "family"],
    "properties": {
        "name": NAME,
        "type": {"type": "string", "description": "Logix axis data type, e.g. AXIS_SERVO or AXIS_CIP_DRIVE."},
        "family": {"type": "string", "description": "The axis model it follows: AxisNonCIP or AxisCIP."},
        "state": {"type": "string", "description": "Start state (a state id of the family); default: its initial state."},
        "variables": {"type": "object", "additionalProperties": SCALAR,
                      "description": "Start values of axis attributes (configuration)."},
    },
}
CALL = {
    "type": "object", "additionalProperties": False,
    "required": ["tag", "instruction", "axis"],
    "properties": {
        "tag": NAME, "instruction": {"type": "string"}, "axis": NAME,
        "master": {**NAME, "description": "The axis of the instruction's master axis operand (MAG's Master Axis)."},
        "operands": {"type": "object", "additionalProperties": SCALAR},
    },
}
SETUP = {
    "type": "object", "additionalProperties": False,
    "required": ["scan_ms", "coarse_update_ms", "axes", "program"],
    "properties": {
        "scan_ms": {"type": "integer", "minimum": 1},
        "coarse_update_ms": {"type": "integer", "minimum": 1},
        "axes": {"type": "array", "items": AXIS, "minItems": 1},
        "program": {"type": "array", "items": CALL},
    },
}
INPUTS = {
    "type": "object", "additionalProperties": False,
    "required": ["rungs"],
    "properties": {
        "rungs": {"type": "object", "additionalProperties": {"type": "boolean"},
                  "description": "The rung-condition-in of every instruction call in this scan."},
        "operands": {"type": "object", "additionalProperties": {"type": "object", "additionalProperties": SCALAR},
                     "description": "Operand values written before this scan: tag -> operand -> value."},
        "events": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["axis", "event"],
            "properties": {"axis": NAME, "event": NAME}},
            "description": "Environment events, delivered at the next coarse update in this order."},
        "prescan": {"type": "boolean", "description": "This scan is a prescan pass."},
    },
}
COVERS = {
    "type": "object", "additionalProperties": False,
    "required": ["states", "transitions", "error_codes", "cells", "checks"],
    "properties": dict.fromkeys(("states", "transitions", "error_codes", "cells", "checks", "orders", "refusals",
                                 "stated"), NAME_LIST),
}
REQUIRES = {
    "type": "object", "additionalProperties": False,
    "required": ["axis_families", "instructions", "events", "features"],
    "properties": {"axis_families": NAME_LIST, "instructions": NAME_LIST, "events": NAME_LIST,
                   "features": NAME_LIST},
}

VECTOR_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/vector.schema.json",
    "title": "motionchart conformance vector",
    "description": "One self-contained test case: a set-up, the inputs of each scan and the observations expected after it (docs/conformance.md).",
    "type": "object", "additionalProperties": False,
    "required": ["format", "id", "kind", "name", "sources", "requires", "covers", "setup", "initial", "scans"],
    "properties": {
        "format": {"const": "motionchart-vector/1"},
        "id": {"type": "string", "pattern": "^[A-Za-z0-9_.@-]+$"},
        "kind": {"enum": ["scenario", "generated"]},
        "name": {"type": "string", "minLength": 1},
        "description": {"type": "string"},
        "sources": {"type": "array", "items": {"type": "string"}},
        "origin": {"type": "string"},
        "also": {"type": "array", "items": {"type": "string"}},
        "requires": REQUIRES,
        "covers": COVERS,
        "setup": SETUP,
        "initial": OBSERVATIONS,
        "scans": {"type": "array", "minItems": 1, "items": {
            "type": "object", "additionalProperties": False, "required": ["index", "inputs", "expect"],
            "properties": {"index": {"type": "integer", "minimum": 0}, "label": {"type": "string"},
                           "inputs": INPUTS, "expect": OBSERVATIONS}}},
    },
}

COVERAGE_KIND = {
    "type": "object", "additionalProperties": False,
    "required": ["total", "covered", "explained", "uncovered"],
    "properties": {"total": {"type": "integer"}, "covered": {"type": "integer"},
                   "explained": {"type": "object", "additionalProperties": {"type": "string"}},
                   "uncovered": NAME_LIST},
}
MANIFEST_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/vector-manifest.schema.json",
    "title": "motionchart conformance suite manifest",
    "type": "object", "additionalProperties": False,
    "required": ["format", "vector_format", "count", "vectors", "left_out", "systems", "coverage"],
    "properties": {
        "format": {"const": "motionchart-vector-manifest/1"},
        "vector_format": {"const": "motionchart-vector/1"},
        "count": {"type": "integer", "minimum": 0},
        "vectors": {"type": "array", "items": {
            "type": "object", "additionalProperties": False,
            "required": ["id", "file", "kind", "name", "requires", "covers"],
            "properties": {"id": {"type": "string"}, "file": {"type": "string"}, "kind": {"enum": ["scenario", "generated"]},
                           "name": {"type": "string"}, "requires": REQUIRES, "covers": COVERS}}},
        "left_out": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["file", "reason"],
            "properties": {"file": {"type": "string"}, "reason": {"type": "string"}}}},
        "systems": {"type": "array", "items": {"type": "object"}},
        "coverage": {"type": "object", "additionalProperties": COVERAGE_KIND},
    },
}


def _message(name: str, description: str, required: list[str], properties: dict[str, Any]) -> dict[str, Any]:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": f"https://motionchart.invalid/schema/vector-message-{name}.schema.json",
        "title": f"conformance protocol message: {name}",
        "description": description,
        "type": "object", "additionalProperties": True,
        "required": ["type", *required],
        "properties": {"type": {"const": name.split("-")[0] if name != "hello-reply" else "hello"}, **properties},
    }


SUPPORTS = {
    "type": "object", "additionalProperties": False,
    "required": ["axis_families", "instructions", "observables"],
    "properties": {
        "axis_families": NAME_LIST,
        "instructions": NAME_LIST,
        "observables": {"type": "object", "additionalProperties": NAME_LIST,
                        "description": "`tag` -> MOTION_INSTRUCTION members; an axis family -> its fields; `*` for all."},
        "events": {"type": "object", "additionalProperties": NAME_LIST,
                   "description": "An axis family -> the environment events it accepts (default: all)."},
        "features": NAME_LIST,
    },
}

MESSAGES: dict[str, dict[str, Any]] = {
    "hello": _message("hello", "Runner -> implementation, first line: the protocol version.", ["protocol"],
                      {"protocol": {"const": PROTOCOL}}),
    "hello-reply": _message("hello-reply", "Implementation -> runner: its name and what it supports.",
                            ["protocol", "implementation", "supports"],
                            {"protocol": {"const": PROTOCOL},
                             "implementation": {"type": "object", "required": ["name"],
                                                "properties": {"name": {"type": "string"}, "version": {"type": "string"}}},
                             "supports": SUPPORTS}),
    "reset": _message("reset", "Runner -> implementation: start a vector in this set-up.", ["vector", "setup"],
                      {"vector": {"type": "string"}, "setup": SETUP}),
    "ready": _message("ready", "Implementation -> runner: the set-up is built; observations before the first scan.",
                      ["observations"], {"observations": OBSERVATIONS}),
    "scan": _message("scan", "Runner -> implementation: run one scan with these inputs.", ["index", "inputs"],
                     {"index": {"type": "integer", "minimum": 0}, "inputs": INPUTS}),
    "observations": _message("observations", "Implementation -> runner: what is observed after the scan.",
                             ["index", "observations"],
                             {"index": {"type": "integer", "minimum": 0}, "observations": OBSERVATIONS}),
    "error": _message("error", "Implementation -> runner: the last request cannot be served (the vector is an error).",
                      ["message"], {"message": {"type": "string"}}),
    "bye": _message("bye", "Runner -> implementation: the run is over; exit.", [], {}),
}

SCHEMAS: dict[str, dict[str, Any]] = {
    "vector.schema.json": VECTOR_SCHEMA,
    "vector-manifest.schema.json": MANIFEST_SCHEMA,
    **{f"vector-message-{name}.schema.json": doc for name, doc in MESSAGES.items()},
}
