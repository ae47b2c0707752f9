"""Sweeps on a real Dask cluster: a ``dask scheduler`` and two ``dask worker`` processes on
random 127.0.0.1 ports, driven through ``bilevel-kit repro fig6 --scheduler`` (docs/cluster.md).

Each test compares the cell records with a serial run of the same grid (every field but the
wall times), kills a worker or the client mid-sweep by PID, and checks that nothing is lost
or written twice.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bilevel_kit.cli import main

ROOT = Path(__file__).resolve().parents[2]
#: A small Figure 6 grid: 1 reference + 3 grid cells, long enough to kill things mid-sweep.
GRID = ["--quick", "--reps", "4", "--mats", "30,60,120", "--mttfs", "60"]
N_CELLS = 4
#: A guard against a hang, not a speed check: a fig6 cell took more than 50 s at a load of 6
#: (two other sweeps and a test run on the 2 cores), so the waits are generous.
HANG_S = 300.0
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1"}
ENV.pop("DASK_SCHEDULER_ADDRESS", None)
CLI = "from bilevel_kit.cli import main; raise SystemExit(main())"

pytestmark = pytest.mark.slow


def _spawn(args: list[str], log: Path, cwd: Path = ROOT) -> subprocess.Popen[bytes]:
    with open(log, "wb") as fh:
        return subprocess.Popen(args, cwd=cwd, env=ENV, stdout=fh, stderr=subprocess.STDOUT)


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Stop one process we started, by its PID."""
    if proc.poll() is None:
        os.kill(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()


class Cluster:
    """A scheduler and ``n`` workers (``--no-nanny``: the worker's PID is the worker), all
    started in the folder ``cwd``."""

    def __init__(self, folder: Path, n: int = 2, cwd: Path = ROOT) -> None:
        self.folder = folder
        sfile = folder / "scheduler.json"
        self.scheduler = _spawn(
            [
                *(sys.executable, "-m", "distributed.cli.dask_scheduler"),
                *("--host", "127.0.0.1", "--port", "0", "--no-dashboard"),
                *("--scheduler-file", str(sfile)),
            ],
            folder / "scheduler.log",
            cwd,
        )
        deadline = time.monotonic() + 30
        while not sfile.exists() or not sfile.read_text().strip():
            assert time.monotonic() < deadline, (folder / "scheduler.log").read_text()
            time.sleep(0.1)
        self.address: str = json.loads(sfile.read_text())["address"]
        self.workers = [
            _spawn(
                [
                    *(sys.executable, "-m", "distributed.cli.dask_worker", self.address),
                    *("--nthreads", "1", "--no-nanny", "--no-dashboard"),
                    *("--host", "127.0.0.1", "--name", f"w{i}"),
                ],
                folder / f"worker{i}.log",
                cwd,
            )
            for i in range(n)
        ]
        from distributed import Client

        with Client(self.address, timeout=30) as client:
            client.wait_for_workers(n, timeout=30)
            self.worker_cwds = set(client.run(os.getcwd).values())

    def close(self) -> None:
        for proc in [*self.workers, self.scheduler]:
            _stop(proc)


@pytest.fixture
def cluster(tmp_path: Path) -> Iterator[Cluster]:
    c = Cluster(tmp_path)
    try:
        yield c
    finally:
        c.close()


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict]:
    """The grid's cell records, computed in this process (``--jobs 1``)."""
    out = tmp_path_factory.mktemp("serial")
    assert main(["repro", "fig6", *GRID, "-q", "--out", str(out)]) == 0
    return _records(out)


def _cell_files(out: Path) -> list[Path]:
    """The finished cells' files (not a temporary file being written)."""
    folder = out / "cells"
    return (
        sorted(p for p in folder.glob("*.json") if not p.name.startswith("."))
        if folder.exists()
        else []
    )


def _records(out: Path) -> dict[str, dict]:
    """Cell file name -> record without the wall times."""
    recs = {}
    for p in _cell_files(out):
        rec = json.loads(p.read_text())
        rec.pop("wall_s")
        recs[p.name] = rec
    return recs


def _assert_clean(out: Path, serial: dict[str, dict]) -> None:
    """Every cell once, no temporary files left, records equal to the serial run's."""
    names = sorted(p.name for p in (out / "cells").iterdir())
    assert names == sorted(serial), names
    assert _records(out) == serial


def _fig6(out: Path, address: str) -> list[str]:
    cmd = [sys.executable, "-c", CLI, "repro", "fig6", *GRID, "--out", str(out)]
    return [*cmd, "-q", "--scheduler", address]


