"""The one resumable cell runner: a cell is a pure function of (config, seed).

Why: ``compare``, ``simulate --reps``, ``repro fig6``, the user study's repeated studies and the
benchmarks must scale out to a cluster and resume after an interruption (docs/cluster.md). A
cell therefore holds only plain data (an instance path, a method or a grid point, options,
seeds) and has a stable :meth:`Cell.key` (a digest of its configuration); the function turns it
into a JSON-serialisable record.

Only this process (the client) writes results: each record is saved as
``<cell_dir>/<key>.json`` through :mod:`bilevel_kit.atomic` as soon as it arrives, so a rerun
skips every finished cell and an interrupted sweep (Ctrl-C, a killed client) loses only the
cells in flight. A record names the code that computed it (:mod:`.provenance`); a rerun
recomputes the cells other code made (docs/cluster.md#cells-and-the-code-that-made-them). A
cell that raises becomes an *error record* (``status: "error"``, the error, its traceback and
the cell's configuration); the sweep goes on and a rerun retries it.

Where cells run is an :class:`Executor`: :class:`SerialExecutor` (in order, in this process,
without importing Dask) or :class:`DaskExecutor` (a ``distributed.Client`` on a
``LocalCluster`` of ``jobs`` single-threaded worker processes, or on an existing cluster at a
scheduler address; a worker that dies mid-cell has its cell retried elsewhere by Dask).
:func:`sweep_session` sets the executor, the progress bar and the summary line for every sweep
a command runs, which is how the CLI's ``--jobs``, ``--scheduler`` and ``-q`` reach them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import sys
import threading
import time
import traceback
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypedDict, Unpack

import numpy as np

from .. import atomic
from ..interrupt import on_forced_exit, remove_path, say
from .provenance import CODE, code_identity, describe, reusable, without_code

if TYPE_CHECKING:
    from distributed import Client, LocalCluster

Record = dict[str, Any]

#: Dask retries of a cell whose worker died (on top of the scheduler's own allowed failures).
RETRIES = 2


class Cell(Protocol):
    """A unit of work: plain data with a stable, file-name-safe key."""

    def key(self) -> str: ...


class Executor(Protocol):
    """Runs ``fn`` on cells and yields ``(index, record)`` as each one finishes."""

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]: ...


# ---------------------------------------------------------------------------------------------
# Failures
# ---------------------------------------------------------------------------------------------


def cell_config(cell: Any) -> Any:
    """The cell's configuration as plain data (a dataclass as a dict without the fields it
    names ``unrecorded``, e.g. an instance's text; else its ``repr``)."""
    if dataclasses.is_dataclass(cell) and not isinstance(cell, type):
        skip = getattr(cell, "unrecorded", ())
        config = {k: v for k, v in dataclasses.asdict(cell).items() if k not in skip}
        return json.loads(json.dumps(config, default=str))
    return repr(cell)


def error_record(cell: Any, exc: BaseException, tb: str | None = None) -> Record:
    """The record of a cell that raised: its key, the error and the cell's configuration."""
    return {
        "key": cell.key(),
        "status": "error",
        "error": f"{type(exc).__name__}: {exc}",
        "traceback": tb if tb is not None else "".join(traceback.format_exception(exc)),
        "cell": cell_config(cell),
    }


def is_failed(record: Record) -> bool:
    """A record whose cell raised (or, for ``compare``, whose solve reported an error)."""
    return record.get("status") == "error"


def split_failed(records: Sequence[Record]) -> tuple[list[Record], list[Record]]:
    """The records of the cells that ran, and the key and error of each one that raised."""
    failed = [{"key": r["key"], "error": r["error"]} for r in records if is_failed(r)]
    return [r for r in records if not is_failed(r)], failed


