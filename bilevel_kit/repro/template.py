"""The reproduction's documents rendered from templates and the committed CSVs, so that no
table and no number in their prose is typed by hand (docs/reproduction.md).

A template is Markdown with placeholders: ``{{name}}`` is a fact (:mod:`.facts`: a number or
a phrase computed from the CSVs) and ``{{table:NAME}}`` a table (:mod:`.report`). Each target
is a whole file (``paper_repro/README.md``, ``docs/reproduction.md``) or the section of a file
between two markers (``docs/simulation.md``). The top-level ``README.md`` carries no
reproduction number, only links to these files.
``python paper_repro/render_readme.py`` writes them; :func:`check` is what the drift test runs,
and :func:`typed_numbers` what the template lint runs (a decimal number or a percentage
typed into a template's prose).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from .report import render_table

ROOT = Path(__file__).resolve().parents[2]
PLACEHOLDER = re.compile(r"\{\{\s*([\w.:-]+)\s*\}\}")
BEGIN, END = "<!-- paper-repro:begin -->", "<!-- paper-repro:end -->"


@dataclass(frozen=True)
class Target:
    """A template and where its rendering goes (the whole file, or between the markers)."""

    template: str
    output: str
    section: bool = False

    def note(self) -> str:
        return (
            f"<!-- Rendered from {self.template} and paper_repro/results/ by "
            "`python paper_repro/render_readme.py`: edit the template, not this text. -->"
        )


TARGETS = (
    Target("paper_repro/templates/README.md", "paper_repro/README.md"),
    Target("paper_repro/templates/reproduction.md", "docs/reproduction.md"),
    Target("paper_repro/templates/simulation_adaptive.md", "docs/simulation.md", section=True),
    Target("paper_repro/templates/stations_results.md", "docs/stations.md", section=True),
    Target("paper_repro/templates/robust_results.md", "docs/robust.md", section=True),
)


def render(text: str, facts: Mapping[str, str], results_dir: str | Path) -> str:
    """``text`` with every placeholder replaced (an unknown name is an error naming it)."""
    tables: dict[str, str] = {}

    def sub(m: re.Match[str]) -> str:
        name = m.group(1)
        if name.startswith("table:"):
            key = name[len("table:") :]
            if key not in tables:
                tables[key] = render_table(key, results_dir)
            return tables[key]
        if name not in facts:
            raise KeyError(f"unknown fact {{{{{name}}}}} (facts are computed in repro/facts.py)")
        return facts[name]

    return PLACEHOLDER.sub(sub, text)


def rendered(target: Target, root: Path, facts: Mapping[str, str]) -> tuple[str, str]:
    """(the output file's text now, what it must be)."""
    body = render((root / target.template).read_text(), facts, root / "paper_repro" / "results")
    out = root / target.output
    current = out.read_text() if out.exists() else ""
    if not target.section:
        return current, f"{target.note()}\n\n{body.rstrip()}\n"
    if BEGIN not in current or END not in current:
        raise ValueError(f"{target.output} has no {BEGIN} ... {END} section")
    head, rest = current.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return current, f"{head}{BEGIN}\n{target.note()}\n\n{body.strip()}\n{END}{tail}"


def render_all(root: Path = ROOT) -> dict[Path, tuple[str, str]]:
    """Every target: path -> (its text now, what it must be)."""
    from .facts import facts

    known = facts(root / "paper_repro" / "results")
    return {root / t.output: rendered(t, root, known) for t in TARGETS}


def check(root: Path = ROOT, context: int = 1) -> list[str]:
    """A diff per target that disagrees with its template and the CSVs (empty: all agree)."""
    out = []
    for path, (now, want) in render_all(root).items():
        if now != want:
            diff = difflib.unified_diff(
                now.splitlines(),
                want.splitlines(),
                f"{path.name} (committed)",
                f"{path.name} (rendered from the CSVs)",
                n=context,
                lineterm="",
            )
            out.append("\n".join(diff))
    return out


def write_all(root: Path = ROOT) -> list[Path]:
    """Write every target that disagrees; returns the files written."""
    written = []
    for path, (now, want) in render_all(root).items():
        if now != want:
            path.write_text(want)
            written.append(path)
    return written


#: Numbers a template may type: the intervals' and the power's levels, the factor quantiles.
ALLOWED = ("95 %", "80 %", "2.5 %", "97.5 %", "10 %", "50 %", "90 %")
_CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)
_NUMBER = re.compile(r"(?<![\w.])\d+\.\d+|(?<![\w.])\d+(?:\.\d+)?\s?%")


def typed_numbers(text: str) -> list[str]:
    """Decimal numbers and percentages typed into a template's prose (outside code and
    placeholders, and not one of :data:`ALLOWED`): results must come from the CSVs."""
    prose = PLACEHOLDER.sub(" ", _CODE.sub(" ", text))
    for word in ALLOWED:
        prose = prose.replace(word, " ")
    return _NUMBER.findall(prose)


__all__ = ["TARGETS", "Target", "check", "render", "render_all", "typed_numbers", "write_all"]
