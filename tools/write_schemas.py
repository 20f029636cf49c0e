"""Writes the JSON Schemas in spec/schema/ (run when the spec or scenario language changes).

A test regenerates them in memory and compares, so the files cannot go stale."""
import json
from pathlib import Path

ID = {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"}
EXPR = {"type": "string", "minLength": 1}
ACTIONS = {"type": "array", "items": EXPR}
SOURCE = {"type": "string", "minLength": 1,
          "description": "Citations of the registered sources (spec/sources.yaml) separated by ';', "
                         "e.g. 'LDH-MDO Execution' or 'RM002H p79; INT-004'."}
INTERP = {"type": "string", "pattern": "^INT-[0-9]{3}$", "description": "Id of an interpretation in interpretations.yaml."}
CONF = {"enum": ["C", "C3", "I", "U"]}
SCALAR = {"type": ["boolean", "integer", "number", "string"]}

variable = {
    "type": "object", "additionalProperties": False,
    "required": ["name", "type", "initial", "source"],
    "properties": {
        "name": ID, "type": {"enum": ["bool", "int", "enum", "real"]},
        "domain": {"type": "array", "items": SCALAR, "minItems": 1},
        "range": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        "initial": SCALAR, "description": {"type": "string"},
        "writable": {"type": "boolean", "description": "A program may write this attribute (SSV): a scenario step may `set:` it."},
        "values": {"type": "array", "description": "Documented values (status codes): what each means and where it is documented.",
                   "items": {"type": "object", "additionalProperties": False, "required": ["value", "meaning", "source"],
                             "properties": {"value": SCALAR, "meaning": {"type": "string", "minLength": 1},
                                            "confidence": CONF, "source": SOURCE, "interpretation": INTERP}}},
        "source": SOURCE, "interpretation": INTERP,
    },
}
state = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "source"],
    "properties": {
        "id": ID, "name": {"type": "string"},
        "kind": {"enum": ["atomic", "compound", "parallel", "history", "final"]},
        "value": {"type": "integer"}, "initial": ID,
        "history": {"enum": ["shallow", "deep"]},
        "description": {"type": "string"},
        "entry": ACTIONS, "exit": ACTIONS,
        "states": {"type": "array", "items": {"$ref": "#/$defs/state"}},
        "implies": {"type": "object", "additionalProperties": SCALAR,
                    "description": ("Values of chart variables that an axis set up in this state (or a descendant) has, "
                                    "e.g. a connected drive with its DC bus up.")},
        "source": SOURCE, "interpretation": INTERP,
    },
}
transition = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "from", "source"],
    "properties": {
        "id": ID, "from": ID, "to": ID, "event": ID, "guard": EXPR,
        "actions": ACTIONS, "priority": {"type": "integer"},
        "source": SOURCE, "interpretation": INTERP,
    },
}
event = {
    "type": "object", "additionalProperties": False,
    "required": ["name", "kind", "source"],
    "properties": {
        "name": ID, "kind": {"enum": ["request", "environment", "clock", "drive"],
                             "description": ("drive: an outcome of the drive model (a move reaching its target, "
                                             "a homing sequence ending), applied right after the coarse update's tick.")},
        "description": {"type": "string"}, "actions": ACTIONS,
        "parameters": {"type": "array", "items": ID},
        "source": SOURCE, "interpretation": INTERP,
    },
}
chart = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "name", "kind", "state_attribute", "axis_types", "states", "transitions", "source"],
    "properties": {
        "id": ID, "name": {"type": "string"},
        "kind": {"enum": ["axis", "handler"], "description": "axis: an axis state model; handler: a device handler an add-on instruction is given."},
        "parameters": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["name", "type", "source"],
            "description": "An instance parameter: configuration each instance of the chart is given in a set-up (not a chart variable).",
            "properties": {"name": ID, "type": {"enum": ["int", "axis"]}, "default": SCALAR,
                           "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP}}},
        "state_attribute": ID,
        "axis_types": {"type": "array", "items": ID, "minItems": 1},
        "description": {"type": "string"},
        "variables": {"type": "array", "items": variable},
        "events": {"type": "array", "items": event},
        "states": {"type": "array", "items": {"$ref": "#/$defs/state"}, "minItems": 1},
        "initial": ID,
        "transitions": {"type": "array", "items": transition},
        "drive_model": {"enum": ["motion"],
                        "description": "The chart carries the motion variables the drive model advances at every coarse update."},
        "source": SOURCE, "interpretation": INTERP,
    },
}
operand = {
    "type": "object", "additionalProperties": False,
    "required": ["name", "type", "source"],
    "properties": {
        "name": ID, "type": {"enum": ["axis", "tag", "real", "int", "enum"]},
        "domain": {"type": "array", "items": SCALAR, "minItems": 1},
        "range": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        "text_values": {"type": "object", "additionalProperties": {"type": "integer"}},
        "default": SCALAR, "description": {"type": "string"},
        "role": {"enum": ["master"], "description": "A second axis operand (MAG's master axis), read as master.X."},
        "source": SOURCE, "interpretation": INTERP,
    },
}
check = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "fails_when", "err", "source"],
    "properties": {
        "id": ID, "fails_when": EXPR, "err": {"type": "integer", "minimum": 1},
        "exerr": {"type": "integer", "minimum": 0},
        "stage": {"enum": ["execute", "message"]},
        "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP,
    },
}
abort = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "when", "err", "source"],
    "properties": {
        "id": ID, "when": EXPR, "err": {"type": "integer", "minimum": 1},
        "exerr": {"type": "integer", "minimum": 0},
        "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP,
    },
}
instruction = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "name", "charts", "axis_types", "operands", "execution", "execution_table", "checks", "done", "source"],
    "properties": {
        "id": ID, "name": {"type": "string"},
        "mnemonic": {**ID, "description": "The instruction as a program calls it; defaults to id. Variants of one mnemonic list disjoint charts."},
        "charts": {"type": "array", "items": ID, "minItems": 1},
        "axis_types": {"type": "array", "items": ID, "minItems": 1},
        "description": {"type": "string"},
        "operands": {"type": "array", "items": operand},
        "execution": {"enum": ["transitional", "level"]},
        "execution_table": ID,
        "checks": {"type": "array", "items": check},
        "aborts": {"type": "array", "items": abort},
        "request": {
            "type": "object", "additionalProperties": False, "required": ["event"],
            "properties": {"event": ID, "actions": ACTIONS},
        },
        "done": {
            "type": "object", "additionalProperties": False, "required": ["source"],
            "properties": {"when": EXPR, "source": SOURCE, "interpretation": INTERP},
        },
        "status_bits": {"type": "object", "additionalProperties": {"type": "boolean"}},
        "process": {
            "type": "object", "additionalProperties": False, "required": ["kind", "source"],
            "description": ("The process the instruction starts once the axis accepts it: IP until it completes "
                            "(PC) or ends; a request of the same kind on the axis supersedes it."),
            "properties": {"kind": ID, "complete_when": EXPR, "ends_when": EXPR,
                           "source": SOURCE, "interpretation": INTERP},
        },
        "source": SOURCE, "interpretation": INTERP,
    },
}
block = {
    "type": "object", "additionalProperties": False, "required": ["actions", "source"],
    "properties": {"actions": ACTIONS, "source": SOURCE, "interpretation": INTERP},
}
table = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "rows", "on_execute", "on_error", "on_accept", "on_done", "source"],
    "properties": {
        "id": ID, "source": SOURCE, "interpretation": INTERP,
        "rows": {"type": "array", "items": {
            "type": "object", "additionalProperties": False,
            "required": ["condition", "actions", "source"],
            "properties": {
                "condition": {"enum": ["prescan", "rung_false", "rung_true", "postscan"]},
                "guard": EXPR, "actions": ACTIONS, "execute": {"type": "boolean"},
                "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP,
            }}},
        "on_execute": block, "on_error": block, "on_accept": block, "on_done": block,
        "on_complete": block, "on_end": block,
    },
}
tag_type = {
    "type": "object", "additionalProperties": False,
    "required": ["name", "members", "source"],
    "properties": {
        "name": ID, "source": SOURCE,
        "wrong_axis_family": {
            "type": "object", "additionalProperties": False, "required": ["err", "source"],
            "description": "The error of an instruction called on an axis none of its variants' charts covers.",
            "properties": {
                "err": {"type": "integer", "minimum": 1}, "exerr": {"type": "integer", "minimum": 0},
                "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP,
            }},
        "members": {"type": "array", "items": {
            "type": "object", "additionalProperties": False,
            "required": ["name", "type", "source"],
            "properties": {
                "name": ID, "type": {"enum": ["BOOL", "SINT", "INT", "DINT"]},
                "bit": {"type": "integer", "minimum": 0, "maximum": 31},
                "description": {"type": "string"}, "source": SOURCE,
            }}},
        "internal": {"type": "array", "items": variable},
    },
}
interpretation = {
    "type": "object", "additionalProperties": False,
    "required": ["id", "title", "confidence", "text", "evidence"],
    "properties": {
        "id": INTERP, "title": {"type": "string"}, "confidence": CONF,
        "text": {"type": "string", "minLength": 1},
        "evidence": {"type": "array", "items": {"type": "string"}, "minItems": 1},
    },
}
error = {
    "type": "object", "additionalProperties": False,
    "required": ["code", "name", "meaning", "confidence", "source"],
    "properties": {
        "code": {"type": "integer", "minimum": 0}, "name": ID, "meaning": {"type": "string"},
        "confidence": CONF, "source": SOURCE, "interpretation": INTERP,
    },
}
exerror = {
    "type": "object", "additionalProperties": False,
    "required": ["instruction", "err", "exerr", "name", "meaning", "confidence", "source"],
    "properties": {
        "instruction": ID, "err": {"type": "integer"}, "exerr": {"type": "integer"},
        "name": ID, "meaning": {"type": "string"}, "confidence": CONF,
        "source": SOURCE, "interpretation": INTERP,
    },
}
PROV = {"source": SOURCE, "interpretation": INTERP}


