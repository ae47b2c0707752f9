"""Stopping on Ctrl-C or SIGTERM at any moment, within about a second, cleaning up.

Python raises ``KeyboardInterrupt`` only when the main thread runs Python code: a native call
(a CP-SAT solve, a compiled kernel, a large numpy operation) delays it until the call returns,
which for a solve can be its whole time limit. Three pieces make every command stop at once
(docs/cli.md#interrupting-a-command):

* :func:`run_stoppable` runs a native call that releases the GIL (a CP-SAT solve) in a helper
  thread while the main thread waits, so the main thread takes the signal at once, asks the
  call to stop and waits for it to return; the interrupt then goes on up, and every
  ``finally`` and ``with`` on the way cleans up (temporary files, child processes). The call
  never outlives the command: a solver thread still running while the interpreter exits
  aborts the process (CPython ends a thread that takes the GIL during its exit with
  ``pthread_exit``, which a C++ frame of OR-Tools turns into ``std::terminate``: "terminate
  called without an active exception", exit -6);
* SIGTERM raises :class:`Terminated`, a ``KeyboardInterrupt``, so a ``kill`` cleans up like
  Ctrl-C (and exits 130 too: one code for "interrupted");
* :func:`signal_guard`, around a whole command, watches for the signals from a thread of its
  own: if the process has not ended :data:`GRACE` seconds after the first signal (the main
  thread is stuck in a native call), or at a second signal, it runs the cleanups registered
  with :func:`on_forced_exit`, prints one line and ends the process with ``os._exit``.

Nothing here imports beyond the standard library: the CLI installs the guard before any
heavy import.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from types import FrameType
from typing import IO, NoReturn, TypeVar

T = TypeVar("T")

#: Exit code after SIGINT (Ctrl-C) and after SIGTERM alike: 128 + SIGINT.
EXIT_INTERRUPTED = 128 + signal.SIGINT
#: Seconds the main thread has to stop by itself after a signal before the process is ended.
GRACE = 2.0


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that the same cleanups run."""


def message(exc: BaseException | None = None) -> str:
    """The one line a command prints when it was interrupted."""
    return "bilevel-kit: interrupted" + (" (SIGTERM)" if isinstance(exc, Terminated) else "")


#: Set once the interrupt's line is on stderr: a watchdog that must still end the process
#: (its exit outlived the grace period) then exits without a second line.
_REPORTED = threading.Event()
#: Held while the line is written: a watchdog firing in that instant waits for it instead of
#: writing a second line beside it (seen once beside two busy loops).
_REPORTING = threading.Lock()


#: The first signal the guard's handler took (None: none yet), for :func:`signalled`.
_SIGNAL: list[int] = []
#: One entry per active guard (:func:`guarded`).
_ACTIVE: list[bool] = []
#: Set when our interrupt was swallowed (:func:`_quiet_unraisable`): to be raised again.
_LOST = threading.Event()


def guarded() -> bool:
    """Is a :func:`signal_guard` active in this process (its handlers installed)?"""
    return bool(_ACTIVE)


def signalled() -> int | None:
    """The signal a guard took in this process, if any. The handler raises once, and the
    exception does not always reach the command: raised inside a C extension's import it
    becomes ``ImportError: initialization failed`` (OR-Tools), inside a compiled kernel a
    ``SystemError`` (numba), and code that falls back on an ``ImportError`` swallows it. So
    the command decides by this, not by the exception (docs/cli.md#interrupting-a-command)."""
    return _SIGNAL[0] if _SIGNAL else None


def interrupt_for(signum: int) -> KeyboardInterrupt:
    """The exception a signal raises: :class:`Terminated` for SIGTERM, else
    ``KeyboardInterrupt``."""
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def checkpoint() -> None:
    """Raise the interrupt again if a signal came (:func:`signalled`): called before a
    result is committed, so no file is presented as complete after a signal whose
    exception was swallowed on its way up."""
    signum = signalled()
    if signum is not None:
        raise interrupt_for(signum)