def all_failed_line(desc: str, records: Sequence[Record]) -> str | None:
    """One line for a sweep whose every cell failed (``None`` otherwise, or without cells):
    there is nothing to tabulate or draw, and one error repeated N times is no news."""
    if not records or not all(is_failed(r) for r in records):
        return None
    errors = [" ".join(str(r.get("error") or "no error message").split()) for r in records]
    how = "each with" if len(set(errors)) == 1 else "the first with"
    return f"{desc}: all {len(records)} cells failed ({how} {errors[0]})"


def _clear_packing_memo() -> None:
    from ..models import packing_oracle

    packing_oracle.clear_cache()


#: Every process-wide state an earlier cell can leave behind that could change a result, with
#: its reset (docs/cluster.md): add a module's cache or solver object here, not a call of its
#: own. ``packing oracle memo``: a kit implied to fit by an earlier, larger kit takes that
#: kit's layout (a layout sets the robot's pick times), and a verdict decided with a longer
#: limit stands for this cell's. (The kit-count LP makes a HiGHS object per LP: a reused one
#: timed every later LP out once the process had spent its limit, docs/simulation.md.)
PROCESS_RESETS: dict[str, Callable[[], None]] = {"packing oracle memo": _clear_packing_memo}


def fresh_process_state() -> None:
    """Forget what earlier cells left in this process and could change a result
    (:data:`PROCESS_RESETS`). A cell is then a pure function of (config, seed), whichever
    worker runs it and whatever ran there before (docs/cluster.md)."""
    for reset in PROCESS_RESETS.values():
        reset()


@dataclass(frozen=True)
class Guarded:
    """``fn`` with its exceptions turned into error records, run from a fresh process state
    (:func:`fresh_process_state`; runs on the worker, pickles)."""

    fn: Callable[[Any], Record]

    def __call__(self, cell: Any) -> Record:
        try:
            fresh_process_state()
            record = self.fn(cell)
        except Exception as exc:
            record = error_record(cell, exc)
        return {**record, CODE: code_identity()}  # the code that computed it: the worker's


# ---------------------------------------------------------------------------------------------
# Executors
# ---------------------------------------------------------------------------------------------


class SerialExecutor:
    """Every cell in order, in this process (no Dask import)."""

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]:
        for i, cell in enumerate(cells):
            yield i, fn(cell)

    def close(self) -> None:
        """Nothing to release."""


@contextlib.contextmanager
def _local_workers(scratch: str) -> Iterator[None]:
    """Start local workers that ignore SIGINT, so that Ctrl-C (which a terminal sends to the
    whole process group) is the client's alone, without ignoring it in the client.

    An ignored signal stays ignored across ``exec`` and ``fork``; so the workers are forked
    from a multiprocessing fork server started while this process ignores SIGINT, for the
    few milliseconds of that start only (a worker started by ``spawn`` would need the client
    to ignore Ctrl-C during the whole cluster start, seconds). Every scratch space (the
    scheduler's too, with its lock files) goes to ``scratch``, removed with the cluster."""
    import multiprocessing.forkserver
    import multiprocessing.resource_tracker
    import signal
    import threading

    import dask

    config = {
        "distributed.worker.multiprocessing-method": "forkserver",
        "temporary-directory": scratch,
    }
    with dask.config.set(config):
        if threading.current_thread() is threading.main_thread():
            multiprocessing.resource_tracker.ensure_running()  # it guards itself: not here
            old = signal.signal(signal.SIGINT, signal.SIG_IGN)
            try:
                multiprocessing.forkserver.ensure_running()
            finally:
                signal.signal(signal.SIGINT, old)
        yield


