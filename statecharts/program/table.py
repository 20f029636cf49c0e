"""The ladder instruction table (``instructions.yaml`` beside this module), as frozen records.

Pipeline position: read once by the program readers (operand counts and kinds) and by
the ladder interpreter (which mnemonics it executes).  The operands of the motion
instructions are those of the specification (``spec/instructions/``), so they are
looked up there, not repeated here.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

from ruamel.yaml import YAML

OPERAND_KINDS = ("bit_in", "bit_out", "value", "dest", "timer", "counter", "timer_or_counter", "shown",
                 "expression", "array", "routine", "axis", "motion")


@dataclass(frozen=True, slots=True)
class LadderInstruction:
    mnemonic: str
    name: str
    kind: str  # "input" | "output" | "motion"
    operands: tuple[str, ...]
    optional: tuple[str, ...]  # operands that may follow (JSR's input count)
    source: str


@dataclass(frozen=True, slots=True)
class InstructionTable:
    instructions: tuple[LadderInstruction, ...]
    motion: tuple[str, ...]
    motion_not_modelled: tuple[str, ...]
    unsupported: tuple[str, ...]

    def get(self, mnemonic: str) -> LadderInstruction | None:
        for i in self.instructions:
            if i.mnemonic == mnemonic:
                return i
        return None

    def supported(self) -> tuple[str, ...]:
        """Every mnemonic a program may use, sorted."""
        return tuple(sorted([i.mnemonic for i in self.instructions] + list(self.motion)))

    def why_not(self, mnemonic: str) -> str:
        """The message for a mnemonic the interpreter does not execute."""
        listing = f"supported: {', '.join(self.supported())}"
        if mnemonic in self.motion_not_modelled:
            return (f"motion instruction {mnemonic} is not modelled yet; the modelled motion instructions are "
                    f"{', '.join(self.motion)} ({listing})")
        if mnemonic in self.unsupported:
            return f"Logix instruction {mnemonic} is not supported by the ladder interpreter; {listing}"
        return f"unknown instruction {mnemonic!r}; {listing}"


@functools.lru_cache(maxsize=1)
def instruction_table() -> InstructionTable:
    doc = YAML(typ="safe").load((Path(__file__).parent / "instructions.yaml").read_text(encoding="utf-8"))
    out = []
    for mnemonic, entry in doc["instructions"].items():
        for k in (*entry["operands"], *entry.get("optional", ())):
            if k not in OPERAND_KINDS:  # pragma: no cover - the shipped table is checked by a test
                raise ValueError(f"instructions.yaml: {mnemonic}: unknown operand kind {k!r}")
        out.append(LadderInstruction(mnemonic, entry["name"], entry["kind"], tuple(entry["operands"]),
                                     tuple(entry.get("optional", ())), entry["source"]))
    return InstructionTable(tuple(out), tuple(doc["motion"]), tuple(doc["motion_not_modelled"]),
                            tuple(doc["unsupported"]))
