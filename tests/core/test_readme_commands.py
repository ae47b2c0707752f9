"""Every command the README and the tutorial show runs, and exits as they say.

The commands are read from the documents, not copied here, so the test follows any rewrite:
every fenced ``bash`` (or ``sh``/``shell``) block is split into commands (a trailing ``\\``
continues a line, ``&&`` chains stay one command, ``#`` starts a comment), and every
``python`` block is one script. The commands of one document run in order, in one temporary
folder that holds a copy of the repository files they name (``instances/`` always), so a
later command may read what an earlier one wrote, as a reader's would.

A comment on a command line steers the test:

* ``# readme-test: skip REASON``: do not run it (it needs a file of the reader's own, ...);
* ``# readme-test: exit=N``: it is shown failing on purpose and must exit with ``N``.

**Quoted output.** A ``text`` block right after a command's block (blank lines between at
most) is what the document says that command prints: each of its non-blank lines must appear,
in order, among the lines the command printed (stdout, then stderr), its words a prefix of the
printed line's (a document may trim a trailing column). Durations are not compared, and only
they are masked (on both sides): a summary's ``time 2.524 s`` and ``in N s``, and in a table
the cell that starts where its header's ``time (s)`` starts (until a blank line). Any other
number, to whatever precision, must match. Checked only where the command ran as shown, not
made fast.

Otherwise a command must exit 0. What the test changes, and why:

* **Not run, shell syntax and named paths checked only**: creating a virtual environment or
  installing with pip (the test runs in an installed environment already; a path such a
  command names, ``-e '.[dev]'`` included, must exist); the test suite itself, the CI script,
  the linters and the type checker (CI runs them, and running them here would recurse); the
  documentation build and server (tests/core/test_docs_render.py builds the site); a command
  put in the background (``&``: a service, such as a Dask scheduler) and a command that needs
  one (``--scheduler``).
* ``.venv/bin/TOOL`` is the tool installed next to the Python running the tests, and that
  folder comes first on ``PATH``, so ``bilevel-kit`` is the one under test.
* **Optional arguments** shown in brackets (``[--kit K]``) are left out, except ``[--quick]``,
  which is kept: it is the fast form.
* **Parsed, not run**: the ``repro`` studies. Their arguments go through the CLI's own
  parser (a misspelt option fails), but a study takes 15-120 s even with ``--quick``
  (measured under load), and tests/repro/ and tests/cli/ run each quick study end to end.
* **Fast options**, so the whole file runs in minutes: ``--methods all`` (or ``default``) becomes
  ``single-task,greedy-ce,cpsat`` (``bilevel-milp`` alone spends its 60 s default limit and
  ``milp`` starts a HiGHS child, both tested elsewhere); ``--time-limit`` is capped at 10 s;
  replications at 2 (``--reps``, and ``simulate`` without ``--reps`` gets ``--reps 2``).
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCUMENTS = ["README.md", "docs/tutorial.md"]
BIN = Path(sys.executable).parent
SHELL_BLOCKS = ("bash", "sh", "shell")

MARKER = re.compile(r"readme-test:\s*(?P<what>skip|exit=(?P<code>\d+))\s*(?P<why>.*)")
#: Commands that are not run, and why (the first match wins).
NOT_RUN = [
    (re.compile(r"(?:^|\s)-m venv\b|\bpip install\b"), "sets up an environment"),
    (re.compile(r"\bpytest\b|\.ci/run\b"), "runs the test suite or CI"),
    (re.compile(r"\bruff\b|\bmypy\b"), "a linter or type checker (CI runs it)"),
    (re.compile(r"\bmkdocs\b"), "builds or serves the docs (test_docs_render.py builds them)"),
    (re.compile(r"&\s*$"), "starts a background service"),
    (re.compile(r"--scheduler\b"), "needs a running Dask scheduler"),
]
#: Commands whose arguments are parsed by the CLI's own parser but which are not run, and why.
PARSE_ONLY = [
    (
        re.compile(r"\bbilevel-kit\s+repro\b"),
        "a study: 15-120 s even with --quick; tests/repro/ and tests/cli/ run each quick study",
    ),
]
FAST_METHODS = "single-task,greedy-ce,cpsat"
MAX_TIME_LIMIT = 10.0
MAX_REPS = 2


@dataclass(frozen=True)
class Command:
    document: str
    line: int
    shown: str  # as the document shows it (continuations joined, comment removed)
    kind: str  # "bash" or "python"
    expected: int = 0
    skip: str | None = None
    output: str | None = None  # the quoted output right after its block (module docstring)

    @property
    def id(self) -> str:
        return f"{self.document}:{self.line}"


def _strip_comment(line: str) -> tuple[str, str]:
    """(code, comment) of one shell line: a ``#`` outside quotes after a blank starts it."""
    quote = ""
    for i, ch in enumerate(line):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i].rstrip(), line[i + 1 :].strip()
    return line.rstrip(), ""