def _connect(client: type[Client], address: str) -> Client:
    """A client of the scheduler at ``address``; a scheduler that is not there (or an address
    Dask cannot read) is a :class:`UsageError` naming it, not a traceback (Dask waits 30 s)."""
    from ..errors import UsageError

    _probe(address)
    try:
        return client(address, timeout=30)
    except (OSError, ValueError, TimeoutError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise UsageError(
            f"--scheduler {address}: no Dask scheduler to connect to ({reason})"
        ) from None
    except (MemoryError, EOFError, TypeError, KeyError) as exc:  # a server that is not Dask
        reason = f"its reply is not Dask's: {type(exc).__name__}"
        raise UsageError(
            f"--scheduler {address}: no Dask scheduler to connect to ({reason})"
        ) from None


#: Seconds to wait for a TCP scheduler to accept a connection before Dask's own handshake.
PROBE_TIMEOUT = 5.0


def _probe(address: str) -> None:
    """A plain TCP connect to a ``tcp://``/``tls://`` scheduler first: Dask retries a refused
    or unanswered connection for its whole 30 s timeout, this says so at once (refused) or
    after :data:`PROBE_TIMEOUT` seconds (no answer)."""
    import socket

    from distributed.comm.addressing import parse_address, parse_host_port

    from ..errors import UsageError

    try:
        scheme, loc = parse_address(address)
        host, port = parse_host_port(loc)
    except ValueError:
        return  # Dask's own message names what it cannot read
    if scheme not in ("tcp", "tls"):
        return
    try:
        socket.create_connection((host, port), timeout=PROBE_TIMEOUT).close()
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else exc.strerror or str(exc)
        raise UsageError(
            f"--scheduler {address}: no Dask scheduler to connect to ({reason})"
        ) from None


class DaskExecutor:
    """Cells as Dask tasks: on a ``LocalCluster`` of ``jobs`` single-threaded worker processes,
    or on the existing cluster whose scheduler listens at ``scheduler`` (``tcp://HOST:PORT``).

    The client is started on first use and kept until :meth:`close`, so the sweeps of one
    command share it. Each cell is one task with ``retries`` (a worker that dies mid-cell: the
    scheduler reschedules the cell on another worker); results are yielded as they complete.
    """

    def __init__(
        self, jobs: int | None = None, scheduler: str | None = None, retries: int = RETRIES
    ) -> None:
        if (jobs is None) == (scheduler is None):
            raise ValueError("give exactly one of jobs and scheduler")
        self.jobs = jobs
        self.scheduler = scheduler
        self.retries = retries
        self._client: Client | None = None
        self._cluster: LocalCluster | None = None
        self._interrupted = False
        self._scratch: str | None = None  # the local workers' folder, removed at close
        self._forced = contextlib.ExitStack()  # cleanups if the process has to be ended

    def client(self) -> Client:
        """The Dask client (started on first call)."""
        if self._client is None:
            import logging

            from distributed import Client, LocalCluster

            if self.scheduler is not None:
                self._client = _connect(Client, self.scheduler)
            else:
                import tempfile

                # every scratch space (and its lock files) in a folder of our own
                self._scratch = tempfile.mkdtemp(prefix="bilevel_dask_")
                self._forced.enter_context(on_forced_exit(remove_path(self._scratch)))
                with _local_workers(self._scratch):  # Ctrl-C is the client's
                    # the scheduler first, then the workers: an interrupt while they start
                    # finds a cluster to stop (a half-built one would fail at exit)
                    self._cluster = cluster = LocalCluster(
                        n_workers=0,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                        silence_logs=logging.ERROR,
                        local_directory=self._scratch,
                    )
                    self._forced.enter_context(on_forced_exit(lambda: _kill_workers(cluster)))
                    self._client = Client(cluster)
                    try:
                        jobs = self.jobs or 1
                        cluster.scale(jobs)
                        self._client.wait_for_workers(jobs)
                    except BaseException:
                        self._interrupted = True  # close() stops the workers at once
                        raise
        return self._client

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]:
        from distributed import as_completed

        client = self.client()
        token = uuid.uuid4().hex[:8]  # unique task keys: never share a task with another sweep
        index: dict[Any, int] = {}  # Dask task key -> cell position
        futures = []
        for i, cell in enumerate(cells):
            fut = client.submit(
                fn, cell, key=f"cell-{cell.key()}-{token}", retries=self.retries, pure=False
            )
            index[fut.key] = i
            futures.append(fut)
        pending = set(futures)
        try:
            for fut in as_completed(futures):
                pending.discard(fut)
                i = index[fut.key]
                try:
                    rec = fut.result()
                except Exception as exc:  # the task itself failed: e.g. KilledWorker
                    rec = error_record(cells[i], exc)
                fut.release()
                yield i, rec
        finally:
            if pending:  # interrupted: drop the cells in flight
                self._interrupted = True
                with contextlib.suppress(Exception):
                    client.cancel(list(pending), force=True)

    def close(self) -> None:
        """Disconnect (and stop the ``LocalCluster`` this executor started; after an
        interrupt, at once: its workers are killed, and a cluster still starting is not
        waited for)."""
        client, cluster = self._client, self._cluster
        self._client = self._cluster = None
        if cluster is not None and self._interrupted:
            import logging

            # The in-process scheduler logs each killed worker's closed connection with a
            # traceback; after Ctrl-C that is noise, not news.
            logging.getLogger("distributed").setLevel(logging.CRITICAL)
            _kill_workers(cluster)  # busy with cells nobody waits for: stop now
        with contextlib.suppress(Exception):
            if client is not None:
                client.close(timeout=2)
        if cluster is not None:
            try:
                cluster.close(timeout=1 if self._interrupted else 2)
            except Exception:  # e.g. workers still starting: not waited for at exit either
                cluster.shutdown_on_close = False
        if self._scratch is not None:
            import shutil

            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None
        self._forced.close()