#: Depth of :func:`deferred` blocks: the guard's handler then records a signal, and the block's
#: end raises it.
_DEFERRING: list[bool] = []


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """A block no signal's exception cuts in two: under the guard a signal that comes inside
    is recorded and its interrupt raised at the block's end (:func:`checkpoint`)."""
    _DEFERRING.append(True)
    try:
        yield
    finally:
        _DEFERRING.pop()
    checkpoint()


def report(exc: BaseException | None, stream: IO[str]) -> None:
    """Print the interrupt's one line (:func:`message`), once per process."""
    with _REPORTING:
        print(message(exc), file=stream, flush=True)
        _REPORTED.set()


def say(line: str, stream: IO[str]) -> None:
    """Print one whole line while a signal may end the process: one write of the line and its
    newline, under the lock the watchdog's forced line waits for, so that line never lands
    on the end of this one (``print`` writes the text and the newline apart; seen once beside
    two busy loops)."""
    with _REPORTING:
        stream.write(line + "\n")
        stream.flush()


def exit_now(code: int) -> NoReturn:
    """End the process with ``code`` at once, its output flushed, without the interpreter's
    exit. For an interrupted command line: every cleanup has run on the way up (the
    ``finally`` and ``with`` blocks, and none of them relies on the exit's ``atexit``), and
    that exit, tearing down the loaded modules (numba, OR-Tools, pandas), only delayed the end
    past the second of docs/cli.md#interrupting-a-command on a loaded machine; nor can a
    solver thread that still runs abort the process then (module docstring)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def forget_unhandled_interrupt() -> None:
    """Tell CPython that the interrupt was handled. A ``KeyboardInterrupt`` that crossed a C
    ``PyRun_*`` call (some imports run code that way) is remembered even once our code has
    caught it, and the interpreter then ends the process with SIGINT after it exits, instead
    of with the command's exit code."""
    import ctypes

    with contextlib.suppress(Exception):  # best effort: another interpreter may lack it
        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0


# ---------------------------------------------------------------------------------------------
# Cleanups for a forced exit
# ---------------------------------------------------------------------------------------------

_CLEANUPS: dict[int, Callable[[], None]] = {}
_COUNTER = itertools.count()
_LOCK = threading.Lock()


@contextlib.contextmanager
def on_forced_exit(cleanup: Callable[[], None]) -> Iterator[None]:
    """While inside, ``cleanup`` runs if the guard has to end the process (it may run in
    another thread, so it only removes paths or kills processes, and never raises)."""
    key = next(_COUNTER)
    with _LOCK:
        _CLEANUPS[key] = cleanup
    try:
        yield
    finally:
        with _LOCK:
            _CLEANUPS.pop(key, None)


def _run_cleanups() -> None:
    with _LOCK:
        todo = list(_CLEANUPS.values())[::-1]  # the innermost first
    for cleanup in todo:
        with contextlib.suppress(BaseException):
            cleanup()


def remove_path(path: str | os.PathLike[str]) -> Callable[[], None]:
    """A cleanup removing a file or a folder tree (if it still exists)."""

    def cleanup() -> None:
        import shutil

        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.unlink(path)

    return cleanup


def kill_pid(pid: int) -> Callable[[], None]:
    """A cleanup killing a child process (SIGKILL; gone already: nothing)."""

    def cleanup() -> None:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)

    return cleanup


# ---------------------------------------------------------------------------------------------
# Native calls that can be stopped
# ---------------------------------------------------------------------------------------------


def run_stoppable(call: Callable[[], T], stop: Callable[[], object]) -> T:
    """``call()``, a native call that releases the GIL and returns soon after ``stop()``.

    In the main thread the call runs in a helper thread and the main thread waits on an
    event, which a signal interrupts: then ``stop()`` is called until the call has returned
    (a stop that comes before the solver is set up does nothing), and the interrupt is
    raised again (module docstring). The helper thread is started in a :func:`deferred`
    block, so an interrupt never leaves it running unwaited for; it blocks SIGINT and SIGTERM,
    and the solver's own threads inherit that, so the signals reach the main thread.
    Elsewhere ``call()`` runs directly. A signal already recorded (its interrupt lost on the
    way up) starts no call (:func:`checkpoint`).
    """
    if threading.current_thread() is not threading.main_thread():
        return call()
    checkpoint()
    done = threading.Event()
    box: list[T] = []
    failure: list[BaseException] = []

    def target() -> None:
        try:
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
            box.append(call())
        except BaseException as exc:  # handed to the main thread
            failure.append(exc)
        finally:
            done.set()

    helper = threading.Thread(target=target, name="native-call", daemon=True)
    started = False
    try:
        with deferred():
            helper.start()
            started = True
        done.wait()
    except BaseException:
        if started:
            while not done.is_set():
                stop()
                done.wait(0.02)
            helper.join()
        raise
    if failure:
        raise failure[0]
    return box[0]