def _blocks(text: str) -> list[tuple[str, int, list[str]]]:
    """(language, first line number, lines) of every fenced code block."""
    out, lang, start, lines = [], None, 0, []  # type: ignore[var-annotated]
    for n, line in enumerate(text.splitlines(), 1):
        fence = re.match(r"^\s*```\s*([\w+-]*)", line)
        if fence and lang is None:
            lang, start, lines = fence[1].lower(), n + 1, []
        elif fence:
            out.append((lang, start, lines))
            lang = None
        elif lang is not None:
            lines.append(line)
    return out


def _marked(comment: str) -> tuple[int, str | None]:
    marker = MARKER.search(comment)
    if not marker:
        return 0, None
    if marker["what"] == "skip":
        return 0, marker["why"] or "marked skip"
    return int(marker["code"]), None


def commands(document: str) -> list[Command]:
    return commands_in((ROOT / document).read_text(encoding="utf-8"), document)


def _quoted_after(text: str, blocks: list[tuple[str, int, list[str]]], i: int) -> str | None:
    """The ``text`` block right after block ``i`` (blank lines between at most), if any."""
    if i + 1 >= len(blocks) or blocks[i + 1][0] != "text":
        return None
    _, start, lines = blocks[i]
    between = text.splitlines()[start + len(lines) : blocks[i + 1][1] - 2]
    return "\n".join(blocks[i + 1][2]) if not any(s.strip() for s in between) else None


def commands_in(text: str, document: str) -> list[Command]:
    out: list[Command] = []
    blocks = _blocks(text)
    for i, (lang, start, lines) in enumerate(blocks):
        quoted = _quoted_after(text, blocks, i)
        if lang == "python":
            markers = [_marked(line) for line in lines if "readme-test:" in line]
            expected, skip = markers[0] if markers else (0, None)
            shown = "\n".join(lines)
            out.append(Command(document, start, shown, "python", expected, skip, quoted))
            continue
        if lang not in SHELL_BLOCKS:
            continue
        pending, first, block_start = "", start, len(out)
        for n, raw in enumerate(lines, start):
            code, comment = _strip_comment(raw)
            if not pending:
                first = n
            if code.endswith("\\"):
                pending += code[:-1] + " "
                continue
            shown = " ".join((pending + code).split())
            pending = ""
            if shown:
                expected, skip = _marked(comment)
                out.append(Command(document, first, shown, "bash", expected, skip))
        if quoted is not None and len(out) > block_start:  # the block's last command prints it
            out[-1] = replace(out[-1], output=quoted)
    return out


#: Durations in a summary, not compared (module docstring): "time 2.524 s", "in N s".
DURATION = re.compile(r"(?:(?<=\btime )|(?<=\bin ))\d+(?:\.\d+)?(?= s\b)")
#: A table's duration column (its header cell) and a number starting a cell.
TIME_COLUMN = "time (s)"
NUMBER = re.compile(r"\d+(?:\.\d+)?")


