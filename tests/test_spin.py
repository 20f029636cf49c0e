"""SPIN as a second engine: the Promela export finds exactly the Python search's states.

The Promela model (:mod:`checker.promela`) is verified by SPIN's own search, hashing and
symmetry handling (the product of the axes, the clock, the interleaving of inputs and
the sorting of interchangeable axes are SPIN's); the counts must equal those of
:func:`checker.search.explore`.  A seeded fault must be found by both engines with
counterexamples of the same length, and SPIN's trail must replay on the engine as a
scenario that shows the violation.

Needs ``spin`` and a C compiler (``make deps-spin`` installs them as root); without them
these tests are skipped and the reason is printed once in the warnings summary.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from conftest import sampled

from checker import mutate, spin
from checker.model import Model
from checker.promela import build
from checker.properties import load_properties
from checker.report import build_report
from checker.search import explore
from checker.system import SystemDef, bundled_systems, load_system
from statecharts import ir
from statecharts.loader import bundled_spec_dir, load_spec
from statecharts.scenario import load_scenario, run_scenario

ROOT = Path(__file__).resolve().parents[1]
FIVE = ROOT / "benchmarks" / "five_state"
MISSING = spin.missing_tools()
if MISSING is not None:
    warnings.warn(f"SPIN tests skipped: {MISSING}", stacklevel=1)
needs_spin = pytest.mark.skipif(MISSING is not None, reason=f"SPIN tests skipped: {MISSING}")


def _five(n: int, *, symmetry: bool = True) -> Model:
    spec = load_spec([bundled_spec_dir(), FIVE / "chart.yaml"])
    sd = load_system(FIVE / "system.yaml", spec).scaled(n)
    return Model(spec, sd, (), symmetry=None if symmetry else False)


def _bundled(name: str, spec: ir.Spec) -> Model:
    return Model(spec, load_system(bundled_systems()[name], spec), load_properties(spec))


def _small_system(spec: ir.Spec) -> SystemDef:
    sd = load_system(bundled_systems()["noncip"], spec)
    g = dataclasses.replace(sd.groups[0], configurations=sd.groups[0].configurations[:1],
                            program=("MSO", "MSF", "MDO", "MASD", "MAFR"))
    return dataclasses.replace(sd, name="small", groups=(g,), max_live_calls=1)


def test_export_is_deterministic() -> None:
    a = build(_five(3)).text
    b = build(_five(3)).text
    assert a == b
    assert "active proctype scan()" in a and a.count("do\n") == 1
    # the names of the spec's states and the axes are in the model
    assert "mtype = { FiveState_READY, FiveState_DDC, FiveState_SERVO" in a
    assert "#define Axis1 0" in a


def test_export_command_writes_the_model(tmp_path: Path) -> None:
    out = tmp_path / "model.pml"
    cmd = [sys.executable, "-m", "checker", "export", "--format", "promela", "--spec", str(bundled_spec_dir()),
           "--spec", str(FIVE / "chart.yaml"), "--system", str(FIVE / "system.yaml"), "--axes", "2", "-o", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, check=False)
    assert p.returncode == 0, p.stderr
    assert out.read_text().startswith("/* motionchart-promela/1: system five_state")
    p2 = subprocess.run(cmd[:-2], capture_output=True, text=True, cwd=ROOT, check=False)
    assert p2.returncode == 0 and p2.stdout == out.read_text()


def test_export_rejects_an_unknown_system() -> None:
    p = subprocess.run([sys.executable, "-m", "checker", "export", "--system", "nope"], capture_output=True,
                       text=True, cwd=ROOT, check=False)
    assert p.returncode == 2 and "unknown system 'nope'" in p.stderr and "Traceback" not in p.stderr


def test_spin_options_need_the_spin_engine() -> None:
    p = subprocess.run([sys.executable, "-m", "checker", "check", "--cores", "2"], capture_output=True, text=True,
                       cwd=ROOT, check=False)
    assert p.returncode == 2 and "--engine spin" in p.stderr


def test_missing_spin_is_a_clear_error(tmp_path: Path) -> None:
    p = subprocess.run([sys.executable, "-m", "checker", "check", "--engine", "spin", "--spec",
                        str(bundled_spec_dir()), "--spec", str(FIVE / "chart.yaml"), "--system",
                        str(FIVE / "system.yaml"), "--axes", "1"], capture_output=True, text=True, cwd=ROOT,
                       check=False, env={"PATH": str(tmp_path), "HOME": str(tmp_path)})
    assert p.returncode == 1 and "spin" in p.stderr and "not found" in p.stderr and "Traceback" not in p.stderr


@needs_spin
@pytest.mark.parametrize(("n", "symmetry"), sampled([(3, True), (3, False), (6, True), (9, True), (6, False), (9, False)],
                                                    {(3, True), (3, False)}))
def test_five_state_counts_equal(n: int, symmetry: bool) -> None:
    python = explore(_five(n, symmetry=symmetry), progress=False)
    run = spin.verify(_five(n, symmetry=symmetry), spin.SpinOptions())
    assert run.stats.complete and run.stats.errors == 0
    assert run.stats.states == python.states


@needs_spin
@pytest.mark.parametrize("name", sampled(["noncip", "cip", "noncip_pairs"], {"noncip"}))
def test_bundled_system_counts_and_verdicts_equal(name: str, spec: ir.Spec) -> None:
    python = explore(_bundled(name, spec), progress=False)
    run = spin.verify(_bundled(name, spec), spin.SpinOptions())
    assert run.stats.complete
    assert run.stats.states == python.states
    assert set(run.result.violations) == set(python.violations)
    assert set(run.result.reached) == set(python.reached)
    # breadth-first: the same shortest witnesses
    assert {k: w.depth for k, w in run.result.reached.items()} == {k: w.depth for k, w in python.reached.items()}


@needs_spin
def test_seeded_fault_is_found_by_both_engines(spec: ir.Spec, tmp_path: Path) -> None:
    # MSO on a faulted axis now reports ER with ERR 0
    mutant, _m = mutate.set_error_code(spec, "MSO", "faulted", 0)
    props = load_properties(mutant)
    prop = "er_implies_err_and_not_dn"
    python = build_report(explore(Model(mutant, _small_system(mutant), props), progress=False),
                          counterexamples=tmp_path / "python")
    run = spin.verify(Model(mutant, _small_system(mutant), props), spin.SpinOptions(workdir=tmp_path / "spin"))
    assert run.stats.states == python.result.states
    report = build_report(run.result, counterexamples=tmp_path / "spin-ce")
    by_engine = {}
    for r in (python, report):
        v = next(v for v in r.verdicts if v.prop.name == prop)
        assert v.holds is False and v.trace is not None and v.scenario is not None
        by_engine[r is report] = v
    sv = by_engine[True]
    assert len(sv.trace.steps) == len(by_engine[False].trace.steps) == 2  # a servo fault, then MSO
    assert list((tmp_path / "spin").glob("model.pml*.trail"))
    # SPIN's trail, replayed on the engine as a scenario, shows the violation
    scenario = load_scenario(sv.scenario, mutant)
    replayed = run_scenario(scenario, mutant)
    assert replayed.passed, [str(m) for m in replayed.mismatches]
    last = sv.trace.steps[-1].observations
    assert last["Axis"]["state"] == "AxisFaulted"
    assert last["Axis_MSO"]["ER"] is True and last["Axis_MSO"]["ERR"] == 0  # ER without an error code
    # the unmutated spec does not reproduce it
    assert not run_scenario(load_scenario(sv.scenario, spec), spec).passed


@needs_spin
def test_check_engine_spin_json_has_the_python_fields(tmp_path: Path) -> None:
    base = [sys.executable, "-m", "checker", "check", "--spec", str(bundled_spec_dir()), "--spec",
            str(FIVE / "chart.yaml"), "--system", str(FIVE / "system.yaml"), "--axes", "3", "--json",
            "--properties", str(tmp_path / "none.yaml")]
    (tmp_path / "none.yaml").write_text("format: motionchart-properties/1\nproperties: []\n")
    py = subprocess.run(base, capture_output=True, text=True, cwd=ROOT, check=False)
    sp = subprocess.run([*base, "--engine", "spin", "--cores", "2"], capture_output=True, text=True, cwd=ROOT,
                        check=False)
    assert py.returncode == 0, py.stderr
    assert sp.returncode == 0, sp.stderr
    a, b = json.loads(py.stdout), json.loads(sp.stdout)
    assert set(a) <= set(b)
    assert b["engine"] == "spin" and a["states"] == b["states"] == 35
    assert "-DBFS_PAR" in b["spin"]["flags"]


@needs_spin
def test_swarm_finds_the_seeded_fault(spec: ir.Spec, tmp_path: Path) -> None:
    mutant, _m = mutate.set_error_code(spec, "MSO", "faulted", 0)
    props = [p for p in load_properties(mutant) if p.name == "er_implies_err_and_not_dn"]
    run = spin.verify(Model(mutant, _small_system(mutant), props),
                      spin.SpinOptions(swarm=2, cores=2, workdir=tmp_path))
    assert not run.result.complete  # a swarm is not exhaustive
    assert "er_implies_err_and_not_dn" in run.result.violations
    assert (tmp_path / "swarm.lib").is_file()
    report = build_report(run.result)
    (v,) = report.verdicts
    assert v.holds is False and v.trace is not None


def test_pan_output_is_parsed(tmp_path: Path) -> None:
    text = """pan:1: assertion violated (viol!=3) (at depth 2)