def _kill_workers(cluster: LocalCluster) -> None:
    """Kill the worker processes a ``LocalCluster`` started, by their PIDs (their nannies
    told first not to start new ones)."""
    import os
    import signal

    nannies = list(cluster.workers.values())
    for nanny in nannies:
        nanny.auto_restart = False
    for nanny in nannies:
        with contextlib.suppress(Exception):
            os.kill(nanny.process.process.pid, signal.SIGKILL)


def make_executor(
    jobs: int = 1, n_cells: int = 2, scheduler: str | None = None
) -> SerialExecutor | DaskExecutor:
    """A cluster at ``scheduler`` if given; else serial for one job (or a single cell), else a
    ``LocalCluster`` of ``jobs`` worker processes."""
    if scheduler:
        return DaskExecutor(scheduler=scheduler)
    return SerialExecutor() if jobs <= 1 or n_cells <= 1 else DaskExecutor(jobs=jobs)


# ---------------------------------------------------------------------------------------------
# Sessions: what a command's sweeps share
# ---------------------------------------------------------------------------------------------


@dataclass
class SweepReport:
    """What one sweep did: cells computed now, reused from the cell store, failed."""

    desc: str
    total: int
    done: int = 0
    skipped: int = 0
    failed: int = 0
    wall_s: float = 0.0
    interrupted: bool = False
    stale: int = 0  # saved cells of other code, recomputed (counted in done/failed)
    foreign: int = 0  # cells computed now by workers running other code than this process

    def foreign_line(self) -> str:
        """The line saying that workers ran other code (a rerun recomputes their cells)."""
        return (
            f"{self.desc}: {self.foreign} cells were computed by workers running other code "
            f"than this client ({describe(code_identity())}); a rerun recomputes them"
        )

    def line(self) -> str:
        """The one-line summary printed at the end of a sweep."""
        text = (
            f"{self.desc}: {self.done} done, {self.skipped} skipped, {self.failed} failed "
            f"of {self.total} cells in {self.wall_s:.1f} s"
        )
        return text + (" (interrupted)" if self.interrupted else "")