def masked(text: str) -> list[list[str]]:
    """Each line's words with its durations masked (module docstring): the summary forms, and
    the cell of a ``time (s)`` column, found by its header's offset, until a blank line."""
    out, column = [], -1
    for line in text.splitlines():
        if not line.strip():
            column = -1
        elif TIME_COLUMN in line:
            column = line.index(TIME_COLUMN)
        elif column >= 0 and line[column - 1 : column] in ("", " "):
            cell = NUMBER.match(line, column)
            if cell is not None:
                line = line[:column] + "#" + line[cell.end() :]
        out.append(DURATION.sub("#", line).split())
    return out


def missing_output(quoted: str, printed: str) -> list[str]:
    """The quoted lines not found, in order, in what a command printed (module docstring)."""
    lines = masked(printed)
    at, missing = 0, []
    for shown, want in zip(quoted.splitlines(), masked(quoted), strict=True):
        if not want:
            continue
        hit = next((k for k in range(at, len(lines)) if lines[k][: len(want)] == want), None)
        if hit is None:
            missing.append(shown)
        else:
            at = hit + 1
    return missing


ALL = [c for d in DOCUMENTS for c in commands(d)]


def _not_run(segment: str) -> str | None:
    return next((why for pattern, why in NOT_RUN if pattern.search(segment)), None)


def runnable(command: Command) -> tuple[str, list[str], list[str]]:
    """The shell line to run (substitutions applied), the segments only parsed, and the
    segments left out with why."""
    kept, parsed, left_out = [], [], []
    for segment in re.split(r"\s*&&\s*", command.shown):
        why = _not_run(segment)
        if why:
            left_out.append(f"{segment}  ({why})")
        elif any(pattern.search(segment) for pattern, _ in PARSE_ONLY):
            parsed.append(fast(segment))
        else:
            kept.append(fast(segment))
    return " && ".join(kept), parsed, left_out


def parse_only(segment: str) -> None:
    """Parse a ``bilevel-kit`` command's arguments as the CLI would, without running it."""
    from bilevel_kit.cli import build_parser

    tokens = shlex.split(segment)
    start = next(i for i, t in enumerate(tokens) if t.endswith("bilevel-kit"))
    try:
        build_parser().parse_args(tokens[start + 1 :])
    except SystemExit as exc:
        pytest.fail(f"the CLI rejects {segment!r} (exit {exc.code})")


def fast(segment: str) -> str:
    """One command with the substitutions of the module docstring."""
    segment = re.sub(r"(?<![\w/.])\.venv/bin/", f"{BIN}/", segment)
    segment = re.sub(r"\[\s*--quick\s*\]", "--quick", segment)
    segment = re.sub(r"\s*\[[^\]]*\]", "", segment)
    segment = re.sub(
        r"--methods(\s+|=)(?:all|default)\b", rf"--methods\g<1>{FAST_METHODS}", segment
    )

    def cap(match: re.Match[str], most: float) -> str:
        value = min(float(match[2]), most)
        return f"{match[1]}{value:g}"

    limit = r"(--time-limit[\s=]+)(\d+(?:\.\d+)?)"
    segment = re.sub(limit, lambda m: cap(m, MAX_TIME_LIMIT), segment)
    segment = re.sub(r"(--reps[\s=]+)(\d+)", lambda m: cap(m, MAX_REPS), segment)
    if re.search(r"\bbilevel-kit\s+simulate\b", segment) and "--reps" not in segment:
        segment = re.sub(r"(\bbilevel-kit\s+simulate\b)", rf"\1 --reps {MAX_REPS}", segment)
    return segment


