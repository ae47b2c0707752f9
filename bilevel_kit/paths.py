"""Output paths, checked before any work: every file or folder a command will write.

A command that solves for an hour and then cannot write its result has lost the hour, and one
that writes some outputs before failing on the next leaves a half-done result. So each output
option is checked up front (:func:`check_outputs`, docs/cli.md#output-paths):

* a file is a regular file that can be opened for writing, or a new file; either way its
  folder (or the nearest existing ancestor) must let a file be created there, since results are
  written to a temporary file and renamed over the target (:mod:`bilevel_kit.atomic`). A
  character device or a pipe (``/dev/null``, ``/dev/stdout``) is written in place, never
  replaced; any other kind of file is refused;
* a folder is an existing folder new files can be created in, or a new one;
* a figure's suffix names a format the figures can be saved in (none: PNG);
* no two outputs, and no output and an input, are the same file once the paths are resolved
  (``a/../y.png`` is ``y.png``; links are followed), and no output is inside a folder another
  output replaces as a whole (a ROS 2 bag). The files a command names itself (the bags in
  ``--bag DIR``, the figures in ``--figures DIR``) are declared too (:class:`Output`);
* an existing file of a kind told apart by its first bytes (:data:`SIGNATURES`: a ROS 1 bag,
  an HTML page, a PNG, a PDF) is replaced only by a file of the same kind: ``--html x.bag``
  over a bag is refused, as a CSV over a PNG.

Whether a folder takes new files is tried, not guessed from permission bits (root passes every
permission check, yet nothing can be created in ``/proc``): a temporary file is created and
removed at once, and the folder's modification time put back. Names that become parts of paths
(an instance's ``name`` in figure file names) go through :func:`safe_name` first.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from .errors import UsageError

#: The longest file-name stem :func:`safe_name` returns.
MAX_NAME = 100
#: The figure formats matplotlib saves, by suffix (a figure without a suffix is a PNG).
FIGURE_SUFFIXES = (
    ".png",
    ".pdf",
    ".svg",
    ".svgz",
    ".eps",
    ".ps",
    ".jpg",
    ".jpeg",
    ".tif",
    ".tiff",
    ".webp",
    ".pgf",
)

PathLike = str | os.PathLike[str]


def _nearest_existing(path: Path) -> Path:
    """``path`` itself or its closest ancestor that exists."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(".")


def _takes_new_files(folder: Path) -> str | None:
    """Why no file can be created in the existing folder ``folder`` (None: one can). Tried:
    a temporary file is created and removed, and the folder's times are put back."""
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"cannot create files in {folder} (permission denied)"
    try:
        times = os.stat(folder)
        fd, probe = tempfile.mkstemp(prefix=".bilevel-kit-probe-", dir=folder)
    except OSError as exc:
        return f"cannot create files in {folder} ({exc.strerror or exc})"
    os.close(fd)
    os.unlink(probe)
    with contextlib.suppress(OSError):
        os.utime(folder, ns=(times.st_atime_ns, times.st_mtime_ns))
    return None


def _parent_problem(path: Path) -> str | None:
    """Why no file or folder can be created at ``path`` (None: it can)."""
    base = _nearest_existing(path.absolute().parent)
    if not base.is_dir():
        return f"{base} is not a folder"
    return _takes_new_files(base)


def _existing(path: Path) -> tuple[os.stat_result | None, str | None]:
    """``os.stat`` of ``path`` and None, or None and why nothing can be written there: it
    cannot be reached, or nothing is there yet (a missing folder or a file where a folder
    would be on the way) and :func:`_parent_problem` says whether it can be created."""
    try:
        return os.stat(path), None
    except OSError as exc:
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return None, _parent_problem(path)
        return None, f"cannot be reached ({exc.strerror or exc})"


