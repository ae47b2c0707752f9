"""``solve -m milp`` killed with SIGTERM leaves no HiGHS child and no temporary folder."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bilevel_kit.cli import main

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(x) for x in text.split()]


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _milp_folders(folder: Path) -> set[str]:
    return {p.name for p in folder.glob("bilevel_milp_*")}


def test_solve_milp_sigterm_kills_its_child_and_removes_its_folder(tmp_path, capsys):
    pytest.importorskip("highspy")
    inst = tmp_path / "g.json"
    # ten table units with one tray: the MILP needs its whole budget (an easy instance
    # could be proven optimal before the signal arrives, and the test would race)
    assert main(["generate", "table", "--size", "10", "--out", str(inst)]) == 0
    capsys.readouterr()
    private = tmp_path / "tmp"  # its own temporary folder: other processes' folders don't count
    private.mkdir()
    root = str(Path(__file__).resolve().parents[2])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    env["TMPDIR"] = str(private)
    cmd = [sys.executable, "-m", "bilevel_kit.cli", "solve", str(inst), "-m", "milp"]
    proc = subprocess.Popen(
        [*cmd, "--time-limit", "30"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 30  # model building comes first: wait for the child
        kids: list[int] = []
        while time.monotonic() < deadline and not kids and proc.poll() is None:
            time.sleep(0.2)
            kids = _children(proc.pid)
        assert kids, "the HiGHS child never started"
        time.sleep(1.0)
        assert proc.poll() is None, "the solve finished before the signal: use a harder instance"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=5)
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and any(_alive(k) for k in kids):
            time.sleep(0.1)
        assert not any(_alive(k) for k in kids), "HiGHS child survived its parent"
        assert not _milp_folders(private), "a bilevel_milp_* folder was left behind"
        assert "Traceback" not in err and "interrupted" in err
        assert proc.returncode == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
