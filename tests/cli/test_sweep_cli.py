"""Sweep commands end to end: a failing cell (exit 5) and Ctrl-C (exit 130, finished cells
kept) in process and on a local Dask cluster (docs/cluster.md)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.cli.common import EXIT_FAILED, EXIT_INTERRUPTED

ROOT = Path(__file__).resolve().parents[2]


def test_a_failing_cell_is_recorded_and_the_exit_code_says_so(tmp_path, capsys):
    cells = tmp_path / "cells"
    argv = [
        "compare",
        str(ROOT / "instances/tiny.json"),
        str(ROOT / "instances/hrc_table.json"),
        *("--methods", "single-task,bilevel-milp", "-p", "bilevel-milp:max_tasks=5"),
        *("--time-limit", "1", "--cells", str(cells), "-q"),
    ]
    assert main(argv) == EXIT_FAILED
    out, err = capsys.readouterr()
    assert "compare: 3 done, 0 skipped, 1 failed of 4 cells" in err
    assert "1 cell(s) failed" in err
    rows = [line.split() for line in out.splitlines()[2:]]
    assert [(r[0], r[1], r[5]) for r in rows if r[5] == "error"] == [
        ("hrc_table", "bilevel-milp", "error")
    ]
    (bad,) = [p for p in cells.glob("hrc_table__bilevel-milp__*.json")]
    rec = json.loads(bad.read_text())
    assert rec["status"] == "error" and "at most 5" in rec["error"]
    assert rec["cell"]["params"] == {"max_tasks": 5} and rec["cell"]["method"] == "bilevel-milp"
    assert len(list(cells.glob("*.json"))) == 4


@pytest.mark.slow
@pytest.mark.parametrize("jobs", ["1", "2"])
def test_ctrl_c_stops_quickly_and_keeps_finished_cells(tmp_path, jobs):
    out = tmp_path / "fig6"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    env.pop("DASK_SCHEDULER_ADDRESS", None)
    grid = ["--quick", "--reps", "6", "--mats", "30,60,90,120", "--mttfs", "60"]
    cmd = [sys.executable, "-m", "bilevel_kit.cli", "repro", "fig6", *grid, "--jobs", jobs]
    proc = subprocess.Popen(
        [*cmd, "--out", str(out)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    try:
        deadline = time.monotonic() + 50
        while not [p for p in out.glob("cells/*.json") if not p.name.startswith(".")]:
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        t0 = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C reaches the whole group
        _, err = proc.communicate(timeout=30)
        stop = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
    text = err.decode()
    assert proc.returncode == EXIT_INTERRUPTED, text[-2000:]
    assert "bilevel-kit: interrupted" in text
    assert "(interrupted)" in text or text.rstrip().endswith("(forced)")  # the summary, or the
    # watchdog ended a slow exit on a busy machine (same cleanups)
    assert "Traceback" not in text  # the workers leave Ctrl-C to the client
    # ~0.5-1.2 s measured (docs/cli.md); the bound is what the mechanism needs (the workers
    # are stopped, not waited for), not the goal: a busy machine took 12.3 s against 5 s
    assert stop < 20, stop
    kept = [p for p in out.glob("cells/*.json") if not p.name.startswith(".")]
    assert 1 <= len(kept) < 5
    assert all(json.loads(p.read_text())["runs"] for p in kept)
    shutil.rmtree(out)