pan: wrote model.pml1.trail
(Spin Version 6.5.2 -- 6 December 2019)
State-vector 28 byte, depth reached 27, errors: 1
    79913 states, stored
   401220 states, matched
   481133 transitions (= stored+matched)
  132.000	total actual memory usage
pan: elapsed time 0.6 seconds
"""
    st = spin.parse_pan(text, tmp_path)
    assert (st.states, st.transitions, st.depth, st.errors, st.seconds) == (79913, 481133, 27, 1, 0.6)
    assert st.memory_mb == 132.0 and st.complete
    assert st.trails == [(2, tmp_path / "model.pml1.trail")]
    assert not spin.parse_pan(text + "error: max search depth too small\n", tmp_path).complete


def test_a_time_out_stops_every_process_the_search_started(tmp_path: Path) -> None:
    """pan's parallel search forks workers; a time-out must stop them too, not only the
    process that was started (a left-over worker keeps a core and gigabytes busy)."""
    import time

    marker = "97.25"  # a sleep no other process runs
    with pytest.raises(spin.SpinError, match="did not finish within"):
        spin.run_tool(["sh", "-c", f"sleep {marker} & sleep {marker}"], tmp_path, "pan", timeout=0.5)
    def running() -> bool:
        ps = subprocess.run(["ps", "-eo", "args"], capture_output=True, text=True, check=True).stdout
        return f"sleep {marker}" in ps

    # a killed process may take a moment to go on a busy machine: wait for it, boundedly
    end = time.monotonic() + 10
    while running() and time.monotonic() < end:
        time.sleep(0.05)
    assert not running()