def _wait_for_cells(out: Path, n: int, proc: subprocess.Popen[bytes], timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while len(_cell_files(out)) < n:
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        assert time.monotonic() < deadline, "no cell finished in time"
        time.sleep(0.05)


def test_fig6_through_the_scheduler_equals_the_serial_run(cluster, serial, tmp_path):
    out = tmp_path / "out"
    proc = subprocess.run(_fig6(out, cluster.address), cwd=ROOT, env=ENV, capture_output=True)
    err = proc.stderr.decode()
    assert proc.returncode == 0, err[-3000:]
    assert f"fig6 cells: {N_CELLS} done, 0 skipped, 0 failed" in err
    _assert_clean(out, serial)


@contextlib.contextmanager
def _fig6_client(
    cluster: Cluster, tmp_path: Path
) -> Iterator[tuple[Path, subprocess.Popen[bytes]]]:
    """A fig6 client on ``cluster``, yielded (output folder, process) once its first cell is
    saved; stopped on exit."""
    out = tmp_path / "out"
    proc = _spawn(_fig6(out, cluster.address), tmp_path / "client.log")
    try:
        _wait_for_cells(out, 1, proc, timeout=HANG_S)
        yield out, proc
    finally:
        _stop(proc)


def test_a_worker_killed_mid_sweep_loses_nothing(cluster, serial, tmp_path):
    with _fig6_client(cluster, tmp_path) as (out, proc):
        os.kill(cluster.workers[0].pid, signal.SIGKILL)
        assert proc.wait(timeout=HANG_S) == 0, (tmp_path / "client.log").read_text()[-3000:]
    assert cluster.workers[0].wait(timeout=5) == -signal.SIGKILL
    _assert_clean(out, serial)


def test_a_killed_client_resumes_with_the_finished_cells(cluster, serial, tmp_path):
    with _fig6_client(cluster, tmp_path) as (out, proc):
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    kept = len(_cell_files(out))
    assert 1 <= kept < N_CELLS
    again = subprocess.run(_fig6(out, cluster.address), cwd=ROOT, env=ENV, capture_output=True)
    err = again.stderr.decode()
    assert again.returncode == 0, err[-3000:]
    assert f"fig6 cells: {N_CELLS - kept} done, {kept} skipped, 0 failed" in err
    _assert_clean(out, serial)


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])  # closed again when the block ends


def _junk_server() -> tuple[socket.socket, threading.Thread]:
    """A TCP server that answers every connection with bytes that are not Dask's."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen()

    def serve() -> None:
        with contextlib.suppress(OSError):
            while True:
                conn, _ = srv.accept()
                conn.sendall(b"\xff" * 64)
                conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return srv, thread


@pytest.mark.parametrize("kind", ["refused", "not dask"])
def test_a_scheduler_that_is_not_there_is_reported_before_dask_s_timeout(tmp_path, kind):
    """Dask retries a refused connection for its 30 s timeout, and a server that is not Dask
    crashed it (a 3 EiB allocation): both are exit 2 naming the option, before any cell."""
    srv = None
    if kind == "refused":
        port = _closed_port()
    else:
        srv, _ = _junk_server()
        port = srv.getsockname()[1]
    out = tmp_path / "cells"
    try:
        t0 = time.monotonic()
        proc = subprocess.run(
            [
                *(sys.executable, "-c", CLI, "compare", str(ROOT / "instances" / "tiny.json")),
                *("--methods", "single-task", "--scheduler", f"tcp://127.0.0.1:{port}"),
                *("--cells", str(out)),
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        seconds = time.monotonic() - t0
    finally:
        if srv is not None:
            srv.close()
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and f"--scheduler tcp://127.0.0.1:{port}" in err[0]
    assert "no Dask scheduler to connect to" in err[0]
    assert kind != "refused" or "Connection refused" in err[0]
    assert not out.exists() and seconds < 25  # Dask alone took its 30 s timeout


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    """The command line in a process of its own, from the repository's folder."""
    return subprocess.run(
        [sys.executable, "-c", CLI, *args],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_cells_carry_their_instances_to_workers_in_another_folder(tmp_path, root):
    """A worker started in another folder (as on any cluster node) cannot read the client's
    relative instance paths: the cells carry the instance documents (docs/cluster.md)."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    cluster = Cluster(tmp_path, n=1, cwd=elsewhere)
    try:
        assert cluster.worker_cwds == {str(elsewhere)}  # not the client's folder
        sweep = ["-q", "--scheduler", cluster.address]
        compare = ["compare", "instances/tiny.json", "--methods", "single-task,whole-assembly"]
        out = tmp_path / "compare.csv"
        proc = _cli(*compare, *sweep, "--csv", str(out))
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert "compare: 2 done, 0 skipped, 0 failed of 2 cells" in proc.stderr
        here = tmp_path / "here.csv"
        assert (
            main([*compare[:1], str(root / compare[1]), *compare[2:], "-q", "--csv", str(here)])
            == 0
        )

        def rows(path: Path) -> list[tuple[str, str, str, str]]:
            with path.open() as fh:
                return [
                    (r["method"], r["status"], r["makespan"], r["n_kits"])
                    for r in csv.DictReader(fh)
                ]

        assert rows(out) == rows(here) and rows(out)[0][1] == "feasible"
        bench = ["bench", "run", "--methods", "single-task", "--filter", "tasks<=12"]
        run = tmp_path / "bench"
        proc = _cli(*bench, *sweep, "--out", str(run))
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert "bench: 9 done, 0 skipped, 0 failed of 9 cells" in proc.stderr
        assert (run / "profile.png").is_file() and (run / "gap_size.png").is_file()
    finally:
        cluster.close()
