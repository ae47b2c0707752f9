"""A command line signalled as a terminal would (docs/cli.md#interrupting-a-command): one piece
of code for tests/cli/test_cli_signals.py and the stress script bench/signals.py.

The command runs as a separate process in a session of its own (a terminal's foreground job),
with a private temporary folder; its process tree is read from ``/proc`` (Linux only).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from timing import load_factor

ROOT = Path(__file__).resolve().parents[1]
#: The longest :meth:`Command.wait_for` waits for a command to reach the moment it signals at,
#: on a machine that runs nothing else; times the load per core (:func:`timing.load_factor`),
#: as a fresh clone's first compile of greedy-ce's kernels (docs/scaling.md#first-run) beside
#: other work can take longer (a fresh-clone run beside two busy loops hit 120 s).
REACH_S = 120.0
#: The interrupt's one line, by signal.
LINES = {
    signal.SIGINT: "bilevel-kit: interrupted",
    signal.SIGTERM: "bilevel-kit: interrupted (SIGTERM)",
}


def children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(x) for x in text.split()]


def descendants(pid: int) -> list[int]:
    out = []
    for child in children(pid):
        out += [child, *descendants(child)]
    return out


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def catches(pid: int, sig: int) -> bool:
    """Does process ``pid`` catch ``sig`` (a handler installed at the C level)?"""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    caught = next(line for line in status.splitlines() if line.startswith("SigCgt:"))
    return bool(int(caught.split()[1], 16) & (1 << (sig - 1)))


def one_line(sig: int, err: str) -> bool:
    """Is ``err`` the interrupt's one line (the command's, or the watchdog's when the exit
    outlived the grace period: it runs the same cleanups), and nothing else?"""
    line = LINES[signal.Signals(sig)]
    return [x for x in err.splitlines() if x.strip()] in ([line], [f"{line} (forced)"])


class Command:
    """``python -m bilevel_kit.cli ARGS`` in its own session, with its own temporary folder."""

    def __init__(self, work: Path, *args: str) -> None:
        self.tmp = work / "tmp"
        self.tmp.mkdir(exist_ok=True)
        env = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
            "TMPDIR": str(self.tmp),
            "MPLBACKEND": "Agg",
        }
        env.pop("DASK_SCHEDULER_ADDRESS", None)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "bilevel_kit.cli", *args],
            cwd=work,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        self.kids: set[int] = set()

    def wait_for(self, reached: Callable[[], bool], what: str) -> None:
        """Wait until ``reached()`` while the command runs (it must not end first)."""
        deadline = time.monotonic() + REACH_S * load_factor()
        while not reached():
            self.kids.update(descendants(self.proc.pid))
            assert self.proc.poll() is None, f"the command ended before {what}"
            assert time.monotonic() < deadline, f"never reached: {what}"
            time.sleep(0.005)

    def guarded(self) -> bool:
        """Has the command installed its signal guard (SIGTERM caught)? Before that the
        interpreter is still starting, where Python's own Ctrl-C applies."""
        return catches(self.proc.pid, signal.SIGTERM)

    def child_started(self) -> bool:
        return bool(children(self.proc.pid))

    def sleep(self, seconds: float) -> bool:
        """Sleep up to ``seconds`` while noting child processes; False if the command ended."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds and self.proc.poll() is None:
            self.kids.update(descendants(self.proc.pid))
            time.sleep(0.005)
        return self.proc.poll() is None

    def stop(self, sig: int, times: int = 1) -> tuple[int, str, float]:
        """Signal the session (as a terminal would) and wait; the exit code, stderr and
        seconds from the first signal to the exit."""
        assert self.proc.poll() is None, "the command ended before the signal"
        self.kids.update(descendants(self.proc.pid))
        t0 = time.monotonic()
        try:
            for _ in range(times):
                os.killpg(self.proc.pid, sig)
            _, err = self.proc.communicate(timeout=60)
        finally:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        return self.proc.returncode, err, time.monotonic() - t0

    def leftovers(self) -> tuple[list[int], list[Path]]:
        """Child processes still alive (after up to 3 s) and files left in the temporary
        folder."""
        deadline = time.monotonic() + 3
        while any(alive(k) for k in self.kids) and time.monotonic() < deadline:
            time.sleep(0.1)
        return [k for k in self.kids if alive(k)], sorted(self.tmp.iterdir())