def _opens_for_writing(path: Path) -> bool:
    """Can the existing regular file be opened for writing? (Nothing is written, nothing
    changes; a pipe is never opened here: its reader would see the end of the data.)"""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND)
    except OSError:
        return False
    os.close(fd)
    return True


def file_problem(path: PathLike, figure: bool = False) -> str | None:
    """Why ``path`` cannot be written as a file (None: it can); ``figure``: also its suffix."""
    p = Path(path)
    if not str(path) or p.name in ("", ".", ".."):
        return "not a file name"
    if figure and p.suffix and p.suffix.lower() not in FIGURE_SUFFIXES:
        return f"unknown figure format {p.suffix!r} (use {', '.join(FIGURE_SUFFIXES)})"
    st, problem = _existing(p)
    if st is None:
        return problem
    if stat.S_ISDIR(st.st_mode):
        return "is a folder, not a file"
    if not (stat.S_ISREG(st.st_mode) or stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):
        return "exists and is not a regular file, a device or a pipe"
    if not stat.S_ISREG(st.st_mode):  # a device or a pipe: written in place
        return None if os.access(p, os.W_OK) else "exists and is not writable"
    if not _opens_for_writing(p):
        return "exists and is not writable"
    return _takes_new_files(Path(os.path.realpath(p)).parent)  # a temporary file, renamed


def folder_problem(path: PathLike) -> str | None:
    """Why ``path`` cannot be used as an output folder (None: it can)."""
    p = Path(path)
    if not str(path):
        return "not a folder name"
    st, problem = _existing(p)
    if st is None:
        return problem
    if not stat.S_ISDIR(st.st_mode):
        return "exists and is not a folder"
    return None if _takes_new_files(p) is None else "is not writable"


def same_file_keys(path: PathLike) -> list[tuple[object, ...]]:
    """What identifies the file ``path`` names: its resolved path (``a/../y.png`` is
    ``y.png``, links followed) and, when it exists, its device and inode (hard links)."""
    keys: list[tuple[object, ...]] = [("path", os.path.realpath(path))]
    with contextlib.suppress(OSError):
        st = os.stat(path)
        keys.append(("inode", st.st_dev, st.st_ino))
    return keys


#: Kinds of file told apart by their first bytes: an output never replaces an existing file
#: of one of these kinds with a file of another kind (docs/cli.md#output-paths).
SIGNATURES: dict[str, tuple[bytes, ...]] = {
    "a ROS 1 bag": (b"#ROSBAG V",),
    "an HTML page": (b"<!DOCTYPE html", b"<!doctype html", b"<html"),
    "a PNG image": (b"\x89PNG\r\n\x1a\n",),
    "a PDF document": (b"%PDF-",),
}
#: What a figure holds, by suffix (the kinds of :data:`SIGNATURES`; others: not told apart).
FIGURE_KINDS = {"": "a PNG image", ".png": "a PNG image", ".pdf": "a PDF document"}
#: What a file output holds when its option says nothing: text (JSON, CSV, Markdown).
TEXT = "text"


@dataclass(frozen=True)
class Output:
    """One file or folder a command will write. ``subject`` names it in messages (``--out
    s.json``, or for a file the command names itself ``--bag b (its ROS 1 bag b/x.bag)``);
    ``writes``: what a file holds (a key of :data:`SIGNATURES`, or :data:`TEXT`);
    ``replaced``: a folder replaced as a whole (a ROS 2 bag), so nothing else may be in it."""

    subject: str
    path: PathLike
    kind: str = "file"  # "file", "figure" or "folder"
    writes: str = TEXT
    replaced: bool = False
    label: str = ""  # how a later clash names it (default: the subject)

    def problem(self) -> str | None:
        """Why this output cannot be written where it is asked for (None: it can)."""
        if self.kind == "folder":
            return folder_problem(self.path)
        writes = self.writes
        if self.kind == "figure" and writes == TEXT:  # a figure holds what its suffix says
            writes = FIGURE_KINDS.get(Path(self.path).suffix.lower(), TEXT)
        return file_problem(self.path, figure=self.kind == "figure") or clobber_problem(
            self.path, writes
        )


