"""Documented laws of motion instructions and the non-CIP axis, on random programs.

A hypothesis ``RuleBasedStateMachine`` is generated from the spec at run time: one tag
per instruction of the axis chart, each bound to one of one or two axes, and one rule
per tag (set its rung, with operands drawn from the operands' domains), plus rules that
set several rungs at once, apply an environment event, run a prescan, or run a plain
scan.  Every rule is exactly one :meth:`System.scan`.

The expected behaviour is *not* taken from the spec (that would restate it, see
DESIGN.md "Quality rules").  The laws below are written by hand from the source
documents; the bit numbers and state values are typed in from
``shared/reference/domain-facts.md``:

* tag laws (domain-facts §2, DESIGN "ER implies ERR != 0 and not DN"):
  ER implies ERR != 0 and not DN; DN and ER are never both set; with ER clear, ERR and
  EXERR are 0 (qualified: a prescan clears ER but the documents do not say that it
  clears ERR, see ``test_err_zero_whenever_er_clear_even_after_prescan``);
* FLAGS is EN<<31 | DN<<29 | ER<<28 | PC<<27 | IP<<26 read as a signed 32-bit DINT
  (domain-facts §2; packed with ``struct``, an encoding independent of the engine's);
* execution table (domain-facts §4, RM002H-p79):
  - prescan clears EN, DN, ER on every tag;
  - rung-condition-in false clears EN only if DN or ER was already set:
    ``EN_after == EN_before and not (DN_before or ER_before)``.  This holds for the
    whole scan, not only for the program part, because nothing else in a scan may
    touch EN (the coarse update sets DN or ER of a completing request, never EN);
  - rung-condition-in true with EN already set does nothing: DN, ER, ERR, EXERR
    change only when a request still in progress (EN set, DN and ER clear) completes,
    and then to exactly one of DN or ER; EN stays set;
  - rung-condition-in true with EN clear sets EN (the instruction executes);
* a refused instruction changes nothing on its axis: in a scan in which it is the only
  instruction that executes, no other request of its axis is outstanding and no
  environment event is applied, an ER (whatever its ERR, state-related or not) leaves
  AxisState as it was;
* no instruction hangs: a request that was accepted ends with DN or ER within
  ceil(500 ms / coarse update) + 2 coarse updates after the last environment event
  (EN "held until messaging is done", DN "finished", ER "failed": domain-facts §2, §4;
  the longest documented wait of the state instructions is MDO's ~500 ms enable delay).
  MRHD's motor/encoder test may take its 2 s time-out (000), so ceil(2000 ms / coarse
  update) + 2; its encoder and marker tests have no time-out and end only on feedback,
  a marker pulse or an abort (000: "abort the test using the MAS instruction"), so they
  are exempt.  A prescan drops every pending request, which then gets no DN (INT-020);
* axis status bits (domain-facts §3a, §3e): DriveEnableStatus exactly in Direct Drive
  Control (1) and Servo Control (2); ServoActionStatus exactly in Servo Control;
  ShutdownStatus exactly in Shutdown (4); the OK contact open exactly in Shutdown;
  AxisState is one of 0..4.

``test_laws_catch_*`` show that the laws are not vacuous: the same state machine run on
deliberately broken variants (a scan whose rung-false row clears EN unconditionally; a
chart whose Servo Control entry forgets DriveEnableStatus; a chart that ignores MSO's
request in Axis Ready) must fail.

A law the current spec breaks is kept as a strict xfail with the shrunk step list
replayed deterministically: "ERR == 0 whenever ER is clear" without the prescan
exception.
"""

from __future__ import annotations

import contextlib
import dataclasses
import struct
from collections.abc import Mapping

import pytest
from hypothesis import HealthCheck, Phase, Verbosity, settings
from hypothesis import event as record_event
from hypothesis import strategies as st
from hypothesis.errors import InvalidArgument
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
    run_state_machine_as_test,
)