def _repository_paths(line: str) -> list[Path]:
    """Paths a command names inside the repository: those whose first part is a top-level
    file or folder of it (``instances/x.json``, ``tests/extending/example_plugin``)."""
    paths = []
    for token in shlex.split(line, comments=True):
        value = token.split("=", 1)[-1] if token.startswith("-") else token
        head = value.split("/")[0]
        if "/" in value and head not in ("", ".", "..", ".venv", "out") and (ROOT / head).exists():
            paths.append(Path(value.rstrip("/")))
    return paths


def _extras() -> set[str]:
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    section = text.split("[project.optional-dependencies]")[1].split("\n[")[0]
    return set(re.findall(r"^(\w[\w-]*)\s*=", section, re.M))


def check_paths(line: str) -> list[str]:
    """What a command names in the repository that does not exist."""
    missing = [str(p) for p in _repository_paths(line) if not (ROOT / p).exists()]
    missing += [f"extra [{e}]" for e in re.findall(r"\.\[([\w-]+)\]", line) if e not in _extras()]
    return missing


@pytest.fixture(scope="module")
def workdirs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One folder per document, holding ``instances/`` and what its commands wrote."""
    out = {}
    for document in DOCUMENTS:
        folder = tmp_path_factory.mktemp(Path(document).stem)
        shutil.copytree(ROOT / "instances", folder / "instances")
        out[document] = folder
    return out


def _copy_named(line: str, folder: Path) -> None:
    for path in _repository_paths(line):
        source, target = ROOT / path, folder / path
        if source.exists() and not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            if source.is_dir():
                shutil.copytree(source, target)
            else:
                shutil.copy2(source, target)


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    return env


def test_documents_show_commands() -> None:
    """The parser finds the README's main job and the tutorial's steps."""
    shown = [c.shown for c in ALL]
    assert any("bilevel-kit compare instances/hrc_table.json" in s for s in shown)
    assert any("instances/tutorial_shelf.json" in s for s in shown)
    assert all(not c.shown.endswith("\\") for c in ALL)


def test_parsing_and_substitution_rules() -> None:
    text = "\n".join(
        [
            "```bash",
            "bilevel-kit solve a/b.json --time-limit 600 \\",
            "    --out 'x # y.json'   # a comment",
            "bilevel-kit pack mine.json  # readme-test: skip not ours",
            "bilevel-kit check x.json  # readme-test: exit=1",
            "python3.11 -m venv .venv && .venv/bin/bilevel-kit compare i.json --methods all",
            "bilevel-kit simulate i.json [--jobs 2] && bilevel-kit repro fig6 [--quick]",
            "```",
            "```text",
            "not a command",
            "```",
        ]
    )
    solve, pack, check, compare, chain = commands_in(text, "doc.md")
    assert solve.shown == "bilevel-kit solve a/b.json --time-limit 600 --out 'x # y.json'"
    assert (solve.line, solve.expected, solve.skip) == (2, 0, None)
    assert fast(solve.shown).startswith("bilevel-kit solve a/b.json --time-limit 10 ")
    assert pack.skip == "not ours" and check.expected == 1
    line, parsed, left_out = runnable(compare)
    assert line == f"{BIN}/bilevel-kit compare i.json --methods {FAST_METHODS}"
    assert parsed == [] and left_out == ["python3.11 -m venv .venv  (sets up an environment)"]
    line, parsed, _ = runnable(chain)
    assert line == "bilevel-kit simulate --reps 2 i.json"
    assert parsed == ["bilevel-kit repro fig6 --quick"]
    parse_only(parsed[0])
    with pytest.raises(pytest.fail.Exception, match="the CLI rejects"):
        parse_only("bilevel-kit repro fig6 --no-such-option")
    # the text block after the bash block is its last command's quoted output
    assert chain.output == "not a command"
    assert {solve.output, pack.output, check.output, compare.output} == {None}


def test_quoted_output_is_compared_in_order_with_durations_masked() -> None:
    printed = "\n".join(
        [
            "note: compiling (first run)",
            "x: greedy-ce feasible  makespan 223.085 s  time 2.524 s",
            "a  b       time (s)  file",
            "1  2.000   0.005     i.json",
            "",
            "c  time (s)",
            "3  7.250",
            "done: 1 cell in 10.9 s",
        ]
    )
    ok = "x: greedy-ce feasible  makespan 223.085 s  time 9.999 s\n"
    ok += "a  b       time (s)\n1  2.000   3.141"
    assert missing_output(ok + "\nc  time (s)\n3  1.5\ndone: 1 cell in 3 s", printed) == []
    assert missing_output("x: greedy-ce feasible  makespan 224.00 s", printed) == [
        "x: greedy-ce feasible  makespan 224.00 s"
    ]
    # in order: a line quoted before one it follows is missing
    assert missing_output("1  2.000\na  b", printed) == ["a  b"]
    # only durations are masked: a result to the millisecond, in a summary or a table, is not
    assert missing_output("x: greedy-ce feasible  makespan 223.086 s", printed) == [
        "x: greedy-ce feasible  makespan 223.086 s"
    ]
    assert missing_output("a  b       time (s)\n1  2.001", printed) == ["1  2.001"]
    # the time column ends at a blank line: after it, a number at that offset is a result
    assert missing_output("a  b       time (s)\n\n1  2.000   3.141", printed) == [
        "1  2.000   3.141"
    ]


@pytest.mark.slow
@pytest.mark.parametrize("command", ALL, ids=[c.id for c in ALL])
def test_command_runs(command: Command, workdirs: dict[str, Path]) -> None:
    folder = workdirs[command.document]
    if command.kind == "python":
        if command.skip:
            pytest.skip(command.skip)
        compile(command.shown, command.id, "exec")
        done = subprocess.run(
            [sys.executable, "-c", command.shown],
            cwd=folder,
            env=_environment(),
            capture_output=True,
            text=True,
            timeout=600,
        )
    else:
        syntax = subprocess.run(["bash", "-n", "-c", command.shown], capture_output=True)
        assert syntax.returncode == 0, f"{command.id}: not valid shell: {command.shown}"
        missing = check_paths(command.shown)
        assert not missing, f"{command.id}: names what the repository lacks: {missing}"
        line, parsed, left_out = runnable(command)
        if command.skip:
            pytest.skip(command.skip)
        for segment in parsed:
            parse_only(segment)
        if not line:
            why = [w for pattern, w in PARSE_ONLY if parsed and pattern.search(parsed[0])]
            pytest.skip("; ".join(left_out + why))
        _copy_named(line, folder)
        done = subprocess.run(
            ["bash", "-c", line],
            cwd=folder,
            env=_environment(),
            capture_output=True,
            text=True,
            timeout=900,
        )
    report = json.dumps({"ran": command.shown, "stdout": done.stdout[-2000:]}, indent=1)
    assert done.returncode == command.expected, (
        f"{command.id}: exit {done.returncode}, expected {command.expected}\n"
        f"{report}\nstderr: {done.stderr[-3000:]}"
    )
    as_shown = command.kind == "python" or line == command.shown
    if command.output is not None and as_shown:
        missing = missing_output(command.output, done.stdout + "\n" + done.stderr)
        assert not missing, (
            f"{command.id}: the document's quoted output is not what the command prints; "
            f"lines not found (in order): {missing}\nstdout: {done.stdout[-3000:]}\n"
            f"stderr: {done.stderr[-2000:]}"
        )


def test_the_license_is_an_spdx_expression_the_build_backend_reads():
    """The README's install builds the project with the newest setuptools from the index:
    a ``license`` table (``{text = ...}``) is deprecated there and stops building after
    2027-02-18, so the licence is an SPDX expression with its file, which setuptools reads from
    version 77 on (the build requirement says so)."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    project = config["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    assert (ROOT / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    assert "setuptools>=77" in config["build-system"]["requires"]
    assert not any(c.startswith("License ::") for c in project.get("classifiers", []))
