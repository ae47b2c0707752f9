"""The documentation in docs/ is the reference the code cites: keep the two consistent.

* No docstring or comment of the package cites a file users do not have (``DESIGN.md``).
* Every ``docs/<page>.md`` the package cites exists, and so does its ``#anchor`` if it has one.
* docs/formats.md lists every field of the instance, solution and pack-file schemas.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bilevel_kit import instance, packfile, solution

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "bilevel_kit"
DOCS = ROOT / "docs"
CITATION = re.compile(r"docs/([A-Za-z0-9_.-]+\.md)(?:#([A-Za-z0-9_-]+))?")


def _sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _slug(heading: str) -> str:
    """The anchor Python-Markdown's toc extension gives a heading (its default slugify)."""
    text = re.sub(r"[`*]", "", heading)
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _anchors(page: Path) -> set[str]:
    anchors = set()
    in_code = False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            in_code = not in_code
        elif not in_code and line.startswith("#"):
            anchors.add(_slug(line.lstrip("#")))
    return anchors


def test_docs_folder_exists() -> None:
    assert (DOCS / "index.md").is_file()
    assert (ROOT / "mkdocs.yml").is_file()


@pytest.mark.parametrize("path", _sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_package_does_not_cite_design_notes(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    lines = [i + 1 for i, line in enumerate(text.splitlines()) if "DESIGN.md" in line]
    assert not lines, (
        f"{path.relative_to(ROOT)}:{lines}: cites DESIGN.md, which users do not have; "
        "cite a page of docs/ instead"
    )


def test_cited_docs_pages_exist() -> None:
    pages = {p.name for p in DOCS.glob("*.md")}
    missing = []
    for path in _sources():
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for page, anchor in CITATION.findall(line):
                where = f"{path.relative_to(ROOT)}:{n}"
                if page not in pages:
                    missing.append(f"{where}: docs/{page} does not exist")
                elif anchor and anchor not in _anchors(DOCS / page):
                    missing.append(f"{where}: docs/{page} has no anchor #{anchor}")
    assert not missing, "\n".join(missing)


def test_docs_pages_do_not_cite_design_notes() -> None:
    bad = [p.name for p in DOCS.glob("*.md") if "DESIGN.md" in p.read_text(encoding="utf-8")]
    assert not bad, f"docs pages citing DESIGN.md: {bad}"


def _field_paths(node: dict[str, Any], prefix: str = "") -> Iterator[str]:
    """Dotted paths of a JSON Schema's fields, as docs/formats.md writes them."""
    for key, sub in node.get("properties", {}).items():
        path = f"{prefix}{key}"
        yield path
        yield from _field_paths(sub, path + ".")
        extra = sub.get("additionalProperties")
        if isinstance(extra, dict):
            yield from _field_paths(extra, path + ".<key>.")
        items = sub.get("items")
        if isinstance(items, dict):
            yield from _field_paths(items, path + "[].")


@pytest.mark.parametrize(
    "schema",
    [instance.schema, solution.schema, packfile.schema],
    ids=["instance", "solution", "pack"],
)
def test_formats_page_lists_every_schema_field(schema: Any) -> None:
    text = (DOCS / "formats.md").read_text(encoding="utf-8")
    missing = [p for p in _field_paths(schema()) if f"`{p}`" not in text]
    assert not missing, f"docs/formats.md does not describe: {missing}"


def test_tutorial_shows_its_instance_file_verbatim() -> None:
    """The tutorial's instance is inline (a snippet include shows nothing on the repository
    page, issue 40 item 5) and is the file ``instances/tutorial_shelf.json``, byte for byte."""
    text = (DOCS / "tutorial.md").read_text(encoding="utf-8")
    shown = re.search(r"identical\):\n\n```json\n(?P<body>.*?\n)```\n", text, re.DOTALL)
    assert shown is not None and "--8<--" not in text
    inst = (ROOT / "instances" / "tutorial_shelf.json").read_text(encoding="utf-8")
    assert shown["body"] == inst
    assert len(instance.loads(shown["body"], "docs/tutorial.md").tasks) == 8