def obj(required: list, props: dict, description: str = "") -> dict:
    out = {"type": "object", "additionalProperties": False, "required": required, "properties": props}
    if description:
        out["description"] = description
    return out


EXPR_MAP = {"type": "object", "propertyNames": ID, "additionalProperties": EXPR}
ID_LIST = {"type": "array", "items": ID}
# the add-on instruction (docs/aoi.md): parameters, its status tag, local tags, codes,
# ordered checks, the recovery chart, the false-rung and prescan rules, its world
add_on_instruction = obj(
    ["id", "name", "execution", "parameters", "status", "errors", "checks", "recovery", "rung_false", "prescan",
     "world", "source"], {
        "id": ID, "name": {"type": "string"}, "description": {"type": "string"},
        "execution": obj(["mode", "source"], {"mode": {"enum": ["level"]}, **PROV},
                         "How the rung condition drives it (Level: runs while the rung is true)."),
        "parameters": {"type": "array", "minItems": 1, "items": obj(["name", "usage", "type", "source"], {
            "name": ID, "usage": {"enum": ["Input", "Output", "InOut"]},
            "type": {"enum": ["axis", "handle", "BOOL", "DINT", "REAL"]}, "data_type": ID,
            "alias": {**ID, "description": "Short name the expressions use for an axis or handle parameter (phy, pth, handler)."},
            "default": SCALAR, "description": {"type": "string"},
            "values": {"type": "array", "minItems": 1, "items": {"type": "integer"},
                       "description": "The only values a program may give a DINT parameter (a scenario giving another is refused)."},
            **PROV})},
        "status": {"type": "array", "minItems": 1, "items": obj(["name", "type", "source"], {
            "name": ID, "type": {"enum": ["BOOL", "DINT"]}, "description": {"type": "string"}, **PROV})},
        "local_tags": {"type": "array", "items": variable},
        "errors": {"type": "array", "minItems": 1, "items": obj(["code", "name", "source"], {
            "code": {"type": "integer", "minimum": 1}, "name": {"type": "string", "minLength": 1},
            "description": {"type": "string"}, **PROV})},
        "checks": {"type": "array", "items": check},
        "recovery": obj(["initial", "states", "transitions", "source"], {
            "initial": ID, "description": {"type": "string"}, **PROV,
            "states": {"type": "array", "minItems": 1, "items": obj(["id", "source"], {
                "id": ID, "description": {"type": "string"}, "error": {"type": "integer", "minimum": 1},
                "call": obj(["instruction", "axis"], {
                    "instruction": ID, "axis": ID, "master": ID,
                    "operands": {"type": "object", "propertyNames": ID, "additionalProperties": {"type": ["number", "string"]}},
                }, "A motion instruction the state issues on an axis parameter (by alias)."),
                **PROV})},
            "transitions": {"type": "array", "items": obj(["from", "to", "when", "source"], {
                "from": ID, "to": ID, "when": EXPR, **PROV})},
        }),
        "on_done": {"type": "array", "items": obj(["when", "set", "source"], {
            "when": EXPR, "set": {"enum": ["path_verified", "handler.OnPath"]}, **PROV})},
        "rung_false": obj(["clear", "source"], {"clear": ID_LIST, "abort_call": ID, "forget": ID_LIST, **PROV},
                          "What a false rung (or a prescan: `prescan`) does: members cleared, the call aborted, local tags forgotten."),
        "prescan": obj(["clear", "source"], {"clear": ID_LIST, "abort_call": ID, "forget": ID_LIST, **PROV},
                       "What a false rung (or a prescan: `prescan`) does: members cleared, the call aborted, local tags forgotten."),
        "world": obj(["objects", "source"], {
            **PROV,
            "objects": {"type": "array", "minItems": 1, "items": obj(["kind", "chart", "facts", "source"], {
                "kind": ID, "chart": ID, **PROV,
                "register": {**ID_LIST, "description": "The events a method sends to register with a device of this kind."},
                "facts": {"type": "array", "items": obj(["name", "source"], {
                    "name": ID, "when": EXPR, "variable": ID, **PROV,
                    "set": {"type": "array", "description": "The events that give the fact a value (on_done sets facts).",
                            "items": obj(["value", "fire"], {
                                "value": SCALAR, "fire": {"type": "array", "minItems": 1, "items": ID}})},
                })},
            })},
        }),
        **PROV,
    }, "An add-on instruction: a routine with parameters, its own status tag and a recovery chart.")