@dataclass
class SweepSession:
    """The settings of every sweep a command runs, and their reports."""

    jobs: int = 1
    scheduler: str | None = None
    progress: bool | None = None
    summary: bool = False
    reports: list[SweepReport] = field(default_factory=list)
    _executor: SerialExecutor | DaskExecutor | None = None

    def executor(self, n_cells: int) -> SerialExecutor | DaskExecutor:
        """The session's executor (one Dask client for all its sweeps)."""
        if self._executor is None or isinstance(self._executor, SerialExecutor):
            ex = make_executor(self.jobs, n_cells, self.scheduler)
            if isinstance(ex, SerialExecutor):
                return ex
            self._executor = ex
        return self._executor

    @property
    def failed(self) -> int:
        """Cells that failed over all the session's sweeps."""
        return sum(r.failed for r in self.reports)

    def close(self) -> None:
        if self._executor is not None:
            self._executor.close()
            self._executor = None


_SESSION: SweepSession | None = None


@contextlib.contextmanager
def sweep_session(
    jobs: int = 1,
    scheduler: str | None = None,
    progress: bool | None = None,
    summary: bool = True,
    connect: bool = False,
) -> Iterator[SweepSession]:
    """Run every sweep inside on ``jobs`` local workers or the cluster at ``scheduler``,
    with a progress bar (``None``: only on a terminal) and a summary line on stderr.
    ``connect``: connect to ``scheduler`` now (the CLI: exit 2 before any cell), not at the
    first sweep."""
    global _SESSION
    previous = _SESSION
    session = SweepSession(jobs, scheduler, progress, summary)
    _SESSION = session
    try:
        if connect and scheduler is not None:  # a scheduler that is not there: no sweep
            executor = session.executor(2)
            assert isinstance(executor, DaskExecutor)
            executor.client()
        yield session
    finally:
        _SESSION = previous
        session.close()


# ---------------------------------------------------------------------------------------------
# The runner
# ---------------------------------------------------------------------------------------------


def json_default(o: Any) -> Any:
    """JSON for numpy scalars and tuples inside records."""
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, tuple):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def write_json(path: str | Path, obj: Any) -> Path:
    """``obj`` as indented JSON, written atomically."""
    atomic.write_text(path, json.dumps(obj, indent=1, default=json_default) + "\n")
    return Path(path)


#: The longest cell file name kept as the cell's key (a file name has at most 255 bytes, and
#: the temporary file it is written through adds a prefix and a suffix).
MAX_CELL_NAME = 180


def cell_file(folder: Path, key: str) -> Path:
    """The file of the cell ``key`` in ``folder``: ``KEY.json``, or for a key too long for a
    file name (a long instance file name) its start and a hash of the whole key."""
    import hashlib

    name = f"{key}.json"
    if len(name.encode()) > MAX_CELL_NAME:
        digest = hashlib.sha256(key.encode()).hexdigest()[:16]
        name = f"{key.encode()[: MAX_CELL_NAME - 40].decode(errors='ignore')}~{digest}.json"
    return folder / name


def _saved(path: Path | None) -> Record | None:
    """A finished cell's saved record (an error record counts as not finished: retried).
    A file there that is not a record (empty, not JSON, not an object) is a
    :class:`UsageError`: the folder is not what ``--cells`` wrote, and guessing is worse."""
    from ..errors import UsageError

    if path is None or not path.exists():
        return None
    try:
        rec: Record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc).split(":")[0]
        raise UsageError(
            f"{path}: not a saved cell ({reason}); remove it to rerun the cell"
        ) from None
    if not isinstance(rec, dict):
        raise UsageError(
            f"{path}: not a saved cell (not a JSON object); remove it to rerun the cell"
        )
    return None if is_failed(rec) and "traceback" in rec else rec


