"""Rewrite citations that name working files (``001 ...``, ``domain-facts §4 MSO``) as
citations of the sources registry (``LDH-MSI ...``, ``RM002H p78 (...)``).

Usage: ``python tools/cite_registry.py FILE...`` rewrites the ``sources:`` lists of
scenario files in place (text substitution, the rest of each file untouched) and prints
what it could not map.  Each mapping below says which publication the cited fact comes
from; the original wording stays as a parenthesised note.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

#: working-file number -> registry code of the publication it holds
SEEDS = {"000": "LDH-MRHD", "001": "LDH-MSI", "002": "LDH-MDO", "003": "SYNC-RM"}
#: a section name as the citations write it -> the registry's section name
SECTION_ALIASES = {
    "LDH-MSI": {"Motion State Instructions table": "instruction table", "state instructions table": "instruction table"},
}
#: fact-list section -> the publication and locator that section's facts cite
FACT_SECTIONS = {
    "1b": "RM002H p255", "2": "RA37 motion_instruction-data-type", "3a": "RM002H p576", "3b": "RM003I p236",
    "3c": "RM002H p31", "3d": "RM003I p54", "3e": "RM003I p346",
}
#: per-instruction facts -> the page or help topic they cite
INSTRUCTION_PAGES = {
    "MSO": "RM002H p78, p79", "MSF": "RA37 msf", "MASD": "RM002H p221", "MASR": "RM002H p47", "MDO": "LDH-MDO Description",
    "MDF": "RA37 motion-state-instructions", "MDS": "RM002H p65", "MAFR": "RA37 motion-state-instructions",
    "MRHD": "LDH-MRHD Description", "MAHD": "RM002H p327", "MAH": "RM002H p96", "MAM": "RM002H p120",
    "MAG": "RM002H p126", "MRP": "RM002H p152", "MAS": "RA37 mas", "generic": "RM002H p79", "common": "RM002H p79",
    "multi-scan": "RM002H p79",
}


def _note(text: str) -> str:
    text = text.strip().strip(",").strip()
    if not text:
        return ""
    if text.startswith("(") and text.endswith(")"):
        return " " + text
    return f" ({text})"


def convert(citation: str) -> str | None:
    """The registry citation for ``citation``, or None when it names no working file."""
    c = citation.strip()
    m = re.match(r"^(00[0-3])\s+(.*)$", c)
    if m:
        code = SEEDS[m.group(1)]
        rest = m.group(2)
        for alias, name in SECTION_ALIASES.get(code, {}).items():
            if rest.lower().startswith(alias.lower()):
                rest = name + rest[len(alias):]
        return f"{code} {rest}"
    m = re.match(r"^domain-facts\s+§(\w+)\s*(.*)$", c)
    if m:
        section, rest = m.group(1), m.group(2)
        if section == "1a":
            n = re.match(r"^(?:code\s+)?(\d+)\b(.*)$", rest)
            if n:
                return f"ICS code {n.group(1)}{_note(n.group(2))}"
            return f"ICS{_note(rest)}"
        if section == "4":
            word = re.match(r"^([A-Za-z-]+),?\s*(.*)$", rest)
            if word and word.group(1) in INSTRUCTION_PAGES:
                return f"{INSTRUCTION_PAGES[word.group(1)]}{_note(rest)}"
            return None
        if section in FACT_SECTIONS:
            return f"{FACT_SECTIONS[section]}{_note(rest)}"
        return None
    return None


def rewrite(path: Path) -> list[str]:
    """Rewrite the citations in ``path``'s ``sources:`` entries; the ones left unmapped."""
    text = path.read_text(encoding="utf-8")
    unmapped: list[str] = []
    lines = text.split("\n")
    in_sources = False
    for i, line in enumerate(lines):
        if line.startswith("sources:"):
            in_sources = True
        elif in_sources and line and not line.startswith((" ", "-")):
            in_sources = False
        if not in_sources:
            continue
        for item in re.findall(r'"([^"]*)"|\'([^\']*)\'|(?<=[\[,])\s*([^"\',\[\]]+?)\s*(?=[,\]])', line):
            raw = next(x for x in item if x)
            new = convert(raw)
            if new is None:
                if re.match(r"^(00[0-3]\s|domain-facts)", raw.strip()):
                    unmapped.append(raw)
                continue
            quoted = '"' + new.replace('"', "'") + '"'
            for form in (f'"{raw}"', f"'{raw}'"):
                if form in line:
                    line = line.replace(form, quoted, 1)
                    break
            else:
                line = re.sub(r"(?<=[\[,])(\s*)" + re.escape(raw.strip()) + r"(\s*)(?=[,\]])",
                              lambda mm, q=quoted: mm.group(1) + q + mm.group(2), line, count=1)
        lines[i] = line
    new_text = "\n".join(lines)
    if new_text != text:
        path.write_text(new_text, encoding="utf-8")
    return unmapped


def main(argv: list[str]) -> int:
    left = []
    for name in argv:
        left += [f"{name}: {c}" for c in rewrite(Path(name))]
    for line in left:
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
