"""Griffe extension: the package's reST-flavoured docstrings rewritten as Markdown for the API page.

The docstrings are written for readers of the code, in the reST idiom (``code``,
:func:`name`, :math:`x`, ``.. math::`` blocks). mkdocstrings renders Markdown, where those
would show as raw text, so before rendering this extension rewrites, in every docstring of the
package:

* a cross-reference role (``:func:``, ``:class:``, ``:mod:``, ``:meth:``, ``:attr:``,
  ``:data:``, ``:exc:``, ``:obj:``, ``:const:``) into an autorefs cross-reference to the
  object's full path, resolved like Python resolves the name in the docstring's scope:
  ``.name`` and ``..name`` as relative imports from the docstring's module, a bare name through
  the scope of the documented object (its members, its module's names and imports), ``~``
  showing only the last component and ``title <target>`` an explicit title. The reference is
  *optional*: a target the site does not render (a private helper, another library) shows as
  code instead of a broken link;
* ``:math:`tex``` into inline maths and a ``.. math::`` block into display maths, both in the
  syntax of ``pymdownx.arithmatex`` (generic mode), which KaTeX renders in the browser;
* a doctest block (a paragraph opening with ``>>>``) into a fenced ``pycon`` code block: to
  Markdown its ``>>>`` would be three nested blockquotes around one run-on line.

``mkdocs.yml`` loads it as a mkdocstrings-python extension; ``docs/hooks/check_rendered.py``
fails the build on any role left in the HTML.
"""

from __future__ import annotations

import html
import re
from collections.abc import Callable, Iterator
from typing import Any

import griffe

#: The cross-reference roles of the Python domain, with or without the ``py:`` prefix.
ROLE = re.compile(
    r":(?:py:)?(?P<role>func|class|mod|meth|attr|data|exc|obj|const):`(?P<body>[^`]+)`"
)
MATH_ROLE = re.compile(r":math:`(?P<tex>[^`]+)`")
MATH_BLOCK = re.compile(r"^(?P<indent>[ ]*)\.\. math::(?P<first>.*)$")
#: The prompt that opens a doctest block, at any indentation.
DOCTEST = re.compile(r"^(?P<indent>[ ]*)>>>(?: |$)")
EXPLICIT_TITLE = re.compile(r"^(?P<title>.+?)\s*<(?P<target>[^<>]+)>$", re.DOTALL)


