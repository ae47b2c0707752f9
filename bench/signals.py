"""Ctrl-C and SIGTERM at random moments of ``bilevel-kit solve``, every method (issue 35,
item 6; docs/cli.md#interrupting-a-command).

Each run starts ``solve INSTANCE -m METHOD --time-limit T -o OUT`` in a session of its own
with a private temporary folder (tests/sigproc.py, shared with the signal tests), waits a
random time drawn uniformly over the method's measured run length (from the moment the
command's signal guard is in place: before it, the interpreter is still starting and Python's
defaults apply), sends SIGINT or SIGTERM (one in two) to the session as a terminal would, and
records the exit code, the seconds from the signal to the exit, the load average, whether
stderr holds a traceback or other lines than the interrupt's, whether OUT was written after
the signal, and whether a temporary file or child process was left behind. A run that ended
before its signal, or whose signal came once the command had finished (its guard lifted, its
own exit code, nothing on stderr, its complete result written before the signal: the rule of
the docs page), is counted apart; each method gets runs until ``--runs`` of them took their
signal (at most 3x).

The goal: every interrupted run exits 130 within 1 s with one line, no traceback, nothing
written after the signal, nothing left behind. Writes ``--out`` (default
bench/results/signals.csv, one row per run, as it goes) and the counts per method beside it
(signals.md); ``--report`` rewrites that summary from the rows alone (runs split over several
processes, their rows joined). Usage: python bench/signals.py [--runs 50] [--methods
lns,cpsat,...] [--time-limit 3] [--seed 0] [--out FILE] [--report]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import random
import signal
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from sigproc import Command, one_line  # noqa: E402  (the signal tests' own helper)

TABLE = ROOT / "instances" / "hrc_table.json"
METHODS = ("single-task", "whole-assembly", "greedy-ce", "cpsat", "milp", "bilevel-milp", "lns")


def _args(method: str, out: Path, limit: float) -> list[str]:
    return ["solve", str(TABLE), "-m", method, "-q", "--time-limit", f"{limit:g}", "-o", str(out)]


def measure(method: str, limit: float) -> float:
    """Seconds from the guard to the exit of one undisturbed run."""
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        cmd = Command(work, *_args(method, work / "out.json", limit))
        cmd.wait_for(cmd.guarded, "the signal guard")
        t0 = time.monotonic()
        cmd.proc.communicate()
        return time.monotonic() - t0


def _complete(out: Path) -> bool:
    """Is ``out`` a whole solution file?"""
    try:
        return "kits" in json.loads(out.read_text())
    except (OSError, ValueError):
        return False


def one_run(method: str, limit: float, length: float, rng: random.Random) -> dict[str, Any]:
    """One signalled run (module docstring); its row."""
    sig = rng.choice((signal.SIGINT, signal.SIGTERM))
    delay = rng.uniform(0.0, length)
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        out = work / "out.json"
        cmd = Command(work, *_args(method, out, limit))
        cmd.wait_for(cmd.guarded, "the signal guard")
        ended_first = not cmd.sleep(delay)
        load1 = os.getloadavg()[0]
        guard_gone = not cmd.guarded()
        t_sig = time.time()
        if not ended_first:
            try:
                code, err, seconds = cmd.stop(sig)
            except AssertionError:  # it ended between the sleep and the signal
                ended_first = True
        if ended_first:
            _, err = cmd.proc.communicate()
            code, seconds = cmd.proc.returncode, 0.0
        kids, files = cmd.leftovers()
        lines = [x for x in err.strip().splitlines() if x]
        written_after = out.exists() and out.stat().st_mtime > t_sig
        return {
            "method": method,
            "signal": signal.Signals(sig).name,
            "delay_s": round(delay, 3),
            "ended_first": ended_first,
            "code": code,
            "stop_s": round(seconds, 3),
            "load1": round(load1, 2),
            "traceback": "Traceback" in err,
            "one_line": one_line(sig, err),
            "forced": err.rstrip().endswith("(forced)"),
            "guard_gone": guard_gone,
            "complete": not out.exists() or _complete(out),
            "written_after": written_after,
            "left_tmp": bool(files),
            "left_child": bool(kids),
            "stderr": " | ".join(lines)[-300:],
        }


def late(row: dict[str, Any]) -> bool:
    """Did the signal come once the command had finished (docs/cli.md#interrupting-a-command):
    its guard lifted before the signal, its own exit code, nothing on stderr, its result (if
    any) complete and written before the signal? (Rows without ``complete`` predate that
    column; a result not written after the signal was renamed into place whole before it.)"""
    return bool(
        not row["ended_first"]
        and row["guard_gone"]
        and row["code"] != 130
        and not row["stderr"]
        and not row["written_after"]
        and row.get("complete", True)
    )


def taken(row: dict[str, Any]) -> bool:
    """Did the command take the signal (a run that ended before its signal, or whose signal
    came once the command had finished, is no test of an interrupt)?"""
    return not row["ended_first"] and not late(row)


def clean(row: dict[str, Any]) -> bool:
    """Did the interrupted run meet the goal (the time aside)?"""
    return (
        row["code"] == 130
        and not row["traceback"]
        and row["one_line"]
        and not row["written_after"]
        and not row["left_tmp"]
        and not row["left_child"]
    )


def summary(rows: list[dict[str, Any]]) -> list[str]:
    """Counts per method (a Markdown table), then the stop-time distribution of the
    interrupted runs and the machine's load at the signals."""
    out = [
        "| method | signalled | exit 130 | clean | <= 1 s | max s | forced | tracebacks "
        "| load at signal | after the command | ended first | failures |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, commit in dict.fromkeys((r["method"], r.get("commit", "")) for r in rows):
        mine = [r for r in rows if (r["method"], r.get("commit", "")) == (name, commit)]
        method = f"{name} @{commit}" if commit else name
        hit = [r for r in mine if taken(r)]
        loads = [r["load1"] for r in hit] or [0.0]
        bad = {f"{r['signal']} exit {r['code']}: {r['stderr'][:80]}" for r in hit if not clean(r)}
        slow = sorted(r["stop_s"] for r in hit if r["stop_s"] > 1.0)
        out.append(
            f"| {method} | {len(hit)} | {sum(r['code'] == 130 for r in hit)} "
            f"| {sum(clean(r) for r in hit)} | {len(hit) - len(slow)} "
            f"| {max((r['stop_s'] for r in hit), default=0.0):.2f} "
            f"| {sum(r['forced'] for r in hit)} | {sum(r['traceback'] for r in hit)} "
            f"| {min(loads):.1f}-{max(loads):.1f} "
            f"| {sum(late(r) for r in mine)} | {sum(r['ended_first'] for r in mine)} "
            f"| {'; '.join(sorted(bad))[:200]} |"
        )
    stops = sorted(r["stop_s"] for r in rows if taken(r))
    if stops:
        q = [stops[min(len(stops) - 1, int(p * len(stops)))] for p in (0.5, 0.9, 0.99)]
        out.append(
            f"\nstop time over {len(stops)} interrupted runs: median {q[0]:.2f} s, "
            f"90 % {q[1]:.2f} s, 99 % {q[2]:.2f} s, max {stops[-1]:.2f} s"
        )
    return out


def _commit() -> str:
    """The code measured: the short commit, ``+`` when the tree has changes."""
    import subprocess

    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout

    return git("rev-parse", "--short", "HEAD").strip() + (
        "+" if git("status", "--porcelain") else ""
    )


def _typed(row: dict[str, str]) -> dict[str, Any]:
    """A row read back from the CSV, with its numbers and flags."""
    out: dict[str, Any] = dict(row)
    for key, value in row.items():
        if key == "complete" and not value:  # a row from before the column: see late()
            del out[key]
        elif value in ("True", "False"):
            out[key] = value == "True"
        elif key in ("delay_s", "stop_s", "load1"):
            out[key] = float(value)
        elif key == "code":
            out[key] = int(value)
    return out


def write_summary(rows: list[dict[str, Any]], csv_path: Path, command: str) -> Path:
    """The summary next to the rows (``signals.md`` beside ``signals.csv``)."""
    path = csv_path.with_suffix(".md")
    head = [
        "# Signals at random moments (issue 35, item 6)",
        "",
        f"Written by `{command}` (docs/cli.md#interrupting-a-command). A run is counted as",
        "signalled when the command took its signal; `after the command`: the signal came once",
        "the command had finished (its guard lifted, its own exit code, its complete result",
        "written before the signal, no line on stderr); `ended first`: the run ended before its",
        "signal. `clean`: exit 130, the one line, no traceback, nothing written after the",
        "signal, nothing left behind; `forced`: the guard ended the process 2 s after the",
        "signal (the main thread had not got back to Python). `load`: the 1-minute load",
        "average at the signals (2 cores, shared with other jobs).",
        "",
    ]
    path.write_text("\n".join(head + summary(rows)) + "\n")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=50, help="signalled runs per method")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--time-limit", type=float, default=3.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "signals.csv")
    ap.add_argument("--report", action="store_true", help="summarise the rows of --out only")
    args = ap.parse_args()
    command = "python bench/signals.py " + " ".join(sys.argv[1:])
    if args.report:
        with args.out.open(newline="") as fh:
            rows = [_typed(r) for r in csv.DictReader(fh)]
        print("\n".join(summary(rows)))
        print(f"wrote {write_summary(rows, args.out, command)}")
        return
    rng = random.Random(args.seed)
    rows = []
    commit = _commit()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as fh:  # row by row: a long run can be read as it goes
        writer: csv.DictWriter[str] | None = None
        for method in args.methods.split(","):
            length = measure(method, args.time_limit)
            print(f"{method}: an undisturbed run takes {length:.2f} s after its guard", flush=True)
            signalled = 0
            for _ in range(3 * args.runs):  # a run whose signal the command did not take: again
                if signalled >= args.runs:
                    break
                rows.append(one_run(method, args.time_limit, length * 1.1, rng))
                rows[-1]["commit"] = commit
                signalled += taken(rows[-1])
                if writer is None:
                    writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
                    writer.writeheader()
                writer.writerow(rows[-1])
                fh.flush()
    print("\n".join(summary(rows)))
    print(f"wrote {write_summary(rows, args.out, command)}")


if __name__ == "__main__":
    main()