def file_kind(path: PathLike) -> str | None:
    """The kind of :data:`SIGNATURES` whose first bytes the regular file ``path`` starts
    with; None: none, or not a readable regular file."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb") as fh:
            head = fh.read(16)
    except OSError:
        return None
    for kind, starts in SIGNATURES.items():
        if head.startswith(starts):
            return kind
    return None


def clobber_problem(path: PathLike, writes: str) -> str | None:
    """Why writing ``writes`` over the existing file ``path`` would clobber something else
    (an HTML page over a ROS bag, a CSV over a PNG); None: nothing there, or the same kind."""
    kind = file_kind(path)
    if kind is None or kind == writes:
        return None
    what = "text" if writes == TEXT else writes
    return f"exists and is {kind}; this would replace it with {what} (remove it first)"


def check_outputs(
    files: Mapping[str, PathLike | None],
    folders: Mapping[str, PathLike | None] | None = None,
    *,
    figures: Mapping[str, PathLike | None] | None = None,
    inputs: Mapping[str, PathLike | None] | None = None,
    writes: Mapping[str, str] | None = None,
    derived: Sequence[Output] = (),
) -> None:
    """Raise :class:`UsageError` ``OPTION PATH: reason`` for the first output that cannot be
    written (module docstring). ``files``, ``folders`` and ``figures`` map an output option
    (``"--out"``) to its path, ``inputs`` an input's name to its path; None: not given.
    ``writes`` says what a file option holds (default :data:`TEXT`); ``derived`` are the
    outputs a command names itself (the bags in ``--bag DIR``, the figures in ``--figures``)."""
    outputs: list[Output] = []
    for option, path in files.items():
        if path is not None:
            what = (writes or {}).get(option, TEXT)
            outputs.append(Output(f"{option} {path}", path, "file", what, label=option))
    for option, path in (figures or {}).items():
        if path is not None:
            suffix = Path(path).suffix.lower()
            what = FIGURE_KINDS.get(suffix, TEXT)
            outputs.append(Output(f"{option} {path}", path, "figure", what, label=option))
    for option, path in (folders or {}).items():
        if path is not None:
            outputs.append(Output(f"{option} {path}", path, "folder", label=option))
    _check([*outputs, *derived], inputs or {})


def _check(outputs: Sequence[Output], inputs: Mapping[str, PathLike | None]) -> None:
    """:func:`check_outputs` on the list of every output."""
    seen: dict[tuple[object, ...], str] = {}
    for name, path in inputs.items():
        if path is not None:
            for key in same_file_keys(path):
                seen.setdefault(key, f"the input {name}")
    replaced = [(o, os.path.realpath(o.path)) for o in outputs if o.replaced]
    for out in outputs:
        why = out.problem()
        if why is not None:
            raise UsageError(f"{out.subject}: {why}")
        keys = same_file_keys(out.path)
        kind = "folder" if out.kind == "folder" else "file"
        for key in keys:
            if key in seen:
                raise UsageError(f"{out.subject}: the same {kind} as {seen[key]}")
        real = os.path.realpath(out.path)
        for folder, where in replaced:
            if folder is not out and os.path.commonpath([real, where]) == where:
                raise UsageError(f"{out.subject}: inside {folder.subject}, replaced as a whole")
        seen.update(dict.fromkeys(keys, out.label or out.subject))


def safe_name(name: str, default: str = "unnamed") -> str:
    """``name`` as one harmless file-name component: no path separators, no ``..``, no
    leading dot, only letters, digits and ``_.+-`` (others become ``_``), at most
    :data:`MAX_NAME` characters."""
    cleaned = re.sub(r"[^A-Za-z0-9_.+-]+", "_", name).replace("..", "_").strip("._")
    return cleaned[:MAX_NAME] or default