def _exists(loader: griffe.GriffeLoader, path: str) -> bool:
    try:
        loader.modules_collection.get_member(path)
    except (KeyError, ValueError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return False
    return True


def _canonical(loader: griffe.GriffeLoader, path: str) -> str:
    """The path where the object is defined (re-exports point there), if it is known."""
    member = loader.modules_collection.get_member(path)
    if member.is_alias:
        try:
            return str(member.final_target.path)
        except (griffe.AliasResolutionError, griffe.CyclicAliasError):
            return str(member.target_path)
    return str(member.path)


def _candidates(obj: griffe.Object, target: str) -> Iterator[str]:
    """Full paths the written target may mean, most specific first."""
    module = obj.module
    if target.startswith("."):
        dots = len(target) - len(target.lstrip("."))
        rest = target[dots:]
        is_init = module.is_package or module.is_subpackage
        package = module.path if is_init else module.parent.path  # type: ignore[union-attr]
        parts = package.split(".")
        base = ".".join(parts[: len(parts) - (dots - 1)])
        yield f"{base}.{rest}"
        yield f"{module.path}.{rest}"  # the Sphinx reading: relative to the module itself
        return
    head, _, tail = target.partition(".")
    scopes: list[griffe.Object] = [obj]
    if obj.parent is not None:
        scopes.append(obj.parent)  # type: ignore[arg-type]
    for scope in scopes:
        try:
            resolved = scope.resolve(head)
        except griffe.NameResolutionError:
            continue
        yield f"{resolved}.{tail}" if tail else resolved
    if obj.is_class:
        yield f"{obj.path}.{target}"
    yield target
    yield f"{module.path}.{target}"


def resolve(obj: griffe.Object, loader: griffe.GriffeLoader, target: str) -> str:
    """The full path of ``target`` as written in ``obj``'s docstring (itself if not found)."""
    for path in _candidates(obj, target):
        if _exists(loader, path):
            return _canonical(loader, path)
    return target.lstrip(".")


def cross_reference(obj: griffe.Object, loader: griffe.GriffeLoader, body: str) -> str:
    """An optional autorefs reference for one role's body (``target`` or ``title <target>``)."""
    explicit = EXPLICIT_TITLE.match(body.strip())
    target = (explicit["target"] if explicit else body).strip()
    short = target.startswith("~")
    target = target.lstrip("~")
    if explicit:
        title = explicit["title"]
    elif short:
        title = target.rsplit(".", 1)[-1]
    else:
        title = target.lstrip(".")
    path = resolve(obj, loader, target)
    return (
        f'<autoref identifier="{html.escape(path)}" optional>'
        f"<code>{html.escape(title)}</code></autoref>"
    )


#: A block's start: the match of its opening line, given the output so far (None: no block).
BlockStart = Callable[[str, list[str]], re.Match[str] | None]
#: A block's rewrite: appends its Markdown to the output and returns the index after the block.
BlockRewrite = Callable[[list[str], int, re.Match[str], list[str]], int]


def rewrite_blocks(text: str, starts: BlockStart, block: BlockRewrite) -> str:
    """``text`` line by line, each block that ``starts`` at a line rewritten by ``block`` (the
    one walk that both block kinds share), every other line kept."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        match = starts(lines[i], out)
        if match is None:
            out.append(lines[i])
            i += 1
        else:
            i = block(lines, i, match, out)
    return "\n".join(out)


def math_blocks(text: str) -> str:
    """``.. math::`` directives as ``$$`` blocks, one per blank-line separated equation."""
    return rewrite_blocks(text, lambda line, _: MATH_BLOCK.match(line), _math_block)


def _math_block(lines: list[str], i: int, directive: re.Match[str], out: list[str]) -> int:
    indent = len(directive["indent"])
    body = [directive["first"].strip()] if directive["first"].strip() else []
    i += 1
    while i < len(lines) and (
        not lines[i].strip() or len(lines[i]) - len(lines[i].lstrip()) > indent
    ):
        body.append(lines[i].strip())
        i += 1
    while body and not body[-1]:
        body.pop()  # trailing blank lines belong to the text after the block
        i -= 1
    # A $$ block indented by less than four spaces would not be a block to Markdown.
    pad = " " * indent if indent >= 4 else ""
    equations = "\n".join(body).strip().split("\n\n")
    out.append("")
    for equation in equations:
        out += [f"{pad}$$", *(f"{pad}{line}" for line in equation.split("\n")), f"{pad}$$", ""]
    return i


def doctest_blocks(text: str) -> str:
    """Doctest blocks (``>>>`` up to the next blank line) as fenced ``pycon`` code blocks."""
    return rewrite_blocks(text, _doctest_start, _doctest_block)


def _doctest_start(line: str, out: list[str]) -> re.Match[str] | None:
    prompt = DOCTEST.match(line)
    if out and out[-1].strip():
        return None  # a ">>>" inside a paragraph is not a doctest block
    return prompt


def _doctest_block(lines: list[str], i: int, prompt: re.Match[str], out: list[str]) -> int:
    pad = prompt["indent"]
    out.append(f"{pad}```pycon")
    while i < len(lines) and lines[i].strip():
        out.append(lines[i])
        i += 1
    out.append(f"{pad}```")
    return i


def rewrite(text: str, obj: griffe.Object, loader: griffe.GriffeLoader) -> str:
    """One docstring rewritten: doctests, display maths, inline maths, then cross-references."""
    text = math_blocks(doctest_blocks(text))
    text = MATH_ROLE.sub(lambda m: rf"\({m['tex'].strip()}\)", text)
    return ROLE.sub(lambda m: cross_reference(obj, loader, m["body"]), text)


class RestDocstrings(griffe.Extension):
    """Rewrite every docstring of a loaded package before mkdocstrings renders it."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **_: Any) -> None:
        self._walk(pkg, loader)

    def _walk(self, obj: griffe.Object, loader: griffe.GriffeLoader) -> None:
        if obj.docstring is not None:
            obj.docstring.value = rewrite(obj.docstring.value, obj, loader)
        for member in list(obj.members.values()):
            if not member.is_alias:
                self._walk(member, loader)  # type: ignore[arg-type]
