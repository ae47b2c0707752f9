"""Named registries of methods, objectives and policies, and the plugins that add to them.

Why: a researcher's own method, objective or simulation policy, in their own package, should
appear in ``bilevel-kit solve``/``compare``/``simulate`` without editing this package. A
package declares a function in the entry-point group ``bilevel_kit.plugins``; the first time a
registry is listed, or asked for a name it does not hold, every such function is called once,
and it registers its objectives (:func:`bilevel_kit.objectives.register`), methods
(:func:`bilevel_kit.methods.register`) and policies
(``bilevel_kit.sim.registry.POLICIES.register``). docs/extending.md#plugins shows one.

A plugin that fails to load (an import error, a name that is already taken or not valid,
any exception, ``SystemExit`` and ``KeyboardInterrupt`` included) is reported on standard
error in one line with its name, what it registered is taken back, and it is skipped: one
broken package must not break the toolkit. Each registration remembers the plugin that made
it (:meth:`Registry.plugin_of`), so a plugin method's failure names the plugin.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Iterator, MutableMapping
from typing import Any, Generic, Protocol, TypeVar

from .errors import UsageError, one_line

#: The entry-point group a plugin declares its registration function in.
PLUGIN_GROUP = "bilevel_kit.plugins"

#: What a method or policy name may be (docs/extending.md#plugins): a lower-case letter, then
#: up to 39 lower-case letters, digits, ``-`` or ``_``. A name is a command-line word, part of
#: ``-p NAME:KEY=VALUE`` and ``--methods A,B``, and of cell file names.
NAME_PATTERN = r"[a-z][a-z0-9_-]{0,39}"

_state: dict[str, Any] = {"loaded": False, "plugin": None, "added": []}


def check_name(kind: str, name: object) -> str:
    """``name`` if it matches :data:`NAME_PATTERN`, else a :class:`UsageError` saying why."""
    if not isinstance(name, str) or not re.fullmatch(NAME_PATTERN, name):
        raise UsageError(
            f"{kind} name {name!r} is not valid: a lower-case letter, then up to 39 lower-case "
            "letters, digits, '-' or '_'"
        )
    return name


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
        _state["plugin"], _state["added"] = ep.name, []
        try:
            ep.load()()
        except BaseException as exc:  # any failure of third-party code: report, go on
            if _real_interrupt(exc):
                raise
            for registry, name in _state["added"]:
                registry.remove(name)
            what = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            print(
                one_line(f"bilevel-kit: plugin {ep.name!r} ({ep.value}) was not loaded: {what}"),
                file=sys.stderr,
            )
            continue
        finally:
            _state["plugin"], _state["added"] = None, []
        loaded.append(ep.name)
    return loaded


def _real_interrupt(exc: BaseException) -> bool:
    """Is ``exc`` a Ctrl-C or SIGTERM rather than a plugin's own ``KeyboardInterrupt``? Under
    the CLI's guard a signal is recorded (:func:`bilevel_kit.interrupt.signalled`); outside
    it, an interrupt is taken for real."""
    from .interrupt import guarded, signalled

    if not isinstance(exc, KeyboardInterrupt):
        return False
    return signalled() is not None or not guarded()


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
        self._plugins: dict[str, str] = {}

    def add(self, spec: SpecT) -> None:
        """Register ``spec`` under its name (:data:`NAME_PATTERN`); a name is registered once
        (built-ins first). Registered while a plugin loads, it is that plugin's."""
        check_name(self.kind, spec.name)
        if spec.name in self._specs:
            raise UsageError(f"{self.kind} {spec.name!r} is already registered")
        self._specs[spec.name] = spec
        if _state["plugin"] is not None:
            self._plugins[spec.name] = _state["plugin"]
            _state["added"].append((self, spec.name))

    def plugin_of(self, name: str) -> str | None:
        """The plugin that registered ``name`` (None: this package or a direct call)."""
        return self._plugins.get(name)

    def remove(self, name: str) -> None:
        """Unregister ``name`` (a test's own method, when the test ends)."""
        self._specs.pop(name, None)
        self._plugins.pop(name, None)

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
