"""MkDocs hook: fail the build when a page shows reST markup instead of rendering it.

``docs/hooks/rest_docstrings.py`` rewrites the docstrings' reST roles and maths for the API
page; a role it misses (a new role, a typo such as ``:func:`` without its backticks closed)
would reach the reader as raw text. This hook looks at every page's HTML outside code and
raises, which fails ``mkdocs build`` with or without ``--strict``.
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


def raw_markup(page_html: str) -> list[str]:
    """Every raw role or directive in a page's HTML, with some context, outside code."""
    found = []
    for pattern in (RAW_ROLE, RAW_DIRECTIVE):
        # Blank out code but keep the opening tag, so ":func:<code>x</code>" stays visible.
        text = CODE.sub(lambda m: f"<{m[1]}>", page_html)
        for match in pattern.finditer(text):
            start = max(0, match.start() - 40)
            found.append(re.sub(r"\s+", " ", text[start : match.end() + 40]))
    return found


def on_post_page(output: str, *, page: Any, config: Any) -> str:
    found = raw_markup(output)
    if found:
        shown = "\n  ".join(found[:10])
        raise PluginError(
            f"{page.file.src_uri}: {len(found)} raw reST role(s) or directive(s) in the "
            f"rendered page (see docs/hooks/rest_docstrings.py):\n  {shown}"
        )
    return output
