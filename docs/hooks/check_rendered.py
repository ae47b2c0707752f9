"""MkDocs hook: fail the build when a page shows markup instead of rendering it.

``mkdocs build --strict`` passes on pages that do not render; this hook looks at every page's
HTML outside code and raises, which fails the build with or without ``--strict``, on:

* a reST role or directive: ``docs/hooks/rest_docstrings.py`` rewrites the docstrings' roles
  and maths for the API page, and a role it misses (a new role, a typo such as ``:func:``
  without its backticks closed) would reach the reader as raw text;
* a raw ``$$`` outside the maths that ``pymdownx.arithmatex`` recognised (its
  ``class="arithmatex"`` elements): a display block Markdown did not take as a block, such as
  one indented by two spaces under a list item, shows its LaTeX as text;
* a doctest read as Markdown: ``>>>`` becomes three nested blockquotes around one run-on line
  (the rewrite turns doctest blocks of docstrings into code; a page must fence its own).
"""

from __future__ import annotations

import re
from typing import Any

from mkdocs.exceptions import PluginError

#: Code and preformatted blocks may show markup on purpose; what is inside them is not checked.
CODE = re.compile(r"<(pre|code)\b[^>]*>.*?</\1>", re.DOTALL)
#: A role as the reader would see it: ``:func:`` followed by its code span or a backtick.
RAW_ROLE = re.compile(r":(?:py:)?[a-z]+:(?=<code>|`)")
RAW_DIRECTIVE = re.compile(r"\.\. (?:math|note|warning|code-block|[a-z]+)::")
#: Maths that arithmatex recognised (generic mode): KaTeX renders what is inside.
MATH = re.compile(r"<(div|span) class=\"arithmatex\">.*?</\1>", re.DOTALL)
RAW_DISPLAY_MATH = re.compile(r"\$\$")
#: A doctest prompt as Markdown renders it: nested blockquotes, or ">>>" inside a blockquote.
DOCTEST_QUOTE = re.compile(
    r"<blockquote>\s*<blockquote>|<blockquote>(?:(?!</blockquote>).)*?&gt;&gt;&gt;", re.DOTALL
)


def raw_markup(page_html: str) -> list[str]:
    """Every raw role, directive, ``$$`` or quoted doctest in a page's HTML, outside code."""
    found = []
    # Blank out code but keep the opening tag, so ":func:<code>x</code>" stays visible.
    text = CODE.sub(lambda m: f"<{m[1]}>", page_html)
    without_math = MATH.sub(lambda m: f"<{m[1]}>", text)
    for pattern, where in (
        (RAW_ROLE, text),
        (RAW_DIRECTIVE, text),
        (RAW_DISPLAY_MATH, without_math),
        (DOCTEST_QUOTE, text),
    ):
        for match in pattern.finditer(where):
            start = max(0, match.start() - 40)
            found.append(re.sub(r"\s+", " ", where[start : match.end() + 40]))
    return found


def on_post_page(output: str, *, page: Any, config: Any) -> str:
    found = raw_markup(output)
    if found:
        shown = "\n  ".join(found[:10])
        raise PluginError(
            f"{page.file.src_uri}: {len(found)} unrendered markup(s) in the page (a reST role "
            f"or directive, a raw $$, a doctest read as blockquotes; see "
            f"docs/hooks/check_rendered.py):\n  {shown}"
        )
    return output
