"""The cell runner's sweep behaviour: error records, the summary, sessions, and no Dask import
for a serial sweep (docs/cluster.md)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from toycells import Div, invert

from bilevel_kit.experiments import (
    DaskExecutor,
    SerialExecutor,
    run_sweep,
    sweep_session,
)

ROOT = Path(__file__).resolve().parents[2]


def test_a_raising_cell_is_recorded_with_its_config_and_retried_on_rerun(tmp_path, capsys):
    cells = [Div(i) for i in (2, 0, 4)]
    with sweep_session(progress=False) as session:
        records, report = run_sweep(cells, invert, cell_dir=tmp_path, desc="div")
    assert (report.done, report.skipped, report.failed) == (2, 0, 1)
    assert session.failed == 1
    err = json.loads((tmp_path / "div0.json").read_text())
    assert err["status"] == "error" and err["cell"] == {"x": 0}
    assert err["error"].startswith("ZeroDivisionError") and "Traceback" in err["traceback"]
    assert [r.get("y") for r in records] == [0.5, None, 0.25]
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("div: 2 done, 0 skipped, 1 failed of 3 cells in ")
    _, again = run_sweep(cells, invert, cell_dir=tmp_path, progress=False)
    assert (again.done, again.skipped, again.failed) == (0, 2, 1)  # only the failed one reran


def test_local_cluster_records_errors_too(tmp_path):
    cells = [Div(i) for i in (1, 0, 5, 8)]
    serial, _ = run_sweep(cells, invert, progress=False)
    ex = DaskExecutor(jobs=2)
    try:
        pooled, report = run_sweep(cells, invert, cell_dir=tmp_path, executor=ex, progress=False)
    finally:
        ex.close()
    assert report.failed == 1 and report.done == 3
    strip = [{k: v for k, v in r.items() if k != "traceback"} for r in serial]
    assert [{k: v for k, v in r.items() if k != "traceback"} for r in pooled] == strip
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"div{i}.json" for i in (0, 1, 5, 8)]


def test_a_session_picks_the_executor():
    with sweep_session(jobs=1) as s1:
        assert isinstance(s1.executor(5), SerialExecutor)
    with sweep_session(jobs=3) as s3:
        assert isinstance(s3.executor(1), SerialExecutor)  # one cell: no cluster
    with sweep_session(scheduler="tcp://127.0.0.1:1") as sx:
        ex = sx.executor(1)
        assert isinstance(ex, DaskExecutor) and ex._client is None  # connects lazily


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["compare", str(ROOT / "instances/tiny.json"), "--methods", "single-task", "-q"],
        ["simulate", str(ROOT / "instances/tiny.json"), "--reps", "2", "--policy", "single-task"],
    ],
)
def test_serial_sweeps_and_help_never_import_dask(argv):
    code = (
        "import sys\n"
        "from bilevel_kit.cli import main\n"
        "try:\n"
        f"    code = main({argv!r})\n"
        "except SystemExit as e:\n"
        "    code = e.code\n"
        "assert code == 0, code\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed'))\n"
        "assert not bad, bad[:5]\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg"},
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
