"""Atomic file output: write to a temporary file in the same folder, then rename.

A reader (or a crash) never sees a half-written result file, and a failed command leaves
no partial output behind. The file gets the mode a plain write would give (umask honoured).
The target's path is resolved first (``a/../y.png`` is ``y.png`` and creates no ``a``; a
link's file is replaced, not the link). Only a regular file (or a new one) is replaced: a
device or a pipe (``/dev/null``, ``/dev/stdout``) is written in place, never renamed over.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .interrupt import checkpoint, on_forced_exit, remove_path


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path next to ``path`` (same suffix); rename it over ``path`` on success.

    On an exception (``KeyboardInterrupt`` included), or after a signal whose exception
    was lost on its way (:func:`bilevel_kit.interrupt.checkpoint`), the temporary file is
    removed and ``path`` is left untouched.
    """
    try:
        in_place = not stat.S_ISREG(os.stat(path).st_mode)  # a device or a pipe
    except OSError:
        in_place = False  # a new file
    if in_place:
        yield Path(path)
        return
    target = Path(os.path.realpath(path))
    folder = target.parent
    folder.mkdir(parents=True, exist_ok=True)
    tmp: str | None = None
    try:  # whatever ends the write (an error, Ctrl-C, SIGTERM raised as one) removes the temp
        fd, tmp = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=target.suffix or ".tmp", dir=folder
        )
        os.close(fd)
        with on_forced_exit(remove_path(tmp)):
            os.chmod(tmp, _mode_for(target))
            yield Path(tmp)
            checkpoint()  # a signal came while the result was computed: no complete file
            os.replace(tmp, target)
            tmp = None
    finally:
        if tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)


def _mode_for(target: Path) -> int:
    """The mode a plain ``open(target, "w")`` would give: the existing file's, else 0o666
    less the umask (``mkstemp`` creates 0o600, which would hide results from other users)."""
    try:
        return target.stat().st_mode & 0o777
    except OSError:
        mask = os.umask(0o022)  # reading the umask means setting it; restore it at once
        os.umask(mask)
        return 0o666 & ~mask


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        if stat.S_ISREG(os.fstat(fh.fileno()).st_mode):  # a pipe cannot be synced
            os.fsync(fh.fileno())
