"""Ctrl-C and SIGTERM at random moments of ``bilevel-kit solve``, every method (issue 35,
item 6; docs/cli.md#interrupting-a-command).

Each run starts ``solve INSTANCE -m METHOD --time-limit T -o OUT`` in a session of its own
with a private temporary folder, waits a random time drawn uniformly over the method's
measured run length (from the moment the command's signal guard is in place: before it, the
interpreter is still starting and Python's defaults apply), sends SIGINT or SIGTERM (one in
two) to the session as a terminal would, and records the exit code, the seconds from the
signal to the exit, whether stderr holds a traceback or other lines than the interrupt's,
whether OUT was written after the signal, and whether a temporary file or child process
was left behind. A run that ended before its signal is counted apart (it is no test of an
interrupt).

The goal: every interrupted run exits 130 within 1 s with one line, no traceback, nothing
written after the signal, nothing left behind. Writes bench/results/signals.csv (one row per
run, ``--out``) and prints the counts per method and the distribution of stop times.
Usage: python bench/signals.py [--runs 50] [--methods lns,cpsat,...] [--time-limit 3]
[--seed 0] [--out FILE]
"""

from __future__ import annotations

import argparse
import csv
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
TABLE = ROOT / "instances" / "hrc_table.json"
METHODS = ("single-task", "whole-assembly", "greedy-ce", "cpsat", "milp", "bilevel-milp", "lns")
LINES = ("bilevel-kit: interrupted", "bilevel-kit: interrupted (SIGTERM)")


def _caught(pid: int, sig: int) -> bool:
    """Does process ``pid`` catch ``sig`` (its guard is installed)?"""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    line = next(x for x in status.splitlines() if x.startswith("SigCgt:"))
    return bool(int(line.split()[1], 16) & (1 << (sig - 1)))


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _descendants(pid: int) -> list[int]:
    try:
        kids = [int(x) for x in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []
    return [k for c in kids for k in (c, *_descendants(c))]


def _command(method: str, out: Path, limit: float) -> list[str]:
    return [
        sys.executable,
        *("-m", "bilevel_kit.cli", "solve", str(TABLE), "-m", method, "-q"),
        *("--time-limit", f"{limit:g}", "-o", str(out)),
    ]


def _env(tmp: Path) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmp), "MPLBACKEND": "Agg"}
    env.pop("DASK_SCHEDULER_ADDRESS", None)
    return env


def measure(method: str, limit: float) -> float:
    """Seconds from the guard to the exit of one undisturbed run."""
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        proc = subprocess.Popen(
            _command(method, tmp / "out.json", limit),
            env=_env(tmp),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        while not _caught(proc.pid, signal.SIGTERM) and proc.poll() is None:
            time.sleep(0.002)
        t0 = time.monotonic()
        proc.wait()
        return time.monotonic() - t0


def one_run(method: str, limit: float, length: float, rng: random.Random) -> dict[str, Any]:
    """One signalled run (module docstring); its row."""
    sig = rng.choice((signal.SIGINT, signal.SIGTERM))
    delay = rng.uniform(0.0, length)
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        tmp = work / "tmp"
        tmp.mkdir()
        out = work / "out.json"
        proc = subprocess.Popen(
            _command(method, out, limit),
            env=_env(tmp),
            cwd=work,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        while not _caught(proc.pid, signal.SIGTERM) and proc.poll() is None:
            time.sleep(0.002)
        t_guard = time.monotonic()
        kids: set[int] = set()
        while time.monotonic() - t_guard < delay and proc.poll() is None:
            kids.update(_descendants(proc.pid))
            time.sleep(0.005)
        kids.update(_descendants(proc.pid))
        ended_first = proc.poll() is not None
        t_sig = time.time()
        t0 = time.monotonic()
        if not ended_first:
            os.killpg(proc.pid, sig)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            _, err = proc.communicate()
        seconds = time.monotonic() - t0
        time.sleep(0.2)
        lines = [x for x in err.strip().splitlines() if x]
        expected = LINES[1] if sig == signal.SIGTERM else LINES[0]
        return {
            "method": method,
            "signal": signal.Signals(sig).name,
            "delay_s": round(delay, 3),
            "ended_first": ended_first,
            "code": proc.returncode,
            "stop_s": round(seconds, 3),
            "traceback": "Traceback" in err,
            "one_line": lines in ([expected], [f"{expected} (forced)"]),
            "forced": err.rstrip().endswith("(forced)"),
            "written_after": out.exists() and out.stat().st_mtime > t_sig,
            "left_tmp": bool(list(tmp.iterdir())),
            "left_child": any(_alive(k) for k in kids),
            "stderr": " | ".join(lines)[-300:],
        }


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


def report(rows: list[dict[str, Any]]) -> None:
    """Counts per method, then the stop-time distribution of the interrupted runs."""
    print(f"{'method':<16}{'runs':>6}{'ended':>7}{'clean':>7}{'<=1s':>7}{'max s':>8}  failures")
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        hit = [r for r in mine if not r["ended_first"]]
        ok = [r for r in hit if clean(r)]
        fast = [r for r in hit if r["stop_s"] <= 1.0]
        worst = max((r["stop_s"] for r in hit), default=0.0)
        bad = {f"{r['signal']} exit {r['code']}: {r['stderr'][:80]}" for r in hit if not clean(r)}
        print(
            f"{method:<16}{len(mine):>6}{len(mine) - len(hit):>7}{len(ok):>7}{len(fast):>7}"
            f"{worst:>8.2f}  {'; '.join(sorted(bad))[:300]}"
        )
    stops = sorted(r["stop_s"] for r in rows if not r["ended_first"])
    if stops:
        q = [stops[min(len(stops) - 1, int(p * len(stops)))] for p in (0.5, 0.9, 0.99)]
        print(
            f"stop time over {len(stops)} interrupted runs: median {q[0]:.2f} s, "
            f"90 % {q[1]:.2f} s, 99 % {q[2]:.2f} s, max {stops[-1]:.2f} s"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=50, help="signalled runs per method")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--time-limit", type=float, default=3.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "signals.csv")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    rows: list[dict[str, Any]] = []
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as fh:  # row by row: a long run can be read as it goes
        writer: csv.DictWriter[str] | None = None
        for method in args.methods.split(","):
            length = measure(method, args.time_limit)
            print(f"{method}: an undisturbed run takes {length:.2f} s after its guard", flush=True)
            for _ in range(args.runs):
                rows.append(one_run(method, args.time_limit, length * 1.1, rng))
                if writer is None:
                    writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
                    writer.writeheader()
                writer.writerow(rows[-1])
                fh.flush()
    report(rows)


if __name__ == "__main__":
    main()
