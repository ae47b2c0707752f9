"""Named registries of methods and policies, and the plugins that add to them.

Why: a researcher's own method or simulation policy, in their own package, should appear in
``bilevel-kit solve``/``compare``/``simulate`` without editing this package. A package
declares a function in the entry-point group ``bilevel_kit.plugins``; the first time a
registry is listed, or asked for a name it does not hold, every such function is called once,
and it registers its methods (:func:`bilevel_kit.methods.register`) and policies
(``bilevel_kit.sim.registry.POLICIES.register``). docs/extending.md#plugins shows one.

A plugin that fails to load (an import error, a name that is already taken) is reported on
standard error with its name and skipped: one broken package must not break the toolkit.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, MutableMapping
from typing import Generic, Protocol, TypeVar

from .errors import UsageError

#: The entry-point group a plugin declares its registration function in.
PLUGIN_GROUP = "bilevel_kit.plugins"

_state = {"loaded": False}


class _Named(Protocol):
    @property
    def name(self) -> str: ...


SpecT = TypeVar("SpecT", bound=_Named)


def load_plugins() -> list[str]:
    """Call every installed plugin's registration function, once per process; return the
    names of the plugins that loaded."""
    if _state["loaded"]:
        return []
    _state["loaded"] = True  # first: a plugin that lists a registry must not recurse
    from importlib.metadata import entry_points

    loaded = []
    for ep in sorted(entry_points(group=PLUGIN_GROUP), key=lambda e: e.name):
        try:
            ep.load()()
        except Exception as exc:  # any failure of third-party code: report, go on
            print(
                f"bilevel-kit: plugin {ep.name!r} ({ep.value}) was not loaded: {exc}",
                file=sys.stderr,
            )
            continue
        loaded.append(ep.name)
    return loaded


def reset_plugins() -> None:
    """Forget that plugins were loaded (tests that install one in the middle of a run)."""
    _state["loaded"] = False


class Registry(MutableMapping[str, SpecT], Generic[SpecT]):
    """Name -> registration, in registration order; plugins are loaded on the first listing
    or on a lookup that misses, so a built-in lookup costs no entry-point scan.

    :meth:`add` refuses a name that is taken; item assignment replaces one on purpose (a test
    swapping a method's options, say)."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._specs: dict[str, SpecT] = {}

    def add(self, spec: SpecT) -> None:
        """Register ``spec`` under its name; a name is registered once (built-ins first)."""
        if spec.name in self._specs:
            raise UsageError(f"{self.kind} {spec.name!r} is already registered")
        self._specs[spec.name] = spec

    def remove(self, name: str) -> None:
        """Unregister ``name`` (a test's own method, when the test ends)."""
        self._specs.pop(name, None)

    def __setitem__(self, name: str, spec: SpecT) -> None:
        self._specs[name] = spec

    def __delitem__(self, name: str) -> None:
        del self._specs[name]

    def __getitem__(self, name: str) -> SpecT:
        if name not in self._specs:
            load_plugins()
        return self._specs[name]

    def __contains__(self, name: object) -> bool:
        if name not in self._specs:
            load_plugins()
        return name in self._specs

    def __iter__(self) -> Iterator[str]:
        load_plugins()
        return iter(list(self._specs))

    def __len__(self) -> int:
        load_plugins()
        return len(self._specs)