# ---------------------------------------------------------------------------------------------
# The guard around a command
# ---------------------------------------------------------------------------------------------


#: Environment variable naming a file to which a forced exit appends every thread's stack
#: (where the main thread was held; docs/cli.md#interrupting-a-command).
ENV_FORCED_TRACE = "BILEVEL_KIT_FORCED_TRACE"


def _trace_stacks() -> None:
    path = os.environ.get(ENV_FORCED_TRACE)
    if not path:
        return
    import faulthandler

    with contextlib.suppress(Exception), open(path, "a") as fh:
        fh.write(f"--- pid {os.getpid()}: forced exit\n")
        fh.flush()
        faulthandler.dump_traceback(fh, all_threads=True)


class _Guard:
    """The state of :func:`signal_guard`: the first signal, and the watchdog thread."""

    def __init__(self, grace: float) -> None:
        self.grace = grace
        self.first: int | None = None  # the signal the handler raised for
        self.armed = False  # the watchdog's deadline runs
        self.finished = threading.Event()
        self.reader, self.writer = socket.socketpair()
        self.writer.setblocking(False)
        self.thread = threading.Thread(target=self._watch, name="signal-guard", daemon=True)

    def handler(self, signum: int, frame: FrameType | None) -> None:
        """The Python-level handler: raise at the first signal only (a second one is the
        watchdog's, so that a cleanup under way is not cut short by another exception)."""
        if self.first is not None:
            return
        self.first = signum
        if not _SIGNAL:
            _SIGNAL.append(signum)
        if not _DEFERRING:  # else raised at the deferred block's end
            raise interrupt_for(signum)

    def _watch(self) -> None:
        """Read the signal numbers Python's C handler writes to the wake-up socket."""
        seen = 0
        while True:
            try:
                data = self.reader.recv(64)
            except OSError:
                return
            if not data:  # the guard was closed
                return
            for signum in data:
                if signum not in (signal.SIGINT, signal.SIGTERM):
                    continue
                seen += 1
                if seen == 1:
                    self.armed = True
                    threading.Thread(
                        target=self._deadline, args=(signum,), name="signal-deadline", daemon=True
                    ).start()
                else:
                    self._force(signum)

    def _deadline(self, signum: int) -> None:
        """End the process if it still runs ``grace`` s after the first signal; meanwhile
        raise the interrupt again in the main thread whenever it was swallowed
        (:func:`_quiet_unraisable`)."""
        end = time.monotonic() + self.grace
        while not self.finished.wait(min(0.02, max(0.0, end - time.monotonic()))):
            if _LOST.is_set():
                _LOST.clear()
                _raise_in_main(type(interrupt_for(signum)))
            if time.monotonic() >= end:
                self._force(signum)
                return

    def _force(self, signum: int) -> None:
        """End the process now: cleanups, one line, the exit code of the signal."""
        if self.finished.is_set():
            return
        _trace_stacks()
        _run_cleanups()
        term = signum == signal.SIGTERM
        # a line being written now is waited for (bounded: a stuck stream must not keep the
        # process alive) and then counts as written
        locked = _REPORTING.acquire(timeout=0.5)
        try:
            if not _REPORTED.is_set() and locked:  # the command's own line is enough
                with contextlib.suppress(OSError):
                    os.write(2, f"{message(Terminated() if term else None)} (forced)\n".encode())
            os._exit(EXIT_INTERRUPTED)
        finally:  # (reached only where ``os._exit`` is replaced, as in the tests)
            if locked:
                _REPORTING.release()

    def close(self, linger: bool) -> None:
        """Stop watching; ``linger``: a deadline already running stays (the process is
        ending after a signal, and its exit must not hang either)."""
        if not (linger and self.armed):
            self.finished.set()
        with contextlib.suppress(OSError):
            self.writer.close()
        with contextlib.suppress(OSError):
            self.reader.shutdown(socket.SHUT_RDWR)
        self.thread.join(timeout=1.0)
        with contextlib.suppress(OSError):
            self.reader.close()


