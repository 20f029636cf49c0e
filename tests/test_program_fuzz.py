"""Damaged programs never crash the readers: every outcome is a program or a ProgramError."""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from statecharts.loader import load_spec
from statecharts.program import Controller, ProgramError, ProgramFault, load_program

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "programs"
SPEC = load_spec()
SOURCES = {name: (EXAMPLES / name).read_text(encoding="utf-8")
           for name in ("state_machine.rll", "state_machine.txt", "state_machine.L5X", "fault_recovery.txt")}
ALPHABET = "XIC()[],;. ?#\"\n\t0123456789ABTONMSF_:<>/=&!-+*"


def _load(tmp_path: Path, name: str, text: str) -> None:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    try:
        program = load_program(path, spec=SPEC)
        # what loads also binds and scans, or says why not
        controller = Controller(program, axes={t.name: "AXIS_CIP_DRIVE" for t in program.axes()}, spec=SPEC)
        controller.scan(3)
    except ProgramError as exc:
        assert exc.diagnostics and all(d.file == str(path) for d in exc.diagnostics)
    except ProgramFault as exc:
        assert str(path) in str(exc)


@settings(max_examples=200)  # cheap examples; the mutations are many
@given(st.sampled_from(sorted(SOURCES)), st.data())
def test_mutated_programs_give_a_program_or_located_errors(tmp_path_factory, name: str, data) -> None:
    text = SOURCES[name]
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, len(text)))
        cut = data.draw(st.integers(0, 8))
        insert = data.draw(st.text(ALPHABET, max_size=6))
        text = text[:at] + insert + text[at + cut:]
    _load(tmp_path_factory.mktemp("fuzz"), name, text)


@settings(max_examples=200)
@given(st.sampled_from([".rll", ".txt"]), st.text(ALPHABET, max_size=200))
def test_random_rung_text_gives_a_program_or_located_errors(tmp_path_factory, suffix: str, text: str) -> None:
    _load(tmp_path_factory.mktemp("fuzz"), "p" + suffix, text)
