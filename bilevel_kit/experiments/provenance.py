"""The identity of the code that computes a cell: the package version and a digest of its
source (docs/cluster.md#cells-and-the-code-that-made-them).

Why: a saved cell is reused only when the code that would compute it again is the code that
computed it, so a changed method never serves an old result. The identity is recorded in
every cell record (not in the cell's key), which keeps the file names of committed cells and
of the golden lists in ``tests/data/golden/`` as they are.

What is hashed, exactly: every ``*.py`` file under the package folder ``bilevel_kit/``
(recursively; folders named ``__pycache__`` are skipped), in the order of their paths relative
to that folder (POSIX form, compared as strings). Each file adds its relative path, a NUL
byte, its size in bytes as decimal text, a NUL byte and its raw bytes to one SHA-256. Nothing
else is: not the non-Python files (``py.typed``, the 3-D viewer's ``scene.html``), not
plugins registered from other packages, not the versions of numpy, numba, OR-Tools or HiGHS.
It is computed once per process (about 180 files, 2 MB: some 50 ms).
"""

from __future__ import annotations

import functools
import hashlib
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TypedDict

#: The package folder whose ``*.py`` files make the source digest.
PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: The field of a saved cell record naming the code that computed it; the cell runner reads
#: it and drops it from the records it returns.
CODE = "code"


class CodeIdentity(TypedDict):
    """What a cell record says about the code that computed it."""

    version: str
    source_sha256: str


def source_files(folder: Path = PACKAGE_DIR) -> list[Path]:
    """The files the source digest covers, in the order they are hashed."""
    files = [p for p in folder.rglob("*.py") if "__pycache__" not in p.relative_to(folder).parts]
    return sorted(files, key=lambda p: p.relative_to(folder).as_posix())


def source_digest(folder: Path = PACKAGE_DIR) -> str:
    """SHA-256 (hex) over :func:`source_files`: relative path, size and bytes of each."""
    h = hashlib.sha256()
    for path in source_files(folder):
        data = path.read_bytes()
        h.update(path.relative_to(folder).as_posix().encode() + b"\0")
        h.update(str(len(data)).encode() + b"\0")
        h.update(data)
    return h.hexdigest()


@functools.cache
def code_identity() -> CodeIdentity:
    """This process's code: the package version and :func:`source_digest` (computed once)."""
    from .. import __version__

    return {"version": __version__, "source_sha256": source_digest()}


def describe(identity: object) -> str:
    """A code identity in a few words (``bilevel_kit 0.1.0, source 1a2b3c4d5e6f``), or
    ``code not recorded`` for a record saved before cells recorded their code."""
    if not isinstance(identity, dict):
        return "code not recorded"
    return (
        f"bilevel_kit {identity.get('version', '?')}, "
        f"source {str(identity.get('source_sha256', '?'))[:12]}"
    )


def reusable(
    saved: Sequence[dict[str, Any] | None], current: CodeIdentity, desc: str, loud: bool
) -> tuple[list[dict[str, Any] | None], int]:
    """Of a sweep's saved records (``None``: none saved), those it reuses (the others become
    ``None``: the cell runs), and how many finished ones it recomputes because other code made
    them (an older version, changed source, or a record saved before records named their
    code). ``loud``: say so in one line on stderr."""
    stale = [r for r in saved if r is not None and r.get(CODE) != current]
    if stale and loud:
        makers = sorted({describe(r.get(CODE)) for r in stale})
        made = makers[0] if len(makers) == 1 else f"{len(makers)} other versions"
        print(
            f"{desc}: recomputing {len(stale)} of {len(saved)} saved cells made by other code "
            f"({made}; this is {describe(current)})",
            file=sys.stderr,
            flush=True,
        )
    kept = [None if r is None or r.get(CODE) != current else without_code(r) for r in saved]
    return kept, len(stale)


def without_code(record: dict[str, Any]) -> dict[str, Any]:
    """A record as a sweep's caller sees it: without the code identity (kept in the cell
    files only, so tables and golden files do not change with every commit)."""
    return {k: v for k, v in record.items() if k != CODE}
