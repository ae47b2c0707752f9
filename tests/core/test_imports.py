"""The package's import graph: no cycles, and arrows only point down (docs/extending.md).

Every module of ``bilevel_kit`` is parsed with ``ast`` (imports inside functions count too);
relative imports are resolved, and ``from pkg import name`` where ``name`` is a submodule is an
edge to that submodule. A package's ``__init__`` importing its own submodules is not an
upward edge; a cycle is a loop in the graph that does not consist only of such parent->child
edges closed by a child importing its parent package (which Python resolves through the
partially initialised package), so ``pkg/__init__ -> pkg/mod -> pkg/other`` is fine unless
``pkg/other`` imports back into ``pkg/mod``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = "bilevel_kit"
ROOT = Path(__file__).resolve().parents[2] / PKG

#: The core (docs/extending.md#the-house): the data model, evaluator, checker, bounds, kit
#: fitness, registry, options, errors and I/O, at the package root. Everything both method
#: rooms share lives here.
CORE = (
    "instance",
    "plan",
    "validate",
    "objectives",
    "stochastic",
    "bounds",
    "stations",
    "geometry",
    "fitness",
    "reachability",
    "methods",
    "registry",
    "options",
    "errors",
    "atomic",
    "jsonio",
    "paths",
    "progress",
    "style",
    "solution",
    "packfile",
    "interrupt",
    "_native",
)
#: The rooms above the core, bottom to top; a room imports only the core, ``sawyer`` and rooms
#: below it (``heuristics`` never imports ``models``: models may start from a heuristic plan,
#: never the reverse).
ROOMS = ("heuristics", "models", "generate", "plots", "sim", "experiments", "repro", "cli")


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _resolve(module: str, level: int, target: str | None) -> str:
    """The absolute name of a (possibly relative) import in ``module``."""
    if level == 0:
        return target or ""
    base = module.split(".")
    if not _is_package(module):
        base = base[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def _known(name: str) -> str | None:
    """The longest ``bilevel_kit`` module that is ``name`` or contains it."""
    while name:
        if name in MODULES:
            return name
        name = name.rpartition(".")[0]
    return None


def _edges(module: str) -> set[str]:
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    out: set[str] = set()
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = _resolve(module, node.level, node.module)
            names = [base]
            names += [f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in MODULES]
        for n in names:
            hit = _known(n)
            if hit is not None and hit != module:
                out.add(hit)
    return out


GRAPH = {m: _edges(m) for m in MODULES}


def _allowed_back_edge(src: str, dst: str) -> bool:
    """A child importing one of its enclosing packages (their ``__init__``)."""
    return src.startswith(dst + ".")


def _cycles() -> list[list[str]]:
    """Strongly connected components (Tarjan) with more than one module, after dropping
    child -> parent-package edges (parent -> child edges of an ``__init__`` stay, so a real
    loop through a package's modules is still found)."""
    graph = {m: {d for d in ds if not _allowed_back_edge(m, d)} for m, ds in GRAPH.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _one_loop(component: list[str]) -> list[str]:
    """A concrete loop inside a cycle component, for the failure message."""
    comp = set(component)
    start = component[0]
    path, seen = [start], {start}
    while True:
        nxt = sorted(
            d for d in GRAPH[path[-1]] if d in comp and not _allowed_back_edge(path[-1], d)
        )
        back = [d for d in nxt if d in seen]
        if back:
            return [*path[path.index(back[0]) :], back[0]]
        fresh = [d for d in nxt if d not in seen]
        if not fresh:
            return path
        path.append(fresh[0])
        seen.add(fresh[0])


def _under(name: str, top: str) -> bool:
    full = f"{PKG}.{top}"
    return name == full or name.startswith(full + ".")


def _room(name: str) -> str:
    """The room a module lives in: its top-level folder or module below ``bilevel_kit``."""
    return name.split(".")[1] if "." in name else "__init__"


def test_every_module_is_in_a_known_room():
    """A new module must be placed deliberately: in the core list or one of the rooms."""
    known = {*CORE, *ROOMS, "sawyer", "__init__", "__main__"}
    assert sorted({_room(m) for m in MODULES} - known) == []


def test_the_walker_sees_function_level_and_submodule_imports():
    assert f"{PKG}.sim.policies" in GRAPH[f"{PKG}.sim"]  # from .policies import ...
    assert f"{PKG}.instance" in GRAPH[f"{PKG}.plan"] or f"{PKG}.instance" in GRAPH[f"{PKG}.bounds"]
    assert any(d.startswith(f"{PKG}.models") for d in GRAPH[f"{PKG}.sim.cpsat_rolling"])
    # a function-level import (greedy-ce's lazy convex polish) is an edge too
    assert f"{PKG}.heuristics.convex" in GRAPH[f"{PKG}.heuristics.greedy_ce"]


def test_no_import_cycles():
    loops = [" -> ".join(_one_loop(c)) for c in _cycles()]
    assert not loops, "import cycles:\n" + "\n".join(loops)


def _imports_into(sources: tuple[str, ...], targets: tuple[str, ...]) -> list[str]:
    return sorted(
        f"{m} -> {d}"
        for m, deps in GRAPH.items()
        if any(_under(m, s) for s in sources)
        for d in deps
        if any(_under(d, t) for t in targets)
    )


@pytest.mark.parametrize("top", [*CORE, "sawyer"])
def test_the_core_imports_no_room(top):
    bad = _imports_into((top,), ROOMS)
    assert not bad, "the core reaches into a room:\n" + "\n".join(bad)


def test_heuristics_never_import_models():
    bad = _imports_into(("heuristics",), ("models",))
    assert not bad, "heuristics -> models:\n" + "\n".join(bad)


@pytest.mark.parametrize("i", range(len(ROOMS)))
def test_rooms_import_only_downwards(i):
    bad = _imports_into((ROOMS[i],), ROOMS[i + 1 :])
    assert not bad, f"{ROOMS[i]} imports a room above it:\n" + "\n".join(bad)


def test_the_rules_can_fail():
    """The checker itself: a made-up upward edge is reported (so a green run means something)."""
    GRAPH[f"{PKG}.heuristics.shelf"].add(f"{PKG}.models.packing")
    try:
        assert _imports_into(("heuristics",), ("models",)) == [
            f"{PKG}.heuristics.shelf -> {PKG}.models.packing"
        ]
    finally:
        GRAPH[f"{PKG}.heuristics.shelf"].discard(f"{PKG}.models.packing")


def test_modules_and_functions_stay_small():
    """Small modules with one job each (docs/extending.md#the-house): at most 700 lines per
    module and 100 per function, so a reader can hold one in view."""
    import ast
    from pathlib import Path

    package = Path(__file__).resolve().parents[2] / "bilevel_kit"
    too_long = []
    for path in sorted(package.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        name = path.relative_to(package.parent)
        if text.count("\n") > 700:
            too_long.append(f"{name}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > 100:
                    too_long.append(f"{name}:{node.lineno} {node.name}: {length} lines")
    assert not too_long, "\n".join(too_long)