from motionchart.strategies import (
    AxisSetup,
    axis_setups,
    environment_event_names,
    instructions_for,
    operand_sets,
    programs,
    rung_patterns,
    scan_timings,
    tag_name,
    value_operands,
)
from statecharts import ir
from statecharts.loader import load_spec
from statecharts.scan import EnvironmentEvent, ScanInputs, System, TagInstance

SPEC = load_spec()
CHART = SPEC.chart("AxisNonCIP")
AXIS_NAMES = ("Axis1", "Axis2")

# --- typed in from domain-facts, never read from the spec ---------------------------------
# §2 MOTION_INSTRUCTION bit numbers in FLAGS (IP = 26, PC = 27 per RM002H-p129)
BIT_EN, BIT_DN, BIT_ER, BIT_PC, BIT_IP = 31, 29, 28, 27, 26
# §3a non-CIP AxisState values
AXIS_READY, DIRECT_DRIVE_CONTROL, SERVO_CONTROL, AXIS_FAULTED, SHUTDOWN = 0, 1, 2, 3, 4
AXIS_STATES = frozenset({AXIS_READY, DIRECT_DRIVE_CONTROL, SERVO_CONTROL, AXIS_FAULTED, SHUTDOWN})

STEPS = 30
# §4 MDO: about 500 ms between drive enable and the output (the longest documented delay
# of the state instructions)
ENABLE_DELAY_MS = 500
# 000 MRHD: the motor/encoder test times out after 2 s; the encoder (1) and marker (2)
# tests have no time-out
MRHD_TIME_OUT_MS = 2000
MRHD_UNTIMED_TESTS = (1, 2)


def flags_dint(tag: Mapping[str, object]) -> int:
    """FLAGS from the five bits, reinterpreted as a little-endian signed 32-bit integer."""
    word = 0
    for name, bit in (("EN", BIT_EN), ("DN", BIT_DN), ("ER", BIT_ER), ("PC", BIT_PC), ("IP", BIT_IP)):
        if tag[name]:
            word |= 1 << bit
    (value,) = struct.unpack("<i", struct.pack("<I", word))
    return value


def _note(label: str) -> None:
    """Count how often a conditional law was exercised (``--hypothesis-show-statistics``)."""
    with contextlib.suppress(InvalidArgument):  # a replay outside hypothesis
        record_event(label)


def _result(tag: Mapping[str, object]) -> tuple[object, ...]:
    return (tag["DN"], tag["ER"], tag["ERR"], tag["EXERR"])


def _show(tag: Mapping[str, object]) -> str:
    return " ".join(f"{k}={tag[k]!r}" for k in ("EN", "DN", "ER", "ERR", "EXERR"))


