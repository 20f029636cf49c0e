"""Hypothesis strategies for property tests of a ladder program (needs ``hypothesis``).

Pipeline position: a user's test -> these strategies -> :class:`~statecharts.program.api.Controller`.

* :func:`free_inputs` names the BOOL tags a program only reads (push buttons, limit
  switches: nothing in the program writes them), the inputs the outside world drives;
* :func:`input_sequences` draws, per scan, values for such inputs;
* :func:`fault_injections` draws environment events (faults, shutdowns, connection
  loss) with the scan they happen in;
* :func:`axis_starts` draws a start state (with the drive-model variables that go with
  it) for each axis, from :data:`CIP_STARTS` or presets of one's own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from hypothesis import strategies as st

from statecharts.program.environment import CIP_STARTS, free_inputs
from statecharts.program.ir import Program

__all__ = ["CIP_STARTS", "axis_starts", "fault_injections", "free_inputs", "input_sequences", "programs"]

def input_sequences(program: Program, inputs: Sequence[str] | None = None, *, min_scans: int = 1,
                    max_scans: int = 50) -> st.SearchStrategy[list[dict[str, bool]]]:
    """Per scan, a dict of input writes (only the inputs that change need be there)."""
    names = tuple(inputs) if inputs is not None else free_inputs(program)
    if not names:
        return st.lists(st.just({}), min_size=min_scans, max_size=max_scans)
    return st.lists(st.dictionaries(st.sampled_from(names), st.booleans(), max_size=len(names)),
                    min_size=min_scans, max_size=max_scans)


def fault_injections(axes: Sequence[str], events: Sequence[str], *, max_events: int = 2,
                     max_scan: int = 50) -> st.SearchStrategy[list[tuple[int, str, str]]]:
    """Sorted (scan, axis, event) triples: environment events to inject."""
    one = st.tuples(st.integers(0, max_scan), st.sampled_from(tuple(axes)), st.sampled_from(tuple(events)))
    return st.lists(one, max_size=max_events).map(sorted)


def axis_starts(axes: Sequence[str], presets: Mapping[str, Mapping[str, Any]] | None = None
                ) -> st.SearchStrategy[dict[str, Mapping[str, Any]]]:
    """For each axis, one start (``{state:, variables:}``) from ``presets`` (default: :data:`CIP_STARTS`)."""
    table = dict(presets or CIP_STARTS)
    names = tuple(table)
    return st.fixed_dictionaries({a: st.sampled_from(names) for a in axes}).map(
        lambda chosen: {a: {"type": "AXIS_CIP_DRIVE", **table[s]} if presets is None else dict(table[s])
                        for a, s in chosen.items()})


#: the tag pool of :func:`programs`: free BOOL inputs, BOOL and DINT tags, a timer, a counter
PROGRAM_INPUTS = ("I0", "I1", "I2")
_BOOLS = ("B0", "B1", "B2", "B3")
_MOTION = ("MSO", "MSF", "MAFR", "MASR", "MASD", "MSO", "MSF", "MAFR")


@st.composite
def programs(draw: st.DrawFn, *, max_rungs: int = 8, axes: Sequence[str] = ("X_axis", "Y_axis")) -> str:
    """A random routine in neutral text over a fixed pool of tags: contacts of the free inputs
    (:data:`PROGRAM_INPUTS`) and of BOOL, DINT, TIMER, COUNTER and motion-tag members,
    branches, coils, latches, one-shots, compares, moves, adds, a timer, a counter and
    motion instructions (each with its own MOTION_INSTRUCTION tag) on ``axes``."""
    motion_left = list(range(len(_MOTION) * len(axes)))
    draw(st.randoms()).shuffle(motion_left)
    used_motion: list[str] = []

    def contact() -> str:
        choices = ["bool", "input", "equ", "grt", "timer", "counter"] + (["motion"] if used_motion else [])
        kind = draw(st.sampled_from(choices))
        if kind == "bool":
            return f"{draw(st.sampled_from(('XIC', 'XIO')))}({draw(st.sampled_from(_BOOLS))})"
        if kind == "input":
            return f"{draw(st.sampled_from(('XIC', 'XIO')))}({draw(st.sampled_from(PROGRAM_INPUTS))})"
        if kind == "equ":
            return f"EQU(D0,{draw(st.integers(0, 3))})"
        if kind == "grt":
            return f"GRT(D1,{draw(st.integers(0, 3))})"
        if kind == "timer":
            return f"XIC(T0.{draw(st.sampled_from(('DN', 'TT', 'EN')))})"
        if kind == "counter":
            return "XIC(C0.DN)"
        tag = draw(st.sampled_from(used_motion))
        return f"{draw(st.sampled_from(('XIC', 'XIO')))}({tag}.{draw(st.sampled_from(('DN', 'ER', 'EN')))})"

    def conditions() -> str:
        out = "".join(contact() for _ in range(draw(st.integers(0, 2))))
        if draw(st.booleans()):
            legs = [contact() + (contact() if draw(st.booleans()) else "") for _ in range(draw(st.integers(2, 3)))]
            out += "[" + ",".join(legs) + "]"
        return out

    def output() -> str:
        kinds = ["ote", "otl", "otu", "ons", "osr", "mov", "add", "ton", "ctu", "res"]
        if motion_left:
            kinds += ["motion", "motion"]
        kind = draw(st.sampled_from(kinds))
        b = draw(st.sampled_from(_BOOLS))
        if kind == "ote":
            return f"OTE({b})"
        if kind == "otl":
            return f"OTL({b})"
        if kind == "otu":
            return f"OTU({b})"
        if kind == "ons":
            return f"ONS(S{draw(st.integers(0, 3))})OTE({b})"
        if kind == "osr":
            return f"OSR(S{draw(st.integers(4, 5))},{b})"
        if kind == "mov":
            return f"MOV({draw(st.integers(0, 3))},{draw(st.sampled_from(('D0', 'D1')))})"
        if kind == "add":
            return "ADD(D1,1,D1)"
        if kind == "ton":
            return "TON(T0,30,0)"
        if kind == "ctu":
            return "CTU(C0,2,0)"
        if kind == "res":
            return "RES(C0)"
        n = motion_left.pop()
        mnemonic, axis = _MOTION[n % len(_MOTION)], axes[n // len(_MOTION)]
        tag = f"M{n}"
        used_motion.append(tag)
        return f"{mnemonic}({axis},{tag})"

    # the timer, the counter and the DINTs are declared by use in the first rungs
    rungs = ["XIC(I0)TON(T0,30,0);", "XIC(I1)CTU(C0,2,0);", "XIC(I2)MOV(1,D0);", "XIC(I0)XIC(I1)ADD(D1,1,D1);"]
    rungs += [conditions() + output() + ";" for _ in range(draw(st.integers(1, max_rungs)))]
    rungs.append("GRT(D1,3)CLR(D1);")  # D1 stays small
    return "\n".join(rungs) + "\n"
