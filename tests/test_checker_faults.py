"""Seeded faults are found, with shortest counterexamples that replay on the engine.

Each test mutates the spec IR (:mod:`checker.mutate`: a dropped guard, a swapped
target, a changed error code), checks a small system built on it, and requires

* the violated property to be reported with a counterexample;
* the counterexample to be of least length -- compared with an independent
  breadth-first search over *concrete* states (``System.snapshot()``, no abstraction,
  no symmetry);
* the counterexample, written as a scenario file, to pass ``simulate`` on the engine
  (python-statemachine) with the mutated spec: same observations, scan by scan.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from pathlib import Path

from checker import mutate
from checker.model import Model
from checker.properties import Property, load_properties
from checker.report import build_report
from checker.search import explore
from checker.system import SystemDef, bundled_systems, load_system
from statecharts import ir
from statecharts.scenario import load_scenario, run_scenario


def _small_system(spec: ir.Spec) -> SystemDef:
    sd = load_system(bundled_systems()["noncip"], spec)
    g = dataclasses.replace(sd.groups[0], configurations=sd.groups[0].configurations[:1],
                            program=("MSO", "MSF", "MDO", "MASD", "MAFR"))
    return dataclasses.replace(sd, name="small", groups=(g,), max_live_calls=1)


def _shortest_concrete(model: Model, prop: str, limit: int = 8) -> int | None:
    """Least number of scans to violate ``prop``, by plain BFS over exact snapshots."""
    model.initial(model.assignments[0])
    start = (model.system.snapshot(), tuple(model.monitor_values))
    seen = {start}
    queue = deque([(start, 0)])
    while queue:
        (snap, mons), depth = queue.popleft()
        if depth >= limit:
            continue
        model.system.restore(snap)
        options = model.enabled()
        for c in options:
            model.system.restore(snap)
            model.monitor_values = list(mons)
            _flat, bad, _good, _facts = model.step(c)
            if any(p.name == prop for p in bad):
                return depth + 1
            nxt = (model.system.snapshot(), tuple(model.monitor_values))
            if nxt not in seen:
                seen.add(nxt)
                queue.append((nxt, depth + 1))
    return None


def _check_mutant(spec: ir.Spec, mutant: ir.Spec, prop_name: str, tmp_path: Path) -> tuple[Property, int]:
    props = load_properties(mutant)
    model = Model(mutant, _small_system(mutant), props)
    result = explore(model, progress=False, stop_on_violation=True)
    assert prop_name in result.violations, f"{prop_name} not reported; violations: {sorted(result.violations)}"
    report = build_report(result, counterexamples=tmp_path)
    verdict = next(v for v in report.verdicts if v.prop.name == prop_name)
    assert verdict.holds is False and verdict.trace is not None and verdict.scenario is not None
    scans = len(verdict.trace.steps)
    # least length, by an independent search without abstractions
    fresh = Model(mutant, _small_system(mutant), props)
    assert _shortest_concrete(fresh, prop_name) == scans
    # the scenario replays on the engine with the mutated spec
    scenario = load_scenario(verdict.scenario, mutant)
    replayed = run_scenario(scenario, mutant)
    assert replayed.passed, [str(m) for m in replayed.mismatches]
    assert len(replayed.rows) == scans
    # and the unmutated spec does not reproduce it
    assert not run_scenario(load_scenario(verdict.scenario, spec), spec).passed
    return verdict.prop, scans


def test_swapped_target_is_found(spec: ir.Spec, tmp_path: Path) -> None:
    # MSO's request now lands in Direct Drive Control: the MSO never completes
    mutant, _m = mutate.swap_target(spec, "AxisNonCIP", "mso", "DirectDriveControl")
    prop, scans = _check_mutant(spec, mutant, "mso_held_rung_ends_in_dn_or_er", tmp_path)
    assert prop.kind == "response"
    assert scans == 2  # rung up (no DN, no ER), one more scan held: the bound of two is exceeded


def test_dropped_guard_is_found(spec: ir.Spec, tmp_path: Path) -> None:
    # the enable delay counts below zero once the output is applied
    mutant, _m = mutate.drop_guard(spec, "AxisNonCIP", "enable_delay")
    _check_mutant(spec, mutant, "output_applied_only_after_the_enable_delay", tmp_path)


def test_changed_error_code_is_found(spec: ir.Spec, tmp_path: Path) -> None:
    # MSO on a faulted axis now reports ER with ERR 0
    mutant, _m = mutate.set_error_code(spec, "MSO", "faulted", 0)
    _prop, scans = _check_mutant(spec, mutant, "er_implies_err_and_not_dn", tmp_path)
    assert scans == 2  # a servo fault (Disable Drive: Axis Faulted), then MSO


def test_changed_extended_error_is_found_by_error_code_coverage(spec: ir.Spec) -> None:
    # the abort of MDO reports 12/9: the catalogued 12/1 is never produced
    mutant, _m = mutate.set_error_code(spec, "MDO", "left_direct_drive", 12, 9)
    props = [p for p in load_properties(mutant) if p.kind == "cover" and p.cover == "error_codes"]
    sd = _small_system(mutant)
    result = explore(Model(mutant, sd, props), progress=False)
    report = build_report(result)
    (verdict,) = report.verdicts
    assert verdict.holds is False and "MDO:12/1" in verdict.detail


def test_every_mutant_kind_is_generated(spec: ir.Spec) -> None:
    kinds = {m.kind for _s, m in mutate.single_mutants(spec)}
    assert kinds == {"drop_guard", "swap_target", "error_code"}


def test_the_unmutated_small_system_has_no_violation(spec: ir.Spec) -> None:
    result = explore(Model(spec, _small_system(spec), load_properties(spec)), progress=False)
    assert result.complete and not result.violations and not result.deadlocks