def make_law_machine(
    *,
    spec: ir.Spec = SPEC,
    chart: ir.Chart = CHART,
    system_cls: type[System] = System,
    prescan_may_keep_err: bool = True,
    check_liveness: bool = True,
    name: str = "MotionLaws",
) -> type[RuleBasedStateMachine]:
    """The law-checking state machine for ``chart``'s instructions, built from the IR.

    ``system_cls`` and ``chart`` let the quality tests run the same laws on broken
    variants; ``prescan_may_keep_err=False`` checks "ERR == 0 when ER is clear" with no
    exception for a stale code left by a prescan; ``check_liveness=False`` switches the
    no-hang law off.
    """
    instructions = instructions_for(spec, chart)
    tag_instruction = {tag_name(i.id): i for i in instructions}
    tags = tuple(tag_instruction)
    operand_strategies = {t: operand_sets(i) for t, i in tag_instruction.items() if value_operands(i)}

    class Laws(RuleBasedStateMachine):
        # ---------------------------------------------------------------- set-up

        @initialize(
            axis1=axis_setups(chart, AXIS_NAMES[0]),
            axis2=st.none() | axis_setups(chart, AXIS_NAMES[1]),
            program=programs(spec, chart, AXIS_NAMES),
            timing=scan_timings(),
        )
        def setup(
            self,
            axis1: AxisSetup,
            axis2: AxisSetup | None,
            program: tuple[tuple[str, str, str], ...],
            timing: tuple[int, int],
        ) -> None:
            scan_ms, coarse_ms = timing
            params = {"scan_ms": scan_ms, "coarse_update_ms": coarse_ms}
            setups = [axis1] if axis2 is None else [axis1, axis2]
            self.axis_names = tuple(s.name for s in setups)
            axes = [s.build(chart, params) for s in setups]
            prog = [(t, m, ax if ax in self.axis_names else self.axis_names[0]) for t, m, ax in program]
            self.axis_of = {t: ax for t, _, ax in prog}
            self.system = system_cls(spec, axes, prog, scan_ms=scan_ms, coarse_update_ms=coarse_ms)
            self.obs: Mapping[str, Mapping[str, object]] = self.system.observe()
            self.rung_state = dict.fromkeys(tags, False)
            self.outstanding: set[str] = set()  # executed, neither DN nor ER seen since
            self.stale_err: set[str] = set()  # had ER when a prescan cleared it
            self.held_events = 0  # environment events not yet applied by a coarse update
            # coarse updates without an environment event since each outstanding tag executed
            self.quiet_updates: dict[str, int] = {}
            self.patience = -(-ENABLE_DELAY_MS // coarse_ms) + 2
            self.coarse_ms = coarse_ms
            self.patience_of: dict[str, int | None] = {}  # per executed tag; None: no bound

        # ---------------------------------------------------------------- rules

        @rule(pattern=rung_patterns(tags), operands=st.fixed_dictionaries(operand_strategies))
        def rungs(self, pattern: dict[str, bool], operands: dict[str, dict[str, object]]) -> None:
            ops = {t: o for t, o in operands.items() if t in pattern}
            self._scan(ScanInputs(rungs=pattern, operands=ops))

        @rule(axis=st.sampled_from(AXIS_NAMES), event=environment_event_names(chart))
        def environment(self, axis: str, event: str) -> None:
            if axis not in self.axis_names:
                axis = self.axis_names[0]
            self._scan(ScanInputs(events=(EnvironmentEvent(axis, event),)))

        @rule()
        def prescan(self) -> None:
            self._scan(ScanInputs(prescan=True))

        @rule()
        def plain_scan(self) -> None:
            self._scan(ScanInputs())

        # ---------------------------------------------------------------- one scan + laws

        def _scan(self, inputs: ScanInputs) -> None:
            before = self.obs
            rungs = {**self.rung_state, **inputs.rungs}
            held = self.held_events + len(inputs.events)
            executed = [] if inputs.prescan else [t for t in tags if rungs[t] and not before[t]["EN"]]

            record = self.system.scan(inputs)
            after = record.observations
            self.rung_state = rungs

            if inputs.prescan:
                for t in tags:
                    a = after[t]
                    assert not (a["EN"] or a["DN"] or a["ER"]), f"[prescan] {t} after a prescan: {_show(a)}"
            else:
                for t in tags:
                    self._execution_table_laws(t, rungs[t], before[t], after[t])

            events_applied = record.coarse_update and held > 0
            if len(executed) == 1 and not events_applied:
                t = executed[0]
                ax = self.axis_of[t]
                others = {o for o in self.outstanding if o != t and self.axis_of[o] == ax}
                if after[t]["ER"] and not others:
                    _note("law applied: refused instruction leaves the axis state")
                    assert after[ax]["AxisState"] == before[ax]["AxisState"], (
                        f"[refused] {t} was refused ({_show(after[t])}) but {ax} went from "
                        f"{before[ax]['state']} to {after[ax]['state']}"
                    )

            # bookkeeping for the next scan
            if inputs.prescan:
                self.stale_err |= {t for t in tags if before[t]["ER"]}
                self.outstanding.clear()  # a prescan drops every pending request (INT-020)
            else:
                self.stale_err -= set(executed)
                self.outstanding |= set(executed)
                for t in executed:
                    self.quiet_updates[t] = 0
                    self.patience_of[t] = self._patience(t)
            self.outstanding -= {t for t in tags if after[t]["DN"] or after[t]["ER"]}
            if record.coarse_update:
                for t in self.outstanding:
                    self.quiet_updates[t] = 0 if events_applied else self.quiet_updates[t] + 1
            if check_liveness:
                for t in sorted(self.outstanding):
                    if self.patience_of.get(t, self.patience) is None:
                        continue
                    assert self.quiet_updates[t] <= self.patience_of.get(t, self.patience), (
                        f"[liveness] {t} executed and has neither DN nor ER after "
                        f"{self.quiet_updates[t]} coarse updates without environment events: "
                        f"{_show(after[t])}; {self.axis_of[t]} in {after[self.axis_of[t]]['state']}"
                    )
            self.held_events = 0 if record.coarse_update else held
            self.obs = after

        def _patience(self, t: str) -> int | None:
            if tag_instruction[t].mnemonic != "MRHD":
                return self.patience
            if self.system.tags[t].operands.get("DiagnosticTest") in MRHD_UNTIMED_TESTS:
                return None
            return -(-MRHD_TIME_OUT_MS // self.coarse_ms) + 2

        @staticmethod
        def _execution_table_laws(
            t: str, rung: bool, b: Mapping[str, object], a: Mapping[str, object]
        ) -> None:
            if not rung:
                expected = bool(b["EN"]) and not (b["DN"] or b["ER"])
                if expected:
                    _note("law applied: rung false while a request is in progress")
                assert a["EN"] == expected, (
                    f"[rung-false] {t}: EN must be cleared only if DN or ER was set; "
                    f"before {_show(b)}, after {_show(a)}"
                )
            elif b["EN"]:
                assert a["EN"], f"[rung-true held] {t} lost EN: before {_show(b)}, after {_show(a)}"
                if _result(a) != _result(b):
                    in_progress = not b["DN"] and not b["ER"]
                    assert in_progress, (
                        f"[rung-true held] {t} changed its result without executing: "
                        f"before {_show(b)}, after {_show(a)}"
                    )
                    _note("law applied: request completed under a held rung")
                    assert bool(a["DN"]) != bool(a["ER"]), (
                        f"[rung-true held] {t} changed but did not complete: before {_show(b)}, after {_show(a)}"
                    )
            else:
                assert a["EN"], f"[rung-true] {t}: a false-to-true rung must set EN; after {_show(a)}"

        # ---------------------------------------------------------------- state laws

        def check_state_laws(self) -> None:
            for t in tags:
                tag = self.obs[t]
                if tag["ER"]:
                    assert tag["ERR"] != 0, f"[ER=>ERR] {t}: {_show(tag)}"
                    assert not tag["DN"], f"[ER=>not DN] {t}: {_show(tag)}"
                assert not (tag["DN"] and tag["ER"]), f"[DN xor ER] {t}: {_show(tag)}"
                if not tag["ER"] and (t not in self.stale_err or not prescan_may_keep_err):
                    assert tag["ERR"] == 0 and tag["EXERR"] == 0, f"[no ER=>ERR 0] {t}: {_show(tag)}"
                assert tag["FLAGS"] == flags_dint(tag), f"[FLAGS] {t}: FLAGS={tag['FLAGS']} for {dict(tag)}"
            for ax in self.axis_names:
                axis = self.obs[ax]
                state = axis["AxisState"]
                assert state in AXIS_STATES, f"[AxisState] {ax}: {state!r}"
                expect = {
                    "DriveEnableStatus": state in (DIRECT_DRIVE_CONTROL, SERVO_CONTROL),
                    "ServoActionStatus": state == SERVO_CONTROL,
                    "ShutdownStatus": state == SHUTDOWN,
                    "OKContact": state != SHUTDOWN,
                }
                got = {k: axis[k] for k in expect}
                assert got == expect, f"[status-bits] {ax} in AxisState {state} ({axis['state']}): {got}"

        @invariant()
        def state_laws(self) -> None:
            self.check_state_laws()

    ns: dict[str, object] = {}
    for t, ins in tag_instruction.items():
        if value_operands(ins):

            def set_rung(self: Laws, rung: bool, operands: dict[str, object], t: str = t) -> None:
                self._scan(ScanInputs(rungs={t: rung}, operands={t: operands}))

            arguments = {"rung": st.booleans(), "operands": operand_sets(ins)}
        else:

            def set_rung(self: Laws, rung: bool, t: str = t) -> None:
                self._scan(ScanInputs(rungs={t: rung}))

            arguments = {"rung": st.booleans()}
        set_rung.__name__ = f"rung_{t}"
        ns[set_rung.__name__] = rule(**arguments)(set_rung)
    return type(name, (Laws,), ns)


MotionLaws = make_law_machine()
MotionLaws.TestCase.settings = settings(stateful_step_count=STEPS)
TestMotionLaws = MotionLaws.TestCase


# --------------------------------------------------------------------------- replays
#
# Step lists that hypothesis shrank a failing law to, replayed as plain sequences so
# that the strict xfail (and the regressions) are deterministic.  The state laws are
# checked after every step, as hypothesis does.

DEFAULT_VARIABLES = (("AxisConfiguration", "Servo"), ("Configured", True), ("FaultAction", "DisableDrive"))
ALL_ON_AXIS1 = tuple((tag_name(i.id), i.id, "Axis1") for i in instructions_for(SPEC, CHART))

Step = tuple[str, dict[str, object]]


def replay(
    machine_cls: type[RuleBasedStateMachine],
    steps: list[Step],
    *,
    axis_type: str = "AXIS_SERVO",
    state: str = "AxisReady",
    variables: tuple[tuple[str, object], ...] = DEFAULT_VARIABLES,
    timing: tuple[int, int] = (10, 10),
    expect_law: str | None = None,
) -> None:
    """Run ``steps`` on ``machine_cls``; a failure of another law than ``expect_law``
    is turned into a RuntimeError (so that an xfail cannot pass for the wrong reason)."""
    m = machine_cls()
    m.setup(
        axis1=AxisSetup(name="Axis1", axis_type=axis_type, state=state, variables=variables),
        axis2=None,
        program=ALL_ON_AXIS1,
        timing=timing,
    )
    try:
        m.check_state_laws()
        for method, kwargs in steps:
            getattr(m, method)(**kwargs)
            m.check_state_laws()
    except AssertionError as e:
        if expect_law is not None and f"[{expect_law}]" not in str(e):
            raise RuntimeError(f"expected the [{expect_law}] law to fail, got: {e}") from e
        raise
    m.teardown()


MDO_50V_THEN_PRESCAN: list[Step] = [
    ("rung_MDO_Ctrl", {"rung": True, "operands": {"DriveOutput": 50.0, "DriveUnits": 0}}),
    ("prescan", {}),
]


# Prescan clears the bits but keeps ERR/EXERR (INT-020); scenarios/noncip/prescan_keeps_err.yaml
# pins the values, and the law below allows exactly that case.
def test_err_law_allows_the_code_a_prescan_leaves() -> None:
    replay(MotionLaws, MDO_50V_THEN_PRESCAN)


#: Step lists that broke the liveness law on an earlier working tree (the first is the
#: list hypothesis shrank to; the other two were written by hand from the same analysis).
#: They were fixed by finishing each request as soon as it is answered (scan.py) and by
#: INT-017 for MASR.  Kept as regressions.
HANG_REGRESSIONS = {
    # two requests for one axis in one coarse update: MASD's completion (ShutdownStatus)
    # was judged after MASR had already left Shutdown, so MASD never set DN or ER
    "masd_and_masr_in_one_update": {
        "steps": [("rungs", {"pattern": {"MASD_Ctrl": True, "MASR_Ctrl": True}, "operands": {}})]
        + [("plain_scan", {})] * 4,
        "timing": (500, 500),
    },
    # MASR on an axis whose fault condition persists with FaultAction Shutdown: the fault
    # latches again in the same update and ShutdownStatus stays set
    "masr_with_persisting_fault": {
        "steps": [("environment", {"axis": "Axis1", "event": "servo_fault"}), ("rung_MASR_Ctrl", {"rung": True})]
        + [("plain_scan", {})] * 4,
        "variables": (("AxisConfiguration", "Servo"), ("Configured", True), ("FaultAction", "Shutdown")),
        "timing": (500, 500),
    },
    # a fault in the update that answers MSO: the axis is Axis Faulted and MSO's
    # completion (servo and drive on) can no longer hold
    "mso_overtaken_by_fault": {
        "steps": [
            ("plain_scan", {}),  # scan 0 has a coarse update; scan 1 has none
            ("rung_MSO_Ctrl", {"rung": True}),  # queued
            ("environment", {"axis": "Axis1", "event": "servo_fault"}),  # answered, then the fault
        ]
        + [("plain_scan", {})] * 8,
        "timing": (250, 500),
    },
}


@pytest.mark.parametrize("case", sorted(HANG_REGRESSIONS))
def test_no_instruction_hangs(case: str) -> None:
    replay(MotionLaws, **HANG_REGRESSIONS[case])


# --------------------------------------------------------------------------- the laws catch bugs

QUALITY_SETTINGS = settings(
    max_examples=600,
    stateful_step_count=STEPS,
    database=None,
    derandomize=True,
    verbosity=Verbosity.quiet,
    phases=(Phase.generate,),
    suppress_health_check=list(HealthCheck),
)


class RungFalseAlwaysClearsEN(System):
    """Broken scan: the rung-false row clears EN whether or not DN or ER is set."""

    def _row(self, tag: TagInstance, condition: str) -> None:
        if condition == "rung_false":
            tag.values["EN"] = False
            return
        super()._row(tag, condition)


def servo_entry_without_drive_enable(chart: ir.Chart) -> ir.Chart:
    """Broken chart: entering Servo Control no longer sets DriveEnableStatus."""
    states = tuple(
        dataclasses.replace(s, entry=tuple(a for a in s.entry if a.target != "DriveEnableStatus"))
        if s.value == SERVO_CONTROL
        else s
        for s in chart.states
    )
    return dataclasses.replace(chart, states=states)


def test_laws_catch_unconditional_rung_false() -> None:
    broken = make_law_machine(system_cls=RungFalseAlwaysClearsEN, name="BrokenRungFalse")
    with pytest.raises(AssertionError, match=r"\[rung-false\]"):
        run_state_machine_as_test(broken, settings=QUALITY_SETTINGS)


def test_laws_catch_servo_control_without_drive_enable() -> None:
    broken = make_law_machine(chart=servo_entry_without_drive_enable(CHART), name="BrokenServoEntry")
    with pytest.raises(AssertionError, match=r"\[status-bits\]"):
        run_state_machine_as_test(broken, settings=QUALITY_SETTINGS)


def servo_on_ignored_in_axis_ready(spec: ir.Spec, chart: ir.Chart) -> ir.Chart:
    """Broken chart: the axis ignores MSO's request (its event) in Axis Ready."""
    event = spec.instruction("MSO").request.event
    ready = [s.id for s in chart.states if s.value == AXIS_READY]
    kept = tuple(t for t in chart.transitions if not (t.event == event and t.source in ready))
    return dataclasses.replace(chart, transitions=kept)


def test_laws_catch_a_request_that_is_never_answered() -> None:
    broken = make_law_machine(chart=servo_on_ignored_in_axis_ready(SPEC, CHART), name="BrokenServoOn")
    with pytest.raises(AssertionError, match=r"\[liveness\]"):
        run_state_machine_as_test(broken, settings=QUALITY_SETTINGS)
