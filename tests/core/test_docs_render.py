"""The documentation site renders what the sources mean: links and maths, not reST markup.

The docstrings use reST roles and ``.. math::``; ``docs/hooks/rest_docstrings.py`` (a griffe
extension) rewrites them for mkdocstrings, and ``docs/hooks/check_rendered.py`` (an MkDocs
hook) fails the build on any role, raw ``$$`` or doctest-as-blockquotes left in a page. These
tests hold the rewriting to its rules, show that the hook catches each kind on a deliberately
broken page rendered with the project's Markdown settings, render every page and the doctests
the same way, build the site once, and (with Chromium) check that every formula renders with
the KaTeX served from the site, fetching nothing from the network.
"""

from __future__ import annotations

import contextlib
import importlib.util
import re
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType, SimpleNamespace

import griffe
import markdown
import pytest
from chromium import Chromium, console_errors, find_chromium, requested_urls
from mkdocs.config import load_config
from mkdocs.exceptions import PluginError

ROOT = Path(__file__).resolve().parents[2]
HOOKS = ROOT / "docs" / "hooks"


def _module(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"docs_hooks_{name}", HOOKS / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


rest = _module("rest_docstrings")
check = _module("check_rendered")


@pytest.fixture(scope="module")
def package() -> griffe.Module:
    """The package as the docs build loads it, docstrings rewritten."""
    extensions = griffe.load_extensions(rest.RestDocstrings)
    loaded = griffe.load("bilevel_kit", extensions=extensions, search_paths=[str(ROOT)])
    assert isinstance(loaded, griffe.Module)
    return loaded


def _objects(obj: griffe.Object) -> list[griffe.Object]:
    out = [obj]
    for member in obj.members.values():
        if not member.is_alias:
            out += _objects(member)  # type: ignore[arg-type]
    return out


def test_no_role_or_math_directive_survives(package: griffe.Module) -> None:
    def raw(text: str) -> bool:
        return bool(rest.ROLE.search(text)) or ":math:`" in text or ".. math::" in text

    left = [o.path for o in _objects(package) if o.docstring and raw(o.docstring.value)]
    assert not left, f"docstrings with reST markup left after the rewrite: {left[:10]}"


def _doc(package: griffe.Module, path: str) -> str:
    obj = package.modules_collection.get_member(path)
    assert obj.docstring is not None
    return str(obj.docstring.value)


def test_relative_names_resolve_like_relative_imports(package: griffe.Module) -> None:
    # heuristics/prefix/__init__.py: ":mod:`..greedy_search`" and ":mod:`.levels`".
    doc = _doc(package, "bilevel_kit.heuristics.prefix")
    assert '<autoref identifier="bilevel_kit.heuristics.greedy_search" optional>' in doc
    assert '<autoref identifier="bilevel_kit.heuristics.prefix.levels" optional>' in doc


def test_bare_names_resolve_through_the_scope(package: griffe.Module) -> None:
    # bounds.py's module docstring: ":func:`tray_wait`", a function of the module itself.
    doc = _doc(package, "bilevel_kit.bounds")
    assert '<autoref identifier="bilevel_kit.bounds.tray_wait" optional>' in doc


def test_tilde_shows_the_last_component_and_explicit_titles_are_kept() -> None:
    obj = griffe.Module("bilevel_kit")
    loader = griffe.GriffeLoader()
    short = rest.cross_reference(obj, loader, "~numpy.random.default_rng")
    assert short == (
        '<autoref identifier="numpy.random.default_rng" optional><code>default_rng</code></autoref>'
    )
    titled = rest.cross_reference(obj, loader, "the rule <bilevel_kit.plan.evaluate>")
    assert "<code>the rule</code>" in titled and 'identifier="bilevel_kit.plan.evaluate"' in titled


def test_math_blocks_become_display_maths() -> None:
    text = "Before:\n\n.. math:: a = b\n          + c\n\n   text? no\n\nAfter :math:`x_i`."
    out = rest.math_blocks(text)
    assert "$$\na = b\n+ c\n$$" in out
    two = rest.math_blocks(".. math::\n\n    x = 1\n\n    y = 2\n\nEnd.")
    assert two.count("$$") == 4 and two.rstrip().endswith("End.")
    obj, loader = griffe.Module("m"), griffe.GriffeLoader()
    assert rest.rewrite(":math:`x_i`", obj, loader) == r"\(x_i\)"


def test_hook_fails_on_a_raw_role_and_ignores_code() -> None:
    assert check.raw_markup("<p>see :func:<code>solve</code> here</p>")
    assert check.raw_markup("<p>.. math:: x</p>")
    assert not check.raw_markup("<p><code>:func:`solve`</code></p><pre>.. math::</pre>")

    page = SimpleNamespace(file=SimpleNamespace(src_uri="api.md"))
    with pytest.raises(PluginError, match=r"api.md: 1 unrendered markup"):
        check.on_post_page("<p>:class:<code>Result</code></p>", page=page, config={})


def test_hook_fails_on_raw_display_maths_and_quoted_doctests() -> None:
    assert len(check.raw_markup("<p>$$\n x = 1\n$$</p>")) == 2
    assert not check.raw_markup('<div class="arithmatex">\\[x\\]</div><code>$$</code>')
    assert check.raw_markup("<blockquote>\n<blockquote>\n<p>from x import y</p>")
    assert check.raw_markup("<blockquote><p>a &gt;&gt;&gt; b</p></blockquote>")
    assert not check.raw_markup("<blockquote><p>a quote</p></blockquote><code>&gt;&gt;&gt;</code>")


def test_doctest_blocks_become_code() -> None:
    text = "Intro.\n\n>>> x = 1\n... + 2\n>>> x\n3\n\nAfter; a >>> in prose stays.\n  >>> y"
    out = rest.doctest_blocks(text)
    assert "\n\n```pycon\n>>> x = 1\n... + 2\n>>> x\n3\n```\n\nAfter" in out
    assert out.endswith("After; a >>> in prose stays.\n  >>> y")


@pytest.fixture(scope="module")
def render() -> Callable[[str], str]:
    """Markdown to HTML with the extensions and settings of the project's ``mkdocs.yml``."""
    config = load_config(str(ROOT / "mkdocs.yml"))
    extensions, settings = config["markdown_extensions"], config["mdx_configs"]

    def _render(text: str) -> str:
        with contextlib.chdir(ROOT):  # pymdownx.snippets' base_path is the repository
            return markdown.Markdown(extensions=extensions, extension_configs=settings).convert(
                text
            )

    return _render


#: The two kinds of page that once passed the strict build unrendered (issue 40, item 4): a
#: ``$$`` block indented by two spaces under a list item, and a doctest outside a code fence.
BROKEN = [
    "- a list item, then its cut:\n\n  $$\n  x \\le 1\n  $$\n",
    "An example:\n\n>>> from bilevel_kit import load\n>>> load('x.json')\n",
]


@pytest.mark.parametrize("page", BROKEN)
def test_the_check_fails_on_a_broken_page(render: Callable[[str], str], page: str) -> None:
    assert check.raw_markup(render(page))


def test_every_page_and_the_package_docstrings_render(
    render: Callable[[str], str], package: griffe.Module
) -> None:
    pages = sorted((ROOT / "docs").glob("*.md"))
    assert len(pages) > 15
    bad = {p.name: found for p in pages if (found := check.raw_markup(render(p.read_text())))}
    assert not bad, bad
    for path in ("bilevel_kit", "bilevel_kit.sim"):
        html = render(_doc(package, path))
        assert '<span class="gp">&gt;&gt;&gt; </span>' in html and not check.raw_markup(html)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    build = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert build.returncode == 0, build.stderr[-3000:]
    return out


MATH_PAGES = ["api", "timeline", "problem", "formulations"]


@pytest.mark.slow
def test_built_api_page_has_links_and_maths_not_roles(site: Path) -> None:
    page = (site / "api" / "index.html").read_text(encoding="utf-8")
    assert check.raw_markup(page) == []
    assert page.count('class="autorefs autorefs-internal"') > 250
    assert page.count('class="arithmatex"') > 100
    for name in MATH_PAGES[1:]:
        assert 'class="arithmatex"' in (site / name / "index.html").read_text(encoding="utf-8")


@pytest.mark.slow
def test_site_loads_nothing_from_the_network(site: Path) -> None:
    remote = re.compile(r"""<(?:script|link)\b[^>]*(?:src|href)="(?:https?:)?//""")
    bad = [str(p.relative_to(site)) for p in site.rglob("*.html") if remote.search(p.read_text())]
    assert not bad, f"pages that load a script or stylesheet from the network: {bad}"
    assert (site / "assets" / "katex" / "katex.min.js").is_file()
    assert (site / "assets" / "katex" / "LICENSE").is_file()


BROWSER = find_chromium()


@pytest.mark.slow
@pytest.mark.skipif(BROWSER is None, reason="no Chromium on this machine (Debian's 'chromium')")
def test_every_formula_renders_in_a_browser(site: Path) -> None:
    assert BROWSER is not None
    browser = Chromium(BROWSER)
    try:
        for name in MATH_PAGES:
            _, events = browser.open(site / name / "index.html")
            counts = {}
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                counts = browser.evaluate(
                    "({math: document.querySelectorAll('.arithmatex').length,"
                    " done: document.querySelectorAll('.arithmatex .katex').length,"
                    " errors: document.querySelectorAll('.katex-error').length})"
                )
                if counts["done"] == counts["math"]:
                    break
                time.sleep(0.2)
            events += browser.drain()
            assert counts["math"] > 0 and counts["done"] == counts["math"], (name, counts)
            assert counts["errors"] == 0, (name, counts)
            remote = [u for u in requested_urls(events) if not u.startswith(("file:", "data:"))]
            assert not remote, (name, remote)
            # The search worker cannot start from file:// (a browser rule, not the site's).
            errors = [e for e in console_errors(events) if "worker.js" not in e]
            assert not errors, (name, errors)
    finally:
        browser.close()