schema = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/spec-1.json",
    "title": "motionchart specification file, format 1",
    "description": "One YAML file of a motionchart specification. A file holds one or more sections.",
    "type": "object", "additionalProperties": False,
    "required": ["format"], "minProperties": 2,
    "properties": {
        "format": {"const": "motionchart-spec/1"},
        "chart": chart, "instruction": instruction, "add_on_instruction": add_on_instruction,
        "tag_type": tag_type,
        "execution_tables": {"type": "array", "items": table},
        "interpretations": {"type": "array", "items": interpretation},
        "errors": {"type": "array", "items": error},
        "extended_errors": {"type": "array", "items": exerror},
    },
    "$defs": {"state": state},
}
NAME_KEY = {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"}
EXPECTED = {"oneOf": [
    {"type": ["boolean", "integer", "number", "string"]},
    {"type": "object", "additionalProperties": False, "required": ["approx", "within"],
     "description": "A number within a tolerance: a number at least 0, or a named tolerance such as dac_step.",
     "properties": {"approx": {"type": "number"}, "within": {"type": ["number", "string"]}}},
    {"type": "object", "additionalProperties": False, "required": ["not"],
     "description": "Any value but this one.", "properties": {"not": {"type": ["boolean", "integer", "number", "string"]}}},
    {"type": "array", "minItems": 1, "items": {"type": "string"},
     "description": "passes_through: states the axis is in during the step, in this order."},
]}
OBS = {"type": "object", "additionalProperties": EXPECTED}
#: a ladder program file (rung text or L5X), relative to the scenario
PROGRAM_FILE = {"type": "string", "minLength": 1}
#: program tag values by path (``START_PB``, ``Arr[2]``, ``T1.PRE``)
TAG_VALUES = {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number"]}}
#: per object its observations; with a program also a tag path with its value (``NEXTSTATE: 1``)
EXPECT = {"type": "object", "additionalProperties": {"oneOf": [OBS, {"type": ["boolean", "integer", "number", "string"]}]}}
scenario = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/scenario-1.json",
    "title": "motionchart scenario, format 1",
    "description": "A set-up and a list of steps of one or more PLC scans, each with expected observations.",
    "type": "object", "additionalProperties": False,
    "required": ["format", "name", "setup", "steps"],
    "properties": {
        "format": {"const": "motionchart-scenario/1"},
        "name": {"type": "string", "minLength": 1},
        "description": {"type": "string"},
        "sources": {"type": "array", "items": {"type": "string"}},
        "covers": {"type": "array", "items": {"type": "string"}},
        "setup": {
            "type": "object", "additionalProperties": False, "required": ["axes"],
            "properties": {
                "scan_ms": {"type": "integer", "minimum": 1},
                "coarse_update_ms": {"type": "integer", "minimum": 1},
                "axes": {"type": "object", "minProperties": 1, "propertyNames": NAME_KEY,
                         "additionalProperties": {
                             "type": "object", "additionalProperties": False, "required": ["type"],
                             "properties": {
                                 "type": {"type": "string"},
                                 "chart": {**ID, "description": "The chart of the axis when several charts model its type "
                                                                "(AXIS_VIRTUAL); default: the first."},
                                 "state": {"type": "string"},
                                 "variables": {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]}},
                             }}},
                "devices": {"type": "object", "propertyNames": NAME_KEY,
                            "description": "Chart instances that are not axes (a device handler), by name.",
                            "additionalProperties": {
                                "type": "object", "additionalProperties": False, "required": ["type"],
                                "properties": {
                                    "type": {"type": "string", "description": "The data type the device's chart models."},
                                    "chart": ID,
                                    "state": {"type": "string"},
                                    "variables": {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]}},
                                    "parameters": {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]},
                                                   "description": "Instance parameters of the chart (a handler's id and axes)."},
                                    "events": {"type": "array", "items": NAME_KEY,
                                               "description": "Environment events sent once the device is set up."},
                                }}},
                "program": {"oneOf": [
                    {"type": "array", "items": {
                        "type": "object", "additionalProperties": False,
                        "required": ["tag", "instruction"],
                        "properties": {
                            "tag": NAME_KEY, "instruction": NAME_KEY, "axis": NAME_KEY,
                            "master": {**NAME_KEY, "description": "The axis of the instruction's master axis operand (MAG's Master Axis)."},
                            "operands": {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]}},
                            "preset": {"type": "object", "additionalProperties": {"type": ["boolean", "integer"]},
                                       "description": ("MOTION_INSTRUCTION members (EN, DN, ER, PC, IP, ERR, EXERR), or an add-on "
                                                       "instruction's status members and local tags, set before the first scan.")},
                        }}},
                    PROGRAM_FILE,
                    {"type": "object", "additionalProperties": False, "required": ["file"],
                     "properties": {"file": PROGRAM_FILE, "routine": NAME_KEY, "program": NAME_KEY}},
                ]},
                "tags": TAG_VALUES,
                "prescan": {"type": "boolean"},
            },
        },
        "steps": {"type": "array", "minItems": 1, "items": {
            "type": "object", "additionalProperties": False,
            "properties": {
                "name": {"type": "string"},
                "prescan": {"type": "boolean"},
                "scans": {"type": "integer", "minimum": 1, "maximum": 100000},
                "within": {"type": "integer", "minimum": 1, "maximum": 100000,
                           "description": "The step lasts until its expectations hold, at most this many scans."},
                "set": {"type": "object",
                        "additionalProperties": {"type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]}},
                        "description": "Attribute writes before the step's first scan, as SSV does: {axis: {attribute: value}}."},
                "rungs": {"type": "object", "additionalProperties": {"type": "boolean"}},
                "operands": {"type": "object", "additionalProperties": {
                    "type": "object", "additionalProperties": {"type": ["boolean", "integer", "number", "string"]}}},
                "events": {"type": "array", "items": {
                    "type": "object", "additionalProperties": False, "required": ["axis", "event"],
                    "properties": {"axis": NAME_KEY, "event": NAME_KEY}}},
                "expect": EXPECT,
                "always": EXPECT,
                "tags": TAG_VALUES,
            }}},
    },
}