def _quiet_unraisable(
    previous: Callable[[sys.UnraisableHookArgs], object],
) -> Callable[[sys.UnraisableHookArgs], None]:
    """An unraisable-exception hook for our own interrupt: raised inside a weakref callback
    (importlib's module locks, at every import) or a ``__del__``, Python prints it as
    "Exception ignored ... Traceback" and goes on, so the command went on computing until the
    guard ended it 2 s later. The text is dropped and, while the guard is active, the
    guard's deadline thread raises the interrupt again in the main thread, at its next
    instruction outside the callback (docs/cli.md#interrupting-a-command). After a signal
    any other unraisable error is dropped too: the interrupt caused it."""

    def hook(args: sys.UnraisableHookArgs) -> None:
        if signalled() is None:
            previous(args)
            return
        # after a signal any such error is the interrupt's doing (an object it cut short
        # mid-construction fails in its __del__: llvmlite's PassBuilder), noise on the line
        if isinstance(args.exc_value, KeyboardInterrupt) and _ACTIVE:
            _LOST.set()  # raised again by the guard's deadline thread, not from in here

    return hook


def _raise_in_main(exc_type: type[BaseException]) -> None:
    """Have the main thread raise ``exc_type`` at its next Python instruction."""
    import ctypes

    ident = threading.main_thread().ident
    if ident is None:
        return
    with contextlib.suppress(Exception):  # best effort: another interpreter may lack it
        set_async = ctypes.pythonapi.PyThreadState_SetAsyncExc
        set_async(ctypes.c_ulong(ident), ctypes.py_object(exc_type))


@contextlib.contextmanager
def signal_guard(grace: float = GRACE, linger: bool = False) -> Iterator[None]:
    """Inside: SIGINT raises ``KeyboardInterrupt`` and SIGTERM :class:`Terminated` in the main
    thread, and a watchdog ends the process ``grace`` seconds after the first signal (at once
    after a second) if it is still running (module docstring). ``linger``: the guard is the
    whole process (the command line), so after a signal the deadline also covers the
    interpreter's exit, and the signals are ignored once the command is over: a Ctrl-C
    that comes as the process exits leaves the command's own exit code (Python's default
    handler would end the process by the signal, exit -2). Outside the main thread, or
    when SIGTERM already has a handler of someone else's, nothing is installed."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, None)
        or sys.platform == "win32"
    ):
        yield
        return
    guard = _Guard(grace)
    _SIGNAL.clear()  # a guard's signal is its command's (tests run several in one process)
    _LOST.clear()
    guard.thread.start()
    old_fd = signal.set_wakeup_fd(guard.writer.fileno(), warn_on_full_buffer=False)
    old_int, old_term = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    try:  # from here on, a signal raises inside the try
        signal.signal(signal.SIGINT, guard.handler)
        signal.signal(signal.SIGTERM, guard.handler)
        _ACTIVE.append(True)
        old_hook, sys.unraisablehook = sys.unraisablehook, _quiet_unraisable(sys.unraisablehook)
        yield
    finally:
        if _ACTIVE:
            _ACTIVE.pop()
            if not linger:
                sys.unraisablehook = old_hook
        if linger:  # the command is over: a late signal must not kill the exiting process
            old_int = old_term = signal.SIG_IGN
        signal.signal(signal.SIGTERM, old_term)
        signal.signal(signal.SIGINT, old_int)
        signal.set_wakeup_fd(old_fd)
        guard.close(linger)
        if not linger:
            _SIGNAL.clear()
