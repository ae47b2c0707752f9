"""The toolkit's error types.

Every error a user can cause (a bad file, a bad option, a kit that cannot fit) is a
:class:`BilevelKitError`; the CLI turns it into a one-line message and exit code 2.
"""

from __future__ import annotations

import re


def one_line(text: object) -> str:
    """``text`` on one line: a message from a plugin or a library may hold newlines, and the
    CLI promises one line per error (line breaks become `` | ``)."""
    return re.sub(r"\s*[\r\n]+\s*", " | ", str(text).strip())


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


class PluginError(BilevelKitError):
    """A plugin's method failed (raised, returned no ``MethodOutput``, or names a module that
    does not import); the message names the plugin. Exit 1, not 2: the input was fine."""
