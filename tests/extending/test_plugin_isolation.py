"""Plugins cannot take the tool down (issue 35, item 7; docs/extending.md#plugins): a plugin
whose registration fails in any way (``SystemExit``, ``KeyboardInterrupt``, an exception with
newlines in its message, a name that is not valid) is one stderr line and skipped, with what
it registered taken back; a plugin method that raises, returns no ``MethodOutput`` or names a
missing module is exit 1 with one line naming the plugin, never a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.interrupt import signal_guard
from bilevel_kit.methods import REGISTRY, MethodOutput, register
from bilevel_kit.objectives import OBJECTIVES
from bilevel_kit.registry import PLUGIN_GROUP, check_name, load_plugins, reset_plugins

ROOT = Path(__file__).resolve().parents[2]
TINY = str(ROOT / "instances" / "tiny.json")

PLUGINS = """
from bilevel_kit.methods import register
from bilevel_kit.sim.registry import POLICIES

OPTIONS = "bilevel_kit.options:NoOptions"


def exits():
    raise SystemExit(7)


def interrupts():
    raise KeyboardInterrupt


def bad_name():
    register("a b/../x\\n", "bad_plugins:nothing", "a bad name", OPTIONS)


def partial():
    from dataclasses import replace

    from bilevel_kit import objectives

    objectives.register(replace(objectives.OBJECTIVES["sum_completion"], name="partial_obj"))
    register("partial-ok", "bad_plugins:nothing", "registered, then the plugin fails", OPTIONS)
    raise ValueError("first line\\nsecond line")


def methods():
    register("raises", "bad_plugins:raises", "raises", OPTIONS)
    register("returns-none", "bad_plugins:returns_none", "returns None", OPTIONS)
    register("exits-in-method", "bad_plugins:exits_in_method", "SystemExit", OPTIONS)
    register("missing-module", "no_such_module_here:fn", "no module", OPTIONS)
    register("missing-options", "bad_plugins:raises", "no options", "no_such_module_here:O")


def raises(instance, options, *, seed, time_limit):
    raise RuntimeError("boom\\nand a second line")


def returns_none(instance, options, *, seed, time_limit):
    return None


def exits_in_method(instance, options, *, seed, time_limit):
    raise SystemExit(3)
"""

BROKEN = ("exits", "interrupts", "bad-name", "partial")
METHODS = ("raises", "returns-none", "exits-in-method", "missing-module", "missing-options")


@pytest.fixture
def plugins(tmp_path, monkeypatch):
    """The plugins above installed (a module and its dist-info on the path), loaded afresh;
    their methods removed afterwards."""
    (tmp_path / "bad_plugins.py").write_text(PLUGINS)
    dist = tmp_path / "bad_plugins-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: bad-plugins\nVersion: 0.1\n")
    names = [*BROKEN, "methods"]
    points = "".join(f"{n} = bad_plugins:{n.replace('-', '_')}\n" for n in names)
    (dist / "entry_points.txt").write_text(f"[{PLUGIN_GROUP}]\n{points}")
    monkeypatch.syspath_prepend(str(tmp_path))
    reset_plugins()
    yield
    reset_plugins()
    for name in (*METHODS, "partial-ok"):
        REGISTRY.remove(name)


def test_a_broken_registration_is_one_line_and_skipped(plugins, capsys):
    with signal_guard():  # as under the CLI: a KeyboardInterrupt without a signal is the plugin's
        assert load_plugins() == ["methods"]
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == len(BROKEN), err
    for name, line in zip(sorted(BROKEN), lines, strict=True):
        assert line.startswith(f"bilevel-kit: plugin '{name}' (bad_plugins:"), line
    assert "SystemExit: 7" in err and "KeyboardInterrupt" in err
    assert "ValueError: first line | second line" in err
    assert "is not valid" in err
    # the failed plugin's registration was taken back; the good plugin's methods stay
    assert "partial-ok" not in REGISTRY and "a b/../x\n" not in REGISTRY
    assert "partial_obj" not in OBJECTIVES  # an objective too
    assert all(m in REGISTRY for m in METHODS) and "cpsat" in REGISTRY


def test_the_other_commands_work(plugins, capsys):
    assert main(["solve", TINY, "-m", "single-task", "-q"]) == 0
    out, err = capsys.readouterr()
    assert "single-task" in out and len(err.splitlines()) == len(BROKEN)
    assert main(["methods"]) == 0
    assert "returns-none" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("method", "words"),
    [
        ("raises", "failed: RuntimeError: boom | and a second line"),
        ("returns-none", "returned NoneType, not a MethodOutput"),
        ("exits-in-method", "failed: SystemExit: 3"),
        ("missing-module", "cannot import no_such_module_here:fn"),
        ("missing-options", "cannot import no_such_module_here:O"),
    ],
)
def test_a_failing_plugin_method_is_exit_1_naming_the_plugin(
    plugins, capsys, tmp_path, method, words
):
    out = tmp_path / "s.json"
    with signal_guard():
        load_plugins()
    capsys.readouterr()
    assert main(["solve", TINY, "-m", method, "-o", str(out)]) == 1
    _, err = capsys.readouterr()
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"plugin 'methods': method '{method}' " in err and words in err, err
    assert err.startswith("bilevel-kit solve: error: ")
    assert not out.exists()


@pytest.mark.parametrize("name", ["a b/../x\n", "", "X", "1abc", "a:b", "a,b", "a" * 41, 7])
def test_names_are_validated(name):
    with pytest.raises(Exception, match="is not valid"):
        check_name("method", name)
    with pytest.raises(Exception, match="is not valid"):
        register(name, "m:f", "bad", "bilevel_kit.options:NoOptions")  # type: ignore[arg-type]


def test_every_built_in_name_is_valid():
    from bilevel_kit.sim.registry import POLICIES

    for name in [*REGISTRY, *POLICIES]:
        assert check_name("method", name) == name


def test_a_method_registered_directly_is_not_wrapped():
    """Only plugins' methods are guarded: a test's own method keeps its exceptions."""
    register(
        "direct-test",
        "bilevel_kit.heuristics.baselines:single_task",
        "x",
        "bilevel_kit.options:NoOptions",
    )
    try:
        assert REGISTRY.plugin_of("direct-test") is None
        assert REGISTRY["direct-test"].load().__name__ == "single_task"
    finally:
        REGISTRY.remove("direct-test")
    assert MethodOutput  # the contract type the guard checks against


def test_outside_the_cli_a_keyboard_interrupt_is_taken_for_real(plugins, capsys):
    """No guard, no way to tell a plugin's KeyboardInterrupt from Ctrl-C: it goes on up."""
    with pytest.raises(KeyboardInterrupt):
        load_plugins()