SYSTEM_CONFIG = {
    "type": "object", "additionalProperties": False, "required": ["name"],
    "properties": {
        "name": NAME_KEY, "description": {"type": "string"},
        "variables": {"type": "object", "additionalProperties": SCALAR},
        "parameters": {"type": "object", "additionalProperties": SCALAR,
                       "description": "A device's chart parameters in this configuration."},
        "state": {"type": "string", "description": "The initial state in this configuration (default: the group's)."},
    },
}
GROUP_ENVIRONMENT = {"type": "array", "items": ID,
                     "description": "The environment events offered on these axes (default: the system's `environment`)."}
system = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/system-1.json",
    "title": "motionchart system for the model checker, format 1",
    "description": "Axes, instruction calls, operand domains, environment and abstractions that `motionchart check` explores.",
    "type": "object", "additionalProperties": False,
    "required": ["format", "name", "axes"],
    "properties": {
        "format": {"const": "motionchart-system/1"},
        "name": NAME_KEY, "description": {"type": "string"}, "source": {"type": "string"},
        "scan_ms": {"type": "integer", "minimum": 1},
        "coarse_update_ms": {"type": "integer", "minimum": 1},
        "axes": {"type": "array", "minItems": 1, "items": {
            "type": "object", "additionalProperties": False, "required": ["name", "type"],
            "properties": {
                "name": NAME_KEY, "type": {"type": "string"},
                "chart": {**ID, "description": "The chart of the axes when several charts model their type (AXIS_VIRTUAL); default: the first."},
                "count": {"type": "integer", "minimum": 1, "maximum": 64},
                "state": {"type": "string"},
                "variables": {"type": "object", "additionalProperties": SCALAR},
                "configurations": {"type": "array", "minItems": 1, "items": SYSTEM_CONFIG},
                "program": {"type": "array", "items": ID},
                "environment": GROUP_ENVIRONMENT,
                "masters": {"type": "object", "propertyNames": ID, "additionalProperties": ID,
                            "description": "The axis bound to the master-axis operand of an instruction of `program` "
                                           "that has one (MAG's MasterAxis): instruction -> the name of an axis (or "
                                           "axis group, meaning its first axis) of another group of the system."},
            }}},
        "devices": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["name", "type"],
            "description": "Chart instances that are not axes (a device handler an add-on instruction is given).",
            "properties": {
                "name": NAME_KEY, "type": {"type": "string"}, "chart": ID, "state": {"type": "string"},
                "variables": {"type": "object", "additionalProperties": SCALAR},
                "parameters": {"type": "object", "additionalProperties": SCALAR,
                               "description": "Instance parameters of the chart (a handler's id and axes)."},
                "events": {"type": "array", "items": ID,
                           "description": "Environment events sent once the instance is set up."},
                "configurations": {"type": "array", "minItems": 1, "items": SYSTEM_CONFIG},
                "environment": GROUP_ENVIRONMENT,
            }}},
        "add_ons": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["tag", "instruction", "operands"],
            "description": "Add-on instruction tags of the program, each with its operands.",
            "properties": {
                "tag": NAME_KEY, "instruction": ID,
                "operands": {"type": "object", "additionalProperties": SCALAR},
                "preset": {"type": "object", "additionalProperties": SCALAR,
                           "description": "Status members and local tags set before the first scan."},
                "inputs": {"type": "object", "additionalProperties": {"type": "array", "items": SCALAR, "minItems": 1},
                           "description": "Input parameters the environment may change while the tag's rung is "
                                          "false, with their values."},
            }}},
        "motion": {"type": "boolean",
                   "description": "Run the drive model (positions, velocities, reaching targets) in the search "
                                  "instead of offering its events as inputs; for systems whose checks read positions."},
        "max_changes": {"type": "integer", "minimum": 0,
                        "description": "At most this many environment events and add-on input changes per run."},
        "operands": {"type": "object", "additionalProperties": {
            "type": "object", "additionalProperties": {"type": "array", "items": SCALAR, "minItems": 1}}},
        "environment": {"type": "array", "items": ID},
        "prescan": {"type": "boolean"},
        "max_live_calls": {"type": "integer", "minimum": 1},
        "abstraction": {
            "type": "object", "additionalProperties": False,
            "properties": {
                "collapse": {"type": "array", "items": ID},
                "symmetry": {"type": "boolean"},
                "retire_idle_tags": {"type": "boolean"},
            }},
    },
}
PROPERTY = {
    "type": "object", "additionalProperties": False, "required": ["name", "kind", "source"],
    "properties": {
        "name": ID,
        "kind": {"enum": ["invariant", "reachable", "deadlock_free", "response", "cover"]},
        "description": {"type": "string"}, "source": SOURCE, "interpretation": INTERP,
        "scope": {"enum": ["axis", "tag", "add_on"]},
        "chart": ID, "instruction": ID,
        "systems": {"type": "array", "items": ID, "minItems": 1,
                    "description": "Check the property only on these systems (by name); default: every system with its chart."},
        "where": EXPR, "holds": EXPR, "goal": EXPR,
        "trigger": EXPR, "response": EXPR, "unless": EXPR,
        "within": {"type": "integer", "minimum": 1, "maximum": 1000},
        "cover": {"enum": ["states", "transitions", "error_codes", "cells", "values"]},
        "variable": ID,
        "unreachable": {"type": "array", "items": {
            "type": "object", "additionalProperties": False, "required": ["item", "reason"],
            "properties": {"item": {"type": "string", "minLength": 1}, "reason": {"type": "string", "minLength": 1},
                           "source": {"type": "string"}}}},
    },
}
properties = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://motionchart.invalid/schema/properties-1.json",
    "title": "motionchart properties for the model checker, format 1",
    "description": "Invariants, reachability goals, deadlock freedom, bounded response and coverage goals, written in the spec expression language.",
    "type": "object", "additionalProperties": False,
    "required": ["format", "properties"],
    "properties": {
        "format": {"const": "motionchart-properties/1"},
        "properties": {"type": "array", "items": PROPERTY},
    },
}


def render(doc: dict) -> str:
    return json.dumps(doc, indent=2, sort_keys=True) + "\n"


SCHEMAS = {"spec.schema.json": schema, "scenario.schema.json": scenario,
           "system.schema.json": system, "properties.schema.json": properties}


# the conformance suite: vectors, their manifest and each protocol message (docs/conformance.md)
from conformance.schemas import SCHEMAS as CONFORMANCE_SCHEMAS

SCHEMAS.update(CONFORMANCE_SCHEMAS)

if __name__ == "__main__":
    out_dir = Path(__file__).resolve().parent.parent / "spec" / "schema"
    for name, doc in SCHEMAS.items():
        (out_dir / name).write_text(render(doc), encoding="utf-8")
        print(out_dir / name)
