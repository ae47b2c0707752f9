"""The toolkit's error types.

Every error a user can cause (a bad file, a bad option, a kit that cannot fit) is a
:class:`BilevelKitError`; the CLI turns it into a one-line message and exit code 2.
"""

from __future__ import annotations


class BilevelKitError(Exception):
    """Base class of every error the CLI reports as bad input (exit code 2)."""


class DocumentError(BilevelKitError):
    """A JSON file is malformed; the message names the file and the JSON path."""

    def __init__(self, source: str, path: str, message: str) -> None:
        self.source = source
        self.path = path
        self.detail = message
        super().__init__(f"{source}: {path}: {message}")


class InstanceError(DocumentError):
    """An instance file is malformed; the message names the file and the JSON path."""


class SolutionError(DocumentError):
    """A solution file is malformed; the message names the file and the JSON path."""


class KitDoesNotFit(BilevelKitError):
    """A kit's parts cannot be laid out on the tray by the method that was asked to."""


class UsageError(BilevelKitError):
    """A command-line option or API argument is invalid."""
