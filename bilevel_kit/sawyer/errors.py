"""Errors of the Sawyer subpackage.

Both are ``ValueError``s (bad input for a function) and :class:`BilevelKitError`s, so the CLI
reports them as one-line messages with exit code 2.
"""

from __future__ import annotations

from ..errors import BilevelKitError


class WorkCellError(BilevelKitError, ValueError):
    """A work cell's geometry (an instance's ``work_cell`` section) is malformed."""


class UnreachableError(BilevelKitError, ValueError):
    """The robot cannot reach where a part must be picked or placed (e.g. an empty map)."""