def run_sweep(
    cells: Sequence[Any],
    fn: Callable[[Any], Record],
    *,
    cell_dir: str | Path | None = None,
    jobs: int | None = None,
    executor: Executor | None = None,
    progress: bool | None = None,
    desc: str = "cells",
) -> tuple[list[Record], SweepReport]:
    """Run ``fn`` on every cell without a saved record; return all records in cell order and
    the sweep's report.

    Records of cells already saved under ``cell_dir`` by this code are read back (the others
    are recomputed, and one line on stderr says how many); new ones are saved as
    they arrive (one client per ``cell_dir``: it also removes the temporary files a killed
    client left behind). Without ``cell_dir`` nothing is saved. Where cells run: ``executor``
    if given, else the active :func:`sweep_session`'s (it overrides ``jobs``), else
    :func:`make_executor` of ``jobs``.
    ``progress=None``: the session's setting, else a bar only on a terminal. On Ctrl-C the
    cells in flight are dropped, the finished ones are kept, and ``KeyboardInterrupt`` is
    raised again after the summary.
    """
    from tqdm import tqdm

    t0 = time.perf_counter()
    session = _SESSION
    folder = Path(cell_dir) if cell_dir is not None else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        for tmp in folder.glob(".*.json.*.json"):  # a killed client's half-written file
            tmp.unlink(missing_ok=True)
    paths = [cell_file(folder, c.key()) if folder is not None else None for c in cells]
    loud = session is None or session.summary
    records, stale = reusable([_saved(p) for p in paths], code_identity(), desc, loud)
    todo = [i for i, r in enumerate(records) if r is None]
    report = SweepReport(desc, len(cells), skipped=len(cells) - len(todo), stale=stale)
    owned = None  # an executor started here, closed here
    if executor is None:
        if session is not None:
            executor = session.executor(len(todo))
        else:
            executor = owned = make_executor(jobs or 1, len(todo))
    if progress is None and session is not None:
        progress = session.progress
    bar = tqdm(
        total=len(todo),
        desc=desc,
        unit="cell",
        disable=None if progress is None else not progress,
        file=sys.stderr,
    )
    ticker = _Ticker(bar)  # the bar's clock moves during a long cell, not only between cells
    try:
        for j, rec in executor.run(Guarded(fn), [cells[i] for i in todo]):
            i = todo[j]
            path = paths[i]
            if path is not None:
                write_json(path, rec)
            records[i] = without_code(rec)
            report.foreign += rec.get(CODE, code_identity()) != code_identity()
            if is_failed(rec):
                report.failed += 1
                bar.set_postfix(failed=report.failed)
            else:
                report.done += 1
            bar.update()
    except KeyboardInterrupt:
        report.interrupted = True
        raise
    finally:
        ticker.stop()
        bar.close()
        if owned is not None:
            owned.close()
        report.wall_s = time.perf_counter() - t0
        if report.foreign and loud:
            say(report.foreign_line(), sys.stderr)
        if session is not None:
            session.reports.append(report)
            if session.summary:
                say(report.line(), sys.stderr)
    return [r for r in records if r is not None], report


class _Ticker:
    """Redraws a shown progress bar once a second from a daemon thread, so its elapsed time
    ticks while one long cell runs (tqdm redraws only when a cell finishes)."""

    def __init__(self, bar: Any, every: float = 1.0) -> None:
        self._bar = bar
        self._stop = threading.Event()
        self._thread = None
        if not bar.disable:
            self._thread = threading.Thread(target=self._run, args=(every,), daemon=True)
            self._thread.start()

    def _run(self, every: float) -> None:
        while not self._stop.wait(every):
            self._bar.refresh()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()


class SweepOptions(TypedDict, total=False):
    """The keyword options of :func:`run_sweep` the thin wrappers pass on unchanged."""

    cell_dir: str | Path | None
    jobs: int | None
    executor: Executor | None
    progress: bool | None
    desc: str


def run_cells_counted(
    cells: Sequence[Any], fn: Callable[[Any], Record], **options: Unpack[SweepOptions]
) -> tuple[list[Record], int]:
    """The records of :func:`run_sweep` (in cell order) and how many cells ran now."""
    records, report = run_sweep(cells, fn, **options)
    return records, report.done + report.failed


def run_cells(
    cells: Sequence[Any], fn: Callable[[Any], Record], **options: Unpack[SweepOptions]
) -> list[Record]:
    """The records of :func:`run_sweep` (resumable under ``cell_dir``)."""
    return run_sweep(cells, fn, **options)[0]
