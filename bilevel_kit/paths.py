"""Output paths, checked before any work: every file or folder a command will write.

A command that solves for an hour and then cannot write its result has lost the hour, and one
that writes some outputs before failing on the next leaves a half-done result. So each output
option is checked up front (:func:`check_outputs`): a file must not be an existing folder, a
folder must not be an existing file, the nearest existing parent must be a writable folder,
and two options must not name the same path. Names that become parts of paths (an instance's
``name`` in figure file names) go through :func:`safe_name` first.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path

from .errors import UsageError

#: The longest file-name stem :func:`safe_name` returns.
MAX_NAME = 100


def _nearest_existing(path: Path) -> Path:
    """``path`` itself or its closest ancestor that exists."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(".")


def _parent_problem(path: Path) -> str | None:
    """Why no file or folder can be created at ``path`` (None: it can)."""
    base = _nearest_existing(path.absolute().parent)
    if not base.is_dir():
        return f"{base} is not a folder"
    if not os.access(base, os.W_OK | os.X_OK):
        return f"cannot create files in {base} (permission denied)"
    return None


def file_problem(path: str | os.PathLike[str]) -> str | None:
    """Why ``path`` cannot be written as a file (None: it can)."""
    p = Path(path)
    if not str(path) or p.name in ("", ".", ".."):
        return "not a file name"
    if p.is_dir():
        return "is a folder, not a file"
    if p.exists():
        if not os.access(p, os.W_OK):
            return "exists and is not writable"
        return None
    return _parent_problem(p)


def folder_problem(path: str | os.PathLike[str]) -> str | None:
    """Why ``path`` cannot be used as an output folder (None: it can)."""
    p = Path(path)
    if not str(path):
        return "not a folder name"
    if p.exists():
        if not p.is_dir():
            return "exists and is not a folder"
        if not os.access(p, os.W_OK | os.X_OK):
            return "is not writable"
        return None
    return _parent_problem(p)


def check_outputs(
    files: Mapping[str, str | os.PathLike[str] | None],
    folders: Mapping[str, str | os.PathLike[str] | None] | None = None,
) -> None:
    """Raise :class:`UsageError` ``OPTION PATH: reason`` for the first output that cannot be
    written. ``files``/``folders`` map an option (``"--out"``) to its path; None: not given."""
    seen: dict[Path, str] = {}
    for kind, given, problem in (
        ("file", files, file_problem),
        ("folder", folders or {}, folder_problem),
    ):
        for option, path in given.items():
            if path is None:
                continue
            why = problem(path)
            if why is not None:
                raise UsageError(f"{option} {path}: {why}")
            key = Path(path).absolute()
            if key in seen:
                raise UsageError(f"{option} {path}: the same {kind} as {seen[key]}")
            seen[key] = option


def safe_name(name: str, default: str = "unnamed") -> str:
    """``name`` as one harmless file-name component: no path separators, no ``..``, no
    leading dot, only letters, digits and ``_.+-`` (others become ``_``), at most
    :data:`MAX_NAME` characters."""
    cleaned = re.sub(r"[^A-Za-z0-9_.+-]+", "_", name).replace("..", "_").strip("._")
    return cleaned[:MAX_NAME] or default
